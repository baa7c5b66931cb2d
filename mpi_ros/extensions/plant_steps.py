# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Streaming building blocks of the effects' plant steps: exact first-order lags and a delay.

The effects' :class:`~mpi_ros.extensions.effect.PlantEffect` passes run on chunks of samples
and carry their state from chunk to chunk, so that a chunked run equals one run (the plant
simulator node advances the plant one sample per command).

Each first-order lag ``tau dy/dt = u - y`` is advanced exactly for an input that is linear
between samples (first-order hold): with ``h = t_k - t_{k-1}``, ``a = exp(-h / tau)`` and
slope ``q = (u_k - u_{k-1}) / h``,

``y_k = a y_{k-1} + (1 - a) u_k + q (a h - tau (1 - a))``.

Before the first sample the plant was at rest; the first sample is applied with no elapsed
time, so a lag starts from rest (``y_0 = 0``).  The delay interpolates linearly on the
sampled stream and reads 0 before the first sample.
"""

from collections import deque
import math
from typing import Any

import numba
import numpy as np
import numpy.typing as npt

__all__ = ['lag_state', 'lag_stream', 'lag_add', 'lag_bank_add',
           'delay_state', 'delay_stream']

FloatArray = npt.NDArray[np.float64]


def lag_state(lags: int = 1) -> FloatArray:
    """
    Return the state of a lag (bank) at rest.

    Parameters
    ----------
    lags : int
        Number of lags sharing one input (a bank); 1 for a single lag.

    Returns
    -------
    ndarray of float, shape (3 + lags,)
        ``[has previous sample, its time [s], its input, output of lag 1, ...]``, zeros.

    """
    return np.zeros(3 + lags)


@numba.njit(cache=True, nogil=True)
def _lag(y0: float, u0: float, u1: float, h: float,
         tau: float) -> float:  # pragma: no cover - compiled
    """Exact first-order-lag update for an input linear between samples (first-order hold)."""
    a = math.exp(-h / tau)
    one_minus_a = -math.expm1(-h / tau)
    slope = (u1 - u0) / h
    return a * y0 + one_minus_a * u1 + slope * (a * h - tau * one_minus_a)


@numba.njit(cache=True, nogil=True)
def lag_stream(time: FloatArray, signal: FloatArray, tau: float,
               state: FloatArray) -> FloatArray:  # pragma: no cover - compiled
    """
    Return the output of one first-order lag over a chunk; advance its state in place.

    Parameters
    ----------
    time : ndarray of float, shape (N,)
        Sample times [s], after the state's previous sample.
    signal : ndarray of float, shape (N,)
        Lag input.
    tau : float
        Time constant [s], > 0.
    state : ndarray of float, shape (4,)
        :func:`lag_state` ``()``, updated.

    Returns
    -------
    ndarray of float, shape (N,)
        Lag output (0 at the very first sample).

    """
    n = time.shape[0]
    out = np.empty(n)
    for k in range(n):
        if state[0] > 0.0:
            state[3] = _lag(state[3], state[2], signal[k], time[k] - state[1], tau)
        state[0] = 1.0
        state[1] = time[k]
        state[2] = signal[k]
        out[k] = state[3]
    return out


@numba.njit(cache=True, nogil=True)
def lag_add(time: FloatArray, driver: FloatArray, tau: float, gain: float, state: FloatArray,
            signal: FloatArray) -> FloatArray:  # pragma: no cover - compiled
    """
    Return ``signal + gain y`` for the first-order lag ``y`` of ``driver``; advance its state.

    Parameters
    ----------
    time : ndarray of float, shape (N,)
        Sample times [s], after the state's previous sample.
    driver : ndarray of float, shape (N,)
        Lag input.
    tau : float
        Time constant [s], > 0.
    gain : float
        Factor of the lag output.
    state : ndarray of float, shape (4,)
        :func:`lag_state` ``()``, updated.
    signal : ndarray of float, shape (N,)
        The signal the lag adds to (left unchanged).

    Returns
    -------
    ndarray of float, shape (N,)
        ``signal + gain * y``.

    """
    n = time.shape[0]
    out = np.empty(n)
    for k in range(n):
        if state[0] > 0.0:
            state[3] = _lag(state[3], state[2], driver[k], time[k] - state[1], tau)
        state[0] = 1.0
        state[1] = time[k]
        state[2] = driver[k]
        out[k] = signal[k] + gain * state[3]
    return out


@numba.njit(cache=True, nogil=True)
def lag_bank_add(time: FloatArray, driver: FloatArray, taus: FloatArray, gain: float,
                 state: FloatArray, signal: FloatArray) -> FloatArray:  # pragma: no cover
    """
    Return ``signal + gain mean_j y_j`` for a bank of lags of one input; advance the state.

    Parameters
    ----------
    time : ndarray of float, shape (N,)
        Sample times [s], after the state's previous sample.
    driver : ndarray of float, shape (N,)
        Common input of the lags.
    taus : ndarray of float, shape (k,)
        Time constants [s], > 0.
    gain : float
        Factor of the lags' mean.
    state : ndarray of float, shape (3 + k,)
        :func:`lag_state` ``(k)``, updated.
    signal : ndarray of float, shape (N,)
        The signal the bank adds to (left unchanged).

    Returns
    -------
    ndarray of float, shape (N,)
        ``signal + gain * (sum_j y_j) / k``, summed in the order of ``taus``.

    """
    n = time.shape[0]
    count = taus.shape[0]
    out = np.empty(n)
    for k in range(n):
        has_prev = state[0] > 0.0
        h = time[k] - state[1]
        acc = 0.0
        for j in range(count):
            if has_prev:
                state[3 + j] = _lag(state[3 + j], state[2], driver[k], h, taus[j])
            acc += state[3 + j]
        state[0] = 1.0
        state[1] = time[k]
        state[2] = driver[k]
        out[k] = signal[k] + gain * acc / count
    return out


def delay_state() -> dict[str, Any]:
    """Return the history buffer of :func:`delay_stream`, empty (at rest)."""
    return {'time': deque(), 'value': deque()}


def delay_stream(state: dict[str, Any], time: FloatArray, signal: FloatArray,
                 dead_time: float) -> FloatArray:
    """
    Return a chunk of a signal delayed by ``dead_time``, using and updating the history.

    Parameters
    ----------
    state : dict
        :func:`delay_state` ``()``, updated (it keeps only what later samples still need).
    time : ndarray of float, shape (N,)
        Sample times [s], after the previous chunk's.
    signal : ndarray of float, shape (N,)
        The signal.
    dead_time : float
        Delay [s], > 0.

    Returns
    -------
    ndarray of float, shape (N,)
        ``signal(t - dead_time)``, linearly interpolated, 0 before the first sample.

    """
    times: deque[float] = state['time']
    values: deque[float] = state['value']
    hist_t = np.concatenate([np.fromiter(times, float, len(times)), time])
    hist_v = np.concatenate([np.fromiter(values, float, len(values)), signal])
    delayed: FloatArray = np.interp(time - dead_time, hist_t, hist_v, left=0.0)
    # Keep only what later samples can still need: the last point at or before t[-1] - L.
    keep_from = max(int(np.searchsorted(hist_t, time[-1] - dead_time, side='right')) - 1, 0)
    times.clear()
    values.clear()
    times.extend(hist_t[keep_from:].tolist())
    values.extend(hist_v[keep_from:].tolist())
    return delayed
