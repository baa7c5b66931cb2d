# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Identification of the MPI operator from measured data, section 4.2 of Kuhnen's paper.

A package by concern: :mod:`.design` (operating point, scaling, thresholds (28)-(31),
burn-in), :mod:`.qp` (the QP (34)-(36) with OSQP), :mod:`.checks` (what is refused, the
straight-line baseline), :mod:`.selection` (order selection); :func:`identify` here ties them
together.

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
from typing import Any

import numpy as np
import numpy.typing as npt

from .checks import _check_excitation, _check_monotone, _check_signals, _quality_check
from .design import (ANCHORS, burn_in, hysteresis_thresholds,
                     inverse_superposition_thresholds, output_sign, scaled_design,
                     ScaledDesign)
from .qp import fit_generalized_error, fit_model, generalized_error_gram, identify_weights
from .selection import DEFAULT_ORDERS, select_order
from ..errors import DataError
from ..model import MPIModel

__all__ = [
    'IdentificationResult', 'identify', 'select_order', 'hysteresis_thresholds',
    'inverse_superposition_thresholds', 'fit_generalized_error', 'generalized_error_gram',
    'DEFAULT_ORDERS', 'ScaledDesign', 'scaled_design', 'identify_weights', 'fit_model',
    'output_sign', 'burn_in', 'ANCHORS',


]


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


def identify(current: npt.ArrayLike, displacement: npt.ArrayLike, *, n: int | None = None,
             l: int | None = None, order: str | tuple[int, int] | None = None,  # noqa: E741
             epsilon: float = 1e-6, holdout: float = 0.3,
             anchor: str = 'operating_point', periodic: bool = False) -> IdentificationResult:
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
    periodic : bool
        The record is one period of a periodic excitation the actuator had been following
        (e.g. a single measured loop that ends where it starts): its start state is then
        the state at its end, so the whole record is fitted (the record is run twice and
        the second pass fitted).  Otherwise the start state is unknown and the samples
        before the input has covered its range are left out.  Needs an explicit order.

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
    if periodic:
        _check_one_period(x, order)
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
    # One period: run the record twice and fit the second pass, whose start state is the
    # first pass's end state; otherwise the samples before the burn-in are left out.
    xf, yf = (np.concatenate([x, x]), np.concatenate([y, y])) if periodic else (x, y)
    rows = np.arange(xf.size) >= x.size if periodic else None
    _check_excitation(xf, yf, n, l, anchor=anchor)
    model, design, info = fit_model(xf, yf, n, l, epsilon=epsilon, anchor=anchor, rows=rows)
    start = x.size if periodic else design.burn_in
    sim = model.simulate(xf)
    rms, peak, linear = _quality_check(xf, yf, sim, start, n, l, anchor,
                                       chosen=order == 'auto')
    return IdentificationResult(
        model=model, order=(n, l), nonlinearity_error=peak, rms_error=rms,
        samples=int(x.size), solver_status=str(info.status), iterations=int(info.iter),
        solve_time=time.perf_counter() - started, order_table=table,
        linear_rms_error=linear, burn_in=0 if periodic else int(design.burn_in))


def _check_one_period(x: npt.NDArray[Any], order: Any) -> None:
    span = float(np.ptp(x))
    if abs(float(x[-1]) - float(x[0])) > 0.02 * span:
        gap = 100.0 * abs(float(x[-1]) - float(x[0])) / span
        msg = (f'periodic: the record must end where it starts (one period); the input goes'
               f' from {float(x[0]):.6g} to {float(x[-1]):.6g}, {gap:.1f} % of its range'
               ' apart; cut it to whole periods')
        raise DataError(msg)
    if order == 'auto':
        msg = ("periodic: order 'auto' needs held-out data beyond one period; give the order"
               ' (e.g. 8,4), or record several periods and leave periodic off')
        raise DataError(msg)
