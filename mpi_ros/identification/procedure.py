# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
The identification procedure: a record, whole, from its first sample, to a model.

Steps (documented in docs/design.md, "Identification on real records"):

1. **What moves the output against the input** (:mod:`.dynamics`): a butterfly loop,
   switching transients or an output unrelated to the input are refused, naming the cause;
   ringing after steps is left out of the fit; lag and dead time are measured.
2. **Segments**: a record stitched from several experiments (time gaps, time running back,
   output jumps the input does not explain) is cut at the joins; each segment gets its own
   start state.
3. **Start state** (below, "Start states"): one QP per candidate history; the best is the
   record's start state, written into the model, so that the model simulated from the
   first sample reproduces the record.  A burn-in is kept only where no candidate explains
   the start (reported).
4. **Dynamics** (with a time base): a grid over the dead time and the time constant of a
   first-order lag of the input, one QP each, scored on held-out blocks by the output's
   RMS error; kept when it beats the static model on them clearly.
5. **Order** (``order='auto'``): raised until the held-out error saturates
   (:mod:`.api`).
6. **Judgement**: the model, simulated over the whole record from its start state, against
   the best straight line on the same samples; never a model worse than the line.

**Start states** of a record: how the actuator came to its first sample.

The plays' states at the first sample (``z_H0``, (32) in the paper, where the actuator rests
demagnetised at the origin) are not in the record, but its history leaves a small family of
states, one per kind of history.  With the input ``u0`` at the first sample and a play of
threshold ``r`` (both in the input unit, relative to the operating point):

- ``descent``: at rest after the input came down to ``u0`` from far above (a step down, or
  the end of a descending sweep): ``z = u0 + r``;
- ``ascent``: after it came up from far below: ``z = u0 - r``;
- ``virgin``: demagnetised at an input ``v`` (on a grid over the range: where the drive's
  zero lies is not known, the identification does not depend on a bias), then loaded to
  ``u0``: ``z = clip(v, u0 - r, u0 + r)``;
- ``reversal`` at ``p``: the input last turned at ``p`` (a maximum above ``u0``, after a
  rise from far below, or a minimum below it, after a descent from far above), then went to
  ``u0``: ``z = clip(p -/+ r, u0 - r, u0 + r)``;
- ``reversals`` at ``p1, p2``: the two last turning points (mid-history: a record cut
  from a longer run), on either side of ``u0``;
- ``periodic``: the record is one period of an excitation the actuator had been following:
  the state at its end, moved to ``u0``;
- ``memory``: a joint estimate of every play's state, when the record starts after a
  history with more turning points than the grid holds: starting from the best history
  above, each play's state is moved on a grid within what a valid memory allows
  (``|z_i - u0| <= r_i`` and ``|z_i - z_j| <= |r_i - r_j|``, the states of some history)
  to the value that explains the samples before the plays are determined best, with the
  weights of the best history; the result is refitted.

The simple kinds (descent, ascent, virgin, periodic) are one convex QP (34)-(36) each on the
whole record; rows after the input has covered twice the largest threshold do not depend on
the candidate (wiping-out property), so their Gram matrix is accumulated once.  The
histories with turning points (a grid of levels, some dozens) are then scored with the best
simple candidate's weights by the generalised error before the plays are determined (cheap:
no QP), and the best one is refitted.  The candidate with the smallest generalised error is
the record's start state; it is written as ``record_start.hysteresis.initial_states``, so that
the model simulated from the record's first sample reproduces the record.
"""

from collections.abc import Callable
from dataclasses import dataclass, field, replace
import math
from typing import Any

import numpy as np
import numpy.typing as npt

from .dynamics import analyse_dynamics, DynamicsAnalysis
from .qp import _IDLE_PLAY, burn_in, fit_generalized_error, FloatArray, GramParts, \
    OUTER_SLOPE, output_sign, regressor_gram, scaled_design, ScaledDesign
from .ties import block_errors, BlockComparison, compare_on_blocks
from ..errors import DataError, IdentificationError
from ..operators.deadzone import dead_zone_operator
from ..operators.model import MPIModel
from ..operators.play import play_end_state, play_operator

__all__ = ['DynamicsEstimate', 'estimate_start_state', 'find_segments', 'fit_record',
           'better_on_folds', 'fold_index', 'fold_line_errors', 'FoldErrors', 'FOLDS',
           'InputDynamics', 'prepare_record', 'PreparedRecord', 'RecordFit', 'refine_memory',
           'Segment', 'start_candidates', 'START_KINDS', 'StartState', 'turning_point_candidates',
           'with_initial_states']

#: The kinds of history a start state is chosen from.
START_KINDS = ('descent', 'ascent', 'virgin', 'reversal', 'reversals', 'periodic',
               'memory')


@dataclass(frozen=True)
class StartState:
    """
    One candidate history before a record's first sample.

    Attributes
    ----------
    kind : str
        One of :data:`START_KINDS`.
    levels : tuple of float
        ``virgin``: the demagnetised input; ``reversal`` / ``reversals``: the inputs of the
        last turning points, oldest first (scaled input units, like the thresholds).
    memory : tuple of (float, float)
        ``memory``: pairs (threshold, play state minus the first input), scaled; states of
        other thresholds are interpolated (a valid memory is 1-Lipschitz in the threshold).

    """

    kind: str
    levels: tuple[float, ...] = ()
    memory: tuple[tuple[float, float], ...] = ()

    def states(self, u0: float, thresholds: FloatArray,
               end_state: FloatArray | None = None) -> FloatArray:
        """
        Return the play outputs at the first sample for this history.

        Parameters
        ----------
        u0 : float
            The first input (scaled).
        thresholds : ndarray of float, shape (n+1,)
            Play thresholds (scaled).
        end_state : ndarray of float, shape (n+1,), optional
            The plays' state at the end of the record (``periodic`` only).

        Returns
        -------
        ndarray of float, shape (n+1,)
            Play outputs (scaled), each inside ``[u0 - r, u0 + r]``.

        """
        r = np.asarray(thresholds, dtype=np.float64)
        lo, hi = u0 - r, u0 + r
        z: FloatArray
        if self.kind == 'virgin':
            z = np.full(r.size, self.levels[0] if self.levels else 0.0)
            return np.asarray(np.clip(z, lo, hi), dtype=np.float64)
        if self.kind == 'periodic':
            z = np.zeros(r.size) if end_state is None else np.asarray(end_state, float)
            return np.asarray(np.clip(z, lo, hi), dtype=np.float64)
        if self.kind == 'memory':
            known = np.array(self.memory, dtype=np.float64).reshape(-1, 2)
            return np.clip(u0 + np.interp(r, known[:, 0], known[:, 1]), lo, hi)
        if self.kind not in ('descent', 'ascent', 'reversal', 'reversals'):
            msg = f'unknown start state {self.kind!r}; one of {", ".join(START_KINDS)}'
            raise ValueError(msg)
        path = [*self.levels, u0]
        if self.kind == 'descent':
            rising_first = False
        elif self.kind == 'ascent':
            rising_first = True
        else:
            rising_first = path[1] < path[0]      # a maximum first: reached from below
        far = float(np.max(r)) * 4.0 + abs(u0) + 4.0
        history = np.array([-far if rising_first else far, *path])
        _, z = play_operator(history, r, np.zeros(r.size))
        return np.clip(np.asarray(z, dtype=np.float64), lo, hi)

    def describe(self, to_input: Callable[[float], float], unit: str = 'A') -> str:
        """
        Say in words how the actuator came to the first sample.

        Parameters
        ----------
        to_input : callable
            Maps a scaled input level to the input's own unit.
        unit : str
            The input's unit.

        Returns
        -------
        str
            E.g. ``'at rest after a descent to the first value'``.

        """
        if self.kind == 'descent':
            return 'at rest after a descent to the first value'
        if self.kind == 'ascent':
            return 'at rest after an ascent to the first value'
        if self.kind == 'periodic':
            return 'in the state the record ends in (one period of a repeated excitation)'
        if self.kind == 'memory':
            return ("after a history with several turning points (every play's state"
                    ' estimated from the start of the record)')
        levels = ' and '.join(f'{to_input(v):.4g} {unit}' for v in self.levels)
        if self.kind == 'virgin':
            return f'demagnetised (virgin) at {levels}, then loaded to the first value'
        return f'after turning points of the input at {levels}'

    def to_json(self, to_input: Callable[[float], float]) -> dict[str, Any]:
        """Return ``{'kind', 'levels'}`` with the levels in the input's unit."""
        return {'kind': self.kind, 'levels': [to_input(float(v)) for v in self.levels]}


