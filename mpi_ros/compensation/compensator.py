# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
The one streaming compensator for every model.

A plain MPI model runs one compiled step; an extended model plugs in its effect's exact
per-step inverse (:class:`InverseStep`); a dead time is compensated by prediction
(:mod:`mpi_ros.compensation.prediction`).
"""

from collections.abc import Callable
import inspect
import math
from typing import Any, Protocol

import numpy as np
import numpy.typing as npt

from .kernels import compensate_axes, compensate_step, COMPILED, INDEX_COLUMNS, inverse_value, \
    LAST_COMMAND, warm_up
from .prediction import DeadTimePredictor, prediction_horizon
from .screening import best_linear_map, operating_range, screen_desired
from ..errors import ModelError
from ..operators.memory import TurningPointMemory
from ..operators.model import hysteresis_step, MPIModel, superposition_value
from ..operators.start import identified_ranges, rest_states, start_range, StartState

__all__ = ['check_sample_period', 'Compensator', 'InverseStep', 'Pack', 'gamma_of',
           'inverse_step_of', 'kind_of',
           'loop_block', 'pack']

FloatArray = npt.NDArray[np.float64]

#: The compiled step's arrays: r_H, w_H, z_H, r_H', w_H', z', r_S', w_S', point (x0, y0, sign).
Kernel = tuple[FloatArray, FloatArray, FloatArray, FloatArray, FloatArray, FloatArray,
               FloatArray, FloatArray, FloatArray]

#: The counters a compiled loop counts, in the order of its ``counts`` array.
COMPILED_COUNTERS = ('messages', 'nonfinite_input', 'out_of_range', 'clamped',
                     'nonfinite_command')


class InverseStep(Protocol):
    """
    An effect's exact per-step inverse, plugged into :class:`Compensator`.

    Per command the compensator calls ``prepare`` (the lag coefficients from the interval
    and the previous command), ``invert`` (the current for the step output ``v`` of S',
    through ``inverse(v, beta)`` = ``x0 + H~'[v]`` with ``H~`` = H whose first weight is
    raised by ``beta``, by (12)-(14)), then ``advance`` with the applied (clamped) current,
    which returns what the material (H) sees.  A step whose lags are fed by the
    displacement also has ``observe(hysteresis_output)``: it gets H's output [A] for the
    applied current after every command, and once after ``start`` or ``carry`` (then it
    settles on it).  ``state`` holds the effect's slow states.
    """

    state: FloatArray

    def start(self, current: float) -> None:
        """Settle the slow states at a steady ``current`` [A]."""

    def carry(self, other: object) -> bool:
        """Take over another step's slow states when compatible; tell whether it did."""

    def prepare(self, previous: float, interval: float, started: bool) -> None:
        """Fix this step's coefficients."""

    def invert(self, v: float, previous: float, started: bool,
               inverse: Callable[[float, float], float]) -> float:
        """Return the current [A] whose step output is ``v``."""

    def advance(self, current: float, previous: float, started: bool) -> float:
        """Update the slow states with the applied current; return the material's input."""


def gamma_of(model: Any) -> MPIModel:
    """Return the forward Gamma of any model (the model interface's ``gamma``)."""
    gamma: MPIModel = model.gamma
    return gamma


def inverse_step_of(model: Any, inverse: MPIModel | None = None, *,
                    lead_gain: float | None = None) -> 'InverseStep | None':
    """
    Return an extended model's per-step inverse, or None (plain, or not invertible).

    Parameters
    ----------
    model : MPIModel or extended model
        A model.
    inverse : MPIModel, optional
        Gamma^-1 of the model, already built: handed to a step that takes it
        (``inverse_step(inverse=...)``), so it is built once.
    lead_gain : float, optional
        The high-frequency gain of a lag's lead filter, handed to a step that takes it
        (``inverse_step(lead_gain=...)``); None: the step's default (bounded,
        :data:`mpi_ros.extensions.rate_dependence.LEAD_GAIN`); ``inf``: the exact lead.

    Returns
    -------
    InverseStep or None
        The step; None for a plain model or an effect without a causal inverse.

    """
    make = getattr(model, 'inverse_step', None)
    if make is None:
        return None
    accepted = inspect.signature(make).parameters
    options: dict[str, Any] = {}
    if inverse is not None and 'inverse' in accepted:
        options['inverse'] = inverse
    if lead_gain is not None and 'lead_gain' in accepted:
        options['lead_gain'] = lead_gain
    step: InverseStep | None = make(**options)
    return step


