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

Robustness choices (documented in the README):

- The data are scaled internally by ``||x||_inf`` and ``||y||_inf``; all
  thresholds follow the data, so results do not depend on units.
- A branch of S' the output never reaches (the output stays on one side of
  0 except for less than 1 % of its range) gets no thresholds: its weights
  would be undetermined by the data.
- A tiny ridge (1e-10 of the mean diagonal) makes the QP strictly convex,
  so the solution is unique even when plays are collinear on the data.
- The solver status is always checked and the constraints re-checked on the
  result: a failure raises :class:`IdentificationError`, never a silently
  non-invertible model.
"""

from dataclasses import dataclass, field
import time
from typing import Any, Callable

import numpy as np
import numpy.typing as npt
import osqp
import scipy.sparse as sp

from .deadzone import dead_zone_operator
from .errors import DataError, IdentificationError
from .hysteresis import PIHysteresisOperator
from .inverse import invert_superposition
from .metrics import nonlinearity_error, relative_rms_error
from .model import MPIModel
from .play import play_operator
from .superposition import PISuperpositionOperator

__all__ = [
    'IdentificationResult', 'identify', 'select_order', 'hysteresis_thresholds',
    'inverse_superposition_thresholds', 'fit_generalized_error', 'generalized_error_gram',
    'DEFAULT_ORDERS', 'ScaledDesign', 'scaled_design', 'identify_weights',
]

FloatArray = npt.NDArray[np.float64]

#: Orders tried by the automatic order selection: l = n/2 as in the paper's table.
DEFAULT_ORDERS: tuple[tuple[int, int], ...] = tuple((2 * k, k) for k in range(11))

#: A branch of S' whose extent is below this fraction of the output range gets no thresholds.
_BRANCH_FRACTION = 0.01


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
        (37) of the model's simulation on the identification data (fraction).
    rms_error : float
        Relative RMS error of the simulation on the identification data.
    samples : int
        Number of samples used.
    solver_status : str
        OSQP's status text (always ``'solved'`` for a returned result).
    iterations : int
        OSQP iterations.
    solve_time : float
        Wall time of the whole identification [s].
    order_table : list of dict
        Rows ``{'n', 'l', 'nonlinearity_error', 'rms_error'}`` (held-out data)
        of the order selection; empty when the order was given.

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

    def summary(self) -> dict[str, Any]:
        """Return the result as a JSON-ready dict: ``order``, errors, ``samples``, table."""
        return {'order': list(self.order), 'nonlinearity_error': self.nonlinearity_error,
                'rms_error': self.rms_error, 'samples': self.samples,
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


def _check_excitation(x: FloatArray, y: FloatArray, n: int, l: int) -> None:  # noqa: E741
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
    if n > 0:
        # A play with threshold r only leaves its initial loading curve after an input
        # reversal larger than 2 r: without one, H degenerates to a static map and the
        # weights are not identifiable.
        r_1 = float(np.max(np.abs(x))) / (n + 1)                                  # (28)
        largest = _largest_reversal(x)
        if largest <= 2.0 * r_1:
            found = 'never reverses' if largest == 0.0 else (
                f'reverses by at most {largest:.4g}')
            msg = (f'too little excitation to identify order n={n}: the current {found}, but'
                   f' the smallest play threshold r_H1 = {r_1:.4g} needs reversals larger than'
                   f' {2 * r_1:.4g}; record an excitation with larger up-and-down sweeps'
                   ' (minor loops), or lower n')
            raise IdentificationError(msg)


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
    return (phi.T @ phi) / phi.shape[0]


def _mpi_gram(xs: FloatArray, ys: FloatArray, r_h: FloatArray, r_s_inv: FloatArray,
              chunk: int = 32768) -> FloatArray:
    # Gram matrix of [H_rH[x], -S_r'S[y]] accumulated chunk by chunk: the full N x (n+1+m)
    # regressor matrix is never formed (1e6 samples stay fast and small in memory).
    nv = r_h.size + r_s_inv.size
    gram = np.zeros((nv, nv))
    z = np.zeros(r_h.size)                                                      # (32)
    for start in range(0, xs.size, chunk):
        plays, z = play_operator(xs[start:start + chunk], r_h, z)
        phi = np.hstack([plays, -dead_zone_operator(ys[start:start + chunk], r_s_inv)])
        gram += phi.T @ phi
    return gram / xs.size


def fit_generalized_error(gram: FloatArray, equality_row: FloatArray, *,
                          n_hysteresis: int, n_superposition: int,
                          superposition_center: int, epsilon: float = 1e-6,
                          extra_lower: FloatArray | None = None) -> tuple[
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
    ridge = 1e-10 * max(float(np.mean(np.diag(gram))), 1e-300)
    gram[np.diag_indices(nv)] += ridge
    hysteresis_center = 0
    # Constraint rows: (36), then (8) on w_H, then (19) on w'_S, then bounds on extras.
    rows = [np.concatenate([equality_row, np.zeros(m + k)])]
    lower = [1.0]
    upper = [1.0]
    for i in range(n1):                                    # (8): U_H w_H <= u_H
        row = np.zeros(nv)
        row[i] = 1.0
        rows.append(row)
        lower.append(epsilon if i == hysteresis_center else 0.0)
        upper.append(np.inf)
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
                 verbose=False, eps_abs=1e-10, eps_rel=1e-10, max_iter=200000,
                 polishing=True, polish_refine_iter=10)
    res = solver.solve(raise_error=False)
    if res.info.status_val != osqp.SolverStatus.OSQP_SOLVED:
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
    Scaled thresholds of the QP (34)-(36) for one record and order (see :func:`scaled_design`).

    Attributes
    ----------
    x_scale : float
        ``||x||_inf`` [A]; the QP sees ``x / x_scale``.
    y_scale : float
        ``||y||_inf`` [m]; the QP sees ``y / y_scale``.
    hysteresis_thresholds : ndarray of float, shape (n+1,)
        ``r_H`` (28) in scaled units.
    inverse_superposition_thresholds : ndarray of float, shape (m,)
        ``r'_S`` (29)-(31) in scaled units.
    center : int
        Index of the zero threshold in ``inverse_superposition_thresholds``.

    """

    x_scale: float
    y_scale: float
    hysteresis_thresholds: FloatArray
    inverse_superposition_thresholds: FloatArray
    center: int

    def model(self, w_h: FloatArray, w_s_inv: FloatArray) -> MPIModel:
        """
        Return the forward MPI model in SI units for QP weights found on the scaled data.

        Parameters
        ----------
        w_h : ndarray of float, shape (n+1,)
            Weights of H (dimensionless, unchanged by the scaling).
        w_s_inv : ndarray of float, shape (m,)
            Weights of S' in scaled units.

        Returns
        -------
        MPIModel
            Gamma with S from S' by (22)-(25) and ``z_H0 = 0`` (32).

        """
        r_h = self.hysteresis_thresholds
        # Back to SI: H maps A -> A (w_H dimensionless); S' maps m -> A.
        hysteresis = PIHysteresisOperator(r_h * self.x_scale, w_h, np.zeros(r_h.size))
        s_inv = PISuperpositionOperator(self.inverse_superposition_thresholds * self.y_scale,
                                        w_s_inv * (self.x_scale / self.y_scale))
        return MPIModel(hysteresis, invert_superposition(s_inv))               # (22)-(25)