def refine_memory(u: FloatArray, thresholds: FloatArray, start: FloatArray,
                  weights: FloatArray, target: FloatArray, rows: npt.NDArray[np.bool_],
                  steps: int = 9, sweeps: int = 2, *,
                  tails: bool = False) -> tuple[FloatArray, float]:
    """
    Refine the plays' start states within a valid memory.

    Minimises ``sum over rows of (H[u; z] - target)^2`` over the start states ``z`` of the
    plays (``H = P w``) within what a valid memory allows (``|z_i - u0| <= r_i``,
    ``|z_i - z_j| <= |r_i - r_j|``), on a grid: one play at a time, largest threshold first;
    with ``tails``, first the step ``z_i - z_(i-1)`` between neighbouring plays, smallest
    threshold first, moving every play from ``i`` on together (a memory is 1-Lipschitz in the
    threshold, so a step keeps it valid whatever the others are).  Moving one play alone
    cannot leave a memory whose neighbours pin it: a record cut mid-descent after several
    turning points stopped there (about 3 % of the cuts of a simulated record, validating
    1.1-1.75x worse); the steps reach it.  They are also free enough to fit transients of the
    output before the plays are determined (ringing tails after a start step), so the
    identification takes them only where a memory already beat every simple history.

    Parameters
    ----------
    u : ndarray of float, shape (K,)
        Scaled input of the samples before the plays are determined.
    thresholds : ndarray of float, shape (n+1,)
        Play thresholds (scaled), ascending from 0.
    start : ndarray of float, shape (n+1,)
        The states to start from (the best history's).
    weights : ndarray of float, shape (n+1,)
        Weights of H.
    target : ndarray of float, shape (K,)
        What H should equal there (``S'[y] - c`` of the current fit).
    rows : ndarray of bool, shape (K,)
        The samples that count (training samples).
    steps : int
        Grid values tried per play and sweep.
    sweeps : int
        Passes over the plays.
    tails : bool
        First move the steps between neighbouring plays (every play from one on together),
        in one sweep.

    Returns
    -------
    states, rms : ndarray of float, float
        The refined states and the RMS residual over the rows.

    """
    r = np.asarray(thresholds, dtype=np.float64)
    z = np.array(start, dtype=np.float64)
    u0 = float(u[0])
    plays, _ = play_operator(u, r, z)
    residual = plays @ weights - target
    count = max(int(np.count_nonzero(rows)), 1)
    best = float(np.sum(residual[rows] ** 2))
    for _ in range(1 if tails else 0):
        for i in range(1, r.size):
            # The step between plays i-1 and i: plays i.. move together.
            gap = r[i] - r[i - 1]
            if not gap > 0.0 or not np.any(weights[i:] != 0.0):
                continue
            shifts = np.linspace(-gap, gap, steps) - (z[i] - z[i - 1])
            kept: tuple[float, FloatArray, FloatArray] | None = None
            for shift in shifts[shifts != 0.0]:
                tail, _ = play_operator(u, r[i:], z[i:] + shift)
                moved = residual + (tail - plays[:, i:]) @ weights[i:]
                sse = float(np.sum(moved[rows] ** 2))
                if sse < best * (1.0 - 1e-9):
                    best, kept = sse, (float(shift), tail, moved)
            if kept is not None:
                z[i:] += kept[0]
                plays[:, i:] = kept[1]
                residual = kept[2]
    for _ in range(sweeps):
        for i in range(r.size - 1, 0, -1):
            lo = max(u0 - r[i], z[i - 1] - (r[i] - r[i - 1]))
            hi = min(u0 + r[i], z[i - 1] + (r[i] - r[i - 1]))
            if i + 1 < r.size:
                lo = max(lo, z[i + 1] - (r[i + 1] - r[i]))
                hi = min(hi, z[i + 1] + (r[i + 1] - r[i]))
            if not hi > lo or weights[i] == 0.0:
                continue
            values = np.linspace(lo, hi, steps)
            trial, _ = play_operator(u, np.full(steps, r[i]), values)
            moved = residual[:, None] + weights[i] * (trial - plays[:, [i]])
            sse = np.sum(moved[rows] ** 2, axis=0)
            k = int(np.argmin(sse))
            if sse[k] < best * (1.0 - 1e-9):
                best = float(sse[k])
                z[i] = values[k]
                residual = moved[:, k]
                plays[:, i] = trial[:, k]
    return z, float(np.sqrt(best / count))


def start_candidates(u: FloatArray) -> list[StartState]:
    """
    Return the simple candidate histories for a record's scaled input (one QP each).

    Parameters
    ----------
    u : ndarray of float, shape (N,)
        Scaled input.

    Returns
    -------
    list of StartState
        ``descent``, ``ascent``, ``periodic`` and virgin at the middle of the range.

    """
    lo, hi = float(np.min(u)), float(np.max(u))
    return [StartState('descent'), StartState('ascent'), StartState('periodic'),
            StartState('virgin', (0.5 * (lo + hi),))]


def turning_point_candidates(u: FloatArray, grid: int = 9) -> list[StartState]:
    """
    Return the histories on a grid of levels: virgin there, one or two turning points.

    Parameters
    ----------
    u : ndarray of float, shape (N,)
        Scaled input.
    grid : int
        Levels spread over the input's range.

    Returns
    -------
    list of StartState
        ``virgin`` at each level; ``reversal`` at each level away from the first input;
        ``reversals`` at pairs of levels on either side of it.

    """
    u0 = float(u[0])
    lo, hi = float(np.min(u)), float(np.max(u))
    gap = 0.05 * (hi - lo)
    grid_levels = np.linspace(lo, hi, grid).tolist()
    # Demagnetised at a level of the grid (where the drive's zero lies is not known: the
    # identification does not depend on the input's bias).
    out = [StartState('virgin', (p,)) for p in grid_levels]
    levels = [p for p in grid_levels if abs(p - u0) > gap]
    out.extend(StartState('reversal', (p,)) for p in levels)
    above = [p for p in levels if p > u0]
    below = [p for p in levels if p < u0]
    for newer in above:                       # came down from `newer` to u0 ...
        for older in below:                   # ... after coming up from `older`
            out.append(StartState('reversals', (older, newer)))
    for newer in below:
        for older in above:
            out.append(StartState('reversals', (older, newer)))
    return out


def determined_from(u: FloatArray, largest_threshold: float) -> int:
    """
    Return the first sample whose play outputs no longer depend on the start state.

    Parameters
    ----------
    u : ndarray of float, shape (N,)
        Scaled input.
    largest_threshold : float
        The largest play threshold (scaled).

    Returns
    -------
    int
        The sample after which the input has covered twice the threshold (N if never).

    """
    if largest_threshold <= 0.0:
        return 1
    return min(burn_in(u, 2.0 * largest_threshold) + 1, int(u.size))


def end_state(u: FloatArray, thresholds: FloatArray) -> FloatArray:
    """Return the plays' state after the record, started at rest after a descent."""
    z0 = np.clip(float(u[0]) + thresholds, float(u[0]) - thresholds, float(u[0]) + thresholds)
    return play_end_state(u, thresholds, z0)


def finite_or(value: float, fallback: float) -> float:
    """Return ``value`` if finite, else ``fallback``."""
    return value if math.isfinite(value) else fallback


def with_initial_states(model: Any, states: FloatArray) -> Any:
    """
    Return a model (Gamma, or an extended model of it) whose plays start in ``states``.

    Parameters
    ----------
    model : MPIModel or extended model
        A forward model; an extended model holds its Gamma as ``model.model``.
    states : ndarray of float, shape (n+1,)
        Play outputs at the first sample [A], relative to the input offset.

    Returns
    -------
    The same kind of model.

    """
    from dataclasses import replace as replace_field
    from ..operators.hysteresis import PIHysteresisOperator
    h = model.gamma.hysteresis
    return model.with_gamma(replace_field(
        model.gamma, hysteresis=PIHysteresisOperator(h.thresholds, h.weights, states)))


def estimate_start_state(model: Any, current: FloatArray, displacement: FloatArray, *,
                         time: FloatArray | None = None,
                         rows: npt.NDArray[np.bool_] | None = None,
                         offset_free: bool = False) -> tuple[Any, StartState, int]:
    """
    Estimate the start state of another record of a fitted model (e.g. a validation record).

    The weights stay; every candidate history (:func:`start_candidates`,
    :func:`turning_point_candidates`) is simulated over the samples before the plays are
    determined and the one with the smallest RMS output error there wins.

    Parameters
    ----------
    model : MPIModel or extended model
        The fitted forward model (an extended model is simulated with ``time``).
    current, displacement : ndarray of float, shape (N,)
        The record [A], [m].
    time : ndarray of float, shape (N,), optional
        Its sample times [s] (needed by an extended model).
    rows : ndarray of bool, shape (N,), optional
        The samples that count (e.g. outside ringing); all by default.
    offset_free : bool
        The record has its own sensor zero: the error is taken about its mean.

    Returns
    -------
    model : same kind
        The model with the estimated initial states.
    start : StartState
        The history chosen.
    determined : int
        The first sample whose plays no longer depend on the start state.

    """
    gamma = model.gamma
    r = np.asarray(gamma.hysteresis.thresholds, dtype=np.float64)
    u = np.asarray(current, dtype=np.float64) - gamma.input_offset
    y = np.asarray(displacement, dtype=np.float64)
    split = determined_from(u, float(r[-1]))
    keep = np.ones(u.size, dtype=bool) if rows is None else np.asarray(rows, dtype=bool)
    part = slice(0, max(split, 2))
    counted = keep[part]
    ends = end_state(u, r)
    best: tuple[float, StartState, Any] | None = None
    for cand in [*start_candidates(u), *turning_point_candidates(u)]:
        trial = with_initial_states(model, cand.states(float(u[0]), r, ends))
        if trial.timed and time is None:
            msg = f'a {trial.cause} model is simulated with its time base: pass time'
            raise ValueError(msg)
        sim = trial.response(None if time is None else time[part], current[part])
        residual = (sim - y[part])[counted]
        if offset_free and residual.size:
            residual = residual - float(np.mean(residual))
        error = float(np.mean(residual ** 2)) if residual.size else 0.0
        if best is None or error < best[0] * (1.0 - 1e-9):
            best = (error, cand, trial)
    assert best is not None
    return best[2], best[1], int(split)


#: Tolerance of the OSQP solves (polished): trial fits are compared on held-out rows,
#: which an unpolished solution can be off by a factor of two in ill-conditioned directions.
_TRIAL_TOLERANCE = 1e-9

#: A time gap: a sample interval this many times the median one.
_GAP_FACTOR = 5.0

#: A record is cut into at most this many experiments, each of at least _MIN_SEGMENT
#: samples; a time column that runs back or jumps more often is not used for joins.
_MAX_SEGMENTS = 20
_MIN_SEGMENT = 50

#: Dynamics are kept when they cut the held-out RMS output error by this fraction.
_DYNAMICS_GAIN = 0.1

#: Contiguous folds of the blocked cross-validation inside a record (:func:`fold_index`).
FOLDS = 5

#: The cross-validation covers the record's first samples, at most this many (a long
#: record's cost stays that of a window; the start is where the rules differ).
_CV_WINDOW = 100000

#: Held-out RMS errors closer than this fraction of the output's range tie, however
#: consistent over the folds (a tenth of the order selection's absolute tolerance; set after
#: seeing issue 17's lag records tie at 1e-5 and a plant seed's real gain of 1.3e-4).
_FOLD_FLOOR = 1e-4

#: Blocks of the rows before the plays are determined, alternately refined on and held out
#: when a memory is refined.
_PREFIX_BLOCKS = 8

#: Rounds of the joint estimate of the plays' start states (refine, refit).
_MEMORY_ROUNDS = 3

#: A start state explains the record's start when the generalised RMS error before the
#: plays are determined is at most this many times the error after, or below
#: :data:`_START_FLOOR` (1 % of H's scaled range of 2): model error, not a wrong state.
_START_TOLERANCE = 3.0
_START_FLOOR = 0.02