def kind_of(model: Any, *, dead_time_prediction: bool = True) -> str:
    """
    Name a model's effect: ``none``, its cause, ``(predicted)`` or ``(not compensated)``.

    Parameters
    ----------
    model : MPIModel or extended model
        A model.
    dead_time_prediction : bool
        Whether a dead time is compensated by prediction (:class:`Compensator`'s option):
        then it reads ``dead_time (predicted)``, else ``dead_time (not compensated)``.

    Returns
    -------
    str
        One token, then the parts left out or predicted in parentheses.

    """
    if model.cause == 'none':
        return 'none'
    cause = str(model.cause).replace(' + ', '+')       # one token (diagnostics join by spaces)
    predicted = dead_time_prediction and prediction_horizon(model) > 0.0
    if inverse_step_of(model) is None:
        return f'{cause} (predicted)' if predicted else f'{cause} (not compensated)'
    left_out = getattr(model, 'not_inverted', ())
    if predicted:
        left_out = tuple(part for part in left_out if part != 'dead_time')
    notes = ([f'{"+".join(left_out)} not compensated'] if left_out else []) + (
        ['dead_time predicted'] if predicted else [])
    return f'{cause} ({"; ".join(notes)})' if notes else cause


class Compensator:
    """
    The streaming inverse compensator ``current = clamp(Gamma^-1[s_c])``, for every model.

    One class owns the safe current range, the screening of the desired values, the
    counters, the turning-point memory and the bumpless handover between models of any
    kind: a plain MPI model (no effect: one compiled step), or an extended model whose
    effect plugs in its exact per-step inverse (:class:`InverseStep`).  A dead time ``L``
    has no causal inverse: by default the desired displacement is predicted ``L`` ahead on
    the stream's nominal time base (``sample_period`` spacing) and Gamma^-1 (with the other
    stages' inverses) drives that
    (:class:`~mpi_ros.compensation.prediction.DeadTimePredictor`: a least-squares straight
    line over the last ``2 L`` at least, exact on ramps, its reach bounded by how far the
    desired value moved per sample in the window, so a step is not extrapolated; clamped to
    the model's displacement range).

    Parameters
    ----------
    model : MPIModel or extended model
        Forward model (the inverse is computed here by (12)-(14), (22)-(25)).
    output_min, output_max : float
        Safe current range [A]; every output lies inside it.
    enabled : bool
        False: output the best linear map of Gamma instead (for comparison).
    sample_period : float
        Interval [s] assumed between two commands when :meth:`command` gets no ``time``
        (effects with lags), and the spacing of the desired values a dead time's
        prediction assumes (always: never their times).
    memory : TurningPointMemory, optional
        Where the applied current's turning points are kept (a row of a multi-axis
        block); a new memory by default.
    inverse : MPIModel, optional
        Gamma^-1 of ``model`` when already built; None: built here.
    start : StartState or str
        Where the actuator is before the first command (:mod:`mpi_ros.operators.start`):
        ``rest_low`` (default: at rest after a sweep up to the highest identified input and
        down to the lowest, each moved inside the limits; the last command starts there),
        ``rest_high``,
        ``record`` (the model's record start) or explicit play states [A] (of another
        number than the model's plays: the record start, as :attr:`start_description` says).
    current_range : (float, float), optional
        The identified current range [A] (e.g. from a parameter file's header); None: what
        the model's thresholds tell (:func:`~mpi_ros.operators.start.identified_ranges`).
        A model that tells none starts a rest start at its record start.
    lead_gain : float, optional
        High-frequency gain of the lead filter that inverts an input lag (rate dependence):
        None, the default, bounds it
        (:class:`~mpi_ros.extensions.rate_dependence.RateDependenceInverse`);
        ``inf`` gives the exact, unbounded inverse of the lag (for comparison).
    dead_time_prediction : bool
        True (the default): compensate a model's dead time by prediction (see above);
        False: Gamma^-1 of the desired displacement itself, the dead time left in the
        tracking error (``kind`` says ``not compensated``).
    input_unit : str
        The input's unit in :attr:`start_description` (``'A'``, or ``'V'`` for a voltage
        model: ``model.input_quantity``); the commands are the model's numbers either way.

    Attributes
    ----------
    counters : dict[str, int]
        ``messages``, ``nonfinite_input``, ``out_of_range`` (desired outside the model's
        operating range), ``clamped``, ``nonfinite_command`` (a non-finite Gamma^-1,
        replaced by the last command: never published), ``bad_time`` (time stamps that did
        not increase).
    version : int
        Incremented by every accepted model.
    start_description : str
        The start in words (the nodes log it).

    """

    def __init__(self, model: Any, *, output_min: float, output_max: float,
                 enabled: bool = True, sample_period: float = 1e-3,
                 memory: TurningPointMemory | None = None,
                 inverse: MPIModel | None = None, start: StartState | str = 'rest_low',
                 current_range: tuple[float, float] | None = None,
                 lead_gain: float | None = None, dead_time_prediction: bool = True,
                 input_unit: str = 'A') -> None:
        self._check_limits(output_min, output_max)
        self.input_unit = str(input_unit)
        self.dead_time_prediction = bool(dead_time_prediction)
        self._predictor: DeadTimePredictor | None = None
        self.start = StartState.parse(start)
        self.lead_gain = lead_gain
        check_sample_period(sample_period)
        self.output_min = float(output_min)
        self.output_max = float(output_max)
        self._enabled = bool(enabled)
        self.sample_period = float(sample_period)
        self.counters = {'messages': 0, 'nonfinite_input': 0, 'out_of_range': 0,
                         'clamped': 0, 'nonfinite_command': 0, 'bad_time': 0}
        self.version = 0
        self.memory = TurningPointMemory() if memory is None else memory
        self.before_change: Callable[[], None] | None = None
        self.last_command = float(np.clip(0.0, self.output_min, self.output_max))
        self._last_time: float | None = None
        self._started = False
        self._step: InverseStep | None = None
        self._own_pack: Pack | None = None
        # A rest start: (current, descent, where the sweep turned before).
        self._rest: tuple[float, bool, float] | None = None
        if inverse is None:
            inverse = gamma_of(model).inverse()            # (12)-(14), (22)-(25), once
        self.start_description = self._settle(gamma_of(model), inverse, current_range)
        self._install(model, replay=False, inverse=inverse)
        self.version = 1

    @staticmethod
    def _check_limits(output_min: float, output_max: float) -> None:
        if not (np.isfinite(output_min) and np.isfinite(output_max)
                and output_min < output_max):
            msg = (f'output.min must be finite and below output.max; found {output_min} and'
                   f' {output_max}')
            raise ModelError(msg)

    def _settle(self, gamma: MPIModel, inverse: MPIModel,
                current_range: tuple[float, float] | None) -> str:
        # The start of the first model: a rest start keeps its current (a later model
        # replays from the same sweep to it, by wiping-out).
        if current_range is None:
            found = identified_ranges(gamma, inverse)
            current_range = None if found is None else found[0]
        allowed = start_range(current_range, (self.output_min, self.output_max))
        _, current, description = self.start.plays(gamma, allowed, strict=False,
                                                   unit=self.input_unit)
        if current is not None and allowed is not None:
            low = self.start.name == 'rest_low'
            self._rest = (current, low, allowed[1] if low else allowed[0])
            self.last_command = current
        return description

    def _start_states(self, gamma: MPIModel) -> FloatArray:
        if self._rest is not None:
            current, descent, turn = self._rest
            return rest_states(gamma, current, descent=descent, turn=turn)
        record = np.array(gamma.hysteresis.initial_states, dtype=np.float64)
        if self.start.name == 'explicit' and len(self.start.states) == record.size:
            return np.array(self.start.states, dtype=np.float64)
        return record

    def _changing(self) -> None:
        # An owner that keeps this compensator's state elsewhere (MultiAxisCompensator)
        # hands it back before anything changes; the packed form is rebuilt when used.
        if self.before_change is not None:
            self.before_change()
        self._own_pack = None

    def _install(self, model: Any, *, replay: bool, inverse: MPIModel | None) -> None:
        self._changing()
        gamma = gamma_of(model)
        if inverse is None:
            inverse = gamma.inverse()                  # (12)-(14), (22)-(25)
        step = inverse_step_of(model, inverse, lead_gain=self.lead_gain)
        if step is not None and not step.carry(self._step):
            step.start(self.last_command)
        h, s_inv, h_inv = gamma.hysteresis, inverse.superposition, inverse.hysteresis
        z_h = self._start_states(gamma)
        if replay and len(self.memory):
            _, z_h = gamma.hysteresis_output(self.memory.points, z_h)
        lo, hi = operating_range(gamma, self.output_min, self.output_max)
        linear = best_linear_map(gamma, self.output_min, self.output_max)
        # One assignment of a tuple: the step never sees half of an old and a new model.
        self._kernel: Kernel = (
            np.ascontiguousarray(h.thresholds), np.ascontiguousarray(h.weights), z_h,
            np.ascontiguousarray(h_inv.thresholds), np.ascontiguousarray(h_inv.weights),
            np.empty_like(z_h), np.ascontiguousarray(s_inv.thresholds),
            np.ascontiguousarray(s_inv.weights),
            np.array([gamma.input_offset, gamma.output_offset, float(gamma.output_sign)]))
        warm_up(self._kernel, lo, self.output_min, self.output_max)
        horizon = prediction_horizon(model) if self.dead_time_prediction else 0.0
        predictor = (DeadTimePredictor(horizon, self.sample_period) if horizon > 0.0
                     else None)
        if predictor is not None and self._predictor is not None:
            predictor.seed(self._predictor.values)    # the desired values seen: bumpless
        self._predictor = predictor
        self._observe: Callable[[float], None] | None = getattr(step, 'observe', None)
        if self._observe is not None:
            self._observe(float(np.dot(h.weights, z_h)))    # H's output in the (replayed) state
        self._step = step
        self.model = model
        self.gamma = gamma
        self.displacement_range = (lo, hi)
        self.linear_map = linear

    def install(self, model: Any, *, inverse: MPIModel | None = None) -> None:
        """
        Switch to a new model of any kind, bumplessly.

        The new forward play state is the replay of the applied current's turning points
        through the new H (the inverse state follows by (14)), from the start: a rest start
        the same sweep to the same current, the record start the new model's,
        explicit states themselves (the new model's record start when its number of plays
        differs); an effect of the same kind
        keeps its slow states, a new one starts them settled at the last command.  The
        counters go on.

        Parameters
        ----------
        model : MPIModel or extended model
            The new (validated) forward model.
        inverse : MPIModel, optional
            Its Gamma^-1 when already built (:func:`mpi_ros.compensation.updates.prepare`);
            None: built here.

        """
        self._install(model, replay=True, inverse=inverse)
        self.version += 1

    @property
    def enabled(self) -> bool:
        """Tell whether Gamma^-1 is applied (False: the best linear map, for comparison)."""
        return self._enabled

    @enabled.setter
    def enabled(self, value: bool) -> None:
        self._changing()
        self._enabled = bool(value)

    @property
    def has_effect(self) -> bool:
        """Tell whether an effect's per-step inverse is in use (its lags need times)."""
        return self._step is not None

    @property
    def kind(self) -> str:
        """Name the installed model's effect: ``none``, a cause, or with a note in parentheses."""
        return kind_of(self.model, dead_time_prediction=self.dead_time_prediction)

    def set_limits(self, output_min: float, output_max: float) -> None:
        """Change the safe current range [A] (validated; the model is kept)."""
        self._check_limits(output_min, output_max)
        self._changing()
        self.output_min, self.output_max = float(output_min), float(output_max)
        self.displacement_range = operating_range(self.gamma, self.output_min,
                                                  self.output_max)
        self.linear_map = best_linear_map(self.gamma, self.output_min, self.output_max)

    @property
    def state(self) -> FloatArray:
        """Forward play state ``z_H`` [A] at the operating point (a copy)."""
        return self._kernel[2].copy()

    @property
    def slow_state(self) -> FloatArray:
        """Return the effect's slow states (creep lags [m], lagged current [A], thermal [A^2])."""
        return np.zeros(0) if self._step is None else self._step.state.copy()

    def command(self, desired: float, *, time: float | None = None) -> float:
        """
        Return the current command [A] for a desired displacement [m].

        Parameters
        ----------
        desired : float
            Desired displacement ``s_c`` [m].
        time : float, optional
            Time stamp [s] of this command; the interval to the previous one drives an
            effect's lags.  Without it (or when it does not increase) ``sample_period``
            is used.

        Returns
        -------
        float
            Finite current inside ``[output_min, output_max]``.

        """
        c = self.counters
        s_c = screen_desired(desired, c, self.displacement_range)
        if s_c is None:
            return self.last_command
        if self._predictor is not None:
            predicted = self._predictor.predict(s_c)
            if self.enabled:                    # the linear map stays the plain baseline
                lo, hi = self.displacement_range     # nowhere beyond the range or s_c
                s_c = min(max(predicted, min(lo, s_c)), max(hi, s_c))
        r_h, w_h, z_h, r_hi, w_hi, z_i, r_si, w_si, point = self._kernel
        step = self._step
        if step is None:
            if self.enabled:
                current, raw = compensate_step(s_c, self.output_min, self.output_max, r_h,
                                               w_h, z_h, r_hi, w_hi, z_i, r_si, w_si, point,
                                               self.last_command)
            else:
                raw = self.linear_map(s_c)
                current = min(max(raw if math.isfinite(raw) else self.last_command,
                                  self.output_min), self.output_max)
                hysteresis_step(current - point[0], r_h, w_h, z_h)
            material = current
        else:
            interval = self._interval(time)
            x0, y0, sign = float(point[0]), float(point[1]), float(point[2])
            previous, started = self.last_command, self._started
            step.prepare(previous, interval, started)
            if self.enabled:
                v = superposition_value(sign * (s_c - y0), r_si, w_si)     # S' (27)

                def inverse(value: float, beta: float) -> float:
                    return x0 + float(inverse_value(value, r_h, w_h, beta, z_h))

                raw = step.invert(v, previous, started, inverse)
            else:
                raw = self.linear_map(s_c)
            current = min(max(raw if math.isfinite(raw) else previous, self.output_min),
                          self.output_max)
            material = step.advance(current, previous, started)
            h_out = hysteresis_step(material - x0, r_h, w_h, z_h)
            if self._observe is not None:
                self._observe(h_out)
            self._started = True
        if not math.isfinite(raw):
            c['nonfinite_command'] += 1
        elif current != raw:
            c['clamped'] += 1
        self.memory.push(material)
        self.last_command = current
        return current

    def command_batch(self, desired: npt.ArrayLike,
                      times: npt.ArrayLike | None = None) -> FloatArray:
        """
        Return the commands for a chunk of desired displacements, as :meth:`command` would.

        A plain model runs the whole chunk in one compiled loop (screening, inverse,
        clamping, counters); an effect's model steps sample by sample.  The results and
        the state afterwards equal those of :meth:`command` called per sample.

        Parameters
        ----------
        desired : array_like of float, shape (K,)
            Desired displacements [m] (NaN/Inf hold the last command and are counted).
        times : array_like of float, shape (K,), optional
            Their time stamps [s] (effects with lags only).

        Returns
        -------
        ndarray of float, shape (K,)
            Current commands [A], finite and inside ``[output_min, output_max]``.

        """
        values = loop_block(np.asarray(desired, dtype=np.float64).reshape(-1))
        if self._step is not None or not self.enabled or self._predictor is not None:
            stamps = (None,) * values.size if times is None else np.asarray(times, float)
            return np.array([self.command(float(v), time=None if t is None else float(t))
                             for v, t in zip(values, stamps)], dtype=np.float64)
        if self._own_pack is None:
            self._own_pack = pack([self])
        coefficients, states, index, table = self._own_pack
        table[0, LAST_COMMAND] = self.last_command
        out = np.empty((values.size, 1))
        counts = np.zeros((1, len(COMPILED_COUNTERS)), dtype=np.int64)
        compensate_axes(values.reshape(-1, 1), out, coefficients, states, index, table,
                        counts, self.memory.buffer.reshape(1, -1),
                        self.memory.state.reshape(1, -1))
        self.last_command = float(table[0, LAST_COMMAND])
        self.add_counts(counts[0])
        return out.reshape(-1)

    def add_counts(self, counts: npt.NDArray[np.int64]) -> None:
        """Add a compiled loop's (messages, nonfinite_input, out_of_range, clamped) counts."""
        c = self.counters
        for key, count in zip(COMPILED_COUNTERS, counts.tolist()):
            c[key] += count

    def bind(self, kernel: Kernel) -> None:
        """
        Keep the compiled step's arrays in given storage (views into packed arrays).

        Parameters
        ----------
        kernel : tuple of ndarray
            Arrays of the same shapes as the current ones, holding the same values.

        """
        self._kernel = kernel

    @property
    def kernel(self) -> Kernel:
        """Return the compiled step's arrays: r_H, w_H, z_H, r_H', w_H', z', r_S', w_S', point."""
        return self._kernel

    @property
    def compiled(self) -> bool:
        """Tell whether commands run the plain compiled step (no effect or prediction, enabled)."""
        return self._step is None and self._enabled and self._predictor is None

    def _interval(self, time: float | None) -> float:
        if time is None:
            return self.sample_period
        t = float(time)
        last, self._last_time = self._last_time, t
        if last is None:
            return self.sample_period
        if not (math.isfinite(t) and t > last):
            self.counters['bad_time'] += 1
            self._last_time = last
            return self.sample_period
        return t - last


