# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
The order selection: raise (n, l) until the held-out error saturates, as in the paper.

:func:`select_order` runs on a record given as arrays; :func:`select_record_order` on a
prepared record with its held-out rows, start states and input dynamics (what
:func:`mpi_ros.model_fit.identify` does with ``order='auto'``, on the busiest
:data:`ORDER_WINDOW` samples of the record).
"""

from collections.abc import Callable
import math
from typing import Any

import numpy as np
import numpy.typing as npt

from .dynamics import InputDynamics
from .fitter import fit_record
from .folds import held_out_rows
from .qp import check_signals, DEFAULT_ORDERS, range_errors
from .record import prepare_record, PreparedRecord, Segment
from ..errors import DataError, IdentificationError

__all__ = ['DEFAULT_ORDERS', 'ORDER_WINDOW', 'select_order', 'select_record_order']

#: Samples of the window the order selection runs on.
ORDER_WINDOW = 100000


def select_order(current: npt.ArrayLike, displacement: npt.ArrayLike, *,
                 orders: tuple[tuple[int, int], ...] = DEFAULT_ORDERS,
                 holdout: float = 0.3, tolerance: float = 0.02, patience: int = 3,
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
    x, y = check_signals(current, displacement)
    if not 0.0 < holdout < 1.0:
        msg = f'holdout must be a fraction in (0, 1); found {holdout}'
        raise DataError(msg)
    record = prepare_record(x, y, anchor=anchor, epsilon=epsilon)
    held = held_out_rows(x.size, holdout, record.keep)
    n_ref = min(8, max(n for n, _ in orders))
    base = fit_record(record, n_ref, n_ref // 2, held=held)
    return select_record_order(record, held, InputDynamics(), base.segments, orders=orders,
                               tolerance=tolerance, patience=patience,
                               absolute_tolerance=absolute_tolerance, burn_in=base.burn_in,
                               rule=base.rule)


def select_record_order(record: PreparedRecord, held: npt.NDArray[np.bool_],
                        dynamics: InputDynamics, starts: list[Segment], *,
                        orders: tuple[tuple[int, int], ...] = DEFAULT_ORDERS,
                        tolerance: float = 0.02, patience: int = 3,
                        absolute_tolerance: float = 1e-3, burn_in: int = 0,
                        progress: Callable[[str], None] | None = None,
                        rule: str = 'joint') -> tuple[
                            tuple[int, int], list[dict[str, Any]]]:
    """
    Choose (n, l) as in the paper: raise the order until the held-out error saturates.

    Each order (with at least ten training samples per weight) is fitted on the training
    blocks with the record's start states and dynamics, simulated over the whole record
    and scored on the held-out blocks by its RMS error over the output's range (and (37),
    reported).  The search stops when ``patience`` successive orders fail to improve the
    best error by the tolerance once an order has halved the linear one's; the chosen
    order is the smallest within ``tolerance`` (relative) of the best.  Orders whose
    held-out error is absurd (over the output's range) are marked ``unstable`` and not
    considered.

    Parameters
    ----------
    record : PreparedRecord
        The record.
    held : ndarray of bool, shape (N,)
        Held-out rows.
    dynamics : InputDynamics
        The input's dynamics.
    starts : list of Segment
        Start states (their kinds are kept for every order).
    orders : tuple of (int, int)
        Candidate orders in increasing complexity.
    tolerance : float
        Relative difference of held-out RMS errors that counts as significant.
    patience : int
        Saturated orders before the search stops.
    absolute_tolerance : float
        Difference, as a fraction of the output range, below which errors count as equal
        for the stop.
    burn_in : int
        Samples at the start left out of every fit (the reference fit's burn-in).
    progress : callable, optional
        Called with a line of text before each order is fitted (a progress display).
    rule : {'joint', 'determined'}
        Where each order's weights come from (the reference fit's rule, see
        :func:`~mpi_ros.identification.fitter.fit_record`).

    Returns
    -------
    order : (int, int)
        The chosen order.
    table : list of dict
        ``{'n', 'l', 'nonlinearity_error', 'rms_error', 'unstable'}`` per order tried
        (held-out blocks, fractions of the output's range).

    """
    y = record.displacement
    train = int(np.count_nonzero(record.keep & ~held))
    table: list[dict[str, Any]] = []
    best = math.inf
    saturated = 0
    for i, (n, l) in enumerate(orders):  # noqa: E741
        if train < 10 * (n + 2 * l + 2) and table:
            break
        if progress is not None:
            progress(f'order selection: n={n}, l={l} ({i + 1} of at most {len(orders)})')
        try:
            fit = fit_record(record, n, l, dynamics=dynamics, held=held, starts=starts,
                             choose=False, burn_in=burn_in, rule=rule)
        except IdentificationError:
            continue
        peak, rms = range_errors(fit.simulate(), y, held)
        unstable = not (math.isfinite(rms) and rms < 1.0)
        table.append({'n': n, 'l': l, 'nonlinearity_error': peak, 'rms_error': rms,
                      'unstable': unstable})
        if unstable:
            continue
        first = next(r for r in table if not r['unstable'])['rms_error']
        margin = max(tolerance * best, absolute_tolerance) if math.isfinite(best) else 0.0
        if rms < best - margin or not math.isfinite(best):
            saturated = 0
        elif best < 0.5 * first:
            saturated += 1      # no better, once hysteresis models work: saturating
        best = min(best, rms)
        if saturated >= patience:
            break
    stable = [r for r in table if not r['unstable']]
    if not stable:
        msg = ('no order could be evaluated on the held-out blocks (every fit was absurd or'
               ' failed); give the order (e.g. 8,4), or record more cycles')
        raise IdentificationError(msg)
    chosen = next(r for r in stable if r['rms_error'] <= best * (1.0 + tolerance))
    return (chosen['n'], chosen['l']), table
