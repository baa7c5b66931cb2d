# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Order selection.

Raise (n, l) until the held-out error saturates.
"""

import math
from typing import Any

import numpy as np
import numpy.typing as npt

from .checks import _check_excitation, _check_signals, _errors
from .design import _MIN_DETERMINED_FRACTION, DEFAULT_ORDERS, scaled_design
from .qp import fit_model
from ..errors import DataError, IdentificationError

__all__ = ['DEFAULT_ORDERS', 'select_order']


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