@dataclass(frozen=True)
class InputDynamics:
    """
    Dynamics of the input path found in a record (0: none).

    Attributes
    ----------
    dead_time : float
        Pure delay ``L`` [s] between input and output.
    lag_time_constant : float
        Time constant ``tau`` [s] of a first-order lag of the input.

    """

    dead_time: float = 0.0
    lag_time_constant: float = 0.0

    @property
    def present(self) -> bool:
        """Tell whether any dynamics is modelled."""
        return self.dead_time > 0.0 or self.lag_time_constant > 0.0

    def apply(self, time: FloatArray, current: FloatArray) -> FloatArray:
        """Return the input the hysteresis sees: delayed, then lagged."""
        from ..extensions._signals import delay, first_order_lag
        x = delay(time, current, self.dead_time) if self.dead_time > 0.0 else current
        if self.lag_time_constant > 0.0:
            x = first_order_lag(time, x, self.lag_time_constant)
        return np.asarray(x, dtype=np.float64)

    def describe(self) -> str:
        """Return the dynamics in words."""
        parts = []
        if self.dead_time > 0.0:
            parts.append(f'a dead time of {1e3 * self.dead_time:.3g} ms')
        if self.lag_time_constant > 0.0:
            parts.append(f'a first-order lag of {1e3 * self.lag_time_constant:.3g} ms')
        return ' and '.join(parts) if parts else 'none'


@dataclass(frozen=True)
class DynamicsEstimate:
    """
    The input's dynamics estimated from a record: both kinds, their errors, the choice.

    Attributes
    ----------
    modelled : InputDynamics
        What the model carries (zeros: the static model is as good on held-out data).
    dead_time : float
        Best dead time [s] of the dead-time-only trials (0 without a time base).
    lag_time_constant : float
        Best time constant [s] of the lag-only trials.
    static_error, dead_time_error, lag_error : float
        Held-out RMS output errors of the static model and of the best of each kind
        [fraction of the output range].
    tie : bool
        The dead time and the lag both beat the static model beyond the noise of the
        held-out blocks and are within it of each other
        (:func:`~mpi_ros.identification.ties.compare_on_blocks`): this record cannot tell
        them apart (a record with bursts at two rates can).
    trials : list of dict
        ``{'dead_time', 'lag_time_constant', 'held_error'}`` per trial.
    block_sizes : tuple of int
        Samples of each held-out block (empty when nothing was estimated).
    static_blocks, dead_time_blocks, lag_blocks : tuple of float
        Mean squared error per held-out block of the static model and of the best of each
        kind [fraction of the output range, squared].

    """

    modelled: InputDynamics = field(default_factory=InputDynamics)
    dead_time: float = 0.0
    lag_time_constant: float = 0.0
    static_error: float = math.nan
    dead_time_error: float = math.nan
    lag_error: float = math.nan
    tie: bool = False
    trials: list[dict[str, float]] = field(default_factory=list)
    block_sizes: tuple[int, ...] = ()
    static_blocks: tuple[float, ...] = ()
    dead_time_blocks: tuple[float, ...] = ()
    lag_blocks: tuple[float, ...] = ()

    def compare(self, first: str, second: str) -> BlockComparison:
        """
        Compare two of ``'static'``, ``'dead_time'``, ``'lag'`` on the held-out blocks.

        Parameters
        ----------
        first, second : str
            The models compared (first minus second).

        Returns
        -------
        BlockComparison
            The paired block test (:func:`~mpi_ros.identification.ties.compare_on_blocks`).

        """
        blocks = {'static': self.static_blocks, 'dead_time': self.dead_time_blocks,
                  'lag': self.lag_blocks}
        return compare_on_blocks(blocks[first], blocks[second], self.block_sizes)

    def to_json(self) -> dict[str, Any]:
        """Return the JSON form (no trials)."""
        return {'dead_time': self.dead_time, 'lag_time_constant': self.lag_time_constant,
                'static_held_out_error': _finite(self.static_error),
                'dead_time_held_out_error': _finite(self.dead_time_error),
                'lag_held_out_error': _finite(self.lag_error), 'tie': self.tie,
                'modelled': ('dead_time' if self.modelled.dead_time > 0.0 else
                             'lag' if self.modelled.lag_time_constant > 0.0 else 'none'),
                'modelled_dead_time': self.modelled.dead_time,
                'modelled_lag_time_constant': self.modelled.lag_time_constant}

    def describe(self) -> str:
        """Return what was found, in words (empty when nothing was estimated)."""
        nothing = self.dead_time == 0.0 and self.lag_time_constant == 0.0
        if not math.isfinite(self.static_error) or nothing:
            return ''
        both = (f'a dead time of {1e3 * self.dead_time:.3g} ms (held-out RMS'
                f' {100 * self.dead_time_error:.3g} %) or a first-order lag of'
                f' {1e3 * self.lag_time_constant:.3g} ms ({100 * self.lag_error:.3g} %),'
                f' against {100 * self.static_error:.3g} % for the static model')
        if not self.modelled.present:
            return (f'the output follows the input with {both}: not modelled (less than'
                    f' {100 * _DYNAMICS_GAIN:.0f} % better); mpi-ros diagnose tests it on'
                    ' validation data')
        tie = (' they tie on this record (one rate): the lag is modelled, its inverse is'
               ' causal; bursts at two rates tell them apart (mpi-ros diagnose'
               ' --excitation)' if self.tie else '')
        return (f'the output follows the input with {both}; modelled:'
                f' {self.modelled.describe()}{";" if tie else ""}{tie}')


def _finite(value: float) -> float | None:
    return value if math.isfinite(value) else None


@dataclass(frozen=True)
class FoldErrors:
    """
    Held-out errors of blocked cross-validation inside a record (see :func:`fold_index`).

    Attributes
    ----------
    error : float
        RMS output error over every held-out row, over the output's range (NaN: none).
    per_fold : list of float
        The same per fold, in the record's order.
    rule : str
        Where the weights came from: ``'determined'`` (the rows after the plays are
        determined; the start state explains the rows before, with those weights) or
        ``'joint'`` (every row, with the chosen start state).
    interior_error : float
        ``error`` over the held-out rows whose input lies inside the range of the input the
        fold was fitted on (no extrapolation).
    outside : float
        Fraction of the held-out rows outside that range.
    interior_per_fold : list of float
        ``interior_error`` per fold (NaN: no such rows).

    """

    error: float = math.nan
    per_fold: list[float] = field(default_factory=list)
    rule: str = 'joint'
    interior_error: float = math.nan
    outside: float = 0.0
    interior_per_fold: list[float] = field(default_factory=list)


@dataclass(frozen=True)
class Segment:
    """
    One experiment of a record: samples ``[start, stop)`` and how it begins.

    Attributes
    ----------
    start, stop : int
        Its samples.
    reason : str
        Why a new segment begins here (``'start'`` for the first).
    start_state : StartState or None
        The chosen start state (None: continues from the previous segment).

    """

    start: int
    stop: int
    reason: str = 'start'
    start_state: StartState | None = None


@dataclass(frozen=True)
class PreparedRecord:
    """
    A record checked and analysed, ready for trial fits.

    Attributes
    ----------
    time : ndarray of float or None
        Sample times [s] (None: no time base).
    current, displacement : ndarray of float, shape (N,)
        The data.
    keep : ndarray of bool, shape (N,)
        Samples that enter the fit (outside ringing).
    segments : list of Segment
        The experiments of the record.
    analysis : DynamicsAnalysis
        What moves the output against the input.
    sign : int
        Whether the output rises (1) or falls (-1) with the input.
    anchor : str
        The design's anchor.
    epsilon : float
        The bound of (8)/(19).

    """

    time: FloatArray | None
    current: FloatArray
    displacement: FloatArray
    keep: npt.NDArray[np.bool_]
    segments: list[Segment]
    analysis: DynamicsAnalysis
    sign: int
    anchor: str = 'operating_point'
    epsilon: float = 1e-6

    def window(self, size: int) -> 'PreparedRecord':
        """
        Return the part of the record with the most input travel, at most ``size`` samples.

        Trial fits on a long record (dynamics grid, order selection) run on such a window:
        its content (the most sweeps, the fastest rates) decides them, and it keeps their
        cost independent of the record's length.  The window is a record of its own: its
        start state is chosen afresh.

        Parameters
        ----------
        size : int
            Largest number of samples.

        Returns
        -------
        PreparedRecord
            This record when it is short enough, else the window.

        """
        n = self.current.size
        if n <= size:
            return self
        travel = np.concatenate([[0.0], np.cumsum(np.abs(np.diff(self.current)))])
        start = int(np.argmax(travel[size - 1:] - travel[:n - size + 1]))
        stop = start + size
        segments = [replace(s, start=max(s.start, start) - start,
                            stop=min(s.stop, stop) - start,
                            start_state=None if s.start > start else s.start_state)
                    for s in self.segments if s.stop > start and s.start < stop]
        segments[0] = replace(segments[0], start_state=None, reason='start')
        time = None if self.time is None else self.time[start:stop]
        return replace(self, time=time, current=self.current[start:stop],
                       displacement=self.displacement[start:stop],
                       keep=self.keep[start:stop], segments=segments)


@dataclass(frozen=True)
class RecordFit:
    """
    One fit of Gamma on a prepared record.

    Attributes
    ----------
    model : MPIModel
        Gamma (SI units) with the first segment's start state as its initial states.
    design : ScaledDesign
        Its design.
    segments : list of Segment
        With the chosen start states.
    material_input : ndarray of float, shape (N,)
        The input Gamma saw (after the dynamics).
    train_error, held_error : float
        Generalised RMS error on the training and held-out rows, in the input's unit
        (NaN without held-out rows).
    burn_in : int
        Samples at the start left out of the fit because no start state explains them.
    info : object
        OSQP's info structure of the final solve.
    notes : list of str
        What the fit noticed (burn-in, weights fitted after the start).
    fitted : ndarray of bool, shape (N,)
        The samples the weights were fitted on (training rows, outside ringing, after a
        burn-in, and, when enough samples follow, after the plays are determined).
    rule : str
        Where the weights came from (see :class:`FoldErrors`).
    folds : dict
        The cross-validation of each rule compared, by rule (empty when none ran).

    """

    model: MPIModel
    design: ScaledDesign
    segments: list[Segment]
    material_input: FloatArray
    train_error: float
    held_error: float
    burn_in: int = 0
    info: Any = None
    notes: list[str] = field(default_factory=list)
    fitted: npt.NDArray[np.bool_] | None = None
    rule: str = 'joint'
    folds: dict[str, FoldErrors] = field(default_factory=dict)

    def simulate(self) -> FloatArray:
        """Return the model's output over the record, each segment from its start state."""
        out = np.empty(self.material_input.size)
        state: FloatArray | None = None
        z_first = np.asarray(self.model.hysteresis.initial_states, dtype=np.float64)
        for seg in self.segments:
            part = self.material_input[seg.start:seg.stop]
            if seg.start_state is None and state is not None:
                z = state
            else:
                z = self._state_of(seg) if seg.start != 0 else z_first
            # The compiled Gamma (plays, H, S in one pass), as ``MPIModel.simulate``.
            out[seg.start:seg.stop], state = self.model.run(part, z)
        return out

    def _state_of(self, seg: Segment) -> FloatArray:
        d = self.design
        u = d.scaled_input(self.material_input[seg.start:seg.stop])
        assert seg.start_state is not None
        z = seg.start_state.states(float(u[0]), d.hysteresis_thresholds,
                                   end_state(u, d.hysteresis_thresholds))
        return _to_model_states(z, d, self.model)


