# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Identification of the MPI operator from measured data, section 4.2 of Kuhnen's paper.

Three parts, as in the paper:

1. Thresholds and initial states from the data: ``r_Hi = i/(n+1) ||x||_inf``
   (28), ``r'_S0 = 0`` (29), ``r'_Si = (i - 1/2)/l max y`` (30),
   ``r'_S-i = (i - 1/2)/l min y`` (31; the printed sign is a slip), ``z_H0 = 0`` (32).
2. The weights ``w_H`` of H and ``w'_S`` of the inverse superposition operator
   S' minimise the L2 norm of the generalised error
   ``E = w_H^T H_rH[x] - w'_S^T S_r'S[y]`` (33)-(34), subject to the
   invertibility constraints (35) and the equality constraint (36); a convex
   QP solved with OSQP.
3. ``S`` follows from ``S'`` by the laws (22)-(25).

Real records (documented in docs/design.md, "Identification on real records"):

- **Operating point.** The paper's data start at the origin (demagnetised actuator,
  displacement 0 at zero current).  A rig's data do not: the sensor has an arbitrary
  zero, the drive a bias, some sensors fall as the actuator extends, and a record starts
  mid-history.  By default (``anchor='operating_point'``) the input is centred on the
  middle of its range ``x0`` and scaled by half its range, so (28) places the play
  thresholds over the loops the data actually contain; the output is centred on the
  middle of its range, multiplied by the sign detected from the data (slope of the
  straight-line fit), and (29)-(31) place S' thresholds on both sides.  A constant term
  ``c`` in the generalised error, ``E = w_H^T H[x - x0] - w'_S^T S'[v] + c``, keeps the
  QP convex (it is eliminated exactly: the columns' covariance replaces their Gram
  matrix, and ``c = -mean(columns) . w``); since ``H[u] + c = H[u + c / sum w_H]``
  once the plays' states are set by the data, it is an exact shift of the input offset.
  The result is invariant to a constant added to the displacement or the current and
  to the output's sign.
  ``anchor='origin'`` is the paper's design as printed (for data that start at rest at
  the origin).
- **Unknown start state.** The plays start at the centre (``z = 0``), which is almost
  never the true state of a record that starts mid-history.  By the wiping-out property a
  play with threshold ``r`` forgets its initial state once the input has swept over a
  range of ``2 r``, and so does the actuator (any hysteresis with that property) once
  the input has visited both extremes of the record; the generalised error is
  therefore minimised only over the samples after the input first covered its range
  (99 %): the fit uses only what the data determine, not the initial loading curve.
  The returned model's initial states are the plays at rest at the record's lowest
  input (where an actuator rests when it is off; the paper's ``z_H0 = 0`` at ``x = 0``
  for data that start there): a compensator starts from that state.
- **Refusals.** A record whose output is not monotone in the input (correlation below
  0.3, or, anywhere in the record, burn-in included, a move against the input within one
  sweep of more than 15 % of the output range beyond the noise: butterfly loops), too
  little excitation for the order, or a fit no better than a straight line on the same
  samples or absurd is refused with :class:`IdentificationError`.
- The data are scaled internally; all thresholds follow the data, so results do not
  depend on units.
- A branch of S' the output never reaches (the output stays on one side of
  0 except for less than 1 % of its range) gets no thresholds: its weights
  would be undetermined by the data.
- A tiny ridge (1e-9 of the mean diagonal) makes the QP strictly convex,
  so the solution is unique even when plays are collinear on the data.
- The solver status is always checked and the constraints re-checked on the
  result: a failure raises :class:`IdentificationError`, never a silently
  non-invertible model.
