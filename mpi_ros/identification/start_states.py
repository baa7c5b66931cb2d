# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Start states of a record: how the actuator came to its first sample.

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
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from .qp import burn_in, FloatArray
from ..operators.play import play_end_state, play_operator

__all__ = ['START_KINDS', 'StartState', 'determined_from', 'end_state', 'estimate_start_state',
           'refine_memory', 'start_candidates', 'turning_point_candidates', 'with_initial_states']


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
                         offset_free: bool = False,
                         through: int | None = None) -> tuple[Any, StartState, int]:
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
    through : int, optional
        Judge the candidates on the samples before this one (default: before the plays are
        determined; a model whose memory outlasts the plays', such as creep's slow lags of
        Gamma's output, needs more).

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
    part = slice(0, max(split if through is None else int(through), 2))
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