def find_segments(time: FloatArray | None, analysis: DynamicsAnalysis, size: int,
                  jumps: list[int] | None = None) -> list[Segment]:
    """
    Cut a record at the joins of the experiments it was stitched from.

    A join is a time gap (an interval over five times the median one), time running back
    (each experiment's clock restarting), or an output jump the input does not explain
    (the unrecorded input between two experiments) after the record's first samples.  At
    most :data:`_MAX_SEGMENTS` experiments of at least :data:`_MIN_SEGMENT` samples each; a
    time column that runs back or jumps more often is not a clock of stitched experiments
    (duplicated, constant or scrambled time) and gives no joins.

    Parameters
    ----------
    time : ndarray of float or None
        Sample times [s].
    analysis : DynamicsAnalysis
        The record's analysis (its output jumps).
    size : int
        Number of samples.
    jumps : list of int, optional
        Output jumps the input does not explain (from the analysis).

    Returns
    -------
    list of Segment
        At least one.

    """
    cuts: dict[int, str] = {}
    if time is not None and size > 2:
        steps = np.diff(time)
        positive = steps[steps > 0.0]
        typical = float(np.median(positive)) if positive.size else 0.0
        back = np.flatnonzero(steps <= 0.0)
        gaps = (np.flatnonzero(steps > _GAP_FACTOR * typical) if typical > 0.0
                else np.zeros(0, dtype=np.int64))
        # A clock that runs back or jumps at many samples is no clock of a few stitched
        # experiments (a duplicated, constant or scrambled time column): no joins from it.
        if back.size + gaps.size <= _MAX_SEGMENTS:
            for k in back.tolist():
                cuts[k + 1] = 'time runs back'
            for k in gaps.tolist():
                cuts.setdefault(k + 1, f'time gap of {steps[k]:.4g} s')
    for k in jumps or []:
        if all(abs(k - c) > _MIN_SEGMENT for c in cuts):
            cuts[k] = 'output jump the input does not explain'
    bounds: list[int] = []
    for c in sorted(cuts):               # experiments of at least _MIN_SEGMENT samples
        if c - (bounds[-1] if bounds else 0) >= _MIN_SEGMENT and size - c >= _MIN_SEGMENT:
            bounds.append(c)
    bounds = bounds[:_MAX_SEGMENTS - 1]
    starts = [0] + bounds
    stops = bounds + [size]
    return [Segment(a, b, 'start' if a == 0 else cuts[a]) for a, b in zip(starts, stops)]


def prepare_record(current: FloatArray, displacement: FloatArray, *,
                   time: FloatArray | None = None, anchor: str = 'operating_point',
                   epsilon: float = 1e-6, sign: int | None = None) -> PreparedRecord:
    """
    Analyse a record: dynamics, ringing, segments (no refusal here).

    Parameters
    ----------
    current, displacement : ndarray of float, shape (N,)
        The data.
    time : ndarray of float, optional
        Sample times [s]; None for a record without a time base.
    anchor : str
        The design's anchor.
    epsilon : float
        The bound of (8)/(19).
    sign : int, optional
        The output's sign (detected by default).

    Returns
    -------
    PreparedRecord
        The record and what was found.

    """
    x = np.asarray(current, dtype=np.float64)
    y = np.asarray(displacement, dtype=np.float64)
    if sign is None:
        sign, _ = output_sign(x, y)
    analysis = analyse_dynamics(_joined_time(time), x, y, sign=sign)
    keep = analysis.mask(x.size)
    segments = find_segments(time, analysis, x.size, jumps=analysis.jumps)
    return PreparedRecord(time, x, y, keep, segments, analysis, int(sign), anchor, epsilon)


def _joined_time(time: FloatArray | None) -> FloatArray | None:
    # The clock of a stitched record with its joins closed: a time gap or a restart of the
    # clock becomes one typical interval, so each experiment's dynamics (ringing after its
    # start, lag) are measured in its own time.
    if time is None or time.size < 3:
        return time
    steps = np.diff(time)
    positive = steps[steps > 0.0]
    if not positive.size:
        return None
    typical = float(np.median(positive))
    joins = (steps <= 0.0) | (steps > _GAP_FACTOR * typical)
    if not np.any(joins):
        return time
    steps = np.where(joins, typical, steps)
    return np.concatenate([[float(time[0])], float(time[0]) + np.cumsum(steps)])


def fit_record(record: PreparedRecord, n: int, l: int, *,  # noqa: E741
               dynamics: InputDynamics = InputDynamics(),
               held: npt.NDArray[np.bool_] | None = None,
               starts: list[Segment] | None = None, choose: bool = True,
               tolerance: float = 1e-9, burn_in: int | None = None,
               memory_steps: bool = False, rule: str | None = None,
               validate: bool = False) -> RecordFit:
    """
    Fit Gamma on a prepared record, choosing each segment's start state.

    Start states are chosen with the weights of the rows after the plays are determined
    fixed (:meth:`_Fitter.choose_starts_determined`), where enough such rows exist (else
    jointly with the weights, one QP per candidate).  The final weights come from the
    determined rows alone (``rule='determined'``) or from every row with the chosen start
    states (``'joint'``), or the start states are chosen jointly with the weights (``'joint
    start'``, the choice before cross-validation): by default the rule with the smallest
    held-out error of blocked cross-validation (:meth:`_Fitter.fold_errors`), beyond the
    folds' noise (:func:`better_on_folds`; a tie keeps ``'joint start'``).

    Parameters
    ----------
    record : PreparedRecord
        The record.
    n, l : int
        Model orders.
    dynamics : InputDynamics
        Dead time and lag applied to the input before the fit.
    held : ndarray of bool, shape (N,), optional
        Held-out rows (scored, not fitted).
    starts : list of Segment, optional
        Segments with start states to use (e.g. from a fit at another order); chosen
        afresh when None or when ``choose`` is True.
    choose : bool
        Choose the start states.
    tolerance : float
        OSQP's tolerance of the final solve.
    burn_in : int, optional
        Samples at the start to leave out (trial fits compared with a reference fit use
        its burn-in); by default 0, or found when the start states are chosen and none
        explains the record's start.
    memory_steps : bool
        Where a memory beats every simple history, refine it also by the steps between
        plays (see :func:`refine_memory`); the final fit of :func:`mpi_ros.identify` does,
        the trial fits of the order selection and the dynamics grid do not.
    rule : {'determined', 'joint', 'joint start'}, optional
        Where the weights come from (``'joint start'``: every row, the start states chosen
        jointly with the weights, one QP per candidate); None: the one of the three with the
        smallest held-out error of blocked cross-validation when the start states are
        chosen (:func:`better_on_folds`; a tie keeps ``'joint start'``), ``'joint'``
        otherwise (trial fits pass their reference fit's rule).
    validate : bool
        Cross-validate the rule used (``RecordFit.folds[rule]``) when it was not already.

    Returns
    -------
    RecordFit
        The fit.

    """
    x = record.current
    if dynamics.present:
        if record.time is None:
            msg = 'input dynamics need a time base'
            raise DataError(msg)
        x = dynamics.apply(record.time, x)
    y = record.displacement
    design = scaled_design(x, y, n, l, anchor=record.anchor,
                           sign=record.sign if record.anchor != 'origin' else None)
    xs, ys = design.scaled_input(x), design.scaled_output(y)
    classes = np.where(record.keep, 0, -1).astype(np.int8)
    if held is not None:
        classes[held & record.keep] = 1
    fitter = _Fitter(xs, ys, design, classes, record.epsilon)
    segments = list(starts) if starts is not None else list(record.segments)
    if record.anchor == 'origin':
        segments = [replace(s, start_state=StartState('virgin', (0.0,))) for s in segments]
        choose = False
    notes: list[str] = []
    folds: dict[str, FoldErrors] = {}
    if choose or any(s.start_state is None and s.start == 0 for s in segments):
        picked = (fitter.choose_starts_determined(segments, memory_steps=memory_steps)
                  if rule in (None, 'determined', 'joint') else None)
        jointly = (fitter.choose_starts(segments, memory_steps=memory_steps)
                   if picked is None or rule is None else segments)
        if picked is None:
            segments, rule = jointly, ('joint' if rule is None else rule)
        elif rule is not None:
            segments = picked
        else:
            # The rules, judged on held-out folds: weights of the determined rows or of
            # every row, with the start states chosen under the determined rows' weights;
            # every row with the start states chosen jointly (the start may pull weights).
            # A rule replaces the best so far only when it is lower beyond the folds' noise
            # (see better_on_folds); on a tie the in-sample choice stays (the start chosen
            # jointly: it also reproduces the record's start best).
            options = {'joint start': jointly, 'determined': picked, 'joint': picked}
            for label, option in options.items():
                folds[label] = fitter.fold_errors(option, _weight_rule(label), x, y)
                if rule is None or better_on_folds(folds[label], folds[rule]):
                    rule, segments = label, option
    rule = rule or 'joint'
    if rule == 'determined' and fitter.determined_parts(segments) is None:
        rule = 'joint'
    burn = int(burn_in or 0)
    every = fitter
    fitter = _rule_fitter(every, segments, _weight_rule(rule), burn)
    parts = fitter.parts(segments)
    if fitter is every and rule == 'determined':
        parts = fitter.determined_parts(segments) or parts      # cached: no new pass
    weights = fitter.solve(parts, tolerance)
    if burn_in is None and choose:
        burn = every.undetermined_start(segments, weights)
    if burn and not burn_in:
        fitter = _rule_fitter(every, segments, _weight_rule(rule), burn)
        parts = fitter.parts(segments)
        weights = fitter.solve(parts, tolerance)
        notes.append(f'the first {burn} samples are left out of the fit: no start state'
                     ' explains them (the record starts on a transient or after a history'
                     ' none of the candidates covers)')
    fit = _finish(record, design, fitter, parts, weights, segments, x, held, burn, notes)
    if _weight_rule(rule) == 'determined' and fit.fitted is not None:
        fitted = fit.fitted.copy()
        for seg in segments:
            fitted[seg.start:fitter.split(seg)] = False
        fit = replace(fit, fitted=fitted)
    if validate and rule not in folds:
        folds[rule] = _rule_fitter(every, segments, 'joint', burn).fold_errors(
            segments, _weight_rule(rule), x, y)
    return replace(fit, rule=rule, folds=folds)


