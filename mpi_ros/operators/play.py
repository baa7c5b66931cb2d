# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Play (backlash) operator, equations (1)-(4) of Kuhnen's paper.

The play operator with threshold ``r`` and initial state ``z0`` maps an input
sequence ``x`` to ``z[k] = max(x[k] - r, min(x[k] + r, z[k-1]))`` with
``z[-1] = z0`` (2)-(4): the initial condition (3) applies the sliding dead-zone
function to the first sample.  All functions here work on a vector of
thresholds at once (one play operator per threshold).

Batch and streaming forms share one compiled kernel, take the state in and
give it back, so a chunked run equals a one-shot run.
"""

import numba
import numpy as np
import numpy.typing as npt

__all__ = ['play_batch', 'play_end_state', 'play_operator', 'PlayOperatorStream', 'play_step',
           'play_clamp']

FloatArray = npt.NDArray[np.float64]


@numba.njit(cache=True, nogil=True, inline='always')
def play_clamp(x: float, r: float, z: float) -> float:  # pragma: no cover - compiled
    """
    Return one play operator's new output (2)-(4): ``max(x - r, min(x + r, z))``.

    The one implementation of the play rule: the batch and streaming plays, H (5), the
    MPI kernels and the compensators all call it.

    Parameters
    ----------
    x : float
        Input sample.
    r : float
        Threshold ``r >= 0``.
    z : float
        Output before the sample.

    Returns
    -------
    float
        Output after the sample.

    """
    # Selects, not branches (the same values): the compiled loops need no jumps.
    hi = x + r
    a = hi if z > hi else z
    lo = x - r
    return lo if a < lo else a


@numba.njit(cache=True, nogil=True)
def play_batch(x: FloatArray, r: FloatArray,
               z: FloatArray) -> FloatArray:  # pragma: no cover - compiled
    """
    Return the play operators' outputs for a batch, from the states ``z`` (4), compiled.

    Parameters
    ----------
    x : ndarray of float, shape (N,)
        Input, unit of the input.
    r : ndarray of float, shape (m,)
        Thresholds.
    z : ndarray of float, shape (m,)
        States before the first sample (updated in place to the states after the last).

    Returns
    -------
    ndarray of float, shape (N, m)
        The plays' outputs.

    """
    n_samples = x.shape[0]
    m = r.shape[0]
    out = np.empty((n_samples, m))
    for k in range(n_samples):
        xk = x[k]
        for i in range(m):
            z[i] = play_clamp(xk, r[i], z[i])
            out[k, i] = z[i]
    return out


@numba.njit(cache=True, nogil=True)
def _play_run(x: FloatArray, r: FloatArray, z: FloatArray) -> None:  # pragma: no cover - compiled
    # The plays over a sequence, keeping only their state (no N x m output to write).
    for k in range(x.shape[0]):
        xk = x[k]
        for i in range(r.shape[0]):
            z[i] = play_clamp(xk, r[i], z[i])


@numba.njit(cache=True, nogil=True)
def play_step(x: float, r: FloatArray, z: FloatArray) -> None:  # pragma: no cover - compiled
    """
    Advance the play operators by one sample, in place (4).

    Parameters
    ----------
    x : float
        Input sample.
    r : ndarray of float, shape (m,)
        Thresholds, unit of the input.
    z : ndarray of float, shape (m,)
        Play outputs before the sample; overwritten with the new outputs.

    """
    for i in range(r.shape[0]):
        z[i] = play_clamp(x, r[i], z[i])


def play_operator(x: npt.ArrayLike, thresholds: npt.ArrayLike,
                  initial_states: npt.ArrayLike | None = None) -> tuple[FloatArray, FloatArray]:
    """
    Apply play operators with several thresholds to a whole input sequence.

    Parameters
    ----------
    x : array_like of float, shape (N,)
        Input sequence (e.g. coil current [A]).
    thresholds : array_like of float, shape (m,)
        Thresholds ``r >= 0``, unit of the input.
    initial_states : array_like of float, shape (m,), optional
        Play outputs before the first sample, unit of the input.  Default:
        zeros, the demagnetised state (32).

    Returns
    -------
    z : ndarray of float, shape (N, m)
        Play outputs, one column per threshold.
    z_end : ndarray of float, shape (m,)
        Play outputs after the last sample (pass as ``initial_states`` to
        continue).

    Examples
    --------
    >>> z, z_end = play_operator([0.0, 1.0, 0.5], [0.0, 0.25])
    >>> z[:, 1].tolist()
    [0.0, 0.75, 0.75]

    """
    x_arr = np.ascontiguousarray(x, dtype=np.float64).reshape(-1)
    r = np.ascontiguousarray(thresholds, dtype=np.float64).reshape(-1)
    z = (np.zeros_like(r) if initial_states is None
         else np.array(initial_states, dtype=np.float64).reshape(-1))
    out = play_batch(x_arr, r, z)
    return out, z


def play_end_state(x: npt.ArrayLike, thresholds: npt.ArrayLike,
                   initial_states: npt.ArrayLike | None = None) -> FloatArray:
    """
    Return the play outputs after a whole input sequence (:func:`play_operator`'s ``z_end``).

    The outputs along the way are not kept: a long sequence costs no ``N x m`` array.

    Parameters
    ----------
    x : array_like of float, shape (N,)
        Input sequence.
    thresholds : array_like of float, shape (m,)
        Thresholds ``r >= 0``, unit of the input.
    initial_states : array_like of float, shape (m,), optional
        Play outputs before the first sample; zeros (32) by default.

    Returns
    -------
    ndarray of float, shape (m,)
        Play outputs after the last sample.

    """
    x_arr = np.ascontiguousarray(x, dtype=np.float64).reshape(-1)
    r = np.ascontiguousarray(thresholds, dtype=np.float64).reshape(-1)
    z = (np.zeros_like(r) if initial_states is None
         else np.array(initial_states, dtype=np.float64).reshape(-1))
    _play_run(x_arr, r, z)
    return z


class PlayOperatorStream:
    """
    Streaming form of :func:`play_operator`: one sample at a time.

    Parameters
    ----------
    thresholds : array_like of float, shape (m,)
        Thresholds ``r >= 0``, unit of the input.
    initial_states : array_like of float, shape (m,), optional
        Play outputs before the first sample; zeros by default (32).

    """

    def __init__(self, thresholds: npt.ArrayLike,
                 initial_states: npt.ArrayLike | None = None) -> None:
        self._r = np.ascontiguousarray(thresholds, dtype=np.float64).reshape(-1)
        self._z0 = (np.zeros_like(self._r) if initial_states is None
                    else np.array(initial_states, dtype=np.float64).reshape(-1))
        self._z = self._z0.copy()

    @property
    def state(self) -> FloatArray:
        """Return the current play outputs (a read-only copy)."""
        z = self._z.copy()
        z.flags.writeable = False
        return z

    def reset(self, state: npt.ArrayLike | None = None) -> None:
        """Reset to the initial states, or to ``state`` when given."""
        self._z[:] = self._z0 if state is None else np.asarray(state, dtype=np.float64)

    def step(self, x: float) -> FloatArray:
        """Advance by one input sample and return the play outputs (a copy)."""
        play_step(float(x), self._r, self._z)
        return self._z.copy()
