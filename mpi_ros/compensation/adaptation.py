# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Online adaptation of a running compensator's model from the measured displacement.

The compensator records every command it publishes, the sensor's readings arrive on their
own topic, and :class:`Adaptation` pairs them (lock step: the k-th reading answers the
k-th command, or ``delay`` commands earlier), screens the readings, feeds the recursive
identification (:class:`~mpi_ros.identification.recursive.RecursiveFit`: forgetting Gram
matrices, the QP (34)-(36) under the same invertibility constraints) and proposes a
candidate model when it is better, by a stated margin, on the most recent readings, which
the fit has not seen.  The node applies a candidate through its ordinary parameter path
(the same validation as a push), so an adapted model is what ``ros2 param get`` and
``ros2 param dump`` show.

The work runs in a child process (:class:`AdaptationProcess`: its own interpreter, so the
command path never waits for the interpreter lock while a step runs) or in a thread of the
node's process (:class:`AdaptationWorker`); either way the command path only appends a float
to a list.  Given a :class:`ReadingSource`, the child takes the readings itself (a
subscriber the node's layer supplies, see :func:`serve_socket`): the node's process then
never handles a reading, and sends the child only its commands.

Rules, in the order they are checked on each batch of paired samples:

- **garbage freezes adaptation, not the compensator**: a non-finite reading, a stuck
  sensor (the same value over ``stuck_samples`` readings while the command moves) or a jump
  of the residual against the running model by more than ``jump`` of the displacement range
  from one sample to the next; the recent window is discarded and adaptation resumes after a
  clean ``holdout``;
- **persistent excitation**: the commands of the recent window must span at least
  ``min_excitation`` of the identified input range, else nothing enters the Gram matrix and
  nothing is solved (a hold, a tiny motion);
- **held out**: the newest ``holdout`` seconds of pairs are not in the Gram matrix; a
  candidate is proposed only when its RMS error there is at most ``1 - margin`` times the
  running model's;
- **bounded change**: a candidate differs from the running model by at most ``max_step``
  of the displacement range over the recent commands (else it is moved only that far
  towards the QP's solution, which the linear constraints allow).
"""

from array import array
from collections import deque
from dataclasses import dataclass, field, replace
import math
import multiprocessing.connection
import os
import pickle
import signal
import socket
import subprocess
import sys
import threading
import time
from typing import Any, Callable, Protocol

import numpy as np
import numpy.typing as npt

from ..errors import ModelError, MPIError
from ..extensions import extended_model_from_params
from ..extensions.thermal_drift import ThermalDriftModel
from ..identification.recursive import heating, RecursiveFit, WeightPoint
from ..operators.model import MPIModel
from ..operators.play import play_end_state

__all__ = ['Adaptation', 'AdaptationProcess', 'AdaptationSettings', 'AdaptationWorker',
           'adaptable', 'Candidate', 'CHILD_NICE', 'child_cpus', 'PRIORITIES', 'ReadingSource',
           'ReadingSubscription', 'serve_socket', 'Subscribe', 'with_gaps', 'yield_cpu']

FloatArray = npt.NDArray[np.float64]

#: The models the adaptation adapts: Gamma, or Gamma with a thermal drift (its weight
#: ``w_T`` re-fitted, its thermal state following the commands, ``tau_T`` kept).
AdaptedModel = MPIModel | ThermalDriftModel

#: First 8 bytes of a message of pairs to the child (the others are pickled tuples).
_PAIRS = b'pairs\x00\x00\x00'
#: Most pairs per message, and most messages of pairs the child has not acknowledged:
#: 4 x 32 KiB stay below a socket pair's buffer (208 KiB by default on Linux).
_CHUNK = 2048
_IN_FLIGHT = 4
#: The state a node shows when its adaptation's child process has ended.
_ENDED = 'stopped: the adaptation process ended'
#: ... and when it was stopped for not taking the commands.
_BEHIND = 'stopped: the adaptation process did not take the commands (stalled)'
#: The child process's CPU priorities (``adaptation.priority``), the default first.
PRIORITIES = ('idle', 'low')
#: A child at idle priority with this many held-out windows of commands not taken, that has
#: taken none for this many held-out durations (``adaptation.holdout`` seconds each), or
#: that has lost a reading, is restarted at ``'low'`` (it would lose its readings next;
#: beside two CPU hogs an idle child took under 500 pairs in 120 s).
_IDLE_BEHIND_WINDOWS = 2
#: Longest wait [s] for a child restarted at ``'low'`` to end after it was asked to.
_RETIRE_S = 2.0
#: Longest wait [s] for a killed child to be gone (see :func:`_end`).
_KILLED_S = 30.0


@dataclass(frozen=True)
class ReadingSource:
    """
    Where the adaptation's child process takes the displacement readings itself.

    Attributes
    ----------
    topic : str
        The readings' topic, fully resolved (the node's namespace and remappings applied),
        e.g. ``/displacement``; each message one reading [m], in order.
    depth : int
        Keep-last depth of the subscription (the node's ``qos_depth``).
    reliability : str
        ``reliable`` or ``best_effort`` (the node's ``qos_reliability``).
    sample_period : float
        Interval between readings [s] (the node's ``sample_period``): the subscriber takes
        the queued ones well before ``depth`` of them fill its history.
    node_name, namespace : str
        Name and namespace of the child's own node (it shows in the ROS graph).

    """

    topic: str
    depth: int
    reliability: str
    sample_period: float
    node_name: str
    namespace: str = '/'


class ReadingSubscription(Protocol):
    """What a subscriber of readings gives back: its faults, and a way to close it."""

    def faults(self) -> dict[str, Any]:
        """
        Return the subscription's state.

        Returns
        -------
        dict
            ``malformed`` (count), ``last_malformed`` (reason), ``lost`` (count) and
            ``publishers`` (matched publishers of the readings).

        """

    def close(self) -> None:
        """Stop taking readings and release the subscription (bounded time)."""


#: Opens a subscription: (source, record a batch of readings [m] in order) -> subscription.
Subscribe = Callable[[ReadingSource, Callable[[FloatArray], None]], ReadingSubscription]


@dataclass(frozen=True)
class AdaptationSettings:
    """
    The adaptation's parameters (the node's ``adaptation.*`` keys).

    Attributes
    ----------
    sample_period : float
        Interval between commands [s] (the node's ``sample_period``).
    forgetting_time : float
        Memory of the Gram matrices [s]: the forgetting factor is
        ``exp(-sample_period / forgetting_time)``.
    offset_time : float
        Memory of the operating point [s] (the regressors' means that set the constant
        term): shorter than ``forgetting_time``, since a zero drifts faster than a shape.
    holdout : float
        Newest part of the readings held out of the fit, on which a candidate must win [s].
    period : float
        Interval between candidate solves [s].
    margin : float
        A candidate's held-out RMS error must be at most ``1 - margin`` of the running
        model's.
    max_step : float
        Largest change of the modelled displacement per update, as a fraction of the
        displacement range.
    min_excitation : float
        Fraction of the identified input range the recent commands must span.
    delay : int
        The reading answering command k arrives as reading ``k + delay`` (a sensor that
        lags by ``delay`` samples; 0: lock step).
    jump : float
        A residual step larger than this fraction of the displacement range between two
        readings is garbage.
    stuck_samples : int
        This many identical readings while the command moves are a stuck sensor.
    hysteresis : bool
        Adapt the weights of H as well (default: S' and the operating point only; the
        plays that a trajectory inside the range never wipes out are not determined by
        its data, see :meth:`RecursiveFit.solve`).
    priority : str
        The child process's share of the CPU (:data:`PRIORITIES`): ``'idle'``, only the
        CPU time no other work wants (``SCHED_IDLE``, once its subscription is open), and
        back to ``'low'`` by itself when it falls behind (:class:`AdaptationProcess`);
        ``'low'``, niceness :data:`CHILD_NICE` below the node.  A thread of the node
        (``adaptation.process`` false) shares the node's priority either way.

    """

    sample_period: float = 1e-3
    forgetting_time: float = 20.0
    holdout: float = 5.0
    period: float = 1.0
    margin: float = 0.1
    max_step: float = 0.05
    min_excitation: float = 0.3
    delay: int = 0
    offset_time: float = 1.0
    jump: float = 0.2
    stuck_samples: int = 50
    hysteresis: bool = False
    priority: str = 'idle'

    def __post_init__(self) -> None:
        """Check the values (a ``ModelError`` naming the key)."""
        positive = ('sample_period', 'forgetting_time', 'offset_time', 'holdout', 'period',
                    'max_step', 'jump')
        for name in positive:
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0.0):
                msg = f'adaptation.{name} must be finite and > 0; found {value!r}'
                raise ModelError(msg)
        for name in ('margin', 'min_excitation'):
            value = getattr(self, name)
            if not (math.isfinite(value) and 0.0 <= value < 1.0):
                msg = f'adaptation.{name} must lie in [0, 1); found {value!r}'
                raise ModelError(msg)
        if self.priority not in PRIORITIES:
            msg = (f'adaptation.priority must be one of {", ".join(PRIORITIES)}; found'
                   f' {self.priority!r}')
            raise ModelError(msg)
        if self.delay < 0 or self.stuck_samples < 2:
            msg = (f'adaptation.delay must be >= 0 and adaptation.stuck_samples >= 2; found'
                   f' {self.delay!r} and {self.stuck_samples!r}')
            raise ModelError(msg)

    @classmethod
    def from_values(cls, values: dict[str, Any], sample_period: float) -> 'AdaptationSettings':
        """
        Build from the node's ``adaptation.*`` values.

        Parameters
        ----------
        values : dict
            Parameter name -> plain value (missing keys keep their defaults).
        sample_period : float
            The node's ``sample_period`` [s].

        Returns
        -------
        AdaptationSettings
            The settings.

        """
        prefix = 'adaptation.'
        switches = ('adaptation.enabled', 'adaptation.process')
        fields = {key[len(prefix):]: value for key, value in values.items()
                  if key.startswith(prefix) and key not in switches}
        return cls(sample_period=sample_period, **fields)

    def samples(self, seconds: float) -> int:
        """Convert a duration [s] to a sample count, at least 1."""
        return max(1, int(round(seconds / self.sample_period)))


@dataclass(frozen=True)
class Candidate:
    """
    A model the adaptation proposes.

    Attributes
    ----------
    model : MPIModel or ThermalDriftModel
        The candidate (same thresholds, and time constant, as the running one).
    point : WeightPoint
        Its point in the recursive fit's design.
    running_error, candidate_error : float
        RMS errors on the held-out readings, fractions of the displacement range.
    step : float
        Largest change of the modelled displacement over the recent commands, as a
        fraction of the displacement range.

    """

    model: AdaptedModel
    point: WeightPoint
    running_error: float
    candidate_error: float
    step: float

    def params(self) -> dict[str, Any]:
        """Return the candidate's ``model.*`` parameter form."""
        return self.model.to_params()

    def describe(self) -> str:
        """Return one log line: the held-out errors and the step."""
        thermal = (f'; thermal weight {self.model.weight:.4g} 1/A'
                   if isinstance(self.model, ThermalDriftModel) else '')
        return (f'held-out RMS {100 * self.running_error:.3g} % -> '
                f'{100 * self.candidate_error:.3g} % of the displacement range '
                f'(step {100 * self.step:.2g} %){thermal}')


@dataclass
class _Counts:
    accepted: int = 0
    not_better: int = 0
    refused: int = 0
    frozen: int = 0
    paused: int = 0
    failed_solves: int = 0
    pairs: int = 0
    garbage: int = 0
    reasons: list[str] = field(default_factory=list)


class Adaptation:
    """
    Pair commands with readings, screen them, fit recursively, propose better models.

    Parameters
    ----------
    model : MPIModel or ThermalDriftModel
        The running forward model: Gamma (n >= 1), or Gamma with a thermal drift, whose
        weight ``w_T`` is adapted with Gamma and whose thermal state follows the commands.
    settings : AdaptationSettings
        See :class:`AdaptationSettings`.

    Raises
    ------
    ModelError
        For a model the recursive fit cannot take (inverse, n = 0).

    """

    def __init__(self, model: AdaptedModel, settings: AdaptationSettings) -> None:
        self.settings = settings
        self._commands: deque[float] = deque()
        self._readings: deque[float] = deque()
        self._lock = threading.Lock()
        self._ready: Candidate | None = None
        self._counts = _Counts()
        self._state = 'collecting readings'
        self._recent_error = math.nan
        # The state _reset sets (declared here, where the type checker meets it first).
        self._in_gram: int = 0
        self._since_solve: int = 0
        self._frozen_left: int = 0
        self._skip: int = 0
        self._determined: bool = False
        self._lo: float = math.inf
        self._hi: float = -math.inf
        self._last_residual: float = math.nan
        self._reset(model)
        # The first ``delay`` readings answer commands before the first one recorded; a
        # reset (a model pushed from outside) restarts the fit, not the stream's pairing.
        self._skip = settings.delay
        # Compile the play kernel the worker uses now, not in the worker's first step:
        # numba compiles holding the interpreter lock, which would stall the command path.
        play_end_state(np.zeros(2), np.zeros(1))

    @property
    def model(self) -> AdaptedModel:
        """Return the running model the adaptation starts its candidates from."""
        with self._lock:
            return self._model

    # -- the node's side ---------------------------------------------------------------
    def record_command(self, current: float) -> None:
        """Record a published command [A] (cheap: the command path calls it)."""
        self._commands.append(current)

    def record_measurement(self, displacement: float) -> None:
        """Record a displacement reading [m], in the order they arrive."""
        self._readings.append(displacement)

    def record_pairs(self, currents: npt.ArrayLike, displacements: npt.ArrayLike) -> None:
        """Record published commands [A] and readings [m] in bulk, each in order."""
        self._commands.extend(np.asarray(currents, dtype=np.float64).tolist())
        self._readings.extend(np.asarray(displacements, dtype=np.float64).tolist())

    def record_measurements(self, displacements: npt.ArrayLike) -> None:
        """Record displacement readings [m] in bulk, in the order they arrived."""
        self._readings.extend(np.asarray(displacements, dtype=np.float64).tolist())

    def discard_readings(self) -> None:
        """Drop the readings not yet paired: no command recorded from now on answers them."""
        self._readings.clear()

    def take_candidate(self) -> Candidate | None:
        """Return the candidate ready to apply, once (None when there is none)."""
        with self._lock:
            candidate, self._ready = self._ready, None
        return candidate

    def applied(self, candidate: Candidate, accepted: bool, reason: str = '') -> None:
        """
        Tell the adaptation whether the node's validation took the candidate.

        Parameters
        ----------
        candidate : Candidate
            What :meth:`take_candidate` returned.
        accepted : bool
            True when the model now runs.
        reason : str
            The refusal's reason (``accepted`` False).

        """
        with self._lock:
            if accepted:
                self._counts.accepted += 1
                self._point = candidate.point
                self._model = candidate.model
                self._fit.remember(candidate.point)
                self._remember(f'update {self._counts.accepted}: {candidate.describe()}')
            else:
                self._counts.refused += 1
                self._remember(f'candidate refused by validation: {reason}')

    def reset(self, model: AdaptedModel) -> None:
        """Start again from a model pushed from outside (the Gram matrices are dropped)."""
        with self._lock:
            self._reset(model)
            self._ready = None

    def status(self) -> dict[str, Any]:
        """Return the values /diagnostics shows (``adaptation_*``)."""
        with self._lock:
            c = self._counts
            recent = self._recent_error
            return {
                'adaptation_state': self._state,
                'adaptation_updates_accepted': c.accepted,
                'adaptation_candidates_not_better': c.not_better,
                'adaptation_candidates_refused': c.refused,
                'adaptation_freezes': c.frozen,
                'adaptation_pairs': c.pairs,
                'adaptation_garbage_readings': c.garbage,
                'adaptation_recent_rms_percent': (round(100 * recent, 4)
                                                  if math.isfinite(recent) else 'n/a'),
                'adaptation_last_event': c.reasons[-1] if c.reasons else '',
            }

    def events(self) -> list[str]:
        """Return and clear the events to log (accepted updates, freezes, pauses)."""
        with self._lock:
            events, self._counts.reasons = self._counts.reasons, []
        return events

    # -- the worker's side -------------------------------------------------------------
    def step(self) -> Candidate | None:
        """
        Take the pairs that arrived, screen them, fit, and maybe propose a candidate.

        Returns
        -------
        Candidate or None
            The new candidate (also kept for :meth:`take_candidate`), or None.

        """
        x, y = self._pairs()
        if x.size == 0:
            return None
        with self._lock:
            model, point = self._model, self._point
        ok = self._screen(model, x, y)
        self._buffer(x, y, ok)
        s = self.settings
        if self._since_solve < s.samples(s.period) or self._frozen_left > 0:
            return None
        self._since_solve = 0
        if not self._excited():
            return None
        if self._fit.samples < s.samples(s.holdout):
            self._set_state('collecting readings')
            return None
        self._set_state('adapting')
        try:
            solution = self._fit.solve(point, hysteresis=s.hysteresis)
        except MPIError as err:
            self._counts.failed_solves += 1
            self._remember(f'solve failed: {err}')
            return None
        candidate = self._candidate(model, point, solution)
        if candidate is None:
            return None
        with self._lock:
            self._ready = candidate
        return candidate

    # -- internals ---------------------------------------------------------------------
    def _reset(self, model: AdaptedModel) -> None:
        s = self.settings
        gamma = _gamma(model)
        drift = model if isinstance(model, ThermalDriftModel) else None
        self._fit = RecursiveFit(
            gamma, forgetting=math.exp(-s.sample_period / s.forgetting_time),
            offset_forgetting=math.exp(-s.sample_period / s.offset_time),
            thermal_time_constant=None if drift is None else drift.time_constant,
            thermal_weight=0.0 if drift is None else drift.weight,
            sample_period=s.sample_period)
        self._model = model
        self._point = self._fit.start
        d = self._fit.design
        self._input_span = 2.0 * d.x_scale
        sweep = d.input_offset + d.x_scale * np.concatenate(
            [np.linspace(-1.0, 1.0, 201), np.linspace(1.0, -1.0, 201)])
        state = np.full(gamma.n + 1, float(sweep[0]) - gamma.input_offset)
        self._output_span = float(np.ptp(gamma.run(sweep, state)[0]))
        # The thermal state (T, x of the last sample) at the newest reading screened and
        # at the first pair of the recent window (NaN: settles at the first sample).
        self._heat_now = np.full(2, math.nan)
        self._heat_window = np.full(2, math.nan)
        # The thermal state of the pairs the fit has taken (the drift on the displacement,
        # k_T T, is held and taken off the readings the fit sees).
        self._heat_fed = np.full(2, math.nan)
        self._bx = np.empty(0)
        self._by = np.empty(0)
        self._bok = np.empty(0, dtype=bool)
        self._in_gram = 0
        self._since_solve = 0
        self._frozen_left = 0
        self._determined = False
        self._lo = math.inf
        self._hi = -math.inf
        self._stuck_x = np.empty(0)
        self._stuck_y = np.empty(0)
        self._last_residual = math.nan
        # Play outputs on the raw input [A] (every model of the design shares the
        # thresholds; a model with input offset x0 has the states minus x0): at the
        # newest reading screened, and at the first pair of the recent window.
        self._thresholds = np.asarray(gamma.hysteresis.thresholds, dtype=np.float64)
        self._plays_now: FloatArray | None = None
        self._plays_window: FloatArray | None = None

    def _pairs(self) -> tuple[FloatArray, FloatArray]:
        commands, readings = self._commands, self._readings
        while self._skip and readings:
            readings.popleft()
            self._skip -= 1
        k = min(len(commands), len(readings))
        x = np.fromiter((commands.popleft() for _ in range(k)), dtype=np.float64, count=k)
        y = np.fromiter((readings.popleft() for _ in range(k)), dtype=np.float64, count=k)
        # Readings that never come (no sensor topic): keep the commands bounded.
        limit = 20 * self.settings.samples(self.settings.holdout)
        while len(commands) > limit:
            commands.popleft()
        self._counts.pairs += k
        return x, y

    def _screen(self, model: AdaptedModel, x: FloatArray,
                y: FloatArray) -> npt.NDArray[np.bool_]:
        # Garbage readings: non-finite, stuck, or a residual jump.  Any of them freezes.
        s = self.settings
        if self._plays_now is None:
            self._plays_now = np.full(self._thresholds.size, float(x[0]))
        prediction, self._plays_now, self._heat_now = self._run(
            model, x, self._plays_now, self._heat_now)
        finite = np.isfinite(y)
        residual = np.where(finite, y - prediction, np.nan)
        previous = np.concatenate([[self._last_residual], residual[:-1]])
        jumps = np.abs(residual - previous) > s.jump * self._output_span
        # A stuck sensor: the same reading stuck_samples times while the commands of that
        # run moved by 5 % of the input range (a hold of the command is no fault).  Runs of
        # equal readings, carried over from the previous batch (vectorised: this thread
        # shares the interpreter with the command path).
        stuck = self._stuck(x, y)
        self._last_residual = float(residual[-1]) if finite[-1] else math.nan
        bad = ~finite | jumps | stuck
        if np.any(bad):
            count = int(np.count_nonzero(bad))
            self._counts.garbage += count
            self._counts.frozen += 1
            what = ('non-finite or missing' if not np.all(finite) else 'stuck' if np.any(stuck)
                    else 'jumping')
            self._set_state(f'frozen: {count} {what} readings; resumes after a clean'
                            f' {s.holdout:g} s')
            self._frozen_left = s.samples(s.holdout)
            # The held-out window may hold the start of the fault: it is discarded.
            self._flush(keep=0, ok=False)
            self._last_residual = math.nan
            return np.zeros(y.size, dtype=bool)
        if self._frozen_left > 0:
            self._frozen_left = max(0, self._frozen_left - y.size)
            if self._frozen_left == 0:
                self._set_state('adapting')
        return np.ones(y.size, dtype=bool)

    def _stuck(self, x: FloatArray, y: FloatArray) -> npt.NDArray[np.bool_]:
        s = self.settings
        xs = np.concatenate([self._stuck_x, x])
        ys = np.concatenate([self._stuck_y, y])
        start = np.ones(ys.size, dtype=bool)
        start[1:] = ys[1:] != ys[:-1]
        run_id = np.cumsum(start) - 1
        run_start = np.flatnonzero(start)
        length = np.arange(ys.size) - run_start[run_id] + 1
        low = np.minimum.reduceat(xs, run_start)[run_id]
        high = np.maximum.reduceat(xs, run_start)[run_id]
        flagged = (length >= s.stuck_samples) & (high - low > 0.05 * self._input_span)
        # Keep the current run (at most stuck_samples of it) for the next batch.
        tail = ys.size - int(run_start[-1]) if ys.size else 0
        keep = min(tail, s.stuck_samples)
        self._stuck_x, self._stuck_y = xs[xs.size - keep:], ys[ys.size - keep:]
        result: npt.NDArray[np.bool_] = flagged[flagged.size - y.size:]
        return result

    def _buffer(self, x: FloatArray, y: FloatArray, ok: npt.NDArray[np.bool_]) -> None:
        s = self.settings
        if self._plays_window is None or self._bx.size == 0:
            self._plays_window = (np.full(self._thresholds.size, float(x[0]))
                                  if self._plays_window is None else self._plays_window)
        self._bx = np.concatenate([self._bx, x])
        self._by = np.concatenate([self._by, y])
        self._bok = np.concatenate([self._bok, ok])
        self._since_solve += x.size
        # Pairs older than the held-out window enter the Gram matrix.
        self._flush(keep=s.samples(s.holdout), ok=True)

    def _flush(self, *, keep: int, ok: bool) -> None:
        # Move the buffered pairs before the newest ``keep`` into the Gram matrix (once
        # each: ``_in_gram`` leading pairs are there already), then trim the buffer to the
        # recent window; ``ok`` False: the pairs only advance the plays, the buffer empties.
        s = self.settings
        end = self._bx.size - keep
        if end > self._in_gram:
            part = slice(self._in_gram, end)
            x, y = self._bx[part], self._by[part]
            good = self._bok[part] & ok
            use = good & self._determined_mask(x) & self._excitation_mask()
            gain = getattr(self._model, 'gain', 0.0)
            if gain != 0.0 and self._fit.heating_coefficient is not None:
                thermal, self._heat_fed = heating(x, coefficient=self._fit.heating_coefficient,
                                                  state=self._heat_fed)
                y = y - self._model.gamma.output_sign * gain * thermal
            self._fit.advance(x, np.where(good, y, 0.0), use=use)
            self._in_gram = end
        window = s.samples(s.holdout) + s.samples(min(s.forgetting_time, 2 * s.holdout))
        start = max(0, self._bx.size - window) if ok else self._bx.size
        if start and self._plays_window is not None:
            self._plays_window = play_end_state(self._bx[:start], self._thresholds,
                                                self._plays_window)
            if self._fit.heating_coefficient is not None:
                _, self._heat_window = heating(self._bx[:start],
                                               coefficient=self._fit.heating_coefficient,
                                               state=self._heat_window)
        self._bx, self._by, self._bok = (self._bx[start:], self._by[start:],
                                         self._bok[start:])
        self._in_gram = max(0, self._in_gram - start)

    def _determined_mask(self, x: FloatArray) -> npt.NDArray[np.bool_]:
        # Samples count once the input has swept most of its recent range: before that
        # the plays' states are not set by the data (the batch identification's burn-in).
        mask = np.zeros(x.size, dtype=bool)
        if self._determined:
            mask[:] = True
            return mask
        lo = np.minimum.accumulate(np.minimum(x, self._lo))
        hi = np.maximum.accumulate(np.maximum(x, self._hi))
        swept = (hi - lo) >= self.settings.min_excitation * self._input_span
        self._lo, self._hi = float(lo[-1]), float(hi[-1])
        if np.any(swept):
            first = int(np.argmax(swept))
            mask[first:] = True
            self._determined = True
        return mask

    def _commands_span(self) -> float:
        # How far the commands of the recent window move [A].
        return float(np.ptp(self._bx)) if self._bx.size else 0.0

    def _excited(self) -> bool:
        s = self.settings
        span = self._commands_span()
        if span < s.min_excitation * self._input_span:
            self._counts.paused += 1
            self._set_state(f'paused: the commands span {100 * span / self._input_span:.3g}'
                            f' % of the identified input range, adaptation needs'
                            f' {100 * s.min_excitation:.3g} %')
            return False
        return True

    def _excitation_mask(self) -> bool:
        return self._commands_span() >= self.settings.min_excitation * self._input_span

    def _candidate(self, model: AdaptedModel, point: WeightPoint,
                   solution: WeightPoint) -> Candidate | None:
        s = self.settings
        held = s.samples(s.holdout)
        x, y, ok = self._bx, self._by, self._bok
        if x.size <= held or not np.all(ok):
            return None
        test = slice(x.size - held, x.size)
        running = self._simulate(model, x)
        proposed = self._build(solution)
        # The output offset follows the newest training readings (a drifting zero): the
        # last held-out length before the held-out part.
        recent = slice(max(0, x.size - 2 * held), x.size - held)
        shift = float(np.mean(y[recent] - self._simulate(proposed, x)[recent]))
        solution = WeightPoint(solution.weights, solution.constant,
                               solution.output_shift + shift)
        fraction = 1.0
        for _ in range(6):
            target = point.toward(solution, fraction)
            candidate_model = self._build(target)
            simulated = self._simulate(candidate_model, x)
            step = float(np.max(np.abs(simulated - running))) / self._output_span
            if step <= s.max_step * (1.0 + 1e-9):
                break
            fraction *= 0.9 * s.max_step / step
        else:
            return None
        span = self._output_span
        running_error = _rms(running[test] - y[test]) / span
        candidate_error = _rms(simulated[test] - y[test]) / span
        with self._lock:
            self._recent_error = running_error
        # Better by the margin on the held-out readings, and on at least four of their
        # five consecutive parts (an improvement that holds throughout, not a lucky
        # stretch).
        parts = np.array_split(np.arange(x.size - held, x.size), 5)
        wins = sum(_rms(simulated[p] - y[p]) < _rms(running[p] - y[p]) for p in parts)
        if not (math.isfinite(candidate_error) and wins >= 4
                and candidate_error <= (1.0 - s.margin) * running_error):
            self._counts.not_better += 1
            return None
        gamma = _gamma(candidate_model)
        if not (gamma.hysteresis.satisfies_constraints()
                and gamma.superposition.satisfies_constraints()):
            self._counts.refused += 1
            self._remember('candidate violates (8)/(19): not proposed')
            return None
        return Candidate(_with_start(candidate_model, model), target, running_error,
                         candidate_error, step)

    def _simulate(self, model: AdaptedModel, x: FloatArray) -> FloatArray:
        # From the plays' state before the window's first pair (shared by the design's
        # models, shifted by each one's input offset) and the thermal state there.
        if self._plays_window is None:
            self._plays_window = np.full(self._thresholds.size, float(x[0]))
        return self._run(model, x, self._plays_window, self._heat_window)[0]

    def _run(self, model: AdaptedModel, x: FloatArray, plays: FloatArray,
             heat: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
        # The model's displacement from the plays' outputs on the raw input [A] and the
        # thermal state; returns both states after the last sample.
        gamma = _gamma(model)
        a = self._fit.heating_coefficient
        if not isinstance(model, ThermalDriftModel) or a is None:
            y, end = gamma.run(x, plays - gamma.input_offset)
            return y, end + gamma.input_offset, heat
        h, end = gamma.hysteresis_output(x, plays - gamma.input_offset)
        thermal, heat = heating(x, coefficient=a, state=heat)
        return (gamma.output(h + model.weight * thermal)
                + gamma.output_sign * model.gain * thermal,
                end + gamma.input_offset, heat)

    def _build(self, point: WeightPoint) -> AdaptedModel:
        # The model of a point of the fit's design, of the running model's kind.
        gamma = self._fit.model(point)
        if isinstance(self._model, ThermalDriftModel):
            return replace(self._model, model=gamma, weight=self._fit.thermal_weight(point))
        return gamma

    def _set_state(self, state: str) -> None:
        with self._lock:
            changed = state != self._state
            self._state = state
        if changed:
            self._remember(state)

    def _remember(self, event: str) -> None:
        reasons = self._counts.reasons
        reasons.append(event)
        del reasons[:-20]


class AdaptationWorker:
    """
    Run :meth:`Adaptation.step` every ``period`` seconds in a daemon thread.

    An exception in a step never reaches the command path: it is counted and logged
    through ``on_error``, and the next period tries again.

    Parameters
    ----------
    adaptation : Adaptation
        What to step.
    on_error : callable, optional
        Called with the exception's text.

    """

    def __init__(self, adaptation: Adaptation, *,
                 on_error: Callable[[str], None] | None = None) -> None:
        self.adaptation = adaptation
        self._stop = threading.Event()
        self._on_error = on_error
        self.errors = 0
        self._thread = threading.Thread(target=self._run, name='mpi_ros adaptation',
                                        daemon=True)

    def start(self) -> None:
        """Start the thread."""
        self._thread.start()

    def stop(self, timeout: float = 5.0) -> None:
        """Stop the thread (waits at most ``timeout`` seconds)."""
        self._stop.set()
        if self._thread.is_alive():
            self._thread.join(timeout)

    def _run(self) -> None:
        period = self.adaptation.settings.period
        while not self._stop.wait(period):
            try:
                self.adaptation.step()
            except Exception as err:  # noqa: B902 - the command path must never see it
                self.errors += 1
                if self._on_error is not None:
                    self._on_error(f'{type(err).__name__}: {err}')


#: The adaptation child's niceness (``os.nice``, 0-19; the node's own is 0): the adaptation
#: is background work that must yield the CPU to the command path.  At 10 kHz on 2 cores
#: (2026-11-26, load 1-3, ``bench_compensator_node.py --adaptation --rounds 2``) the command
#: path's p99 with adaptation on was 1.55-1.61x the runs without it at niceness 0, 1.26-1.35x
#: at 10 and 1.19x at 19; 10 is kept so that the child, 9-13 % of a core there, still gets
#: its share on a loaded machine (at 19 it would lose readings first, and then freeze).
#: It is the child's priority with ``adaptation.priority`` ``'low'``, and its priority
#: until its subscription is open with ``'idle'`` (:func:`yield_cpu`).
CHILD_NICE = 10


def yield_cpu() -> bool:
    """
    Put every thread of this process at idle priority (``SCHED_IDLE``).

    An idle thread runs only on CPU time that no other thread of the machine wants; threads
    started later inherit it from the thread that starts them.  docs/adaptation.md measures
    what the child costs the command path at idle priority and at niceness 10.  An
    unprivileged process cannot leave ``SCHED_IDLE`` again, so a child that falls behind is
    restarted instead (:class:`AdaptationProcess`).

    Returns
    -------
    bool
        True when every thread took it; False where the platform has no ``SCHED_IDLE``
        or a thread refused (those keep niceness :data:`CHILD_NICE`).

    """
    policy = getattr(os, 'SCHED_IDLE', None)
    if policy is None or not hasattr(os, 'sched_setscheduler'):
        return False
    try:
        threads = [int(tid) for tid in os.listdir('/proc/self/task')]
    except OSError:
        threads = [0]
    done = True
    for tid in threads:
        try:
            os.sched_setscheduler(tid, policy, os.sched_param(0))
        except ProcessLookupError:
            pass                        # the thread ended meanwhile
        except OSError:
            done = False
    return done


def child_cpus() -> set[int] | None:
    """
    Return the CPUs for the adaptation's child: those the calling node is not pinned to.

    At 10 kHz the child (about 10-14 % of a core) shares the node's core when the node is
    pinned to one and the child inherits it: the command path's p99 rose to 2.06x the runs
    without adaptation (2026-11-26, ``bench_compensator_node.py --pin``).  None when the
    node may use every CPU (nothing to keep apart) or no other CPU is allowed.

    Returns
    -------
    set of int or None
        The CPUs, or None to leave the child's affinity as inherited.

    """
    if not hasattr(os, 'sched_getaffinity'):
        return None
    mine = os.sched_getaffinity(0)
    allowed = set(range(os.cpu_count() or 0))
    others = allowed - mine
    return others if mine and others and mine < allowed else None


class AdaptationProcess:
    """
    Run an :class:`Adaptation` in a child process; the node's side of it, in the node.

    The node's interpreter runs nothing of a step: the command path appends each command
    (and, without ``readings``, each reading) to a list, and :meth:`exchange` (the node's
    10 Hz timer) sends what arrived to the child in one message and takes back the child's
    candidate, status and events.  The child (a fresh interpreter: a fork of a process with
    DDS threads is unsafe) drains its end of the pipe in a thread of its own, so a long
    solve never fills the pipe, and steps every ``period`` seconds.  Its methods mirror
    :class:`Adaptation`'s node side, so the node treats both alike.

    With ``readings``, the child subscribes to the readings itself (``entry``'s
    ``serve_socket`` supplies the subscriber): the node records only its commands, and
    those recorded before the child says its subscription is open are dropped (their
    readings went to no one).  A child that stops taking the commands (20 held-out windows of
    them waiting) is stopped: its own readings have overflowed by then, so their order no
    longer pairs; the node shows why and compensates on.  A child at idle priority
    (``settings.priority``, :func:`yield_cpu`) is not stopped but restarted at ``'low'`` as
    soon as it falls behind (:data:`_IDLE_BEHIND_WINDOWS` held-out windows of commands not
    taken, none taken for as many held-out durations, or a reading lost): the machine is too
    busy to leave it only the idle CPU time.
    The restarted child starts from the running model; an event says so.

    Parameters
    ----------
    model : MPIModel or ThermalDriftModel
        The running forward model (see :class:`Adaptation`).
    settings : AdaptationSettings
        See :class:`AdaptationSettings`.
    on_error : callable, optional
        Called with the text of an exception a step raised in the child.
    readings : ReadingSource, optional
        Where the child takes the readings itself (None: the node records them with
        :meth:`record_measurement`).
    entry : str
        The module whose ``serve_socket(descriptor)`` the child runs (this one by default;
        with ``readings``, one whose ``serve_socket`` passes a subscriber on to
        :func:`serve_socket`).

    """

    def __init__(self, model: AdaptedModel, settings: AdaptationSettings, *,
                 on_error: Callable[[str], None] | None = None,
                 readings: ReadingSource | None = None, entry: str = __name__) -> None:
        self.settings = settings
        self._model = model
        self._on_error = on_error
        self._source = readings
        self._entry = entry
        self.malformed = 0
        self.last_malformed = ''
        #: Publishers of the readings the child's subscription had matched when it said it
        #: was ready (None: no ``readings``, or not ready yet).
        self.publishers: int | None = None
        self.errors = 0
        self._commands: list[float] = []
        self._readings: list[float] = []
        self._sequence: dict[int, int] = {}
        self._events: list[str] = []
        self._process: subprocess.Popen[bytes] | None = None
        self._conn: multiprocessing.connection.Connection | None = None
        self._candidate: Candidate | None = None
        #: The priority the child runs at, as it said when ready (``'idle'``, or ``'low'``
        #: also when it could not take ``SCHED_IDLE``; None before).
        self.priority: str | None = None
        self._status: dict[str, Any] = {}
        self._fresh_child('starting the adaptation process')
        self._behind = ''
        # When the child last took a message of pairs (or was sent one with none waiting).
        self._progress = time.monotonic()
        #: Times the adaptation was restarted at ``'low'`` (:meth:`_fall_back`).
        self.restarts = 0
        # The counters of the children before a restart, added to the current one's.
        self._carried: dict[str, int] = {}
        # Children restarted at 'low', asked to end: (process, when asked).
        self._retired: list[tuple[subprocess.Popen[bytes], float]] = []

    @property
    def model(self) -> AdaptedModel:
        """Return the running model the adaptation starts its candidates from."""
        return self._model

    @property
    def pid(self) -> int | None:
        """Return the child's process id (None before :meth:`start`)."""
        return None if self._process is None else self._process.pid

    @property
    def priority_words(self) -> str:
        """Return the child's CPU priority in words, for the node's log."""
        if self.priority == 'idle':
            return 'at idle priority: only CPU time nothing else wants'
        if self.priority == 'low':
            return f'at niceness {CHILD_NICE} below the node'
        return 'its priority not reported yet'

    @property
    def running(self) -> bool:
        """Return whether the child process is alive."""
        return self._process is not None and self._process.poll() is None

    @property
    def pending(self) -> tuple[int, int]:
        """Return how many commands and readings are recorded here and not yet sent."""
        return len(self._commands), len(self._readings)

    def start(self) -> None:
        """
        Start the child: this interpreter, on this one's import path, serving a socket pair.

        Not ``multiprocessing``'s spawn, which imports the parent's main module again in
        the child: a script that builds the node without a ``__main__`` guard would start
        it twice.  A node pinned to some of the machine's CPUs (``taskset``) keeps them to
        itself: the child runs on the others (:func:`child_cpus`), set before it starts a
        thread.
        """
        ours, theirs = socket.socketpair()
        with ours, theirs:
            # Set in the child before its first thread: its CPUs (when the node is pinned),
            # then its niceness below the node's (each best effort).
            cpus = child_cpus()
            settings = ([f'os.sched_setaffinity(0, {sorted(cpus)!r})'] if cpus is not None
                        else []) + [f'os.nice({CHILD_NICE})']
            prelude = 'import os\n' + ''.join(
                f'try:\n    {call}\nexcept OSError:\n    pass\n' for call in settings)
            code = (f'{prelude}import sys; from {self._entry} import serve_socket;'
                    ' serve_socket(int(sys.argv[1]))')
            path = os.pathsep.join(p for p in sys.path if p)
            self._process = subprocess.Popen(
                [sys.executable, '-c', code, str(theirs.fileno())],
                pass_fds=(theirs.fileno(),), stdin=subprocess.DEVNULL,
                env=dict(os.environ, PYTHONPATH=path))
            self._conn = multiprocessing.connection.Connection(ours.detach())
        self._conn.send((self._params, self.settings, self._source))

    def wait_ready(self, timeout: float) -> bool:
        """
        Wait until the child is ready (with ``readings``: its subscription is open).

        Parameters
        ----------
        timeout : float
            Longest wait [s].

        Returns
        -------
        bool
            True when the child said it is ready; False after ``timeout`` or when it ended
            (the next :meth:`exchange` reports that).

        """
        conn = self._conn
        deadline = time.monotonic() + timeout
        try:
            while conn is not None and not self._ready:
                left = deadline - time.monotonic()
                if left <= 0.0 or not conn.poll(left):
                    break
                self._receive(conn.recv())
        except (EOFError, OSError):
            return False
        return self._ready

    def stop(self, timeout: float = 1.0) -> None:
        """Stop the child (asked first, terminated after ``timeout`` seconds)."""
        for retired, _ in self._retired:
            _end(retired, timeout)
        self._retired.clear()
        process, conn = self._process, self._conn
        if process is None or conn is None:
            return
        try:
            conn.send(('stop',))
        except (OSError, ValueError):
            pass
        _end(process, timeout)
        conn.close()

    def record_command(self, current: float) -> None:
        """Record a published command [A] (cheap: the command path calls it)."""
        self._commands.append(current)

    def record_measurement(self, displacement: float) -> None:
        """Record a displacement reading [m], in order (only without ``readings``)."""
        self._readings.append(displacement)

    def exchange(self) -> None:
        """Send the pairs that arrived to the child; take back what it sent (non-blocking)."""
        if self._stopped:
            self._commands.clear()              # no child takes them any more
            self._readings.clear()
            return
        conn = self._conn
        if conn is None:
            return
        try:
            while conn.poll():
                self._receive(conn.recv())
        except (EOFError, OSError):
            # The child ended: say so once; what the node records is dropped from now on.
            self._ended(_ENDED)
            return
        # The pipe never fills, so a send never blocks the node: at most _IN_FLIGHT
        # messages of at most _CHUNK pairs each are unacknowledged; the rest waits here.
        commands, readings = self._commands, self._readings
        while self._ready and self._in_flight < _IN_FLIGHT and (commands or readings):
            if self._in_flight == 0:
                self._progress = time.monotonic()       # the child's clock starts now
            a, b = commands[:_CHUNK], readings[:_CHUNK]
            del commands[:_CHUNK]
            del readings[:_CHUNK]
            conn.send_bytes(_PAIRS + array('q', [len(a)]).tobytes()
                            + array('d', a).tobytes() + array('d', b).tobytes())
            self._in_flight += 1
        self._reap()
        window = self.settings.samples(self.settings.holdout)
        idle = _IDLE_BEHIND_WINDOWS * self.settings.holdout
        if self.priority == 'idle' and not self._behind:
            if len(commands) > _IDLE_BEHIND_WINDOWS * window:
                self._behind = (f'{len(commands)} commands not taken, more than'
                                f' {_IDLE_BEHIND_WINDOWS} held-out windows')
            elif self._in_flight and time.monotonic() - self._progress > idle:
                self._behind = f'no commands taken for {idle:g} s'
        if self._behind:
            self._fall_back()
            return
        limit = 20 * window
        if self._source is not None:
            # The child takes the readings: one that has not taken the commands of 20
            # held-out windows has lost its readings too (its subscription's depth is far
            # smaller), so their order no longer pairs: it is stopped.
            if len(commands) > limit:
                self._ended(_BEHIND)
                self.stop()
            return
        # A child that does not keep up (or not yet listening): the newest pairs are kept,
        # as many dropped from both lists, so the k-th reading still answers the k-th
        # command.
        drop = max(0, min(len(commands), len(readings)) - limit)
        del commands[:drop]
        del readings[:drop]

    def take_candidate(self) -> Candidate | None:
        """Return the candidate ready to apply, once (None when there is none)."""
        candidate, self._candidate = self._candidate, None
        return candidate

    @property
    def _stopped(self) -> bool:
        # Whether the adaptation has stopped for good (said once by _ended).
        return bool(self._status.get('adaptation_state', '').startswith('stopped'))

    def _ended(self, state: str) -> None:
        # Say once why the adaptation stopped; what the node records is dropped from now on.
        self._commands.clear()
        self._readings.clear()
        if not self._stopped:
            self._status['adaptation_state'] = state
            self.errors += 1
            if self._on_error is not None:
                self._on_error(state)

    def applied(self, candidate: Candidate, accepted: bool, reason: str = '') -> None:
        """Tell the child whether the node's validation took the candidate."""
        number = self._sequence.pop(id(candidate), None)
        if accepted:
            self._model = candidate.model
        if number is not None:
            self._send(('applied', number, accepted, reason))

    def reset(self, model: AdaptedModel) -> None:
        """Start again from a model pushed from outside."""
        self._model = model
        self._candidate = None
        self._sequence.clear()
        self._params = model.to_params()
        self._send(('reset', self._params))

    def status(self) -> dict[str, Any]:
        """
        Return the values /diagnostics shows (``adaptation_*``), as the child last sent.

        The counters go on across a restart at ``'low'`` (the earlier children's are added),
        and ``adaptation_restarts`` says how many there were.
        """
        status = dict(self._status)
        for key, value in self._carried.items():
            status[key] = status.get(key, 0) + value
        status['adaptation_restarts'] = self.restarts
        return status

    def events(self) -> list[str]:
        """Return and clear the events to log."""
        events, self._events = self._events, []
        return events

    def _fall_back(self) -> None:
        # The machine leaves the idle child too little CPU: the same adaptation again, from
        # the running model, in a child at niceness CHILD_NICE.  The old one is asked to end
        # (reaped by later exchanges: the command path never waits for it).
        why, self._behind = self._behind, ''
        for key, value in self._status.items():
            if type(value) is int and key != 'adaptation_reading_publishers':
                self._carried[key] = self._carried.get(key, 0) + value
        self.restarts += 1
        process, conn = self._process, self._conn
        if process is not None and conn is not None:
            self._send(('stop',))
            conn.close()
            self._retired.append((process, time.monotonic()))
        self.settings = replace(self.settings, priority='low')
        self._fresh_child(f'restarting the adaptation process at niceness {CHILD_NICE}')
        try:
            self.start()
        except OSError as err:          # no process to be had: the node compensates on
            self._process, self._conn = None, None
            self._ended(f'stopped: the adaptation process could not be restarted ({err})')
            return
        self._events.append(f'the adaptation process at idle priority fell behind ({why}: the'
                            ' machine leaves it too little CPU); restarted from the running'
                            f' model at niceness {CHILD_NICE} as process {self.pid}')

    def _fresh_child(self, state: str) -> None:
        # What the parent holds of one child, as before its start: nothing pending, not
        # ready, no candidate; the child starts from the running model.
        self._params = self._model.to_params()
        self._commands.clear()
        self._readings.clear()
        self._sequence.clear()
        self._ready = False
        self._in_flight = 0
        self._candidate = None
        self.priority = None
        self.publishers = None
        self._status = {'adaptation_state': state}

    def _reap(self) -> None:
        # Children asked to end: reaped once they have, killed after _RETIRE_S.
        now = time.monotonic()
        keep = []
        for process, asked in self._retired:
            if process.poll() is not None:
                continue
            if now - asked > _RETIRE_S:
                process.kill()
            keep.append((process, asked))
        self._retired = keep

    def _send(self, message: Any) -> None:
        # To a child that has ended, nothing is sent (the next exchange reports it).
        if self._conn is not None:
            try:
                self._conn.send(message)
            except (OSError, ValueError):
                pass

    def _receive(self, message: Any) -> None:
        kind = message[0]
        if kind == 'taken':
            self._in_flight -= 1
            self._progress = time.monotonic()
        elif kind == 'ready':
            self._ready = True
            self.publishers = message[1]
            self.priority = message[2]
            if self._source is not None:
                # Commands published before the child's subscription was open: their
                # readings went to no one, so they pair with nothing.  The child drops the
                # readings it took before this point in the same way.
                self._commands.clear()
                self._send(('start',))
        elif kind == 'candidate':
            _, number, candidate = message
            self._sequence = {id(candidate): number}
            self._candidate = candidate
        elif kind == 'status':
            self._status, events = message[1], message[2]
            self._events.extend(events)
            self.malformed = int(self._status.get('adaptation_malformed_readings', 0))
            lost = int(self._status.get('adaptation_lost_readings', 0))
            if self.priority == 'idle' and lost > 0 and not self._behind:
                self._behind = f'{lost} readings lost'
            self.last_malformed = str(self._status.get('adaptation_last_malformed_reading',
                                                       ''))
        elif kind == 'error':
            self.errors += 1
            if self._on_error is not None:
                self._on_error(message[1])


def _end(process: 'subprocess.Popen[bytes]', timeout: float) -> None:
    # Wait for a child asked to end; terminated after TIMEOUT, killed after another, then
    # waited for up to _KILLED_S: a child at idle priority runs its exit, too, only on CPU
    # time nothing else wants (beside two CPU hogs a killed child took over 1 s to go).
    # Never raises: the node's cleanup and shutdown go on.
    steps = ((None, timeout), (process.terminate, timeout), (process.kill, _KILLED_S))
    for end, wait in steps:
        if end is not None:
            end()
        try:
            process.wait(wait)
            return
        except subprocess.TimeoutExpired:
            continue


def serve_socket(descriptor: int, *, subscribe: Subscribe | None = None) -> None:
    """
    Serve an :class:`AdaptationProcess` on an inherited socket (the child's entry point).

    Parameters
    ----------
    descriptor : int
        The child's end of the socket pair; the first message is the model's parameters,
        the settings and the :class:`ReadingSource` (or None).
    subscribe : callable, optional
        Opens the subscription of a :class:`ReadingSource` (the ROS side supplies it:
        :mod:`mpi_ros.nodes.adaptation_readings`); needed when the node sends a source.

    """
    # The node's process ends the child (a message, then SIGTERM); a Ctrl-C in a terminal,
    # which reaches the whole process group, is the node's to handle.
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    conn = multiprocessing.connection.Connection(descriptor)
    try:
        params, settings, source = conn.recv()
    except (EOFError, OSError):
        return
    _serve(conn, params, settings, source, subscribe)


def _serve(conn: multiprocessing.connection.Connection, params: dict[str, Any],
           settings: AdaptationSettings, source: ReadingSource | None,
           subscribe: Subscribe | None) -> None:
    # The child's loop: a thread moves the pairs from the pipe into the adaptation (so a
    # long solve never fills the pipe); this thread steps every period and answers.  With
    # a source, the readings come from a subscription of the child's own.
    # The threads that take commands and readings get the interpreter lock back within
    # 0.5 ms of a step holding it (Python's default is 5 ms).
    sys.setswitchinterval(min(sys.getswitchinterval(), 5e-4))
    adaptation = Adaptation(_adapted(params), settings)
    readings: ReadingSubscription | None = None
    if source is not None:
        try:
            if subscribe is None:
                msg = f'no subscriber for the readings on {source.topic}'
                raise ModelError(msg)
            readings = subscribe(source, adaptation.record_measurements)
        except Exception as err:  # noqa: B902 - reported to the node, which logs it
            conn.send(('error', f'readings on {source.topic}: {type(err).__name__}: {err}'))
            conn.close()
            return
    try:
        _loop(conn, adaptation, settings, readings)
    finally:
        if readings is not None:
            readings.close()


def _loop(conn: multiprocessing.connection.Connection, adaptation: Adaptation,
          settings: AdaptationSettings, readings: ReadingSubscription | None) -> None:
    candidates: dict[int, Candidate] = {}
    stop = threading.Event()
    send = threading.Lock()

    def reply(message: Any) -> None:
        with send:
            conn.send(message)

    def listen() -> None:
        try:
            while True:
                data = conn.recv_bytes()
                if data[:8] == _PAIRS:
                    count = array('q', data[8:16])[0]
                    values = np.frombuffer(data, dtype=np.float64, offset=16)
                    adaptation.record_pairs(values[:count], values[count:])
                    reply(('taken',))
                    continue
                message = pickle.loads(data)
                if message[0] == 'stop':
                    break
                if message[0] == 'applied':
                    candidate = candidates.pop(message[1], None)
                    if candidate is not None:
                        adaptation.applied(candidate, message[2], message[3])
                elif message[0] == 'reset':
                    candidates.clear()
                    adaptation.reset(_adapted(message[1]))
                elif message[0] == 'start':
                    adaptation.discard_readings()
        except (EOFError, OSError):
            pass
        stop.set()

    listener = threading.Thread(target=listen, name='pipe', daemon=True)
    listener.start()
    # Idle priority from here on (the imports and the subscription ran at CHILD_NICE).
    priority = 'idle' if settings.priority == 'idle' and yield_cpu() else 'low'
    reply(('ready', None if readings is None else readings.faults()['publishers'], priority))
    number = 0
    deadline = time.monotonic() + settings.period
    while not stop.wait(max(0.0, deadline - time.monotonic())):
        deadline += settings.period
        try:
            adaptation.step()
        except Exception as err:  # noqa: B902 - reported to the node, never raised there
            reply(('error', f'{type(err).__name__}: {err}'))
        candidate = adaptation.take_candidate()
        try:
            if candidate is not None:
                number += 1
                candidates[number] = candidate
                reply(('candidate', number, candidate))
            status = adaptation.status()
            if readings is not None:
                faults = readings.faults()
                status.update({
                    'adaptation_malformed_readings': faults['malformed'],
                    'adaptation_last_malformed_reading': faults['last_malformed'],
                    'adaptation_lost_readings': faults['lost'],
                    'adaptation_reading_publishers': faults['publishers']})
            reply(('status', status, adaptation.events()))
        except (BrokenPipeError, OSError):
            break
    conn.close()


def with_gaps(readings: FloatArray, sequences: npt.NDArray[np.int64],
              previous: int) -> tuple[FloatArray, int, int]:
    """
    Return readings with a NaN in the place of each one missing from the publisher's sequence.

    The adaptation pairs the k-th reading with the k-th command: a reading the
    subscription's history dropped would shift every later pair by one.  Its NaN keeps the
    order, and the adaptation freezes over it as over any garbage reading.  A sequence
    number that goes back (a publisher started again) starts counting afresh.

    Parameters
    ----------
    readings : ndarray of float, shape (N,)
        The readings taken [m], in order.
    sequences : ndarray of int, shape (N,)
        Their publication sequence numbers.
    previous : int
        The sequence number of the reading before them (-1: none yet).

    Returns
    -------
    readings, lost, last : ndarray of float, int, int
        The readings with the NaN placeholders, how many were missing, and the last
        sequence number.

    """
    if sequences.size == 0:
        return readings, 0, previous
    before = np.concatenate([[previous], sequences[:-1]])
    missing = np.where((before >= 0) & (sequences > before + 1), sequences - before - 1, 0)
    lost = int(missing.sum())
    if lost:
        readings = np.insert(readings, np.repeat(np.arange(readings.size), missing), np.nan)
    return readings, lost, int(sequences[-1])


def adaptable(model: object) -> bool:
    """
    Return whether the adaptation adapts ``model``.

    Parameters
    ----------
    model : object
        A model of any kind.

    Returns
    -------
    bool
        True for a forward Gamma with n >= 1, alone or with a thermal drift.

    """
    gamma = model.model if isinstance(model, ThermalDriftModel) else model
    return isinstance(gamma, MPIModel) and not gamma.is_inverse and gamma.n >= 1


def _adapted(params: dict[str, Any]) -> AdaptedModel:
    model = extended_model_from_params(params)
    if not isinstance(model, (MPIModel, ThermalDriftModel)):
        msg = f'the adaptation adapts Gamma or Gamma with a thermal drift; found {model!r}'
        raise ModelError(msg)
    return model


def _gamma(model: AdaptedModel) -> MPIModel:
    return model.model if isinstance(model, ThermalDriftModel) else model


def _with_start(candidate: AdaptedModel, running: AdaptedModel) -> AdaptedModel:
    # The candidate keeps the running model's start state (its plays' initial states,
    # moved with the input offset): only what the adaptation fitted changes.
    if isinstance(candidate, ThermalDriftModel):
        return replace(candidate, model=_gamma_with_start(candidate.model, _gamma(running)))
    return _gamma_with_start(candidate, _gamma(running))


def _gamma_with_start(candidate: MPIModel, running: MPIModel) -> MPIModel:
    # The record the running model was identified on stays its record (start and range).
    states = running.hysteresis.initial_states + (running.input_offset
                                                  - candidate.input_offset)
    return replace(candidate.with_initial_states(states),
                   identified_input_range=running.identified_input_range)


def _rms(values: FloatArray) -> float:
    return float(np.sqrt(np.mean(np.square(values)))) if values.size else math.nan
