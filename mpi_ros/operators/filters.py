# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
First-order lags and a pure delay on a time base: the linear blocks of the input path.

A first-order lag ``tau dq/dt = u - q`` is advanced exactly for an input that is linear
between samples (first-order hold): with ``h = t_k - t_(k-1)``, ``a = exp(-h / tau)`` and
``b = 1 - tau (1 - a) / h``,

``q_k = a q_(k-1) + (1 - a) u_(k-1) + b (u_k - u_(k-1))``.

The present input enters with the positive gain ``b`` (``0 < b < 1``).  Sampling may be
non-uniform.  Batch functions start in steady state at the first sample (``q_0 = u_0``): a
record is assumed to begin at rest.
"""

import math

import numba
import numpy as np
import numpy.typing as npt

__all__ = ['lag_coefficients', 'first_order_lag', 'lag_bank', 'lag_feedback_inverse',
           'delay']

FloatArray = npt.NDArray[np.float64]


def lag_coefficients(h: float, tau: float) -> tuple[float, float]:
    """
    Return ``(a, b)`` of the first-order-hold lag update for a step ``h`` [s].

    Parameters
    ----------
    h : float
        Sample interval [s], > 0.
    tau : float
        Time constant [s], > 0.

    Returns
    -------
    a, b : float
        ``q_k = a q_(k-1) + (1 - a) u_(k-1) + b (u_k - u_(k-1))``.

    """
    one_minus_a = -math.expm1(-h / tau)
    return 1.0 - one_minus_a, 1.0 - tau * one_minus_a / h


@numba.njit(cache=True, nogil=True)
def _lag_bank(t: FloatArray, u: FloatArray,
              taus: FloatArray) -> FloatArray:  # pragma: no cover - compiled
    n = t.shape[0]
    k = taus.shape[0]
    out = np.empty((n, k))
    for j in range(k):
        out[0, j] = u[0]
    for i in range(1, n):
        h = t[i] - t[i - 1]
        for j in range(k):
            one_minus_a = -math.expm1(-h / taus[j])
            b = 1.0 - taus[j] * one_minus_a / h
            out[i, j] = ((1.0 - one_minus_a) * out[i - 1, j] + one_minus_a * u[i - 1]
                         + b * (u[i] - u[i - 1]))
    return out


def lag_bank(time: npt.ArrayLike, signal: npt.ArrayLike,
             time_constants: npt.ArrayLike) -> FloatArray:
    """
    Filter one signal through several first-order lags, starting in steady state.

    Parameters
    ----------
    time : array_like of float, shape (N,)
        Sample times [s], strictly increasing.
    signal : array_like of float, shape (N,)
        Input of the lags (any unit).
    time_constants : array_like of float, shape (k,)
        Time constants [s], > 0.

    Returns
    -------
    ndarray of float, shape (N, k)
        One column per lag, in the unit of ``signal``.

    """
    return _lag_bank(np.ascontiguousarray(time, dtype=np.float64),
                     np.ascontiguousarray(signal, dtype=np.float64),
                     np.ascontiguousarray(np.atleast_1d(time_constants), dtype=np.float64))


@numba.njit(cache=True, nogil=True)
def _lag_feedback_inverse(t: FloatArray, y: FloatArray, taus: FloatArray,
                          w: FloatArray) -> FloatArray:  # pragma: no cover - compiled
    n = t.shape[0]
    k = taus.shape[0]
    g = np.empty(n)
    q = np.empty(k)
    p = np.empty(k)
    b = np.empty(k)
    g[0] = y[0] / (1.0 + np.sum(w))
    for j in range(k):
        q[j] = g[0]
    for i in range(1, n):
        h = t[i] - t[i - 1]
        known = 0.0
        gain = 1.0
        for j in range(k):
            one_minus_a = -math.expm1(-h / taus[j])
            b[j] = 1.0 - taus[j] * one_minus_a / h
            p[j] = (1.0 - one_minus_a) * q[j] + one_minus_a * g[i - 1] - b[j] * g[i - 1]
            known += w[j] * p[j]
            gain += w[j] * b[j]
        g[i] = (y[i] - known) / gain
        for j in range(k):
            q[j] = p[j] + b[j] * g[i]
    return g


def lag_feedback_inverse(time: npt.ArrayLike, signal: npt.ArrayLike,
                         time_constants: npt.ArrayLike, weights: npt.ArrayLike) -> FloatArray:
    """
    Return ``g`` with ``signal = g + sum_j w_j L_j[g]``, the lags settled at ``g_0``.

    The exact inverse of ``g + lag_bank(time, g, time_constants) @ weights``.

    Parameters
    ----------
    time : array_like of float, shape (N,)
        Sample times [s], strictly increasing.
    signal : array_like of float, shape (N,)
        The signal with the lags fed in (any unit).
    time_constants : array_like of float, shape (k,)
        Time constants [s], > 0.
    weights : array_like of float, shape (k,)
        Weights ``w_j >= 0`` [1].

    Returns
    -------
    ndarray of float, shape (N,)
        ``g``, in the unit of ``signal``.

    """
    return _lag_feedback_inverse(np.ascontiguousarray(time, dtype=np.float64),
                                 np.ascontiguousarray(signal, dtype=np.float64),
                                 np.ascontiguousarray(np.atleast_1d(time_constants),
                                                      dtype=np.float64),
                                 np.ascontiguousarray(np.atleast_1d(weights),
                                                      dtype=np.float64))


def first_order_lag(time: npt.ArrayLike, signal: npt.ArrayLike,
                    time_constant: float) -> FloatArray:
    """
    Filter a signal through one first-order lag ``tau dq/dt = u - q`` (identity if tau is 0).

    Parameters
    ----------
    time : array_like of float, shape (N,)
        Sample times [s].
    signal : array_like of float, shape (N,)
        Input (any unit).
    time_constant : float
        ``tau`` [s], >= 0.

    Returns
    -------
    ndarray of float, shape (N,)
        Filtered signal, same unit.

    """
    if time_constant <= 0.0:
        return np.array(signal, dtype=np.float64)
    return lag_bank(time, signal, [time_constant])[:, 0]


def delay(time: npt.ArrayLike, signal: npt.ArrayLike, dead_time: float) -> FloatArray:
    """
    Delay a signal by ``dead_time``: ``u(t - L)``, linearly interpolated, ``u_0`` before.

    Parameters
    ----------
    time : array_like of float, shape (N,)
        Sample times [s].
    signal : array_like of float, shape (N,)
        Signal (any unit).
    dead_time : float
        ``L`` [s], >= 0.

    Returns
    -------
    ndarray of float, shape (N,)
        The delayed signal.

    """
    t = np.asarray(time, dtype=np.float64)
    u = np.asarray(signal, dtype=np.float64)
    if dead_time <= 0.0:
        return u.copy()
    delayed: FloatArray = np.interp(t - dead_time, t, u, left=u[0])
    return delayed