#: The packed arrays of :func:`pack`: coefficients, states, index, table.
Pack = tuple[FloatArray, FloatArray, npt.NDArray[np.int64], FloatArray]


def loop_block(block: FloatArray) -> FloatArray:
    """
    Return ``block`` as the compiled loop takes it: C-contiguous and writable.

    One compiled variant serves every block: a read-only view (a block decoded from
    message bytes) or a strided one would make numba compile another in the middle of a
    stream (7.9 ms with a warm cache, seconds with a cold one), so those are copied.

    Parameters
    ----------
    block : ndarray of float64
        Desired displacements.

    Returns
    -------
    ndarray of float64
        ``block`` itself, or a C-contiguous copy.

    """
    if block.flags.c_contiguous and block.flags.writeable:
        return block
    return np.array(block, order='C')


def pack(axes: list[Compensator]) -> Pack:
    """
    Pack compensators for the compiled block loop; each keeps views of the packed arrays.

    The thresholds, weights, play states, operating points, limits and last commands of
    the axes go into four arrays (the layout of
    :func:`~mpi_ros.compensation.kernels.compensate_axes`); every axis's compiled step is
    then bound to views of them, so its state is the packed one.  The last commands are
    copied: write them back after the loop (column ``last_command`` of ``table``).

    Parameters
    ----------
    axes : list of Compensator
        The axes, in column order.

    Returns
    -------
    coefficients, states : ndarray of float
        r_H, w_H, r_H', w_H', r_S', w_S' of every axis; z_H, z' of every axis.
    index : ndarray of int, shape (N, len(INDEX_COLUMNS))
        Where each axis starts, its sizes, and whether the loop serves it.
    table : ndarray of float, shape (N, len(TABLE_COLUMNS))
        Operating point, operating range, limits, last command of each axis.

    """
    for axis in axes:
        axis._changing()            # an earlier owner of an axis hands its state back
    kernels = [axis.kernel for axis in axes]
    n1 = np.array([k[0].size for k in kernels], dtype=np.int64)
    m1 = np.array([k[6].size for k in kernels], dtype=np.int64)
    coefficients = np.concatenate([np.concatenate([k[0], k[1], k[3], k[4], k[6], k[7]])
                                   for k in kernels])
    states = np.concatenate([np.concatenate([k[2], k[5]]) for k in kernels])
    index = np.zeros((len(kernels), len(INDEX_COLUMNS)), dtype=np.int64)
    index[1:, 0] = np.cumsum(4 * n1 + 2 * m1)[:-1]
    index[:, 1], index[:, 2] = n1, m1
    index[1:, 3] = np.cumsum(2 * n1)[:-1]
    index[:, COMPILED] = [axis.compiled for axis in axes]
    table = np.array([[*k[8], *axis.displacement_range, axis.output_min, axis.output_max,
                       axis.last_command] for k, axis in zip(kernels, axes)])
    for a, axis in enumerate(axes):
        c0, n, m, s0 = (int(v) for v in index[a, :4])
        part = [coefficients[c0 + i * n:c0 + (i + 1) * n] for i in range(4)]
        axis.bind((part[0], part[1], states[s0:s0 + n], part[2], part[3],
                   states[s0 + n:s0 + 2 * n], coefficients[c0 + 4 * n:c0 + 4 * n + m],
                   coefficients[c0 + 4 * n + m:c0 + 4 * n + 2 * m], table[a, 0:3]))
    return coefficients, states, index, table


def check_sample_period(sample_period: float) -> None:
    """
    Refuse a sample period that is not finite and positive.

    Parameters
    ----------
    sample_period : float
        Seconds between commands [s].

    Raises
    ------
    ModelError
        When it is not finite and > 0.

    """
    if not (math.isfinite(sample_period) and sample_period > 0.0):
        msg = f'sample_period must be finite and > 0 [s]; found {sample_period!r}'
        raise ModelError(msg)
