# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Helpers shared by the model extensions: argument checks, parameter reading, 1-D search.

Every extension is fitted with :func:`mpi_ros.model_fit.identify`'s design: input and
output centred on the record's operating point, the output's sign detected, a constant term
in the generalised error, and only the samples after the burn-in (the plays' and the
actuator's states are determined by the data) in the fit and in the trial errors.
"""

from collections.abc import Callable, Mapping
from dataclasses import dataclass
import math
from typing import Any, TypeVar

import numpy as np
import numpy.typing as npt
from scipy.optimize import minimize_scalar

from ..errors import DataError, ModelError
from ..identification import select_order
from ..identification.fitter import fit_record
from ..identification.folds import blocked_folds
from ..identification.record import prepare_record
from ..metrics import rms_range_error
from ..operators.model import MPIModel

__all__ = ['AxisUnits', 'bound_note', 'check_series', 'choose_out_of_sample', 'determined_start',
           'fit_gamma', 'fit_input_stage', 'fixed_held_out_error', 'fold_simulations',
           'held_out_error', 'hold_segments', 'InputStageFit', 'lag_search_limits', 'Order',
           'OutOfSampleChoice', 'rate_cross_correlation', 'record_gamma', 'resolve_order',
           'scalar_parameter', 'search_fit', 'TRIAL_RULE', 'vector_parameter']

FloatArray = npt.NDArray[np.float64]
#: The ``order`` argument of the fits: ``(n, l)``, or ``'auto'`` (see :func:`resolve_order`).
Order = tuple[int, int] | str
#: The result of one trial fit in :func:`search_fit` (a model).
ResultT = TypeVar('ResultT')
BoolArray = npt.NDArray[np.bool_]
#: Where the weights of every fit of an effect's search come from (see
#: :func:`mpi_ros.identification.fitter.fit_record`): the start states chosen jointly with
#: the weights, as in ``identify``'s own trial fits (the dynamics grid, the order selection).
#: One rule for every trial: left to each fit, the rule's cross-validation picked
#: ``'determined'`` for some trial lags and ``'joint start'`` for others, so the search
#: compared two procedures, not two lags (a 3 s dead time then fitted as none), and each
#: trial cost three more cross-validations.
TRIAL_RULE = 'joint start'


def check_series(time: npt.ArrayLike, *signals: npt.ArrayLike) -> tuple[FloatArray, ...]:
    """
    Validate a time vector and signals of the same length; raise DataError.

    Parameters
    ----------
    time : array_like of float, shape (N,)
        Sample times [s], strictly increasing.
    *signals : array_like of float, shape (N,)
        Signals sampled at ``time``.

    Returns
    -------
    tuple of ndarray of float
        ``time`` followed by the signals, as float arrays.

    """
    arrays = [np.ascontiguousarray(time, dtype=np.float64).reshape(-1)]
    for s in signals:
        arrays.append(np.ascontiguousarray(s, dtype=np.float64).reshape(-1))
    n = arrays[0].size
    for i, arr in enumerate(arrays):
        name = 'time' if i == 0 else f'signal {i}'
        if arr.size != n:
            msg = f'{name} must have {n} samples like time; found {arr.size}'
            raise DataError(msg)
        if not np.all(np.isfinite(arr)):
            msg = f'{name} contains non-finite values; remove or interpolate them'
            raise DataError(msg)
    if n < 2 or np.any(np.diff(arrays[0]) <= 0.0):
        msg = 'time must hold at least 2 strictly increasing sample times [s]'
        raise DataError(msg)
    return tuple(arrays)


def resolve_order(current: FloatArray, displacement: FloatArray,
                  order: Order) -> tuple[tuple[int, int], bool]:
    """
    Return the order ``(n, l)`` of Gamma to fit an effect with, and whether it was chosen.

    ``'auto'`` gives :func:`mpi_ros.identification.select_order` on the record as it is: a
    provisional order to find the effect's parameters with.  A fit then selects the order
    again on the effect-free signals (the lagged or delayed current, the creep-free
    output), because an effect Gamma does not model biases the selection: on records with
    an eddy-current lag or a dead time it picks (6, 3) where the lagged current picks
    (14, 7)-(16, 8), and the extended compensator of the low order tracks 3x worse
    (docs/diagnosis.md).

    Parameters
    ----------
    current : ndarray of float, shape (N,)
        Coil current [A].
    displacement : ndarray of float, shape (N,)
        Displacement [m].
    order : (int, int) or 'auto'
        The fit's ``order`` argument.

    Returns
    -------
    order : (int, int)
        ``(n, l)``.
    chosen : bool
        True for ``'auto'`` (select again on the effect-free signals).

    Raises
    ------
    DataError
        When ``order`` is neither ``'auto'`` nor a pair of integers >= 0.

    """
    if isinstance(order, str):
        if order != 'auto':
            msg = f"order must be 'auto' or a pair (n, l); found {order!r}"
            raise DataError(msg)
        chosen, _ = select_order(current, displacement)
        return chosen, True
    n, l = (int(v) for v in order)  # noqa: E741
    if n < 0 or l < 0:
        msg = f'model orders must be >= 0; found n={n}, l={l}'
        raise DataError(msg)
    return (n, l), False


def scalar_parameter(mapping: Mapping[str, Any], key: str, *, minimum: float = 0.0,
                     strict: bool = False, unit: str = 's') -> float:
    """Read one finite float parameter ``>= minimum`` (``>`` if strict); raise ModelError."""
    if key not in mapping:
        msg = f'{key} is missing; add it [{unit}] or remove the extension'
        raise ModelError(msg)
    value = mapping[key]
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        msg = f'{key} must be a number [{unit}]; found {type(value).__name__} {value!r}'
        raise ModelError(msg)
    v = float(value)
    if not math.isfinite(v) or v < minimum or (strict and v == minimum):
        relation = '>' if strict else '>='
        msg = f'{key} must be finite and {relation} {minimum} [{unit}]; found {value!r}'
        raise ModelError(msg)
    return v


def vector_parameter(mapping: Mapping[str, Any], key: str, *, minimum: float = 0.0,
                     strict: bool = False, unit: str = 's') -> FloatArray:
    """Read a non-empty list of finite floats ``>= minimum``; raise ModelError."""
    if key not in mapping:
        msg = f'{key} is missing; add it [{unit}] or remove the extension'
        raise ModelError(msg)
    value = mapping[key]
    if isinstance(value, (str, bytes)) or not hasattr(value, '__len__') or len(value) == 0:
        msg = f'{key} must be a non-empty list of numbers [{unit}]; found {value!r}'
        raise ModelError(msg)
    out = np.array([scalar_parameter({f'{key}[{i}]': item}, f'{key}[{i}]', minimum=minimum,
                                     strict=strict, unit=unit)
                    for i, item in enumerate(value)])
    out.flags.writeable = False
    return out


def search_fit(fit: Callable[[float], tuple[ResultT, float]], grid: FloatArray, *,
               refine: int = 8) -> tuple[float, ResultT, float]:
    """
    Minimise a 1-D fit error: a grid scan, then a bounded search between the neighbours.

    Every trial's fit is kept, so the winner is returned without fitting it again.

    Parameters
    ----------
    fit : callable float -> (result, error)
        Fits at one trial value and returns the fit and its error (to minimise).
    grid : ndarray of float, shape (k,)
        Ascending trial values; the refinement runs in log scale if all are > 0.
    refine : int
        Evaluations of the bounded refinement (0: grid only).

    Returns
    -------
    best, result, error : float, object, float
        Minimiser, its fit and the minimum found.

    """
    fits: dict[float, ResultT] = {}

    def objective(value: float) -> float:
        fits[value], error = fit(value)
        return error

    values = np.array([objective(float(g)) for g in grid])
    i = int(np.argmin(values))
    best, best_value = float(grid[i]), float(values[i])
    if refine > 0 and grid.size >= 3:
        lo, hi = float(grid[max(i - 1, 0)]), float(grid[min(i + 1, grid.size - 1)])
        use_log = lo > 0.0
        a, b = (math.log(lo), math.log(hi)) if use_log else (lo, hi)
        res = minimize_scalar(lambda v: objective(math.exp(v) if use_log else v),
                              bounds=(a, b), method='bounded',
                              options={'maxiter': refine, 'xatol': 1e-3})
        if float(res.fun) < best_value:
            best = float(math.exp(res.x) if use_log else res.x)
            best_value = float(res.fun)
    if best not in fits:             # the optimiser's minimiser is one of its trials
        fits[best], best_value = fit(best)
    return best, fits[best], best_value


def fit_gamma(current: FloatArray, displacement: FloatArray, order: tuple[int, int],
              epsilon: float, *, start: int = 0, held: BoolArray | None = None,
              rule: str = TRIAL_RULE) -> tuple[MPIModel, float]:
    """
    Identify Gamma on a (possibly transformed) current and return it with its error.

    The fit is :func:`mpi_ros.model_fit.identify`'s (operating point, detected sign,
    constant term, the start state estimated, ringing left out); the generalised error and
    the returned error cover the samples from ``start`` on (see :func:`determined_start`),
    so trials on differently transformed inputs are compared on the same samples.

    Parameters
    ----------
    current : ndarray of float, shape (N,)
        Input of Gamma [A] (e.g. the delayed or lagged coil current).
    displacement : ndarray of float, shape (N,)
        Measured displacement [m].
    order : (int, int)
        ``(n, l)`` of Gamma.
    epsilon : float
        Bound of (8)/(19).
    start : int
        First sample of the fit and of the error (see :func:`determined_start`).
    held : ndarray of bool, shape (N,), optional
        Rows left out of the fit (a fold's held-out block, see :func:`held_out_error`).
    rule : str
        Where the weights come from (:data:`TRIAL_RULE`; see
        :func:`~mpi_ros.identification.fitter.fit_record`).

    Returns
    -------
    model, error : MPIModel, float
        The fit and its RMS error over the output's range on the determined samples.

    """
    n, l = order  # noqa: E741
    record = prepare_record(current, displacement, epsilon=epsilon)
    fit = fit_record(record, n, l, burn_in=start or None, held=held, rule=rule)
    keep = slice(max(start, fit.burn_in), None)
    return fit.model, rms_range_error(fit.model.simulate(current)[keep], displacement[keep])


def held_out_error(fold_simulation: Callable[[BoolArray], FloatArray], displacement: FloatArray,
                   folds: list[BoolArray], scored: BoolArray,
                   nested: list[FloatArray] | None = None) -> float:
    """
    Return the pooled error of fits on the blocks they did not see (blocked folds).

    Parameters
    ----------
    fold_simulation : callable
        ``fold_simulation(held)`` -> the simulation over the whole record [m] of a model
        fitted without the rows ``held`` (the plays and the effect's states follow the
        input, so the held-out block is simulated from the states the record leaves).
    displacement : ndarray of float, shape (N,)
        Measured output [m].
    folds : list of ndarray of bool, shape (N,)
        Held-out rows of each fold (:func:`mpi_ros.identification.folds.blocked_folds`).
    scored : ndarray of bool, shape (N,)
        Rows that count (the determined samples).
    nested : list of ndarray of float, shape (N,), optional
        Per fold, the simulation of the baseline (the effect off) fitted on the same rows.
        Each fold then uses the effect's fit only where it fits the fold's own training
        rows better than the baseline, as the whole fit does (so the held-out error judges
        the procedure, nesting included): the fits minimise the generalised error, not the
        output error, and on a fold they can land worse than the baseline on their own rows.

    Returns
    -------
    float
        RMS of every fold's error on its own block, over the output range of the scored
        samples (inf when a fit fails to give a finite simulation).

    """
    total, count = 0.0, 0
    for k, held in enumerate(folds):
        rows = held & scored
        sim = fold_simulation(held)
        if nested is not None:
            fitted = ~held & scored
            if not (np.mean((sim[fitted] - displacement[fitted]) ** 2)
                    < np.mean((nested[k][fitted] - displacement[fitted]) ** 2)):
                sim = nested[k]
        error = float(np.sum((sim[rows] - displacement[rows]) ** 2))
        if not math.isfinite(error):
            return math.inf
        total += error
        count += int(rows.sum())
    span = float(np.ptp(displacement[scored])) if scored.any() else 0.0
    if count == 0 or span <= 0.0:
        return math.inf
    return math.sqrt(total / count) / span


@dataclass(frozen=True)
class OutOfSampleChoice:
    """
    An effect parameter chosen on held-out blocks (:func:`choose_out_of_sample`).

    Attributes
    ----------
    value : float or None
        The chosen value; None when the effect switched off predicts the held-out blocks
        at least as well (the effect is not there, as far as the record shows).
    error : float
        Its held-out error (the off error for None).
    off_error : float
        The held-out error of the effect switched off (inf when not tried).
    bound : str or None
        ``'lower'`` or ``'upper'`` when the best grid value is the first or the last one of
        the searched range (the minimum is not bracketed: the parameter is *not
        identified*, only known to lie beyond that bound); None otherwise.
    grid : ndarray of float
        The searched values.
    errors : ndarray of float
        Their held-out errors.

    """

    value: float | None
    error: float
    off_error: float
    bound: str | None
    grid: FloatArray
    errors: FloatArray


def fold_simulations(fold_simulation: Callable[[BoolArray], FloatArray],
                     folds: list[BoolArray]) -> list[FloatArray]:
    """Return each fold's simulation (e.g. the baseline's, for ``held_out_error(nested=)``)."""
    return [fold_simulation(held) for held in folds]


def fixed_held_out_error(simulations: list[FloatArray], displacement: FloatArray,
                         folds: list[BoolArray], scored: BoolArray) -> float:
    """Return :func:`held_out_error` of simulations computed already (one per fold)."""
    by_fold = {id(held): sim for held, sim in zip(folds, simulations)}
    return held_out_error(lambda held: by_fold[id(held)], displacement, folds, scored)


def choose_out_of_sample(error_of: Callable[[float], float], grid: FloatArray, *,
                         off_error: float = math.inf, refine: int = 4,
                         bounds: tuple[bool, bool] = (True, True),
                         refine_on: Callable[[float], float] | None = None) -> OutOfSampleChoice:
    """
    Choose a 1-D effect parameter by its held-out error: a grid, then a bounded refinement.

    The effect switched off (``off_error``) competes with every trial, so an effect that
    does not predict unseen blocks better than the baseline is not chosen.  A grid
    minimum at an end of the grid that is a bound of the search (``bounds``) is not
    refined: the parameter is reported as at that bound (not identified).  A minimum at an
    end that is a physical limit is refined between that end and the next trial.

    Parameters
    ----------
    error_of : callable float -> float
        Held-out error of a trial value (e.g. :func:`held_out_error` of its fits).
    grid : ndarray of float, shape (k,)
        Ascending trial values > 0 (the refinement runs in log scale).
    off_error : float
        Held-out error with the effect off (inf: the effect cannot be off here).
    refine : int
        Evaluations of the refinement between the winner's neighbours (0: grid only).
    bounds : (bool, bool)
        Whether the grid's lower and upper end are bounds of the search (False for an end
        that is a physical limit, e.g. a dead time's smallest trial of one sample).
    refine_on : callable float -> float, optional
        The error the refinement minimises inside the bracket the held-out errors chose
        (default ``error_of``).  The whole record's fit error sharpens a value the folds
        located to within two grid steps: the held-out error is noisier than the fit's,
        and on a lag of 4 ms its refinement landed at 3.4-3.7 ms against 4.9 ms in sample,
        and the creep fitted behind the lag then lost 14 % of its gain.

    Returns
    -------
    OutOfSampleChoice
        The choice.

    """
    errors = np.array([error_of(float(g)) for g in grid])
    i = int(np.argmin(errors))
    best, best_error = float(grid[i]), float(errors[i])
    bound = ('lower' if i == 0 and bounds[0] else
             'upper' if i == grid.size - 1 and bounds[1] else None)
    if bound is None and refine > 0 and grid.size >= 2:
        # The bracket is the winner's neighbours; at an end of the grid that is no bound
        # (a physical limit) it stops at that end: the value lies between it and the next
        # trial (a dead time of 1.83 ms won at the smallest trial, one sample, and stayed
        # there unrefined: validation gain 0.12, 0.21 at the true value).
        lo = math.log(float(grid[max(i - 1, 0)]))
        hi = math.log(float(grid[min(i + 1, grid.size - 1)]))
        if refine_on is None:
            res = minimize_scalar(lambda v: error_of(math.exp(v)), bounds=(lo, hi),
                                  method='bounded', options={'maxiter': refine, 'xatol': 1e-2})
            if float(res.fun) < best_error:
                best, best_error = float(math.exp(res.x)), float(res.fun)
        else:
            inside = refine_on
            res = minimize_scalar(lambda v: inside(math.exp(v)), bounds=(lo, hi),
                                  method='bounded', options={'maxiter': refine, 'xatol': 1e-2})
            if float(res.fun) < inside(best):
                best = float(math.exp(res.x))
    if not best_error < off_error:
        return OutOfSampleChoice(None, off_error, off_error, None, grid, errors)
    return OutOfSampleChoice(best, best_error, off_error, bound, grid, errors)


@dataclass(frozen=True)
class InputStageFit:
    """
    Gamma behind an input stage with one parameter (a lag, a dead time): :func:`fit_input_stage`.

    Attributes
    ----------
    model : MPIModel
        Gamma, fitted on the transformed current (on the raw one when ``value`` is 0).
    value : float
        The stage's parameter [s]; 0 switches it off (the transform is then the identity).
    not_identified : str or None
        Why the value is not identified (:func:`bound_note`), None when it is.

    """

    model: MPIModel
    value: float
    not_identified: str | None = None


def fit_input_stage(time: npt.ArrayLike, current: npt.ArrayLike, displacement: npt.ArrayLike,
                    transform: Callable[[FloatArray, FloatArray, float], FloatArray], *,
                    order: Order, epsilon: float, lowest: float,
                    settle: float) -> InputStageFit:
    """
    Identify Gamma behind an input stage whose one parameter is chosen on held-out blocks.

    The trial range is ``lowest`` sample intervals to the longest lag worth trying
    (:func:`lag_search_limits`), 8 log-spaced values, and the stage switched off competes
    with every trial.  Every trial (and the fit without the stage) is scored on the same
    determined samples: after the raw current's burn-in and ``settle`` of the longest trial
    (:func:`determined_start`), with :func:`mpi_ros.identification.identify`'s design
    (operating point, sign, constant term) and one rule for the weights
    (:data:`TRIAL_RULE`).  Each trial is judged on three folds of contiguous blocks
    (:func:`~mpi_ros.identification.folds.blocked_folds`), each predicted by the fit on the
    other two, nested (:func:`held_out_error`).  The held-out errors choose the bracket
    (two grid steps); inside it the whole record's fit error refines the value (the held-out
    error is noisier: on a 4 ms lag it refined to 3.4-3.7 ms, in sample 4.9 ms, and the creep
    fitted behind the lag lost 14 % of its gain).  The chosen value is fitted on the whole
    record and kept only when it fits the record better than the stage off (so the model is
    never worse than Gamma alone on its own data); the Gamma returned is fitted as
    ``identify`` fits it (:func:`record_gamma`: from the first sample some start state
    explains for the transformed current), the trials' settling time not left out.  A
    best value at the longest trial is not identified (:func:`bound_note`); the smallest
    trial is no bound: the stage switched off (value 0, the limit of the range) competes
    with every trial, so a smallest trial that beats it and the next trial lies between 0
    and the next trial (on TUM's
    20 + 40 Hz records a lag of half a sample, 0.05 ms, beat both, and the 100 Hz record
    confirms it: gain 0.24), and it is refined between the two as an interior winner is
    (a dead time of 1.83 ms on a 1 kHz record won at one sample, 1 ms).  With
    ``order='auto'`` the order is selected again on the transformed current
    (:func:`resolve_order`).

    Parameters
    ----------
    time, current, displacement : array_like of float, shape (N,)
        The record: sample times [s], coil current [A], displacement [m].
    transform : callable
        ``transform(time, current, value)`` -> the current Gamma sees [A] (the identity at
        ``value = 0``).
    order : (int, int) or 'auto'
        ``(n, l)`` of Gamma, or ``'auto'``.
    epsilon : float
        Bound of (8)/(19).
    lowest : float
        The smallest trial, in median sample intervals.
    settle : float
        How many of the longest trial values the transformed current needs to forget its
        start (1 for a delay, 3 for a first-order lag).

    Returns
    -------
    InputStageFit
        Gamma, the value and whether it is identified.

    """
    t, x, y = check_series(time, current, displacement)
    dt, longest = lag_search_limits(t)
    n_l, chosen = resolve_order(x, y, order)
    start = determined_start(t, x, y, n_l, settle=settle * longest)
    scored = np.arange(t.size) >= start
    folds = blocked_folds(t.size, start=start)

    def fold_fit(seen: FloatArray, held: BoolArray) -> FloatArray:
        return fit_gamma(seen, y, n_l, epsilon, start=start, held=held)[0].simulate(seen)
    baseline = fold_simulations(lambda held: fold_fit(x, held), folds)

    def held_out(value: float) -> float:
        seen = transform(t, x, value)
        return held_out_error(lambda held: fold_fit(seen, held), y, folds, scored,
                              nested=baseline)

    def in_sample(value: float) -> float:
        return fit_gamma(transform(t, x, value), y, n_l, epsilon, start=start)[1]
    choice = choose_out_of_sample(held_out, np.geomspace(lowest * dt, longest, 8),
                                  off_error=fixed_held_out_error(baseline, y, folds, scored),
                                  refine=8, bounds=(False, True), refine_on=in_sample)
    base, base_error = fit_gamma(x, y, n_l, epsilon, start=start)
    if choice.value is None:
        return InputStageFit(base, 0.0)
    seen = transform(t, x, choice.value)
    _, error = fit_gamma(seen, y, n_l, epsilon, start=start)
    if base_error <= error:
        return InputStageFit(base, 0.0)
    final = n_l
    if chosen:
        # The order again, for the current Gamma sees.
        final, _ = select_order(seen, y)
    # The returned Gamma leaves out only its own burn-in (forced to fit the samples no
    # start state explains, the weights of a 13.4 ms dead-time fit tracked a new
    # trajectory at 4.33 % RMS, 1.85 % without them), not the trials' settle (three of the
    # longest trial lags, for comparing trials on the same samples: the model's stage
    # starts settled at the first sample as ``seen`` does); it is fitted as identify's
    # (:func:`record_gamma`).
    model = record_gamma(seen, y, final, epsilon)
    return InputStageFit(model, choice.value, bound_note(choice) if choice.bound else None)


def record_gamma(current: FloatArray, displacement: FloatArray, order: tuple[int, int],
                 epsilon: float) -> MPIModel:
    """
    Return Gamma fitted as ``identify`` fits it (start states, the weights' rule, burn-in).

    The final Gamma of an effect fit, on what Gamma sees and gives after the effect (the
    transformed current, the displacement less the drift, the creep-free output), by
    :func:`~mpi_ros.identification.fitter.fit_record` as :func:`mpi_ros.identify` calls it.
    An effect fitted off is then identify's Gamma exactly, and a candidate's gain is the
    effect's, not the difference between two ways of fitting Gamma.  Fitted by
    :func:`~mpi_ros.identification.identify_weights` (every sample before the plays are
    determined left out), the record's first ramp from rest (the only currents below
    0.2 A on the wide sweep's records) was never fitted and Gamma extrapolated there: a
    creep candidate missed its first second by 59 % of that second's range (creep plant
    405: 3.1x the baseline's error over the whole record), a thermal one by 21 %; fitted
    with the trials' rule, the input stages' Gamma missed an effect-free record by up to
    1.3x identify's.

    Parameters
    ----------
    current : ndarray of float, shape (N,)
        Gamma's input [A].
    displacement : ndarray of float, shape (N,)
        Gamma's output [m].
    order : (int, int)
        ``(n, l)``.
    epsilon : float
        Bound of (8)/(19).

    Returns
    -------
    MPIModel
        Gamma, with the start state its fit estimated.

    """
    fit = fit_record(prepare_record(current, displacement, epsilon=epsilon), *order,
                     memory_steps=True)
    return fit.model


def bound_note(choice: OutOfSampleChoice, unit: str = 's') -> str:
    """
    Say why a parameter at a bound of its search range is not identified.

    Parameters
    ----------
    choice : OutOfSampleChoice
        A choice with ``bound`` set.
    unit : str
        The parameter's unit.

    Returns
    -------
    str
        E.g. ``'not identified: at the upper bound 300 s of the search range 3-300 s (the
        record cannot tell a larger value from this one)'``.

    """
    side = choice.bound or 'lower'
    edge = float(choice.grid[0] if side == 'lower' else choice.grid[-1])
    beyond = 'smaller' if side == 'lower' else 'larger'
    return (f'not identified: at the {side} bound {edge:.3g} {unit} of the search range'
            f' {float(choice.grid[0]):.3g}-{float(choice.grid[-1]):.3g} {unit} (the record'
            f' cannot tell a {beyond} value from this one)')


def determined_start(time: FloatArray, current: FloatArray, displacement: FloatArray,
                     order: tuple[int, int], *, settle: float = 0.0) -> int:
    """
    Return the first sample the data determine, for the raw current and its transforms.

    The samples no start state explains in a fit of the raw current with the search's rule
    (:data:`TRIAL_RULE`; usually none: the start state is estimated, see
    :mod:`mpi_ros.identification.fitter`), plus
    ``settle`` seconds for a delayed or lagged version of it to have forgotten its own
    start.

    Parameters
    ----------
    time, current, displacement : array_like of float, shape (N,)
        The record: sample times [s], coil current [A], displacement [m].
    order : (int, int)
        ``(n, l)`` of Gamma.
    settle : float
        Extra time [s] (e.g. the longest trial delay, or a few lag time constants).

    Returns
    -------
    int
        Sample index (at most N).

    """
    n, l = order  # noqa: E741
    start = fit_record(prepare_record(current, displacement), n, l, rule=TRIAL_RULE).burn_in
    if start >= time.size:
        return int(time.size)
    return int(np.searchsorted(time, time[start] + settle))


def lag_search_limits(time: FloatArray) -> tuple[float, float]:
    """
    Return the median sample interval [s] and the longest lag [s] worth trying.

    The longest lag is the smaller of 200 sample intervals and 5 % of the record, and at
    least 2 intervals.

    Parameters
    ----------
    time : ndarray of float, shape (N,)
        Sample times [s], increasing.

    Returns
    -------
    dt, longest : float
        Median interval and longest trial lag [s].

    """
    dt = float(np.median(np.diff(time)))
    return dt, max(min(200.0 * dt, 0.05 * float(time[-1] - time[0])), 2.0 * dt)


def rate_cross_correlation(time: FloatArray, measured: FloatArray, simulated: FloatArray,
                           longest: float) -> tuple[FloatArray, FloatArray]:
    """
    Correlate the measured and the simulated output rate, the measured one shifted by lags.

    The lags run over whole median sample intervals up to ``longest`` seconds, but never
    beyond half the record: every correlation then uses at least half of the samples, and
    a short record (a validation record scored only after a long burn-in) gets a shorter
    window instead of slices of different lengths.

    Parameters
    ----------
    time : ndarray of float, shape (N,)
        Sample times [s], strictly increasing, N >= 2.
    measured, simulated : ndarray of float, shape (N,)
        Measured and simulated output [m].
    longest : float
        Longest lag wanted [s], > 0.

    Returns
    -------
    lags : ndarray of float, shape (2 m + 1,)
        Shifts of the measured output [s] (``m >= 1``; ``m = 0`` below 2 samples).
    correlations : ndarray of float, shape (2 m + 1,)
        Correlation coefficient at each lag; 0 where either rate is constant (or does not
        fit in a float) over the compared samples.

    """
    dt = float(np.median(np.diff(time)))
    dy, ds = np.gradient(measured, time), np.gradient(simulated, time)
    m = int(min(longest / dt, dy.size // 2))
    m = max(m, min(1, dy.size // 2))
    correlations = np.array([
        _correlation(dy[max(0, k):dy.size + min(0, k)], ds[max(0, -k):ds.size - max(0, k)])
        for k in range(-m, m + 1)])
    return np.arange(-m, m + 1) * dt, correlations


def hold_segments(time: FloatArray, current: FloatArray,
                  minimum: float) -> list[tuple[int, int]]:
    """
    Index ranges ``(start, end)`` where the input is constant for ``minimum`` seconds.

    Parameters
    ----------
    time : ndarray of float, shape (N,)
        Sample times [s].
    current : ndarray of float, shape (N,)
        Input [A].
    minimum : float
        Shortest hold [s].

    Returns
    -------
    list of (int, int)
        ``current[start:end + 1]`` is constant (to 1e-6 of the input range).

    """
    still = np.abs(np.diff(current)) <= 1e-6 * max(float(np.ptp(current)), 1e-300)
    edges = np.flatnonzero(np.diff(np.concatenate([[0], still.astype(np.int8), [0]])))
    return [(int(a), int(b)) for a, b in zip(edges[::2], edges[1::2])
            if time[b] - time[a] >= minimum]


def hold_evidence(residual: Mapping[str, Any]) -> str | None:
    """
    Describe the residual during input holds (creep and thermal drift evidence).

    Parameters
    ----------
    residual : Mapping
        The diagnosis' residual signatures (``hold_signature``).

    Returns
    -------
    str or None
        The sentence, or None when the record has no holds.

    """
    holds = residual.get('hold_signature')
    if holds is None:
        return None
    return (f'during {holds["holds"]} input holds the residual has a log(t) component'
            f' of {holds["log_amplitude"]:.3g} m RMS (chi2 p = {holds["log_p"]:.2g})'
            f' and drifts by {holds["drift_amplitude"]:.3g} m RMS (p ='
            f' {holds["drift_p"]:.2g})')


def burst_evidence(residual: Mapping[str, Any], law: str) -> str | None:
    """
    Describe the phase of the response over bursts (rate dependence and dead time).

    Parameters
    ----------
    residual : Mapping
        The diagnosis' residual signatures (``burst_signature``).
    law : {'lag', 'delay'}
        The law the effect predicts.

    Returns
    -------
    str or None
        The sentence, or None when the record has no bursts.

    """
    bursts = residual.get('burst_signature')
    if bursts is None:
        return None
    freqs = bursts['frequencies']
    fitted = (f'lag law atan(w tau) with tau = {1e3 * bursts["lag_time_constant"]:.2f} ms'
              if law == 'lag' else f'delay law w L with L = {1e3 * bursts["delay"]:.2f} ms')
    return (f'over bursts at {freqs[0]:.3g}-{freqs[-1]:.3g} Hz the phase of the'
            f' measured/simulated response follows the {fitted} (residual'
            f' {min(bursts["lag_sse"], bursts["delay_sse"]):.2g} against'
            f' {max(bursts["lag_sse"], bursts["delay_sse"]):.2g} for the other law)')


def burst_verdict(residual: Mapping[str, Any], level: float, law: str) -> str:
    """Return whether the bursts show a fast effect following ``law`` ('lag'/'delay')."""
    bursts = residual.get('burst_signature')
    if bursts is None:
        return 'unavailable'
    return 'present' if bursts['p'] < level and bursts['law'] == law else 'absent'


@dataclass(frozen=True)
class AxisUnits:
    """
    Units of a report plot's axes (the data's, as the diagnosis report names them).

    Attributes
    ----------
    current : str
        Unit of the input (``'A'``, or ``'V'`` for a voltage-driven actuator).
    displacement : str
        Unit the output is drawn in (``'m'``, ``'µm'``, ``'nm'``, ...).
    scale : float
        Factor from the output's values to the drawn ones (1e6 to draw metres in µm).

    """

    current: str = 'A'
    displacement: str = 'm'
    scale: float = 1.0


def residual_axes(ax: Any, time: FloatArray, measured: FloatArray, baseline: FloatArray,
                  extended: FloatArray, start: int, label: str,
                  against: FloatArray | None = None, *,
                  units: AxisUnits | None = None) -> None:
    """
    Plot the baseline's and an extension's residual (after ``start``) on ``ax``.

    Parameters
    ----------
    ax : matplotlib Axes
        Target.
    time : ndarray of float, shape (N,)
        Sample times [s].
    measured, baseline, extended : ndarray of float, shape (N,)
        Measured output and the two models' simulations (output unit).
    start : int
        First scored sample.
    label : str
        Name of the extended model in the legend.
    against : ndarray of float, shape (N - start,), optional
        Abscissa of a scatter plot (default: a line over time).
    units : AxisUnits, optional
        Units of the axes (default: A and m).

    """
    units = units or AxisUnits()
    val = slice(start, None)
    abscissa = time[val] if against is None else against
    style = {'lw': 0.6} if against is None else {'ls': '', 'marker': '.', 'ms': 1}
    ax.plot(abscissa, units.scale * (measured - baseline)[val], label='baseline MPI residual',
            **style)
    ax.plot(abscissa, units.scale * (measured - extended)[val], label=f'{label} residual',
            **style)
    ax.set_ylabel(f'measured - simulated [{units.displacement}]')


def _correlation(a: FloatArray, b: FloatArray) -> float:
    # Pearson's r, 0 when it is undefined (constant or overflowing values).
    with np.errstate(all='ignore'):
        if a.size < 3 or not (np.std(a) > 0.0 and np.std(b) > 0.0):
            return 0.0
        r = float(np.corrcoef(a, b)[0, 1])
    return r if math.isfinite(r) else 0.0