def _weight_rule(label: str) -> str:
    # 'joint start' (start states chosen jointly with the weights) fits the weights jointly.
    return 'determined' if label == 'determined' else 'joint'


def _rule_fitter(fitter: '_Fitter', segments: list[Segment], rule: str,
                 burn: int) -> '_Fitter':
    # The fitter of the final weights: rows of the burn-in left out, and with the rule
    # 'determined' the rows before each segment's plays are determined (without a burn-in
    # the fitter itself: its determined_parts are those rows).
    if not burn:
        return fitter
    classes = fitter.classes.copy()
    classes[:burn] = -1
    if rule == 'determined':
        for seg in segments:
            classes[seg.start:fitter.split(seg)] = -1
    return _Fitter(fitter.xs, fitter.ys, fitter.design, classes, fitter.epsilon)


def better_on_folds(candidate: FoldErrors, incumbent: FoldErrors) -> bool:
    """
    Tell whether a rule's held-out error is lower than another's beyond the folds' noise.

    The pooled held-out RMS error must fall by more than :data:`_FOLD_FLOOR` of the output's
    range, and either the paired differences of the folds' mean squared errors have a
    negative mean larger than its standard error (one sigma over the folds), or no fold is
    worse by more than :data:`_FOLD_FLOOR` (a gain in one fold only, such as the record's
    start, is a gain); otherwise they tie.

    Parameters
    ----------
    candidate, incumbent : FoldErrors
        The two rules' cross-validations on the same folds.

    Returns
    -------
    bool
        The candidate is better.

    """
    a = np.square(np.asarray(candidate.per_fold, dtype=np.float64))
    b = np.square(np.asarray(incumbent.per_fold, dtype=np.float64))
    if a.size != b.size or not math.isfinite(candidate.error):
        return False
    if not math.isfinite(incumbent.error):
        return True
    finite = np.isfinite(a) & np.isfinite(b)
    d = (a - b)[finite]
    if d.size < 2:
        return bool(candidate.error < incumbent.error)
    if not candidate.error < incumbent.error - _FOLD_FLOOR:
        return False
    noise = float(np.std(d, ddof=1)) / math.sqrt(d.size)
    rms_a = np.asarray(candidate.per_fold, dtype=np.float64)[finite]
    rms_b = np.asarray(incumbent.per_fold, dtype=np.float64)[finite]
    dominates = bool(np.all(rms_a <= rms_b + _FOLD_FLOOR))
    return bool(float(np.mean(d)) < -noise or dominates)