"""

from dataclasses import dataclass, field
import math
import time
from typing import Any, Callable

import numba
import numpy as np
import numpy.typing as npt
import osqp
import scipy.sparse as sp

from .deadzone import dead_zone_operator
from .errors import DataError, IdentificationError
from .hysteresis import PIHysteresisOperator
from .inverse import invert_superposition
from .model import MPIModel
from .play import play_operator
from .superposition import PISuperpositionOperator

__all__ = [
    'IdentificationResult', 'identify', 'select_order', 'hysteresis_thresholds',
    'inverse_superposition_thresholds', 'fit_generalized_error', 'generalized_error_gram',
    'DEFAULT_ORDERS', 'ScaledDesign', 'scaled_design', 'identify_weights', 'fit_model',
    'output_sign', 'burn_in', 'ANCHORS',
]

FloatArray = npt.NDArray[np.float64]

#: Orders tried by the automatic order selection: l = n/2 as in the paper's table.
DEFAULT_ORDERS: tuple[tuple[int, int], ...] = tuple((2 * k, k) for k in range(11))

#: A branch of S' whose extent is below this fraction of the output range gets no thresholds.
_BRANCH_FRACTION = 0.01

#: Where the thresholds are anchored: the data's operating point (default) or the origin.
ANCHORS = ('operating_point', 'origin')

#: Below this |correlation| between input and output the output is not monotone in the
#: input (e.g. a ferroelectric butterfly loop, a wrong column): refused.
_MIN_CORRELATION = 0.3

#: Largest excursion of the output against the input's direction within one monotone
#: sweep of the input (beyond 4 noise standard deviations), as a fraction of the output
#: range.  Hysteresis loops (also with creep, dead time, rate dependence) stay below 0.1;
#: butterfly loops (ferroelectric switching) reach 0.2-0.9.
_MAX_COUNTER_MOVE = 0.15

#: A turning point of the input: it retreats by this fraction of its range.
_TURN_FRACTION = 0.05

#: A play whose standard deviation after the burn-in is below this fraction of the first
#: play's is idle: its weight is fixed at 0.
_IDLE_PLAY = 0.05

#: The burn-in lasts until the input covered this fraction of its range (2 = full range).
_FULL_SWEEP = 2.0 * 0.99

#: After the burn-in the input must rise and fall over this fraction of its range.
_MIN_LOOP_SWEEP = 0.25

#: At least this fraction of the record must remain after the burn-in.
_MIN_DETERMINED_FRACTION = 0.2


@dataclass(frozen=True)
class IdentificationResult:
    """
    Outcome of :func:`identify`.

    Attributes
    ----------
    model : MPIModel
        The identified forward model Gamma (SI units).
    order : tuple of int
        ``(n, l)``.
    nonlinearity_error : float
        (37) of the model's simulation on the identification data, with the output's
        range in place of ``max|Gamma[x]|`` (the two agree when the output starts at 0,
        as in the paper; the range does not depend on the sensor's zero) [fraction].
    rms_error : float
        RMS error of the simulation on the identification data over the output's range.
    samples : int
        Number of samples in the record.
    solver_status : str
        OSQP's status text (always ``'solved'`` for a returned result).
    iterations : int
        OSQP iterations.
    solve_time : float
        Wall time of the whole identification [s].
    order_table : list of dict
        Rows ``{'n', 'l', 'nonlinearity_error', 'rms_error'}`` (held-out data)
        of the order selection; empty when the order was given.
    linear_rms_error : float
        RMS error of the best straight line ``y = a x + b`` on the same samples, over the
        output's range: the baseline every fit is checked against.
    burn_in : int
        Samples at the start left out of the fit and the errors (the plays' states are
        not determined by the data before; see the module notes).

    """

    model: MPIModel
    order: tuple[int, int]
    nonlinearity_error: float
    rms_error: float
    samples: int
    solver_status: str
    iterations: int
    solve_time: float
    order_table: list[dict[str, Any]] = field(default_factory=list)
    linear_rms_error: float = math.nan
    burn_in: int = 0

    def summary(self) -> dict[str, Any]:
        """Return the result as a JSON-ready dict: ``order``, errors, ``samples``, table."""
        m = self.model
        return {'order': list(self.order), 'nonlinearity_error': self.nonlinearity_error,
                'rms_error': self.rms_error, 'linear_rms_error': self.linear_rms_error,
                'samples': self.samples, 'burn_in': self.burn_in,
                'operating_point': {'input_offset': m.input_offset,
                                    'output_offset': m.output_offset,
                                    'output_sign': m.output_sign},
                'solver_status': self.solver_status, 'iterations': self.iterations,
                'solve_time': self.solve_time, 'order_table': self.order_table}


def hysteresis_thresholds(current_abs_max: float, n: int) -> FloatArray:
    """
    Play thresholds (28): ``r_Hi = i/(n+1) ||x||_inf``, ``i = 0..n``.

    Parameters
    ----------
    current_abs_max : float
        ``||x||_inf`` of the input [A].
    n : int
        Order of H.

    Returns
    -------
    ndarray of float, shape (n+1,)
        Thresholds [A].

    """
    return np.arange(n + 1, dtype=np.float64) / (n + 1) * current_abs_max


def inverse_superposition_thresholds(output_max: float, output_min: float, l: int  # noqa: E741
                                     ) -> FloatArray:
    """
    Thresholds of the inverse superposition operator S', (29)-(31).

    A branch whose side of 0 the output does not reach (``output_max <= 0`` or
    ``output_min >= 0``) gets no thresholds.

    Parameters
    ----------
    output_max, output_min : float
        ``max y`` and ``min y`` of the output [m].
    l : int
        Order of S.

    Returns
    -------
    ndarray of float, shape (<= 2l+1,)
        Ascending thresholds [m] containing exactly one 0.

    """
    i = np.arange(1, l + 1, dtype=np.float64)
    positive = (i - 0.5) / l * output_max if output_max > 0.0 and l > 0 else np.empty(0)  # (30)
    # (31) as printed, ((i + 1/2)/l) min y for i = -l..-1, is positive for min y < 0; the
    # evident intent, the mirror image of (30), is (|i| - 1/2)/l min y, which is used here.
    negative = (i - 0.5) / l * output_min if output_min < 0.0 and l > 0 else np.empty(0)
    return np.concatenate([np.sort(negative),
                           [0.0], positive])                                              # (29)


def _check_signals(current: npt.ArrayLike, displacement: npt.ArrayLike) -> tuple[
        FloatArray, FloatArray]:
    x = np.asarray(current, dtype=np.float64).reshape(-1)
    y = np.asarray(displacement, dtype=np.float64).reshape(-1)
    if x.size != y.size:
        msg = (f'current and displacement must have the same length; found {x.size} and'
               f' {y.size} samples')
        raise DataError(msg)
    for name, arr in (('current', x), ('displacement', y)):
        bad = np.flatnonzero(~np.isfinite(arr))
        if bad.size:
            msg = (f'{name} contains {bad.size} non-finite value(s), the first at sample'
                   f' {bad[0]}; remove or interpolate them before identifying')
            raise DataError(msg)
    return x, y


def _check_monotone(x: FloatArray, y: FloatArray) -> None:
    if np.ptp(x) <= 1e-9 * np.max(np.abs(x)) or not np.ptp(y) > 0.0:
        return                                   # _check_excitation says what is wrong
    sign, correlation = output_sign(x, y)
    if abs(correlation) < _MIN_CORRELATION:
        msg = (f'the output is not monotone in the input (correlation {correlation:.2f}):'
               ' the MPI model needs a displacement that rises (or falls) with the input'
               ' around hysteresis loops; check the input and output columns/topics, or,'
               ' for a butterfly loop (ferroelectric switching), lower the amplitude below'
               ' the coercive field')
        raise IdentificationError(msg)
    # The whole record, burn-in included: a butterfly whose determined part happens to be
    # monotone must not pass.  Noise (robust estimate from second differences) is allowed.
    span = float(np.ptp(y))
    move, first, last = _counter_move(x, sign * y, _TURN_FRACTION * float(np.ptp(x)))
    excess = (move - 4.0 * _noise_std(y)) / span
    if excess > _MAX_COUNTER_MOVE:
        msg = (f'the output is not monotone in the input: within one sweep of the input'
               f' (samples {first} to {last}) it moves against the input by'
               f' {100 * move / span:.3g} % of its range (a hysteresis loop: at most'
               f' {100 * _MAX_COUNTER_MOVE:.3g} % beyond the noise);'
               ' this is a butterfly loop (ferroelectric switching: lower the amplitude below'
               ' the coercive field) or a record dominated by drift or switching transients;'
               ' the MPI model cannot represent it')
        raise IdentificationError(msg)


def _noise_std(y: FloatArray) -> float:
    # Robust noise estimate: MAD of the second differences (std of white noise * sqrt 6).
    if y.size < 3:
        return 0.0
    d2 = np.diff(y, 2)
    return 1.4826 * float(np.median(np.abs(d2 - np.median(d2)))) / math.sqrt(6.0)


@numba.njit(cache=True, nogil=True)
def _counter_move(x: FloatArray, v: FloatArray,
                  tolerance: float) -> tuple[float, int, int]:  # pragma: no cover - compiled
    # Largest fall of v from its running maximum within one monotone sweep of x (v is the
    # output times its sign, so it should rise with x); the sweep's direction flips v.
    # A turning point is the extreme of x before x retreats from it by `tolerance`.
    n = x.shape[0]
    turns = np.empty(n + 1, dtype=np.int64)
    count = 1
    turns[0] = 0
    direction = 0
    extreme = 0
    for k in range(1, n):
        if direction == 0:
            if abs(x[k] - x[0]) > tolerance:
                direction = 1 if x[k] > x[0] else -1
                extreme = k
            continue
        if direction * (x[k] - x[extreme]) > 0.0:
            extreme = k
        elif direction * (x[extreme] - x[k]) > tolerance:
            turns[count] = extreme
            count += 1
            direction = -direction
            extreme = k
    turns[count] = n - 1
    count += 1
    worst = 0.0
    first = 0
    last = 0
    for b in range(count - 1):
        a, e = turns[b], turns[b + 1]
        s = 1.0 if x[e] >= x[a] else -1.0
        peak = s * v[a]
        for k in range(a, e + 1):
            value = s * v[k]
            if value > peak:
                peak = value
            elif peak - value > worst:
                worst = peak - value
                first = a
                last = e
    return worst, first, last


def _check_excitation(x: FloatArray, y: FloatArray, n: int, l: int, *,  # noqa: E741
                      anchor: str = 'operating_point') -> None:
    needed = 2 * (n + 1 + 2 * l + 1)
    if x.size < needed:
        msg = (f'too few samples to identify order n={n}, l={l}: found {x.size}, need at'
               f' least {needed}; record longer or lower the order')
        raise IdentificationError(msg)
    if not np.max(np.abs(x)) > 0.0:
        msg = 'the current is zero everywhere: nothing to identify; record an excitation'
        raise IdentificationError(msg)
    if not np.max(np.abs(y)) > 0.0:
        msg = 'the displacement is zero everywhere: check the output topic or column'
        raise IdentificationError(msg)
    if np.ptp(x) <= 1e-9 * np.max(np.abs(x)):
        msg = ('the current is constant: a hysteresis model needs an excitation that moves'
               ' the input up and down over the operating range')
        raise IdentificationError(msg)
    if not np.ptp(y) > 0.0:
        msg = ('the displacement is constant: check the output topic or column and that the'
               ' actuator moved')
        raise IdentificationError(msg)
    if n > 0:
        # A play with threshold r only leaves its initial loading curve after an input
        # reversal larger than 2 r: without one, H degenerates to a static map and the
        # weights are not identifiable.
        scale = float(np.max(np.abs(x))) if anchor == 'origin' else 0.5 * float(np.ptp(x))
        r_1 = scale / (n + 1)                                                     # (28)
        largest = _largest_reversal(x)
        if largest <= 2.0 * r_1:
            found = 'never reverses' if largest == 0.0 else (
                f'reverses by at most {largest:.4g}')
            msg = (f'too little excitation to identify order n={n}: the current {found}, but'
                   f' the smallest play threshold r_H1 = {r_1:.4g} needs reversals larger than'
                   f' {2 * r_1:.4g}; record an excitation with larger up-and-down sweeps'
                   ' (minor loops), or lower n')
            raise IdentificationError(msg)
    if anchor == 'operating_point':
        start = burn_in(x, max(2.0 * n / (n + 1), _FULL_SWEEP) * 0.5 * float(np.ptp(x)),
                        to_turning_point=True)
        if start > x.size * (1.0 - _MIN_DETERMINED_FRACTION):
            msg = (f'the input covers its full range only at sample {start} of {x.size}:'
                   ' before that the states of the plays and of the actuator are unknown'
                   ' (the record starts mid-history or on an initial loading curve),'
                   ' leaving too little data to fit; record more cycles over the full'
                   ' range')
            raise IdentificationError(msg)
        rise, fall = _largest_sweeps(x[start:])
        span = float(np.ptp(x))
        if min(rise, fall) < _MIN_LOOP_SWEEP * span:
            msg = (f'after the burn-in (samples {start} to {x.size}, where the states of the'
                   ' plays and of the actuator are known) the input sweeps at most'
                   f' {100 * rise / span:.3g} % of its range upwards and'
                   f' {100 * fall / span:.3g} % downwards: the loops (both branches) are not'
                   ' determined and a model fitted there is arbitrary elsewhere; record'
                   ' at least two full cycles over the range (a single cycle from an'
                   ' unknown state is not enough)')
            raise IdentificationError(msg)


def _largest_sweeps(x: FloatArray) -> tuple[float, float]:
    # Largest monotone rise and fall between successive turning points of x.
    step = np.diff(x)
    step = step[step != 0.0]
    if step.size == 0:
        return 0.0, 0.0
    turns = np.flatnonzero(np.sign(step[1:]) != np.sign(step[:-1])) + 1
    ends = np.concatenate([[0], turns, [step.size]])
    levels = np.concatenate([[0.0], np.cumsum(step)])[ends]
    moves = np.diff(levels)
    return float(max(np.max(moves), 0.0)), float(max(-np.min(moves), 0.0))


def _largest_reversal(x: FloatArray) -> float:
    # Largest monotone excursion that follows a change of direction (turning point).
    step = np.diff(x)
    step = step[step != 0.0]
    if step.size < 2:
        return 0.0
    turns = np.flatnonzero(np.sign(step[1:]) != np.sign(step[:-1])) + 1
    if turns.size == 0:
        return 0.0
    levels = np.concatenate([[0.0], np.cumsum(step)])[np.concatenate([turns, [step.size]])]
    return float(np.max(np.abs(np.diff(levels))))


def generalized_error_gram(*blocks: FloatArray) -> FloatArray:
    """
    Return the normalised Gram matrix ``Phi^T Phi / N`` of column blocks ``Phi = [B1, B2, ...]``.

    Parameters
    ----------
    *blocks : ndarray of float, shape (N, k_i)
        Regressor blocks with a common number of rows.

    Returns
    -------
    ndarray of float, shape (sum k_i, sum k_i)
        The matrix of the quadratic form (34).

    """
    phi = np.hstack(blocks)
    quadratic: FloatArray = (phi.T @ phi) / phi.shape[0]
    return quadratic


def fit_generalized_error(gram: FloatArray, equality_row: FloatArray, *,
                          n_hysteresis: int, n_superposition: int,
                          superposition_center: int, epsilon: float = 1e-6,
                          extra_lower: FloatArray | None = None,
                          fixed_zero: npt.ArrayLike | None = None) -> tuple[
                              FloatArray, FloatArray, FloatArray, Any]:
    """
    Solve the QP (34)-(36) for the weights ``w_H``, ``w'_S`` (and optional extras).

    Minimises ``v^T G v`` with ``v = [w_H; w'_S; w_X]`` and ``G`` the Gram matrix
    of ``[H_rH[x], -S_r'S[y], X]`` (see :func:`generalized_error_gram`), where X
    holds optional extra regressors that enter the generalised error like H's
    plays (e.g. creep operators), subject to (8) on ``w_H``, (19) on ``w'_S``,
    ``w_X >= extra_lower`` and the equality (36) ``equality_row . w_H = 1``.

    Parameters
    ----------
    gram : ndarray of float, shape (nv, nv)
        Gram matrix of the regressors, in the order H, S', extras.
    equality_row : ndarray of float, shape (n+1,)
        Coefficients of (36), normalised so the right-hand side is 1.
    n_hysteresis : int
        Number of plays (n+1); the first is the identity (r_H0 = 0).
    n_superposition : int
        Number of dead-zone operators of S'.
    superposition_center : int
        Index (within S') of the zero threshold.
    epsilon : float
        The positive bound of (8) and (19) (scaled units).
    extra_lower : ndarray of float, shape (k,), optional
        Lower bounds of the extra weights (default 0).
    fixed_zero : array_like of int, optional
        Indices of plays (other than the first) whose weight is fixed at 0.

    Returns
    -------
    w_h, w_s_inv, w_extra : ndarray of float
        The weights (after a check of every constraint).
    info : object
        OSQP's info structure.

    Raises
    ------
    IdentificationError
        When OSQP does not report ``solved`` or the result violates a constraint.

    """
    n1, m = n_hysteresis, n_superposition
    nv = gram.shape[0]
    k = nv - n1 - m
    gram = np.array(gram, dtype=np.float64)
    ridge = 1e-9 * max(float(np.mean(np.diag(gram))), 1e-300)
    gram[np.diag_indices(nv)] += ridge
    hysteresis_center = 0
    # Constraint rows: (36), then (8) on w_H, then (19) on w'_S, then bounds on extras.
    rows = [np.concatenate([equality_row, np.zeros(m + k)])]
    lower = [1.0]
    upper = [1.0]
    zero = set() if fixed_zero is None else {int(i) for i in np.ravel(fixed_zero)} - {0}
    for i in range(n1):                                    # (8): U_H w_H <= u_H
        row = np.zeros(nv)
        row[i] = 1.0
        rows.append(row)
        lower.append(epsilon if i == hysteresis_center else 0.0)
        upper.append(0.0 if i in zero else np.inf)
    c = superposition_center
    for i in range(m):                                     # (19): slopes outward from 0
        row = np.zeros(nv)
        if i >= c:
            row[n1 + c:n1 + i + 1] = 1.0
        else:
            row[n1 + i:n1 + c + 1] = 1.0
        rows.append(row)
        lower.append(epsilon)
        upper.append(np.inf)
    x_lower = np.zeros(k) if extra_lower is None else np.asarray(extra_lower, dtype=float)
    for i in range(k):
        row = np.zeros(nv)
        row[n1 + m + i] = 1.0
        rows.append(row)
        lower.append(float(x_lower[i]))
        upper.append(np.inf)
    a_mat = sp.csc_matrix(np.array(rows))
    lo = np.array(lower)
    hi = np.array(upper)
    solver = osqp.OSQP()
    solver.setup(P=sp.csc_matrix(np.triu(gram)), q=np.zeros(nv), A=a_mat, l=lo, u=hi,
                 verbose=False, eps_abs=1e-9, eps_rel=1e-9, max_iter=200000,
                 polishing=True, polish_refine_iter=10)
    res = solver.solve(raise_error=False)
    # 'solved inaccurate' and 'maximum iterations reached' (tolerances of 1e-9 not met,
    # typical when the data determine some weights only weakly, e.g. no hysteresis) are
    # accepted when the result is finite and feasible: the constraints are re-checked and
    # projected below, and identify() judges the fit by its output error against a
    # straight line.  Infeasible or diverged solves are refused.
    if res.info.status_val not in (osqp.SolverStatus.OSQP_SOLVED,
                                   osqp.SolverStatus.OSQP_SOLVED_INACCURATE,
                                   osqp.SolverStatus.OSQP_MAX_ITER_REACHED):
        msg = (f'the identification QP was not solved (OSQP status: {res.info.status!r},'
               f' {res.info.iter} iterations); check that the data excite the actuator over'
               ' its range, or lower the model order')
        raise IdentificationError(msg)
    v = np.array(res.x, dtype=np.float64)
    if not np.all(np.isfinite(v)):
        msg = 'the identification QP returned non-finite weights; check the data for outliers'
        raise IdentificationError(msg)
    resid = a_mat @ v
    violation = float(np.max(np.maximum(lo - resid, 0.0)[1:]))
    violation = max(violation, abs(float(resid[0]) - 1.0))
    if violation > 1e-6:
        msg = (f'the identification QP result violates the invertibility constraints by'
               f' {violation:.3g} (OSQP status {res.info.status!r}); the data may be'
               ' degenerate')
        raise IdentificationError(msg)
    # Project the solver's round-off onto the constraint set so (8)/(19) hold exactly.
    w_h = v[:n1].copy()
    w_h[hysteresis_center] = max(w_h[hysteresis_center], epsilon)
    w_h[1:] = np.maximum(w_h[1:], 0.0)
    w_h[sorted(zero)] = 0.0
    w_s = v[n1:n1 + m].copy()
    slopes = np.empty(m)
    slopes[c:] = np.maximum(np.cumsum(w_s[c:]), epsilon)
    slopes[:c + 1] = np.maximum(np.cumsum(w_s[:c + 1][::-1])[::-1], epsilon)
    w_s[c] = slopes[c]
    w_s[c + 1:] = np.diff(slopes[c:])
    w_s[:c] = -np.diff(slopes[:c + 1])
    w_x = np.maximum(v[n1 + m:], x_lower) if k else v[n1 + m:]
    return w_h, w_s, w_x, res.info


@dataclass(frozen=True)
class ScaledDesign:
    """
    Operating point, scaling and thresholds of the QP (34)-(36) for one record and order.

    The QP sees the scaled input ``u = (x - input_offset) / x_scale`` and the scaled
    output ``v = sign * (y - output_offset) / y_scale`` (see :func:`scaled_design`).

    Attributes
    ----------
    x_scale : float
        Input scale [A].
    y_scale : float
        Output scale [m].
    hysteresis_thresholds : ndarray of float, shape (n+1,)
        ``r_H`` (28) in scaled units.
    inverse_superposition_thresholds : ndarray of float, shape (m,)
        ``r'_S`` (29)-(31) in scaled units.
    center : int
        Index of the zero threshold in ``inverse_superposition_thresholds``.
    input_offset : float
        ``x0`` [A] the input is centred on (0 for ``anchor='origin'``).
    output_offset : float
        ``y0`` [m] the output is centred on (0 for ``anchor='origin'``).
    sign : int
        +1, or -1 when the output falls as the input rises.
    burn_in : int
        Samples at the start left out of the generalised error (states not determined).
    constant : bool
        True when the generalised error has the constant term (``anchor='operating_point'``).
    input_rest : float or None
        The input [A] at which the returned model's plays start at rest (its initial
        states): the lowest input of the record, where an actuator rests when it is off;
        None: ``z_H0 = 0`` (32).

    """

    x_scale: float
    y_scale: float
    hysteresis_thresholds: FloatArray
    inverse_superposition_thresholds: FloatArray
    center: int
    input_offset: float = 0.0
    output_offset: float = 0.0
    sign: int = 1
    burn_in: int = 0
    constant: bool = False
    input_rest: float | None = None

    def scaled_input(self, x: FloatArray) -> FloatArray:
        """Return ``(x - x0) / x_scale``, the input the QP sees."""
        return (np.asarray(x, dtype=np.float64) - self.input_offset) / self.x_scale

    def scaled_output(self, y: FloatArray) -> FloatArray:
        """Return ``sign * (y - y0) / y_scale``, the output the QP sees."""
        return self.sign * (np.asarray(y, dtype=np.float64) - self.output_offset) / self.y_scale

    def model(self, w_h: FloatArray, w_s_inv: FloatArray, constant: float = 0.0, *,
              shift_weight: float = 0.0) -> MPIModel:
        """
        Return the forward MPI model in SI units for QP weights found on the scaled data.

        Parameters
        ----------
        w_h : ndarray of float, shape (n+1,)
            Weights of H (dimensionless, unchanged by the scaling).
        w_s_inv : ndarray of float, shape (m,)
            Weights of S' in scaled units.
        constant : float
            The constant term ``c`` of the generalised error (scaled units); it becomes
            the input offset ``x0 - c x_scale / (sum w_H + shift_weight)``.
        shift_weight : float
            Sum of the weights of extra regressors that shift with the input like the
            plays (e.g. creep lags); 0 for none.

        Returns
        -------
        MPIModel
            Gamma with S from S' by (22)-(25), ``z_H0 = 0`` (32) and the operating point.

        """
        r_h = self.hysteresis_thresholds
        # Back to SI: H maps A -> A (w_H dimensionless); S' maps m -> A.
        hysteresis = PIHysteresisOperator(r_h * self.x_scale, w_h, np.zeros(r_h.size))
        s_inv = PISuperpositionOperator(self.inverse_superposition_thresholds * self.y_scale,
                                        w_s_inv * (self.x_scale / self.y_scale))
        # H[u] + c = H[u + c / W] once the states are set by the data (wiping-out).
        x0 = self.input_offset - constant * self.x_scale / (float(np.sum(w_h)) + shift_weight)
        if self.input_rest is not None:
            # Every play at rest at the lowest input: the actuator's state when it has been
            # off (the paper's z_H0 = 0 at x = 0 for data that start there).
            hysteresis = PIHysteresisOperator(hysteresis.thresholds, w_h,
                                              np.full(r_h.size, self.input_rest - x0))
        return MPIModel(hysteresis, invert_superposition(s_inv),                # (22)-(25)
                        input_offset=x0, output_offset=self.output_offset,
                        output_sign=self.sign)


def output_sign(current: npt.ArrayLike, displacement: npt.ArrayLike) -> tuple[int, float]:
    """
    Detect whether the output rises or falls with the input, and how monotone it is.

    Parameters
    ----------
    current : array_like of float, shape (N,)
        Input [A].
    displacement : array_like of float, shape (N,)
        Output [m].

    Returns
    -------
    sign : int
        +1 when the straight-line fit rises, -1 when it falls.
    correlation : float
        Pearson correlation of input and output (|correlation| near 1: monotone with
        narrow loops; near 0: not monotone, e.g. a butterfly loop).

    """
    x = np.asarray(current, dtype=np.float64)
    y = np.asarray(displacement, dtype=np.float64)
    xc, yc = x - np.mean(x), y - np.mean(y)
    denominator = math.sqrt(float(np.dot(xc, xc)) * float(np.dot(yc, yc)))
    correlation = float(np.dot(xc, yc)) / denominator if denominator > 0.0 else 0.0
    return (1 if correlation >= 0.0 else -1), correlation


def burn_in(x: npt.ArrayLike, sweep: float, *, to_turning_point: bool = False) -> int:
    """
    Return the first sample after which the input has covered a range of ``sweep``.

    By the wiping-out property a play with threshold ``r`` no longer depends on its
    initial state once the input has covered a range of ``2 r``.

    Parameters
    ----------
    x : array_like of float, shape (N,)
        Input.
    sweep : float
        Range to cover (``2 r``), unit of the input.
    to_turning_point : bool
        Go on to the input's next turning point (where it has retreated by 1 % of its
        range from its running extreme): the extreme itself, not a sample just below it.

    Returns
    -------
    int
        Index of the first sample whose play outputs are determined; ``N`` when never.

    """
    arr = np.asarray(x, dtype=np.float64)
    if sweep <= 0.0 or arr.size == 0:
        return 0
    covered = np.maximum.accumulate(arr) - np.minimum.accumulate(arr)
    hits = np.flatnonzero(covered >= sweep * (1.0 - 1e-12))
    if not hits.size:
        return int(arr.size)
    start = int(hits[0])
    if not to_turning_point:
        return start
    rising = arr[start] - np.min(arr[:start + 1]) >= np.max(arr[:start + 1]) - arr[start]
    tail = arr[start:] if rising else -arr[start:]
    peak = np.maximum.accumulate(tail)
    retreat = np.flatnonzero(peak - tail >= 0.01 * float(np.ptp(arr)))
    end = int(retreat[0]) if retreat.size else tail.size
    return start + int(np.argmax(tail[:end])) if end > 0 else start


def scaled_design(x: FloatArray, y: FloatArray, n: int, l: int, *,  # noqa: E741
                  anchor: str = 'operating_point') -> ScaledDesign:
    """
    Return the operating point, scaling and thresholds (28)-(31) :func:`identify` uses.

    Parameters
    ----------
    x : ndarray of float, shape (N,)
        Input [A].
    y : ndarray of float, shape (N,)
        Output [m].
    n, l : int
        Model orders.
    anchor : {'operating_point', 'origin'}
        ``'operating_point'``: input and output centred on the middle of their ranges,
        the output's sign detected, a constant term, and a burn-in until the largest play
        is determined.  ``'origin'``: the paper's design as printed (scales
        ``||x||_inf``, ``||y||_inf``, plays from 0 at x = 0, no constant, no burn-in).

    Returns
    -------
    ScaledDesign
        Scales, scaled thresholds, the index of S' zero threshold, the operating point.

    """
    if anchor not in ANCHORS:
        msg = f"anchor must be one of {', '.join(ANCHORS)}; found {anchor!r}"
        raise DataError(msg)
    r_h = hysteresis_thresholds(1.0, n)                                          # (28)
    if anchor == 'origin':
        x_scale = float(np.max(np.abs(x)))
        y_scale = float(np.max(np.abs(y)))
        ys = y / y_scale
        y_max, y_min = float(np.max(ys)), float(np.min(ys))
        span = y_max - y_min
        r_s_inv = inverse_superposition_thresholds(
            y_max if y_max > _BRANCH_FRACTION * span else 0.0,
            y_min if y_min < -_BRANCH_FRACTION * span else 0.0, l)             # (29)-(31)
        c = int(np.flatnonzero(r_s_inv == 0.0)[0])
        return ScaledDesign(x_scale, y_scale, r_h, r_s_inv, c)
    x_lo, x_hi = float(np.min(x)), float(np.max(x))
    y_lo, y_hi = float(np.min(y)), float(np.max(y))
    x_scale = 0.5 * (x_hi - x_lo)
    y_scale = 0.5 * (y_hi - y_lo)
    sign, _ = output_sign(x, y)
    r_s_inv = inverse_superposition_thresholds(1.0, -1.0, l)                    # (29)-(31)
    c = int(np.flatnonzero(r_s_inv == 0.0)[0])
    # Plays are determined once the input covered 2 r_Hn; the actuator itself (any
    # hysteresis with the wiping-out property) only once it visited both extremes of the
    # record: its initial loading curve is not the loops' (1 % tolerance for a noisy input).
    start = burn_in(x, max(2.0 * float(r_h[-1]), _FULL_SWEEP) * x_scale,
                    to_turning_point=True)
    return ScaledDesign(x_scale, y_scale, r_h, r_s_inv, c,
                        input_offset=0.5 * (x_lo + x_hi), output_offset=0.5 * (y_lo + y_hi),
                        sign=sign, burn_in=start, constant=True, input_rest=x_lo)


def _mpi_gram(xs: FloatArray, ys: FloatArray, r_h: FloatArray, r_s_inv: FloatArray, *,
              rows: npt.NDArray[np.bool_] | None = None,
              extra: FloatArray | None = None,
              chunk: int = 32768) -> tuple[FloatArray, FloatArray]:
    # Gram matrix and column means of [H_rH[x], -S_r'S[y], extra] over the selected rows,
    # accumulated chunk by chunk: the full N x nv regressor matrix is never formed (1e6
    # samples stay fast and small in memory).  The plays run over every sample.
    nv = r_h.size + r_s_inv.size + (0 if extra is None else extra.shape[1])
    gram = np.zeros((nv, nv))
    total = np.zeros(nv)
    z = np.zeros(r_h.size)                                                      # (32)
    count = 0
    for start in range(0, xs.size, chunk):
        part = slice(start, start + chunk)
        plays, z = play_operator(xs[part], r_h, z)
        blocks = [plays, -dead_zone_operator(ys[part], r_s_inv)]
        if extra is not None:
            blocks.append(extra[part])
        phi = np.hstack(blocks)
        if rows is not None:
            phi = phi[rows[part]]
        count += phi.shape[0]
        gram += phi.T @ phi
        total += phi.sum(axis=0)
    count = max(count, 1)
    return gram / count, total / count


def identify_weights(x: FloatArray, y: FloatArray, n: int, l: int, *,  # noqa: E741
                     epsilon: float = 1e-6,
                     extra_columns: Callable[['ScaledDesign'], FloatArray] | None = None,
                     extra_lower: FloatArray | None = None,
                     anchor: str = 'operating_point',
                     rows: npt.NDArray[np.bool_] | None = None) -> tuple[
                         ScaledDesign, FloatArray, FloatArray, FloatArray, float, Any]:
    """
    Identify the weights of (34)-(36) on a record, optionally with extra regressors.

    Parameters
    ----------
    x, y : ndarray of float, shape (N,)
        Input [A] and output [m].
    n, l : int
        Model orders.
    epsilon : float
        Bound of (8)/(19), scaled units.
    extra_columns : callable, optional
        Given the :class:`ScaledDesign` (``design.scaled_input(x)`` is the input the QP
        sees), returns extra regressors of shape (N, k) that enter the generalised error
        beside H's plays (e.g. creep operators).
    extra_lower : ndarray of float, shape (k,), optional
        Lower bounds of the extra weights (default 0).
    anchor : {'operating_point', 'origin'}
        See :func:`scaled_design`.
    rows : ndarray of bool, shape (N,), optional
        Samples that enter the generalised error (e.g. the training part); all after the
        burn-in by default.  The plays always run over every sample.

    Returns
    -------
    design : ScaledDesign
        Scales and thresholds; ``design.model(w_h, w_s_inv, constant)`` gives Gamma.
    w_h, w_s_inv, w_extra : ndarray of float
        The weights (scaled units).
    constant : float
        The constant term (0 without one).
    info : object
        OSQP's info structure.

    """
    design = scaled_design(x, y, n, l, anchor=anchor)
    xs, ys = design.scaled_input(x), design.scaled_output(y)
    r_h, r_s_inv = design.hysteresis_thresholds, design.inverse_superposition_thresholds
    selected = np.ones(x.size, dtype=bool) if rows is None else np.array(rows, dtype=bool)
    selected[:design.burn_in] = False
    extra = None if extra_columns is None else np.asarray(extra_columns(design),
                                                          dtype=np.float64)
    gram, mean = _mpi_gram(xs, ys, r_h, r_s_inv, rows=selected, extra=extra)   # (34)
    idle = None
    if design.constant:
        # min over c of |Phi v + c|^2 is c = -mean(Phi) v: the covariance of the columns
        # replaces their Gram matrix, and the QP keeps its variables and constraints.
        gram = gram - np.outer(mean, mean)
        # A play the data never move after the burn-in (its threshold exceeds half the
        # record's later reversals) is a constant column: it would satisfy (36) at no
        # cost and shrink every other weight.  Such plays get weight 0.
        variance = np.diag(gram)[:n + 1]
        idle = np.flatnonzero(variance <= _IDLE_PLAY ** 2 * variance[0])
    w_h, w_s_inv, w_extra, info = fit_generalized_error(
        gram, 1.0 - r_h, n_hysteresis=n + 1, n_superposition=r_s_inv.size,    # (36), scaled
        superposition_center=design.center, epsilon=epsilon, extra_lower=extra_lower,
        fixed_zero=idle)
    constant = (-float(mean @ np.concatenate([w_h, w_s_inv, w_extra]))
                if design.constant else 0.0)
    return design, w_h, w_s_inv, w_extra, constant, info


def fit_model(current: npt.ArrayLike, displacement: npt.ArrayLike, n: int,
              l: int, *, epsilon: float = 1e-6, anchor: str = 'operating_point',  # noqa: E741
              rows: npt.NDArray[np.bool_] | None = None) -> tuple[MPIModel, ScaledDesign, Any]:
    """
    Fit Gamma of order (n, l) by the QP, without the checks of :func:`identify`.

    For internal searches (order selection, diagnosis trials) that judge the fit
    themselves.

    Parameters
    ----------
    current, displacement : array_like of float, shape (N,)
        Input [A] and output [m].
    n, l : int
        Model orders.
    epsilon : float
        Bound of (8)/(19), scaled units.
    anchor : {'operating_point', 'origin'}
        See :func:`scaled_design`.
    rows : ndarray of bool, shape (N,), optional
        Samples that enter the generalised error (after the burn-in).

    Returns
    -------
    model : MPIModel
        The forward model.
    design : ScaledDesign
        Its design (``design.burn_in``: samples not determined by the data).
    info : object
        OSQP's info structure.

    """
    x = np.asarray(current, dtype=np.float64).reshape(-1)
    y = np.asarray(displacement, dtype=np.float64).reshape(-1)
    design, w_h, w_s_inv, _, constant, info = identify_weights(
        x, y, n, l, epsilon=epsilon, anchor=anchor, rows=rows)
    return design.model(w_h, w_s_inv, constant), design, info


def _errors(sim: FloatArray, y: FloatArray,
            keep: slice | npt.NDArray[np.bool_]) -> tuple[float, float]:
    # (37) and RMS over the selected samples, both over the whole record's output range
    # (the same denominator for every order and for the straight line).
    span = float(np.ptp(y))
    error = sim[keep] - y[keep]
    return (float(np.max(np.abs(error))) / span,
            float(np.sqrt(np.mean(error * error))) / span)


def _linear_fit(x: FloatArray, y: FloatArray) -> FloatArray:
    slope, intercept = np.polyfit(x, y, 1)
    line: FloatArray = slope * x + intercept
    return line


def _held_out_rows(start: int, size: int, holdout: float,
                   blocks: int = 10) -> npt.NDArray[np.bool_]:
    # Held-out blocks spread over the determined part of the record (not only its end),
    # so every kind of excitation it contains is represented on both sides.
    held = np.zeros(size, dtype=bool)
    edges = np.linspace(start, size, blocks + 1).astype(int)
    count = min(max(int(round(holdout * blocks)), 1), blocks - 1)
    for b in np.unique(np.round(np.linspace(1, blocks - 2, count)).astype(int)):
        held[edges[b]:edges[b + 1]] = True
    return held


def select_order(current: npt.ArrayLike, displacement: npt.ArrayLike, *,
                 orders: tuple[tuple[int, int], ...] = DEFAULT_ORDERS,
                 holdout: float = 0.3, tolerance: float = 0.05, patience: int = 3,
                 absolute_tolerance: float = 1e-3, epsilon: float = 1e-6,
                 anchor: str = 'operating_point'
                 ) -> tuple[tuple[int, int], list[dict[str, Any]]]:
    """
    Choose (n, l) as in the paper: raise the order until the held-out error saturates.

    The determined part of the record (after the burn-in of the highest order tried) is
    cut into ten blocks; ``holdout`` of them, spread over the record, are held out and
    the rest train each order.  The model is simulated over the whole record (so each
    held-out block starts from the state the data before it leave) and (37), over the
    output's range, is measured on the held-out blocks.  An order that is worse than a
    lower one does not stop the search while no order has halved the first (linear)
    order's error (low orders often are worse, on real records); after that it stops
    when ``patience`` successive orders fail to improve the best error by more than the
    tolerance: the error has saturated.  The tolerance is the larger
    of ``tolerance`` (relative) and ``absolute_tolerance`` (fraction of the output
    range: differences below it are noise) for the stop.  The chosen order is the
    smallest whose held-out error is within ``tolerance`` (relative) of the best.

    Parameters
    ----------
    current : array_like of float, shape (N,)
        Input [A].
    displacement : array_like of float, shape (N,)
        Output [m].
    orders : tuple of (int, int)
        Candidate orders in increasing complexity.
    holdout : float
        Fraction of the determined samples held out, in (0, 1).
    tolerance : float
        Relative difference that counts as significant.
    patience : int
        Saturated orders before the search stops.
    absolute_tolerance : float
        Difference, as a fraction of the output range, below which errors count as equal.
    epsilon : float
        Bound of (8)/(19), scaled units.
    anchor : {'operating_point', 'origin'}
        See :func:`scaled_design`.

    Returns
    -------
    order : (int, int)
        The chosen order.
    table : list of dict
        ``{'n', 'l', 'nonlinearity_error', 'rms_error'}`` per order tried (held-out
        blocks, fractions of the output's range).

    """
    x, y = _check_signals(current, displacement)
    if not 0.0 < holdout < 1.0:
        msg = f'holdout must be a fraction in (0, 1); found {holdout}'
        raise DataError(msg)
    n_max = max(n for n, _ in orders)
    start = scaled_design(x, y, n_max, 0, anchor=anchor).burn_in
    if start >= x.size * (1.0 - _MIN_DETERMINED_FRACTION):
        start = 0 if anchor == 'origin' else scaled_design(x, y, 0, 0, anchor=anchor).burn_in
    held = _held_out_rows(start, x.size, holdout)
    table: list[dict[str, Any]] = []
    best = np.inf
    saturated = 0
    for n, l in orders:  # noqa: E741
        _check_excitation(x, y, n, l, anchor=anchor)
        model, design, _ = fit_model(x, y, n, l, epsilon=epsilon, anchor=anchor, rows=~held)
        sim = model.simulate(x)
        keep = held.copy()
        keep[:design.burn_in] = False
        if not np.any(keep):
            continue
        peak, rms = _errors(sim, y, keep)
        row = {'n': n, 'l': l, 'nonlinearity_error': peak, 'rms_error': rms}
        table.append(row)
        error = row['nonlinearity_error']
        margin = max(tolerance * best, absolute_tolerance) if math.isfinite(best) else 0.0
        if error < best - margin or not math.isfinite(best):
            saturated = 0
        elif best < 0.5 * table[0]['nonlinearity_error']:
            saturated += 1          # no better, once hysteresis models work: saturating
        best = min(best, error)
        if saturated >= patience:
            break
    if not table:
        msg = 'no order could be evaluated: the record is too short for a held-out part'
        raise IdentificationError(msg)
    # The choice is relative only: with a noisy output the held-out errors of the good
    # orders are all near the noise's peak, and an absolute margin would pick an order
    # whose error is well above the best one's.
    chosen = next(r for r in table if r['nonlinearity_error'] <= best * (1.0 + tolerance))
    return (chosen['n'], chosen['l']), table


def _quality_check(x: FloatArray, y: FloatArray, sim: FloatArray, start: int, n: int,
                   l: int, anchor: str, *,  # noqa: E741
                   chosen: bool = False) -> tuple[float, float, float]:
    # Every fit is judged against the straight line on the same samples; a fit that is
    # no better, or absurd, is refused: never a silent garbage model.
    keep = slice(start, None)
    peak, error = _errors(sim, y, keep)
    _, linear = _errors(_linear_fit(x[keep], y[keep]), y[keep], slice(None))
    if not (math.isfinite(error) and error < 1.0):
        msg = (f'the identified model (n={n}, l={l}) is absurd: its simulation is off by'
               f' {100 * error:.3g} % of the output range (RMS); check the input and'
               ' output columns/topics, their units and that they belong to one experiment')
        raise IdentificationError(msg)
    # An explicitly requested (0, 0) is the paper's linear model, reported even when a
    # line fits better; an order chosen by the search must beat the line.
    if (n + l > 0 or chosen) and error > linear:
        hint = ('the data may start at rest at the origin: try anchor=origin'
                if anchor == 'operating_point' else 'the default anchor=operating_point fits'
                ' records with a sensor zero, a bias or a falling sensor')
        if chosen:
            hint = (f'order auto chose n={n}, l={l} by the held-out peak error (37); give the'
                    f' order instead (e.g. 14,7); {hint}')
        msg = (f'the identified model (n={n}, l={l}) is worse than a straight line on the same'
               f' data: RMS error {100 * error:.3g} % of the output range vs {100 * linear:.3g}'
               ' % for the line; the output may not be a hysteretic function of this input'
               ' (wrong column or topic, unrelated signals, creep or drift dominating), or'
               f' the record too short; {hint}')
        raise IdentificationError(msg)
    return error, peak, linear


def identify(current: npt.ArrayLike, displacement: npt.ArrayLike, *, n: int | None = None,
             l: int | None = None, order: str | tuple[int, int] | None = None,  # noqa: E741
             epsilon: float = 1e-6, holdout: float = 0.3,
             anchor: str = 'operating_point') -> IdentificationResult:
    """
    Identify a modified Prandtl-Ishlinskii model from measured input/output data.

    The record may have any sensor zero, input bias or output sign, and may start
    mid-history (see the module notes).  The fit is refused, never returned, when it is
    no better than a straight line on the same data or absurd, when the output is not
    monotone in the input, or when the excitation is too small for the order.

    Parameters
    ----------
    current : array_like of float, shape (N,)
        Measured input ``x`` (coil current [A]; any unit works, results scale).
    displacement : array_like of float, shape (N,)
        Measured output ``y`` (displacement [m]; any zero, either sign).
    n, l : int, optional
        Model orders (default 14 and 7, the paper's final order).
    order : 'auto' or (int, int), optional
        ``'auto'`` runs :func:`select_order`; a tuple gives ``(n, l)``.
    epsilon : float
        The small positive bound in (8) and (19), relative to the scaled data.
    holdout : float
        Held-out fraction for ``order='auto'``.
    anchor : {'operating_point', 'origin'}
        Where thresholds and states are anchored, see :func:`scaled_design`.

    Returns
    -------
    IdentificationResult
        The model and its fit statistics.

    Raises
    ------
    DataError
        For malformed data (lengths, non-finite values).
    IdentificationError
        For too little excitation, an output not monotone in the input, a failed QP, or
        a fit no better than a straight line.

    Examples
    --------
    >>> import numpy as np
    >>> t = np.linspace(0.0, 1.0, 2001)
    >>> x = np.sin(2 * np.pi * 3 * t) * np.exp(-t)
    >>> truth = MPIModel.from_params({
    ...     'model.hysteresis.thresholds': [0.0, 0.3], 'model.hysteresis.weights': [1.0, 0.4],
    ...     'model.hysteresis.initial_states': [0.0, 0.0],
    ...     'model.superposition.thresholds': [0.0], 'model.superposition.weights': [2e-5]})
    >>> y = 3.0 - truth.simulate(x)          # a sensor with its own zero, falling
    >>> result = identify(x, y, n=4, l=2)
    >>> result.nonlinearity_error < 0.05, result.model.output_sign
    (True, -1)

    """
    started = time.perf_counter()
    x, y = _check_signals(current, displacement)
    if anchor not in ANCHORS:
        msg = f"anchor must be one of {', '.join(ANCHORS)}; found {anchor!r}"
        raise DataError(msg)
    table: list[dict[str, Any]] = []
    _check_monotone(x, y)
    if order == 'auto':
        (n, l), table = select_order(x, y, holdout=holdout, epsilon=epsilon, anchor=anchor)
    elif order is not None:
        if isinstance(order, str) or len(order) != 2:
            msg = f"order must be 'auto' or a pair (n, l); found {order!r}"
            raise DataError(msg)
        n, l = int(order[0]), int(order[1])  # noqa: E741
    n = 14 if n is None else int(n)
    l = 7 if l is None else int(l)  # noqa: E741
    if n < 0 or l < 0:
        msg = f'model orders must be >= 0; found n={n}, l={l}'
        raise DataError(msg)
    _check_excitation(x, y, n, l, anchor=anchor)
    model, design, info = fit_model(x, y, n, l, epsilon=epsilon, anchor=anchor)
    sim = model.simulate(x)
    rms, peak, linear = _quality_check(x, y, sim, design.burn_in, n, l, anchor,
                                       chosen=order == 'auto')
    return IdentificationResult(
        model=model, order=(n, l), nonlinearity_error=peak, rms_error=rms,
        samples=int(x.size), solver_status=str(info.status), iterations=int(info.iter),
        solve_time=time.perf_counter() - started, order_table=table,
        linear_rms_error=linear, burn_in=int(design.burn_in))
