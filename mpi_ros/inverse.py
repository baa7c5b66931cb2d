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

import numpy as np
import numpy.typing as npt

from .hysteresis import PIHysteresisOperator
from .superposition import PISuperpositionOperator

__all__ = [
    'invert_hysteresis_thresholds', 'invert_hysteresis_weights',
    'invert_hysteresis_initial_states', 'invert_superposition_thresholds',
    'invert_superposition_weights', 'invert_hysteresis', 'invert_superposition',
]

FloatArray = npt.NDArray[np.float64]


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
    r = np.asarray(thresholds, dtype=np.float64)
    w = np.asarray(weights, dtype=np.float64)
    diffs = r[:, None] - r[None, :]                         # r_Hi - r_Hj
    return np.sum(np.tril(diffs) * w[None, :], axis=1)      # (12)


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
    w = np.asarray(weights, dtype=np.float64)
    cumulative = np.cumsum(w)                               # w_H0 + ... + w_Hi
    out = np.empty_like(w)
    out[0] = 1.0 / w[0]                                     # (13), i = 0
    out[1:] = -w[1:] / (cumulative[1:] * cumulative[:-1])  # (13), i = 1..n
    return out


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
    z = np.asarray(initial_states, dtype=np.float64)
    w = np.asarray(weights, dtype=np.float64)
    wz = w * z
    tail = np.concatenate([np.cumsum(wz[::-1])[::-1][1:], [0.0]])   # sum_{j>i} w_j z_j
    return np.cumsum(w) * z + tail                                  # (14)


def _branch_laws(r: FloatArray, w: FloatArray) -> tuple[FloatArray, FloatArray]:
    # One branch ordered outwards from the zero threshold: (22)-(23) or (24)-(25).
    r_new = invert_hysteresis_thresholds(r, w)
    w_new = invert_hysteresis_weights(w)
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
    out[c:] = invert_hysteresis_weights(w[c:])                      # (23)
    out[:c + 1] = invert_hysteresis_weights(w[:c + 1][::-1])[::-1]  # (25)
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
