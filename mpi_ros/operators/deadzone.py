# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
One-sided dead-zone operator, equations (15)-(17) of Kuhnen's paper.

``S(x, r) = max(x - r, 0)`` for ``r > 0``, ``x`` for ``r = 0`` and
``min(x - r, 0)`` for ``r < 0`` (17).  The operator is memory-free, so the
batch and streaming forms are the same function of the present sample.
"""

import numba
import numpy as np
import numpy.typing as npt

__all__ = ['dead_zone', 'dead_zone_operator', 'dead_zone_step']

FloatArray = npt.NDArray[np.float64]


@numba.njit(cache=True, nogil=True, inline='always')
def dead_zone(x: float, r: float) -> float:  # pragma: no cover - compiled
    """
    Return the one-sided dead-zone operator's output for one sample and threshold (17).

    Parameters
    ----------
    x : float
        Input sample.
    r : float
        Threshold (any sign), unit of the input.

    Returns
    -------
    float
        ``max(x - r, 0)`` for ``r > 0``, ``min(x - r, 0)`` for ``r < 0``, ``x`` for ``r = 0``.

    """
    if r > 0.0:
        d = x - r
        return d if d > 0.0 else 0.0
    if r < 0.0:
        d = x - r
        return d if d < 0.0 else 0.0
    return x


@numba.njit(cache=True, nogil=True)
def dead_zone_step(x: float, r: FloatArray,
                   out: FloatArray) -> None:  # pragma: no cover - compiled
    """
    Evaluate one-sided dead-zone operators on one sample, into ``out`` (17).

    Parameters
    ----------
    x : float
        Input sample.
    r : ndarray of float, shape (m,)
        Thresholds (any sign), unit of the input.
    out : ndarray of float, shape (m,)
        Receives ``S(x, r[i])``.

    """
    for i in range(r.shape[0]):
        out[i] = dead_zone(x, r[i])


@numba.njit(cache=True, nogil=True)
def _dead_zone_batch(x: FloatArray, r: FloatArray) -> FloatArray:  # pragma: no cover - compiled
    out = np.empty((x.shape[0], r.shape[0]))
    for k in range(x.shape[0]):
        for i in range(r.shape[0]):
            out[k, i] = dead_zone(x[k], r[i])
    return out


def dead_zone_operator(x: npt.ArrayLike, thresholds: npt.ArrayLike) -> FloatArray:
    """
    Apply one-sided dead-zone operators with several thresholds (16)-(17).

    Parameters
    ----------
    x : array_like of float, shape (N,)
        Input sequence.
    thresholds : array_like of float, shape (m,)
        Thresholds of any sign, unit of the input.

    Returns
    -------
    ndarray of float, shape (N, m)
        One column per threshold.

    Examples
    --------
    >>> dead_zone_operator([-1.0, 0.5, 2.0], [-0.5, 0.0, 1.0]).tolist()
    [[-0.5, -1.0, 0.0], [0.0, 0.5, 0.0], [0.0, 2.0, 1.0]]

    """
    x_arr = np.ascontiguousarray(x, dtype=np.float64).reshape(-1)
    r = np.ascontiguousarray(thresholds, dtype=np.float64).reshape(-1)
    out: FloatArray = _dead_zone_batch(x_arr, r)
    return out
