# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""Helpers shared by the model extensions: argument checks, parameter reading, 1-D search."""

from collections.abc import Callable, Mapping
import math
from typing import Any

import numpy as np
import numpy.typing as npt
from scipy.optimize import minimize_scalar

from ..errors import DataError, ModelError

__all__ = ['check_series', 'scalar_parameter', 'vector_parameter', 'search_scalar']

FloatArray = npt.NDArray[np.float64]


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


def search_scalar(objective: Callable[[float], float], grid: FloatArray, *,
                  refine: int = 8) -> tuple[float, float]:
    """
    Minimise a 1-D objective: a grid scan, then a bounded search between the neighbours.

    Parameters
    ----------
    objective : callable float -> float
        The function to minimise.
    grid : ndarray of float, shape (k,)
        Ascending trial values; the refinement runs in log scale if all are > 0.
    refine : int
        Evaluations of the bounded refinement (0: grid only).

    Returns
    -------
    best, value : float
        Minimiser and minimum found.

    """
    values = np.array([objective(float(g)) for g in grid])
    i = int(np.argmin(values))
    best, best_value = float(grid[i]), float(values[i])
    if refine <= 0 or grid.size < 3:
        return best, best_value
    lo, hi = float(grid[max(i - 1, 0)]), float(grid[min(i + 1, grid.size - 1)])
    use_log = lo > 0.0
    a, b = (math.log(lo), math.log(hi)) if use_log else (lo, hi)
    res = minimize_scalar(lambda v: objective(math.exp(v) if use_log else v), bounds=(a, b),
                          method='bounded', options={'maxiter': refine, 'xatol': 1e-3})
    if float(res.fun) < best_value:
        best = float(math.exp(res.x) if use_log else res.x)
        best_value = float(res.fun)
    return best, best_value