def fold_index(size: int, folds: int = FOLDS) -> npt.NDArray[np.int8]:
    """
    Return each sample's fold: ``folds`` contiguous blocks of (nearly) equal length.

    Parameters
    ----------
    size : int
        Samples.
    folds : int
        Blocks.

    Returns
    -------
    ndarray of int8, shape (size,)
        0 for the first block, ``folds - 1`` for the last.

    """
    return np.minimum((np.arange(size) * folds) // max(size, 1), folds - 1).astype(np.int8)


def fold_line_errors(current: FloatArray, displacement: FloatArray,
                     rows: npt.NDArray[np.bool_], folds: int = FOLDS) -> FoldErrors:
    """
    Return the straight line's held-out errors on the folds of :meth:`_Fitter.fold_errors`.

    Parameters
    ----------
    current, displacement : ndarray of float, shape (N,)
        The record (the input the model sees).
    rows : ndarray of bool, shape (N,)
        The rows that are fitted and scored (outside ringing).
    folds : int
        Blocks.

    Returns
    -------
    FoldErrors
        The line ``y = a x + b`` fitted on the other folds, scored on each.

    """
    size = min(current.size, _CV_WINDOW)
    fold = fold_index(size, folds)
    x, y, keep = current[:size], displacement[:size], rows[:size]
    span = float(np.ptp(displacement))
    per_fold: list[float] = []
    inner_per_fold: list[float] = []
    total, count, inner, inner_count = 0.0, 0, 0.0, 0
    for k in range(folds):
        train, test = keep & (fold != k), keep & (fold == k)
        inner_per_fold.append(math.nan)
        if int(np.count_nonzero(train)) < 2 or not np.any(test):
            per_fold.append(math.nan)
            continue
        xt, yt = x[train], y[train]
        xc = xt - float(np.mean(xt))
        denominator = float(np.sum(xc * xc))
        slope = float(np.sum(xc * (yt - float(np.mean(yt))))) / denominator if denominator \
            else 0.0
        e = float(np.mean(yt)) + slope * (x[test] - float(np.mean(xt))) - y[test]
        per_fold.append(float(np.sqrt(np.mean(e * e))) / span)
        total += float(np.sum(e * e))
        count += int(e.size)
        inside = (x[test] >= float(np.min(xt))) & (x[test] <= float(np.max(xt)))
        inner += float(np.sum(e[inside] ** 2))
        inner_count += int(np.count_nonzero(inside))
        if np.any(inside):
            inner_per_fold[-1] = float(np.sqrt(np.mean(e[inside] ** 2))) / span
    pooled = math.sqrt(total / count) / span if count else math.nan
    interior = math.sqrt(inner / inner_count) / span if inner_count else math.nan
    return FoldErrors(pooled, per_fold, 'line', interior,
                      1.0 - inner_count / count if count else 0.0, inner_per_fold)


def _finish(record: PreparedRecord, design: ScaledDesign, fitter: '_Fitter',
            parts: GramParts, weights: tuple[FloatArray, FloatArray, float, Any],
            segments: list[Segment], x: FloatArray, held: npt.NDArray[np.bool_] | None,
            burn: int, notes: list[str]) -> RecordFit:
    # The model with the first segment's start state, and its errors.
    w_h, w_s, constant, info = weights
    xs = fitter.xs
    first = segments[0].start_state
    z0 = (first.states(float(xs[0]), design.hysteresis_thresholds,
                       fitter._end(segments[0]) if first.kind == 'periodic' else None)
          if first is not None else np.zeros(w_h.size))
    model = design.model(w_h, w_s, constant, initial_states=z0)
    train = fitter.error(parts, weights, 0) * design.x_scale
    held_error = (fitter.error(parts, weights, 1) * design.x_scale
                  if held is not None else math.nan)
    return RecordFit(model, design, segments, x, train, held_error, burn, info, notes,
                     fitter.classes == 0)


def _finish_model(fitter: '_Fitter', segments: list[Segment], material_input: FloatArray,
                  w_h: FloatArray, w_s: FloatArray, constant: float) -> RecordFit:
    # A fit of given weights with the segments' start states, for its simulation.
    design = fitter.design
    first = segments[0].start_state
    xs = fitter.xs
    z0 = (first.states(float(xs[0]), design.hysteresis_thresholds,
                       fitter._end(segments[0]) if first.kind == 'periodic' else None)
          if first is not None else np.zeros(w_h.size))
    model = design.model(w_h, w_s, constant, initial_states=z0)
    return RecordFit(model, design, segments, material_input, math.nan, math.nan)


def _placeholder(segments: list[Segment]) -> list[Segment]:
    # A start state for every segment that has none: the first segment's periodic one,
    # the others continue.
    return [replace(seg, start_state=seg.start_state or (
        StartState('periodic') if i == 0 else None)) for i, seg in enumerate(segments)]


class _Fitter:
    """Gram matrices per segment and start state, and the QP on their sum."""

    def __init__(self, xs: FloatArray, ys: FloatArray, design: ScaledDesign,
                 classes: npt.NDArray[np.int8], epsilon: float) -> None:
        self.xs, self.ys, self.design = xs, ys, design
        self.classes = classes
        self.epsilon = epsilon
        self.r_h = design.hysteresis_thresholds
        self.r_s = design.inverse_superposition_thresholds
        self._suffix: dict[int, tuple[int, GramParts]] = {}
        self._prefixes: dict[tuple[int, bytes], GramParts] = {}
        self._dead_zones: dict[int, FloatArray] = {}
        self._splits: dict[tuple[int, int], int] = {}
        self._ends: dict[tuple[int, int], FloatArray] = {}
        self._fold_suffix: dict[tuple[int, int, int], GramParts] = {}

    def _state(self, seg: Segment, previous: FloatArray | None) -> FloatArray:
        u = self.xs[seg.start:seg.stop]
        if seg.start_state is None:
            if previous is not None:
                return previous
            return StartState('periodic').states(float(u[0]), self.r_h, self._end(seg))
        end = self._end(seg) if seg.start_state.kind == 'periodic' else None
        return seg.start_state.states(float(u[0]), self.r_h, end)

    def _end(self, seg: Segment) -> FloatArray:
        # The plays' states at the segment's end (a periodic start), once per segment.
        key = (seg.start, seg.stop)
        if key not in self._ends:
            self._ends[key] = end_state(self.xs[seg.start:seg.stop], self.r_h)
        return self._ends[key]

    def _segment_parts(self, seg: Segment, z0: FloatArray) -> GramParts:
        # Rows of the segment once its plays are determined do not depend on its start
        # state: accumulated once and reused.
        split = self.split(seg)
        key = (seg.start, z0.tobytes())
        prefix = self._prefixes.get(key)
        if prefix is None:
            prefix = regressor_gram(self.xs, self.ys, self.r_h, self.r_s, state=z0,
                                    classes=self.classes, n_classes=2, start=seg.start,
                                    stop=split)
            self._prefixes[key] = prefix
        if split >= seg.stop:
            return prefix
        cached = self._suffix.get(seg.start)
        if cached is None or cached[0] != split:
            suffix = regressor_gram(self.xs, self.ys, self.r_h, self.r_s,
                                    state=prefix.end_state, classes=self.classes,
                                    n_classes=2, start=split, stop=seg.stop)
            self._suffix[seg.start] = (split, suffix)
        else:
            suffix = cached[1]
        return prefix + suffix

    def parts(self, segments: list[Segment]) -> GramParts:
        """Return the Gram parts of the whole record for these start states."""
        total: GramParts | None = None
        previous: FloatArray | None = None
        for seg in segments:
            p = self._segment_parts(seg, self._state(seg, previous))
            previous = p.end_state
            total = p if total is None else total + p
        assert total is not None
        return total

    def solve(self, parts: GramParts, tolerance: float,
              selected: tuple[int, ...] = (0,)) -> tuple[FloatArray, FloatArray, float, Any]:
        """Solve the QP on the rows of the selected classes (training: 0); see :meth:`parts`."""
        gram, mean, count = parts.normalised(selected)
        if count == 0:
            msg = 'no samples left to fit (all in ringing windows or held out)'
            raise IdentificationError(msg)
        n1 = self.r_h.size
        idle = None
        if self.design.constant:
            gram = gram - np.outer(mean, mean)
            variance = np.diag(gram)[:n1]
            idle = np.flatnonzero(variance <= _IDLE_PLAY ** 2 * variance[0])
        w_h, w_s, _, info = fit_generalized_error(
            gram, 1.0 - self.r_h, n_hysteresis=n1, n_superposition=self.r_s.size,
            superposition_center=self.design.center, epsilon=self.epsilon, fixed_zero=idle,
            tolerance=tolerance, outer_slope=OUTER_SLOPE)
        constant = (-float(mean @ np.concatenate([w_h, w_s])) if self.design.constant
                    else 0.0)
        return w_h, w_s, constant, info

    def error(self, parts: GramParts, weights: tuple[FloatArray, FloatArray, float, Any],
              cls: int) -> float:
        """Return the generalised RMS error, in scaled units, on the rows of one class."""
        count = int(parts.counts[cls])
        if count == 0:
            return math.nan
        w = np.concatenate([weights[0], weights[1]])
        c = weights[2]
        value = (float(w @ parts.grams[cls] @ w) + 2.0 * c * float(parts.sums[cls] @ w)
                 + c * c * count) / count
        return math.sqrt(max(value, 0.0))

    def split(self, seg: Segment) -> int:
        """Return the first sample of a segment whose plays no longer depend on its start."""
        key = (seg.start, seg.stop)
        if key not in self._splits:
            self._splits[key] = seg.start + determined_from(self.xs[seg.start:seg.stop],
                                                            float(self.r_h[-1]))
        return self._splits[key]

    def choose_starts(self, segments: list[Segment], *,
                      memory_steps: bool = False) -> list[Segment]:
        """
        Choose each segment's start state (see "Start states" above).

        The simple candidates (and, after the first segment, "continues") are one QP each;
        the histories with turning points are scored with the best simple candidate's
        weights on the rows before the plays are determined, and the best of those is
        refitted; the smallest generalised error wins.  A winning memory is refined by the
        steps between plays too with ``memory_steps`` (see :func:`refine_memory`).
        """
        chosen = _placeholder(segments)
        for i, seg in enumerate(segments):
            u = self.xs[seg.start:seg.stop]
            candidates: list[StartState | None] = list(start_candidates(u))
            if i > 0:
                candidates.insert(0, None)                  # continues from the previous
            best: tuple[float, StartState | None, Any] | None = None
            for cand in candidates:
                error, weights = self._trial(chosen, i, cand)
                if best is None or error < best[0] * (1.0 - 1e-6):
                    best = (error, cand, weights)
            if best is None:
                continue
            chosen[i] = replace(seg, start_state=best[1])
            # Histories with turning points, scored without a QP, then the best refitted.
            previous = self._previous_state(chosen, i)
            scored: list[tuple[float, StartState | None]] = [
                (self._prefix_error(seg, cand, best[2], previous), cand)
                for cand in turning_point_candidates(u)]
            scored.append((self._prefix_error(seg, best[1], best[2], previous), best[1]))
            top = scored[-1]
            for item in scored:
                if item[0] < top[0] * (1.0 - 1e-6):
                    top = item
            if top[1] is not best[1]:
                error, weights = self._trial(chosen, i, top[1])
                if error < best[0] * (1.0 - 1e-6):
                    chosen[i] = replace(seg, start_state=top[1])
                    best = (error, top[1], weights)
            chosen[i] = self._refine_memory(chosen, i, best, previous, memory_steps)
        return chosen

    def determined_parts(self, segments: list[Segment]) -> GramParts | None:
        """
        Return the Gram parts of the rows after each segment's plays are determined.

        Those rows do not depend on any start state (wiping-out): they are the segments'
        cached suffixes (no pass over the record of their own).  None: fewer than ten rows
        per weight.
        """
        total: GramParts | None = None
        for seg in segments:
            split = self.split(seg)
            if split >= seg.stop:
                continue
            cached = self._suffix.get(seg.start)
            if cached is None or cached[0] != split:
                u0 = float(self.xs[seg.start])
                self._segment_parts(seg, StartState('descent').states(u0, self.r_h))
                cached = self._suffix[seg.start]
            total = cached[1] if total is None else total + cached[1]
        weights = self.r_h.size + self.r_s.size
        if total is None or int(total.counts[0]) < 10 * weights:
            return None
        return total

    def choose_starts_determined(self, segments: list[Segment], *,
                                 memory_steps: bool = False) -> list[Segment] | None:
        """
        Choose each segment's start state with the weights of the determined rows fixed.

        The weights are fitted on the rows after the plays are determined (one QP); every
        candidate history (simple ones, turning points, "continues") is then scored by the
        generalised error of the rows before, with those weights: the start state explains
        the first samples, it cannot pull weights that only it supports.  A memory (every
        play's state) is refined on half of those rows (alternate blocks) and kept only when
        it lowers the error of the other half (then refined on all of them).

        Returns
        -------
        list of Segment or None
            The segments with their start states; None when too few rows are determined (the
            joint choice of :meth:`choose_starts` applies).

        """
        determined = self.determined_parts(segments)
        if determined is None:
            return None
        try:
            weights = self.solve(determined, _TRIAL_TOLERANCE)
        except IdentificationError:
            return None
        chosen = _placeholder(segments)
        for i, seg in enumerate(segments):
            u = self.xs[seg.start:seg.stop]
            previous = self._previous_state(chosen, i)
            candidates: list[StartState | None] = [*start_candidates(u),
                                                   *turning_point_candidates(u)]
            if i > 0:
                candidates.insert(0, None)                  # continues from the previous
            best: tuple[float, StartState | None] | None = None
            for cand in candidates:
                error = self._prefix_error(seg, cand, weights, previous)
                if best is None or error < best[0] * (1.0 - 1e-6):
                    best = (error, cand)
            assert best is not None
            chosen[i] = replace(seg, start_state=best[1])
            chosen[i] = self._refine_held_out(chosen[i], weights, previous, memory_steps)
        return chosen

    def _refine_held_out(self, seg: Segment, weights: Any, previous: FloatArray | None,
                         memory_steps: bool) -> Segment:
        # The joint estimate of the plays' states with fixed weights, judged on held-out
        # blocks of the rows before the plays are determined.
        split = self.split(seg)
        rows = slice(seg.start, split)
        train = self.classes[rows] == 0
        if split - seg.start < 16 or int(np.count_nonzero(train)) < 16:
            return seg
        index = np.arange(split - seg.start)
        half = (index * _PREFIX_BLOCKS // index.size) % 2 == 0
        u = self.xs[rows]
        w_h, w_s, constant, _ = weights
        target = self.prefix_dead_zones(seg) @ w_s - constant
        z = self._state(seg, previous)

        def error(states: FloatArray, mask: npt.NDArray[np.bool_]) -> float:
            plays, _ = play_operator(u, self.r_h, states)
            e = (plays @ w_h - target)[mask]
            return float(np.mean(e * e)) if e.size else 0.0

        for tails in (False, True) if memory_steps else (False,):
            if tails and not (seg.start_state is not None and seg.start_state.kind == 'memory'):
                break
            trial, _ = refine_memory(u, self.r_h, z, w_h, target, train & half, tails=tails)
            if not error(trial, train & ~half) < error(z, train & ~half) * (1.0 - 1e-6):
                break
            z, _ = refine_memory(u, self.r_h, z, w_h, target, train, tails=tails)
            seg = replace(seg, start_state=StartState('memory', memory=tuple(
                (float(r), float(v - u[0])) for r, v in zip(self.r_h, z))))
        return seg

    def fold_errors(self, segments: list[Segment], rule: str, material_input: FloatArray,
                    displacement: FloatArray, folds: int = FOLDS) -> 'FoldErrors':
        """
        Return the held-out errors of blocked cross-validation of this fit's rule.

        The first :data:`_CV_WINDOW` samples are cut into ``folds`` contiguous blocks; each
        is held out once: the weights are fitted on the training rows of the others (the
        rows before the plays are determined left out with ``rule='determined'``), the model
        is simulated from the record's start state (each segment from its own) and scored by
        the RMS output error on the block's rows.  The Gram matrices are accumulated once
        per block and added.
        """
        size = min(self.xs.size, _CV_WINDOW)
        fold = fold_index(size, folds)
        classes = np.full(self.xs.size, -1, dtype=np.int8)
        train = self.classes[:size] == 0
        classes[:size] = np.where(train, fold, -1)
        if rule == 'determined':
            for seg in segments:
                classes[seg.start:min(self.split(seg), size)] = -1
        parts: GramParts | None = None
        state: FloatArray | None = None
        present = [seg for seg in segments if seg.start < size]
        for seg in present:
            # The rows after the plays are determined are the same for every start state
            # and rule: accumulated once per segment.
            z0 = self._state(seg, state)
            stop = min(seg.stop, size)
            split = min(self.split(seg), stop)
            p = regressor_gram(self.xs, self.ys, self.r_h, self.r_s, state=z0,
                               classes=classes, n_classes=folds, start=seg.start, stop=split)
            if split < stop:
                key = (seg.start, stop, folds)
                if key not in self._fold_suffix:
                    self._fold_suffix[key] = regressor_gram(
                        self.xs, self.ys, self.r_h, self.r_s, state=p.end_state,
                        classes=classes, n_classes=folds, start=split, stop=stop)
                p = p + self._fold_suffix[key]
            state = p.end_state
            parts = p if parts is None else parts + p
        assert parts is not None
        windowed = [replace(seg, stop=min(seg.stop, size)) for seg in present]
        span = float(np.ptp(displacement))
        per_fold: list[float] = []
        inner_per_fold: list[float] = []
        total, count = 0.0, 0
        inner, inner_count = 0.0, 0
        for k in range(folds):
            rows = train & (fold == k)
            others = tuple(c for c in range(folds) if c != k)
            fitted = np.isin(classes[:size], others)
            if np.any(fitted):
                seen = self.xs[:size][fitted]
                inside = (self.xs[:size] >= float(np.min(seen))) & (
                    self.xs[:size] <= float(np.max(seen)))
            else:
                inside = np.zeros(size, dtype=bool)
            inner_per_fold.append(math.nan)
            if not np.any(rows):
                per_fold.append(math.nan)
                continue
            if int(sum(int(parts.counts[c]) for c in others)) == 0:
                # Nothing to fit without this fold: the rule cannot predict it.
                per_fold.append(math.inf)
                total, count = math.inf, count + int(np.count_nonzero(rows))
                continue
            try:
                w_h, w_s, constant, _ = self.solve(parts, _TRIAL_TOLERANCE, others)
            except IdentificationError:
                per_fold.append(math.inf)
                total, count = math.inf, count + int(np.count_nonzero(rows))
                continue
            fit = _finish_model(self, windowed, material_input[:size], w_h, w_s, constant)
            residual = fit.simulate() - displacement[:size]
            e = residual[rows]
            per_fold.append(float(np.sqrt(np.mean(e * e))) / span)
            total += float(np.sum(e * e))
            count += int(e.size)
            e = residual[rows & inside]
            inner += float(np.sum(e * e))
            inner_count += int(e.size)
            if e.size:
                inner_per_fold[-1] = float(np.sqrt(np.mean(e * e))) / span
        pooled = math.sqrt(total / count) / span if count else math.nan
        interior = math.sqrt(inner / inner_count) / span if inner_count else math.nan
        return FoldErrors(pooled, per_fold, rule, interior,
                          1.0 - inner_count / count if count else 0.0, inner_per_fold)

    def _refine_memory(self, chosen: list[Segment], i: int,
                       best: tuple[float, StartState | None, Any],
                       previous: FloatArray | None, memory_steps: bool) -> Segment:
        # A joint estimate of every play's start state (a history with more turning points
        # than the grid), kept when its refit beats the best history.
        seg = chosen[i]
        if self.split(seg) <= seg.start + 1 or best[2] is None:
            return seg
        u = self.xs[seg.start:seg.stop]
        error, _, weights = best
        z = self._state(seg, previous)
        rows = slice(seg.start, self.split(seg))
        # One play at a time; where that memory beats every simple history, the steps
        # between plays too (see refine_memory).
        for tails in (False, True) if memory_steps else (False,):
            if tails and not (seg.start_state is not None
                              and seg.start_state.kind == 'memory'):
                break
            for _ in range(_MEMORY_ROUNDS):       # refine with the weights, refit, again
                w_h, w_s, constant, _ = weights
                target = self.prefix_dead_zones(seg) @ w_s - constant
                refined, _ = refine_memory(self.xs[rows], self.r_h, z, w_h, target,
                                           self.classes[rows] == 0, tails=tails)
                if np.allclose(refined, z):
                    break
                memory = StartState('memory', memory=tuple(
                    (float(r), float(v - u[0])) for r, v in zip(self.r_h, refined)))
                trial_error, trial_weights = self._trial(chosen, i, memory)
                if not trial_error < error * (1.0 - 1e-6):
                    break
                # The steps may fit the generalised error of transients (ringing tails)
                # while the output gets worse: they must lower the output's error there too.
                if tails and trial_weights is not None and not (
                        self._output_error(seg, refined, trial_weights)
                        < self._output_error(seg, z, weights)):
                    break
                seg, error, weights, z = (replace(seg, start_state=memory), trial_error,
                                          trial_weights, refined)
        return seg

    def _output_error(self, seg: Segment, z0: FloatArray, weights: Any) -> float:
        # RMS error (scaled) of the model's output before the segment's plays are
        # determined (after that, the start state does not matter).
        rows_ = slice(seg.start, self.split(seg))
        train = self.classes[rows_] == 0
        if not np.any(train):
            return 0.0
        w_h, w_s, constant, _ = weights
        d = self.design
        model = d.model(w_h, w_s, constant, initial_states=z0)
        simulated = model.simulate(self.xs[rows_] * d.x_scale + d.input_offset)
        e = (d.scaled_output(simulated) - self.ys[rows_])[train]
        return float(np.sqrt(np.mean(e * e)))

    def _trial(self, chosen: list[Segment], i: int,
               cand: StartState | None) -> tuple[float, Any]:
        trial = chosen[:i] + [replace(chosen[i], start_state=cand)] + chosen[i + 1:]
        parts = self.parts(trial)
        try:
            weights = self.solve(parts, _TRIAL_TOLERANCE)
        except IdentificationError:
            return math.inf, None
        return self.error(parts, weights, 0), weights

    def _previous_state(self, chosen: list[Segment], i: int) -> FloatArray | None:
        if i == 0:
            return None
        return self.parts(chosen[:i]).end_state

    def _prefix_error(self, seg: Segment, cand: StartState | None, weights: Any,
                      previous: FloatArray | None) -> float:
        # Generalised RMS error on the training rows before the segment's plays are
        # determined, with fixed weights: what a start state changes.
        if weights is None:
            return math.inf
        return self._prefix_error_of(seg, self._state(replace(seg, start_state=cand), previous),
                                     weights)

    def _prefix_error_of(self, seg: Segment, z0: FloatArray, weights: Any) -> float:
        # The same for given start states of the plays.
        rows_ = slice(seg.start, self.split(seg))
        train = self.classes[rows_] == 0
        if not np.any(train):
            return 0.0
        plays, _ = play_operator(self.xs[rows_], self.r_h, z0)
        w_h, w_s, constant, _ = weights
        e = (plays @ w_h - self.prefix_dead_zones(seg) @ w_s + constant)[train]
        return float(np.sqrt(np.mean(e * e)))

    def prefix_dead_zones(self, seg: Segment) -> FloatArray:
        """Return S' regressors of the samples before the segment's plays are determined."""
        cached = self._dead_zones.get(seg.start)
        if cached is None:
            cached = dead_zone_operator(self.ys[seg.start:self.split(seg)], self.r_s)
            self._dead_zones[seg.start] = cached
        return cached

    def undetermined_start(self, segments: list[Segment],
                           weights: tuple[FloatArray, FloatArray, float, Any]) -> int:
        """Return a burn-in when the first segment's start is explained by no candidate."""
        seg = segments[0]
        split = self.split(seg)
        if split >= seg.stop or split < 10:
            return 0
        z0 = self._state(seg, None)
        rest = self._segment_parts(seg, z0)
        prefix = self._prefixes[(seg.start, z0.tobytes())]
        before = self.error(prefix, weights, 0)
        total = self.error(rest, weights, 0)
        if not (math.isfinite(before) and math.isfinite(total)):
            return 0
        after_sq = (total ** 2 * rest.counts[0] - before ** 2 * prefix.counts[0]) / max(
            int(rest.counts[0] - prefix.counts[0]), 1)
        after = math.sqrt(max(after_sq, 0.0))
        if before > max(_START_TOLERANCE * after, _START_FLOOR):
            return int(split)
        return 0


def _to_model_states(z: FloatArray, design: ScaledDesign, model: MPIModel) -> FloatArray:
    # Scaled play states -> the model's (SI, relative to its input offset): the plays of
    # (x - x0_design) / x_scale shifted by the constant's input shift.
    shift = design.input_offset - model.input_offset
    return np.asarray(z, dtype=np.float64) * design.x_scale + shift


def refuse_if_unmodellable(record: PreparedRecord, correlation: float) -> None:
    """
    Refuse a record the MPI model cannot represent, naming the cause found.

    Parameters
    ----------
    record : PreparedRecord
        The analysed record.
    correlation : float
        Pearson correlation of input and output (outside ringing).

    Raises
    ------
    IdentificationError
        For a butterfly loop, switching transients, an output unrelated to the input or a
        counter-movement nothing explains.

    """
    a = record.analysis
    x = record.current
    move = 100.0 * a.static_counter_move
    first, last = a.worst_sweep
    found, large = a.band_sweeps
    if a.verdict == 'butterfly':
        lo, hi = a.band if a.band is not None else (math.nan, math.nan)
        msg = (f'the output is not monotone in the input: a butterfly loop (ferroelectric'
               f' switching) or another non-monotone map; in {found} of the {large} large'
               f' sweeps of the input the output moves against it by up to {move:.3g} % of'
               f' its range, over the input band {lo:.4g} to {hi:.4g} (samples {first} to'
               f' {last}), well inside the sweep, not after the reversal; no delay or lag'
               f' shorter than {_limit(a)} explains it, and no ringing window covers it.'
               ' The MPI model (a monotone hysteresis) cannot represent it: lower the'
               ' amplitude below the coercive field, record a unipolar excitation, or check'
               ' the input and output columns/topics')
        raise IdentificationError(msg)
    if a.verdict == 'switching':
        msg = (f'the output is not monotone in the input: switching transients'
               f' (ferroelectric switching, as in a butterfly loop); while the input holds'
               f' after a step, the output moves against it by up to'
               f' {move:.3g} % of its range (samples {first} to {last}), for longer than'
               f' {_limit(a)}, without ringing; the MPI model cannot represent it: stay'
               ' below the coercive field, or leave the switching part out of the record')
        raise IdentificationError(msg)
    if abs(correlation) < _MIN_CORRELATION:
        msg = (f'the output is not monotone in the input, nor related to it as a hysteresis:'
               f' their correlation is {correlation:.2f} outside ringing windows (a'
               f' hysteresis loop gives'
               f' 0.3 or more) and the output moves against the input by up to {move:.3g} %'
               ' of its range within one sweep; check the input and output columns/topics'
               ' and that they belong to one experiment')
        raise IdentificationError(msg)
    if a.verdict == 'unexplained':
        msg = (f'the output is not monotone in the input: it moves against the input by up'
               f' to {move:.3g} % of its range within one sweep (samples {first} to {last});'
               f' neither a delay or lag'
               f' shorter than {_limit(a)} ({100 * a.explained_counter_move:.3g} % would be'
               ' left), nor ringing after a step, nor switching over a fixed input band'
               ' explains it: drift, transients or a second input dominate; the MPI model'
               ' cannot represent it; check that the record is one experiment and that'
               ' nothing else drives the output')
        raise IdentificationError(msg)
    del x


def _limit(a: DynamicsAnalysis) -> str:
    if a.unit == 's':
        return f'{1e3 * a.explain_limit:.3g} ms'
    return f'{a.explain_limit:.3g} samples'


#: Below this |correlation| between input and output (outside ringing) the output is not
#: related to the input as a hysteresis.
_MIN_CORRELATION = 0.3


def held_out_rows(size: int, holdout: float, keep: npt.NDArray[np.bool_],
                  blocks: int | None = None) -> npt.NDArray[np.bool_]:
    """
    Return held-out blocks spread evenly over a record, ringing excluded.

    Short blocks (30 of them, at least 8 samples each) keep every kind of excitation the
    record holds on both sides: a long held-out block of a short record (one reversal
    curve of a few) would hold content no training sample has.

    Parameters
    ----------
    size : int
        Samples in the record.
    holdout : float
        Fraction held out, in (0, 1).
    keep : ndarray of bool, shape (N,)
        Samples that may be fitted or scored.
    blocks : int, optional
        Blocks the record is cut into (default: 30, fewer for a record under 240 samples).

    Returns
    -------
    ndarray of bool, shape (N,)
        True on the held-out samples.

    """
    if blocks is None:
        blocks = int(min(30, max(size // 8, 3)))
    held = np.zeros(size, dtype=bool)
    edges = np.linspace(0, size, blocks + 1).astype(int)
    count = min(max(int(round(holdout * blocks)), 1), blocks - 1)
    for b in np.unique(np.round(np.linspace(1, blocks - 2, count)).astype(int)):
        held[edges[b]:edges[b + 1]] = True
    return held & keep


def estimate_dynamics(record: PreparedRecord, n: int, l: int,  # noqa: E741
                      held: npt.NDArray[np.bool_], starts: list[Segment],
                      burn_in: int = 0, *,
                      progress: Callable[[str], None] | None = None,
                      rule: str = 'joint') -> 'DynamicsEstimate':
    """
    Estimate the input's dead time and first-order lag: a grid, one QP each, held-out.

    Dead times from one sample interval and lag time constants from half a sample interval
    up to a quarter of the input's sweep time (and 200 intervals) are tried one kind at a
    time; the best of each kind is refined between its grid neighbours; each trial is
    scored by the RMS error of the model's output on the held-out blocks.  The better kind
    is modelled when it cuts the static model's held-out error by :data:`_DYNAMICS_GAIN` or
    more, also at the highest order the record supports (up to (14, 7); a delay that only
    stands in for hysteresis a low order misses loses its gain there); when the two kinds
    are within the noise of each other on the held-out blocks (a paired test,
    :func:`~mpi_ros.identification.ties.compare_on_blocks`) the record cannot tell them
    apart (one rate), and the lag is modelled (its inverse is causal).

    Parameters
    ----------
    record : PreparedRecord
        The record, with a time base.
    n, l : int
        The order of the trial fits.
    held : ndarray of bool, shape (N,)
        Held-out rows.
    starts : list of Segment
        Start states (from the static fit).
    burn_in : int
        The static fit's burn-in (every trial is scored on the same rows).
    progress : callable, optional
        Called with a line of text before each trial fit (a progress display).
    rule : {'joint', 'determined'}
        Where each trial's weights come from (the static fit's rule, see :func:`fit_record`).

    Returns
    -------
    DynamicsEstimate
        The best dead time and lag, their held-out errors, whether they tie, and what is
        modelled (nothing when the static model is as good).

    """
    t = record.time
    trials: list[dict[str, float]] = []
    blocks: dict[InputDynamics, tuple[tuple[float, ...], tuple[int, ...]]] = {}
    if t is None:
        return DynamicsEstimate()
    dt = float(np.median(np.diff(t)))
    if not dt > 0.0:
        return DynamicsEstimate()
    limit = min(max(record.analysis.explain_limit, 4.0 * dt), 200.0 * dt,
                0.05 * float(t[-1] - t[0]))

    def score(dyn: InputDynamics) -> float:
        if progress is not None:
            progress(f'dynamics: trial fit {len(trials) + 1}, '
                     f'{dyn.describe() if dyn.present else "static"}')
        try:
            fit = fit_record(record, n, l, dynamics=dyn, held=held, starts=starts,
                             choose=False, burn_in=burn_in, rule=rule)
        except (IdentificationError, DataError):
            return math.inf
        residual = (fit.simulate() - record.displacement) / np.ptp(record.displacement)
        blocks[dyn] = block_errors(residual, held)
        error = _held_output_error(fit, record.displacement, held)
        trials.append({'dead_time': dyn.dead_time, 'lag_time_constant': dyn.lag_time_constant,
                       'held_error': error})
        return error

    delays = np.unique(np.round(np.geomspace(1.0, max(limit / dt, 1.0), 8))) * dt
    lags = np.geomspace(0.5 * dt, max(limit, dt), 8)
    static_error = score(InputDynamics())
    if not (math.isfinite(static_error) and static_error > 0.0):
        return DynamicsEstimate(static_error=static_error, trials=trials)
    best: dict[str, tuple[float, float]] = {}
    for kind, grid in (('dead_time', delays), ('lag_time_constant', lags)):
        # The best of each kind, refined between its grid neighbours (a lag and a dead time
        # look alike at one frequency, not over several: both are reported).
        errors = [score(InputDynamics(**{kind: float(v)})) for v in grid.tolist()]
        i = int(np.argmin(errors))
        error, dyn = _refine(score, (errors[i], InputDynamics(**{kind: float(grid[i])})), dt)
        best[kind] = (error, float(getattr(dyn, kind)))
    dead, lag = best['dead_time'], best['lag_time_constant']
    none: tuple[tuple[float, ...], tuple[int, ...]] = ((), ())
    sizes = blocks.get(InputDynamics(), none)[1]
    per_block = {kind: blocks.get(InputDynamics(**{kind: value}), none)[0]
                 for kind, value in (('dead_time', dead[1]), ('lag_time_constant', lag[1]))}
    static_blocks = blocks.get(InputDynamics(), none)[0]
    # Which kinds beat the static model beyond the noise of the blocks; a tie is two that do
    # and are within the noise of each other (the rule of the dynamics finding).
    beats = {kind: compare_on_blocks(per_block[kind], static_blocks, sizes).first_better
             for kind in per_block}
    tie = (beats['dead_time'] and beats['lag_time_constant'] and compare_on_blocks(
        per_block['dead_time'], per_block['lag_time_constant'], sizes).tie)
    # A tie models the lag: its inverse (a lead) is causal, a dead time's is not.
    kind = ('lag_time_constant' if tie else
            'dead_time' if beats['dead_time'] and not beats['lag_time_constant'] else
            'lag_time_constant' if beats['lag_time_constant'] and not beats['dead_time'] else
            'lag_time_constant' if lag[0] < dead[0] else 'dead_time')
    chosen = best[kind]
    modelled = (InputDynamics(**{kind: chosen[1]})
                if chosen[0] <= (1.0 - _DYNAMICS_GAIN) * static_error else InputDynamics())
    if modelled.present and not _persists(record, modelled, held):
        modelled = InputDynamics()
    return DynamicsEstimate(modelled, dead_time=dead[1], lag_time_constant=lag[1],
                            static_error=static_error, dead_time_error=dead[0],
                            lag_error=lag[0], tie=tie, trials=trials, block_sizes=sizes,
                            static_blocks=static_blocks,
                            dead_time_blocks=per_block['dead_time'],
                            lag_blocks=per_block['lag_time_constant'])


def _persists(record: PreparedRecord, dynamics: InputDynamics,
              held: npt.NDArray[np.bool_]) -> bool:
    # The gain must persist at the highest order the record supports (up to (14, 7)): a
    # delay or lag that only stands in for hysteresis a lower order misses (one excitation
    # rate cannot tell them apart) loses its gain there; real dynamics keep it.
    size = int(np.count_nonzero(record.keep & ~held))
    orders = [order for order in ((14, 7), (12, 6), (10, 5))
              if size >= 10 * (order[0] + 2 * order[1] + 2)]
    if not orders:
        return True
    n, l = orders[0]  # noqa: E741
    try:
        static = fit_record(record, n, l, held=held)
        dynamic = fit_record(record, n, l, dynamics=dynamics, held=held,
                             starts=static.segments, choose=False, burn_in=static.burn_in)
    except (IdentificationError, DataError):
        return False
    before = _held_output_error(static, record.displacement, held)
    after = _held_output_error(dynamic, record.displacement, held)
    return bool(after <= (1.0 - _DYNAMICS_GAIN) * before)


def _held_output_error(fit: RecordFit, displacement: FloatArray,
                       held: npt.NDArray[np.bool_]) -> float:
    # RMS error of the model's output on the held-out rows, over the output's range.
    if not np.any(held):
        return math.nan
    error = (fit.simulate() - displacement)[held]
    return float(np.sqrt(np.mean(error * error)) / np.ptp(displacement))


def _refine(score: Any, best: tuple[float, InputDynamics],
            dt: float) -> tuple[float, InputDynamics]:
    # A bounded search on the better kind, in log scale, between the grid's neighbours
    # (a factor 1.6 either side).
    from scipy.optimize import minimize_scalar
    error, dyn = best
    if not dyn.present:
        return best
    kind = 'dead_time' if dyn.dead_time > 0.0 else 'lag_time_constant'
    value = getattr(dyn, kind)

    def make(v: float) -> InputDynamics:
        return replace(dyn, **{kind: float(v)})

    res = minimize_scalar(lambda lv: score(make(math.exp(lv))),
                          bounds=(math.log(value / 1.6), math.log(value * 1.6)),
                          method='bounded', options={'maxiter': 8, 'xatol': 0.02})
    if float(res.fun) < error:
        error, dyn = float(res.fun), make(math.exp(float(res.x)))
    return error, dyn
