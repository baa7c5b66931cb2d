# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Helpers shared by the model extensions: argument checks, parameter reading, 1-D search.

Every extension is fitted with :func:`mpi_ros.identification.identify`'s design: input and
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
from ..identification.procedure import fit_record, prepare_record
from ..metrics import rms_range_error
from ..operators.model import MPIModel

__all__ = ['AxisUnits', 'check_series', 'determined_start', 'fit_gamma', 'lag_search_limits',
           'Order', 'rate_cross_correlation', 'resolve_order',
           'scalar_parameter', 'search_fit', 'vector_parameter']

FloatArray = npt.NDArray[np.float64]
#: The ``order`` argument of the fits: ``(n, l)``, or ``'auto'`` (see :func:`resolve_order`).
Order = tuple[int, int] | str
#: The result of one trial fit in :func:`search_fit` (a model).
ResultT = TypeVar('ResultT')


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
              epsilon: float, *, start: int = 0) -> tuple[MPIModel, float]:
    """
    Identify Gamma on a (possibly transformed) current and return it with its error.

    The fit is :func:`mpi_ros.identification.identify`'s (operating point, detected sign,
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

    Returns
    -------
    model, error : MPIModel, float
        The fit and its RMS error over the output's range on the determined samples.

    """
    n, l = order  # noqa: E741
    record = prepare_record(current, displacement, epsilon=epsilon)
    fit = fit_record(record, n, l, burn_in=start or None)
    keep = slice(max(start, fit.burn_in), None)
    return fit.model, rms_range_error(fit.model.simulate(current)[keep], displacement[keep])


def determined_start(time: FloatArray, current: FloatArray, displacement: FloatArray,
                     order: tuple[int, int], *, settle: float = 0.0) -> int:
    """
    Return the first sample the data determine, for the raw current and its transforms.

    The samples no start state explains in a fit of the raw current (usually none: the
    start state is estimated, see :mod:`mpi_ros.identification.procedure`), plus
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
    start = fit_record(prepare_record(current, displacement), n, l).burn_in
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
