# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Analytic inverse of the MPI operator: transformation laws (12)-(14) and (22)-(25).

The inverse of a Prandtl-Ishlinskii hysteresis operator H is again such an
operator H' (11) whose thresholds, weights and initial states follow from
H's by the laws

- ``r'_Hi = sum_{j<=i} w_Hj (r_Hi - r_Hj)`` (12), i.e. ``r'_Hi = phi(r_Hi)``;
- ``w'_H0 = 1 / w_H0``, ``w'_Hi = -w_Hi / ((w_H0+...+w_Hi)(w_H0+...+w_Hi-1))`` (13);
- ``z'_H0i = (w_H0+...+w_Hi) z_H0i + sum_{j>i} w_Hj z_H0j`` (14).

The inverse of a superposition operator S is a superposition operator S' (20)
with laws (22)-(23) on the positive branch and (24)-(25) on the negative one.
The inverse MPI operator is ``Gamma^-1 = H' o S'`` (27).  No root finding is
involved anywhere: every law is a closed-form sum.

The laws are involutions: applying them to the inverse gives back the
original operator (checked in ``test/test_inverse.py``).
"""

import numba
import numpy as np
import numpy.typing as npt

from .hysteresis import PIHysteresisOperator
from .superposition import PISuperpositionOperator

__all__ = [
    'invert_hysteresis_thresholds', 'invert_hysteresis_weights',
    'invert_hysteresis_initial_states', 'invert_superposition_thresholds',
    'invert_superposition_weights', 'invert_hysteresis', 'invert_superposition',
    'hysteresis_inverse_laws', 'hysteresis_inverse_states',
]

FloatArray = npt.NDArray[np.float64]


@numba.njit(cache=True, nogil=True)
def hysteresis_inverse_laws(r: FloatArray, w: FloatArray, r_out: FloatArray,
                            w_out: FloatArray) -> None:  # pragma: no cover - compiled
    """
    Threshold law (12) and weight law (13), into ``r_out`` and ``w_out``.

    The one implementation of (12)-(13): :func:`invert_hysteresis`, the superposition
    laws (22)-(25) (the same sums per branch) and the extended compensators' per-step
    inverse call it.

    Parameters
    ----------
    r, w : ndarray of float, shape (n+1,)
        Thresholds and weights of H (every cumulative weight sum positive).
    r_out, w_out : ndarray of float, shape (n+1,)
        Receive ``r'_H`` and ``w'_H``.

    """
    cumulative = 0.0
    partial = 0.0
    for i in range(w.shape[0]):
        previous = cumulative
        cumulative += w[i]                                   # w_0 + ... + w_i
        partial += w[i] * r[i]
        r_out[i] = cumulative * r[i] - partial               # (12)
        w_out[i] = 1.0 / w[0] if i == 0 else -w[i] / (cumulative * previous)   # (13)


@numba.njit(cache=True, nogil=True)
def hysteresis_inverse_states(w: FloatArray, z: FloatArray,
                              out: FloatArray) -> None:  # pragma: no cover - compiled
    """
    Initial-state law (14), into ``out``: ``z'_i = (w_0+...+w_i) z_i + sum_{j>i} w_j z_j``.

    The one implementation of (14): :func:`invert_hysteresis_initial_states` and the
    compensators (which map the forward play state to the inverse one every step) call it.

    Parameters
    ----------
    w : ndarray of float, shape (n+1,)
        Weights of H.
    z : ndarray of float, shape (n+1,)
        Play outputs of H.
    out : ndarray of float, shape (n+1,)
        Receives the play outputs of H^-1.

    """
    cumulative = 0.0
    for i in range(w.shape[0]):                 # out holds w_0 + ... + w_i first
        cumulative += w[i]
        out[i] = cumulative
    tail = 0.0                                  # no allocation: this runs every command
    for i in range(w.shape[0] - 1, -1, -1):
        out[i] = out[i] * z[i] + tail
        tail += w[i] * z[i]


def invert_hysteresis_thresholds(thresholds: npt.ArrayLike,
                                 weights: npt.ArrayLike) -> FloatArray:
    """
    Threshold law (12): ``r'_Hi = sum_{j=0}^{i} w_Hj (r_Hi - r_Hj)``.

    Parameters
    ----------
    thresholds : array_like of float, shape (n+1,)
        ``r_H`` of H.
    weights : array_like of float, shape (n+1,)
        ``w_H`` of H.

    Returns
    -------
    ndarray of float, shape (n+1,)
        ``r'_H`` of H^-1.

    """
    r = np.ascontiguousarray(thresholds, dtype=np.float64)
    w = np.ascontiguousarray(weights, dtype=np.float64)
    r_out, w_out = np.empty_like(r), np.empty_like(w)
    hysteresis_inverse_laws(r, w, r_out, w_out)             # (12)
    return r_out


def invert_hysteresis_weights(weights: npt.ArrayLike) -> FloatArray:
    """
    Weight law (13).

    Parameters
    ----------
    weights : array_like of float, shape (n+1,)
        ``w_H`` of H (every cumulative sum positive).

    Returns
    -------
    ndarray of float, shape (n+1,)
        ``w'_H`` of H^-1.

    """
    w = np.ascontiguousarray(weights, dtype=np.float64)
    r_out, w_out = np.empty_like(w), np.empty_like(w)
    hysteresis_inverse_laws(np.zeros_like(w), w, r_out, w_out)   # (13)
    return w_out


def invert_hysteresis_initial_states(initial_states: npt.ArrayLike,
                                     weights: npt.ArrayLike) -> FloatArray:
    """
    Initial-state law (14): ``z'_i = (w_0+...+w_i) z_i + sum_{j>i} w_j z_j``.

    The same law maps any play state of H (not only the initial one) to the
    consistent play state of H^-1; the compensator uses it for bumpless model
    swaps.

    Parameters
    ----------
    initial_states : array_like of float, shape (n+1,)
        Play outputs ``z_H0`` of H [A].
    weights : array_like of float, shape (n+1,)
        ``w_H`` of H.

    Returns
    -------
    ndarray of float, shape (n+1,)
        Play outputs ``z'_H0`` of H^-1 [A].

    """
    z = np.ascontiguousarray(initial_states, dtype=np.float64)
    w = np.ascontiguousarray(weights, dtype=np.float64)
    out = np.empty_like(z)
    hysteresis_inverse_states(w, z, out)                    # (14)
    return out


def _branch_laws(r: FloatArray, w: FloatArray) -> tuple[FloatArray, FloatArray]:
    # One branch ordered outwards from the zero threshold: (22)-(23) or (24)-(25) are
    # the sums (12)-(13) over the branch.
    r = np.ascontiguousarray(r, dtype=np.float64)
    w = np.ascontiguousarray(w, dtype=np.float64)
    r_new, w_new = np.empty_like(r), np.empty_like(w)
    hysteresis_inverse_laws(r, w, r_new, w_new)
    return r_new, w_new


def invert_superposition_thresholds(thresholds: npt.ArrayLike,
                                    weights: npt.ArrayLike) -> FloatArray:
    """
    Threshold laws (22) (positive branch) and (24) (negative branch).

    Parameters
    ----------
    thresholds : array_like of float, shape (m,)
        ``r_S`` of S, ascending with exactly one 0.
    weights : array_like of float, shape (m,)
        ``w_S`` of S.

    Returns
    -------
    ndarray of float, shape (m,)
        ``r'_S`` of S^-1 (``r'_Si = S(r_Si)``), ascending with the 0 at the
        same index.

    """
    r = np.asarray(thresholds, dtype=np.float64)
    w = np.asarray(weights, dtype=np.float64)
    c = int(np.flatnonzero(r == 0.0)[0])
    out = np.empty_like(r)
    out[c:] = _branch_laws(r[c:], w[c:])[0]                       # (22)
    out[:c + 1] = _branch_laws(r[:c + 1][::-1], w[:c + 1][::-1])[0][::-1]   # (24)
    return out


def invert_superposition_weights(thresholds: npt.ArrayLike,
                                 weights: npt.ArrayLike) -> FloatArray:
    """
    Weight laws (23) (positive branch) and (25) (negative branch).

    Parameters
    ----------
    thresholds : array_like of float, shape (m,)
        ``r_S`` of S (locates the zero threshold).
    weights : array_like of float, shape (m,)
        ``w_S`` of S.

    Returns
    -------
    ndarray of float, shape (m,)
        ``w'_S`` of S^-1.

    """
    r = np.asarray(thresholds, dtype=np.float64)
    w = np.asarray(weights, dtype=np.float64)
    c = int(np.flatnonzero(r == 0.0)[0])
    out = np.empty_like(w)
    out[c:] = _branch_laws(r[c:], w[c:])[1]                             # (23)
    out[:c + 1] = _branch_laws(r[:c + 1][::-1], w[:c + 1][::-1])[1][::-1]   # (25)
    return out


def invert_hysteresis(operator: PIHysteresisOperator) -> PIHysteresisOperator:
    """
    Return H^-1 (11) by the laws (12)-(14).

    Parameters
    ----------
    operator : PIHysteresisOperator
        H, with a strictly increasing generator function.

    Returns
    -------
    PIHysteresisOperator
        H^-1.

    """
    r, w, z0 = operator.thresholds, operator.weights, operator.initial_states
    return PIHysteresisOperator(invert_hysteresis_thresholds(r, w),
                                invert_hysteresis_weights(w),
                                invert_hysteresis_initial_states(z0, w))


def invert_superposition(operator: PISuperpositionOperator) -> PISuperpositionOperator:
    """
    Return S^-1 (20) by the laws (22)-(25).

    Parameters
    ----------
    operator : PISuperpositionOperator
        S, strictly increasing (19).

    Returns
    -------
    PISuperpositionOperator
        S^-1.

    """
    r, w = operator.thresholds, operator.weights
    return PISuperpositionOperator(invert_superposition_thresholds(r, w),
                                   invert_superposition_weights(r, w))