def scaled_design(x: FloatArray, y: FloatArray, n: int, l: int  # noqa: E741
                  ) -> ScaledDesign:
    """
    Return the scaling and the thresholds (28)-(31) :func:`identify` uses for a record.

    Parameters
    ----------
    x : ndarray of float, shape (N,)
        Input [A].
    y : ndarray of float, shape (N,)
        Output [m].
    n, l : int
        Model orders.

    Returns
    -------
    ScaledDesign
        Scales, scaled thresholds and the index of S' zero threshold.

    """
    x_scale = float(np.max(np.abs(x)))
    y_scale = float(np.max(np.abs(y)))
    ys = y / y_scale
    r_h = hysteresis_thresholds(1.0, n)                                          # (28)
    y_max, y_min = float(np.max(ys)), float(np.min(ys))
    span = y_max - y_min
    r_s_inv = inverse_superposition_thresholds(
        y_max if y_max > _BRANCH_FRACTION * span else 0.0,
        y_min if y_min < -_BRANCH_FRACTION * span else 0.0, l)                 # (29)-(31)
    c = int(np.flatnonzero(r_s_inv == 0.0)[0])
    return ScaledDesign(x_scale, y_scale, r_h, r_s_inv, c)


def identify_weights(x: FloatArray, y: FloatArray, n: int, l: int, *,  # noqa: E741
                     epsilon: float = 1e-6,
                     extra_columns: Callable[[FloatArray], FloatArray] | None = None,
                     extra_lower: FloatArray | None = None) -> tuple[
                         ScaledDesign, FloatArray, FloatArray, FloatArray, Any]:
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
        Given the scaled input ``x / ||x||_inf``, returns extra regressors of shape
        (N, k) that enter the generalised error beside H's plays (e.g. creep operators).
    extra_lower : ndarray of float, shape (k,), optional
        Lower bounds of the extra weights (default 0).

    Returns
    -------
    design : ScaledDesign
        Scales and thresholds; ``design.model(w_h, w_s_inv)`` gives Gamma in SI units.
    w_h, w_s_inv, w_extra : ndarray of float
        The weights (scaled units).
    info : object
        OSQP's info structure.

    """
    design = scaled_design(x, y, n, l)
    xs, ys = x / design.x_scale, y / design.y_scale
    r_h, r_s_inv = design.hysteresis_thresholds, design.inverse_superposition_thresholds
    if extra_columns is None:
        gram = _mpi_gram(xs, ys, r_h, r_s_inv)                                  # (34)
    else:
        plays, _ = play_operator(xs, r_h)
        gram = generalized_error_gram(plays, -dead_zone_operator(ys, r_s_inv),
                                      extra_columns(xs))                        # (34)
    w_h, w_s_inv, w_extra, info = fit_generalized_error(
        gram, 1.0 - r_h, n_hysteresis=n + 1, n_superposition=r_s_inv.size,    # (36), scaled
        superposition_center=design.center, epsilon=epsilon, extra_lower=extra_lower)
    return design, w_h, w_s_inv, w_extra, info


def _fit(x: FloatArray, y: FloatArray, n: int, l: int,  # noqa: E741
         epsilon: float) -> tuple[MPIModel, Any]:
    design, w_h, w_s_inv, _, info = identify_weights(x, y, n, l, epsilon=epsilon)
    return design.model(w_h, w_s_inv), info


def select_order(current: npt.ArrayLike, displacement: npt.ArrayLike, *,
                 orders: tuple[tuple[int, int], ...] = DEFAULT_ORDERS,
                 holdout: float = 0.3, tolerance: float = 0.05, patience: int = 2,
                 epsilon: float = 1e-6) -> tuple[tuple[int, int], list[dict[str, Any]]]:
    """
    Choose (n, l) as in the paper: raise the order until (37) on held-out data saturates.

    The first ``1 - holdout`` of the record trains each order; the model is
    simulated over the whole record (so the held-out part starts from the state
    the training part leaves) and (37) is measured on the held-out part.  The
    search stops when ``patience`` successive orders fail to improve the best
    error by more than ``tolerance`` (relative).  The chosen order is the
    smallest whose held-out error is within ``tolerance`` of the best.

    Parameters
    ----------
    current : array_like of float, shape (N,)
        Input [A].
    displacement : array_like of float, shape (N,)
        Output [m].
    orders : tuple of (int, int)
        Candidate orders in increasing complexity.
    holdout : float
        Fraction of samples (at the end) held out, in (0, 1).
    tolerance : float
        Relative improvement that counts as significant.
    patience : int
        Non-improving orders before the search stops.
    epsilon : float
        Bound of (8)/(19), scaled units.

    Returns
    -------
    order : (int, int)
        The chosen order.
    table : list of dict
        ``{'n', 'l', 'nonlinearity_error', 'rms_error'}`` per order tried.

    """
    x, y = _check_signals(current, displacement)
    if not 0.0 < holdout < 1.0:
        msg = f'holdout must be a fraction in (0, 1); found {holdout}'
        raise DataError(msg)
    split = int(round(x.size * (1.0 - holdout)))
    table: list[dict[str, Any]] = []
    best = np.inf
    stale = 0
    for n, l in orders:  # noqa: E741
        _check_excitation(x[:split], y[:split], n, l)
        model, _ = _fit(x[:split], y[:split], n, l, epsilon)
        sim = model.simulate(x)
        row = {'n': n, 'l': l,
               'nonlinearity_error': nonlinearity_error(sim[split:], y[split:]),
               'rms_error': relative_rms_error(sim[split:], y[split:])}
        table.append(row)
        if row['nonlinearity_error'] < best * (1.0 - tolerance):
            stale = 0
        else:
            stale += 1
        best = min(best, row['nonlinearity_error'])
        if stale >= patience:
            break
    chosen = next(r for r in table if r['nonlinearity_error'] <= best * (1.0 + tolerance))
    return (chosen['n'], chosen['l']), table


def identify(current: npt.ArrayLike, displacement: npt.ArrayLike, *, n: int | None = None,
             l: int | None = None, order: str | tuple[int, int] | None = None,  # noqa: E741
             epsilon: float = 1e-6, holdout: float = 0.3) -> IdentificationResult:
    """
    Identify a modified Prandtl-Ishlinskii model from measured input/output data.

    Parameters
    ----------
    current : array_like of float, shape (N,)
        Measured input ``x`` (coil current [A]; any unit works, results scale).
    displacement : array_like of float, shape (N,)
        Measured output ``y`` (displacement [m]).
    n, l : int, optional
        Model orders (default 14 and 7, the paper's final order).
    order : 'auto' or (int, int), optional
        ``'auto'`` runs :func:`select_order`; a tuple gives ``(n, l)``.
    epsilon : float
        The small positive bound in (8) and (19), relative to the scaled data.
    holdout : float
        Held-out fraction for ``order='auto'``.

    Returns
    -------
    IdentificationResult
        The model and its fit statistics.

    Raises
    ------
    DataError
        For malformed data (lengths, non-finite values).
    IdentificationError
        For too little excitation or a failed QP.

    Examples
    --------
    >>> import numpy as np
    >>> t = np.linspace(0.0, 1.0, 2001)
    >>> x = np.sin(2 * np.pi * 3 * t) * np.exp(-t)
    >>> truth = MPIModel.from_params({
    ...     'model.hysteresis.thresholds': [0.0, 0.3], 'model.hysteresis.weights': [1.0, 0.4],
    ...     'model.hysteresis.initial_states': [0.0, 0.0],
    ...     'model.superposition.thresholds': [0.0], 'model.superposition.weights': [2e-5]})
    >>> result = identify(x, truth.simulate(x), n=4, l=2)
    >>> result.nonlinearity_error < 0.05
    True

    """
    started = time.perf_counter()
    x, y = _check_signals(current, displacement)
    table: list[dict[str, Any]] = []
    if order == 'auto':
        (n, l), table = select_order(x, y, holdout=holdout, epsilon=epsilon)
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
    _check_excitation(x, y, n, l)
    model, info = _fit(x, y, n, l, epsilon)
    sim = model.simulate(x)
    return IdentificationResult(
        model=model, order=(n, l), nonlinearity_error=nonlinearity_error(sim, y),
        rms_error=relative_rms_error(sim, y), samples=int(x.size),
        solver_status=str(info.status), iterations=int(info.iter),
        solve_time=time.perf_counter() - started, order_table=table)
