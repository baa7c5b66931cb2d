# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Prandtl-Ishlinskii hysteresis operator H, equations (5)-(8) of Kuhnen's paper.

``H[x](t) = w_H^T . H_rH[x, z_H0](t)`` (5): a weighted superposition of play
operators with thresholds ``0 = r_H0 < r_H1 < ... < r_Hn``.  Its initial
loading curve is the generator function ``phi`` (6), whose slope on
``[r_Hi, r_Hi+1)`` is the cumulative weight ``w_H0 + ... + w_Hi`` (7).

Units (see ``docs/design.md``): H maps the actuator input (A) to the same
unit; thresholds and initial states are in A and weights are dimensionless.
"""

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from .play import play_batch
from .vectors import frozen_vector
from ..errors import ModelError

__all__ = ['PIHysteresisOperator']

FloatArray = npt.NDArray[np.float64]


@dataclass(frozen=True, eq=False)
class PIHysteresisOperator:
    """
    Threshold-discrete Prandtl-Ishlinskii hysteresis operator H (5).

    Parameters
    ----------
    thresholds : array_like of float, shape (n+1,)
        Play thresholds ``r_H``, strictly ascending from exactly 0 [A].
    weights : array_like of float, shape (n+1,)
        Weights ``w_H`` [dimensionless]; every cumulative sum (7) must be
        positive so the generator function is strictly increasing.
    initial_states : array_like of float, shape (n+1,), optional
        Play outputs ``z_H0`` before the first sample [A]; zeros (32) by
        default.

    Raises
    ------
    ModelError
        When lengths differ, values are not finite, thresholds do not start at
        0 or do not ascend, or the generator function is not strictly
        increasing.

    """

    thresholds: FloatArray
    weights: FloatArray
    initial_states: FloatArray

    def __init__(self, thresholds: npt.ArrayLike, weights: npt.ArrayLike,
                 initial_states: npt.ArrayLike | None = None) -> None:
        r = frozen_vector(thresholds, 'hysteresis thresholds')
        w = frozen_vector(weights, 'hysteresis weights')
        z0 = frozen_vector(np.zeros_like(r) if initial_states is None else initial_states,
                           'hysteresis initial states')
        if not (r.size == w.size == z0.size):
            msg = (f'hysteresis thresholds, weights and initial states must have equal lengths;'
                   f' found {r.size}, {w.size} and {z0.size}')
            raise ModelError(msg)
        if r[0] != 0.0:
            msg = f'hysteresis thresholds must start at exactly 0 (r_H0 = 0); found {r[0]!r}'
            raise ModelError(msg)
        steps = np.diff(r)
        if np.any(steps <= 0.0):
            i = int(np.flatnonzero(steps <= 0.0)[0])
            msg = (f'hysteresis thresholds must be strictly ascending; found {r[i]!r} then'
                   f' {r[i + 1]!r} at indices {i} and {i + 1}')
            raise ModelError(msg)
        slopes = np.cumsum(w)
        if np.any(slopes <= 0.0):
            i = int(np.flatnonzero(slopes <= 0.0)[0])
            msg = (f'hysteresis weights must keep every cumulative sum positive (a strictly'
                   f' increasing generator function); w_H0 + ... + w_H{i} = {slopes[i]!r}')
            raise ModelError(msg)
        object.__setattr__(self, 'thresholds', r)
        object.__setattr__(self, 'weights', w)
        object.__setattr__(self, 'initial_states', z0)

    @property
    def order(self) -> int:
        """Model order ``n`` (the number of play operators minus one)."""
        return int(self.thresholds.size - 1)

    @property
    def slopes(self) -> FloatArray:
        """Slopes of the generator function on each threshold interval (7)."""
        return np.cumsum(self.weights)

    def generator_function(self, r: npt.ArrayLike) -> FloatArray:
        """
        Evaluate the generator function (initial loading curve) ``phi`` (6).

        Parameters
        ----------
        r : array_like of float
            Arguments ``r >= 0`` [A].

        Returns
        -------
        ndarray of float
            ``phi(r) = sum_j w_Hj * max(r - r_Hj, 0)`` [A].

        """
        r_arr = np.asarray(r, dtype=np.float64)
        return np.maximum(r_arr[..., None] - self.thresholds, 0.0) @ self.weights

    def play_outputs(self, x: npt.ArrayLike,
                     state: npt.ArrayLike | None = None) -> tuple[FloatArray, FloatArray]:
        """
        Return the play outputs ``H_rH[x, z]`` as a matrix and the final state.

        Parameters
        ----------
        x : array_like of float, shape (N,)
            Input [A].
        state : array_like of float, shape (n+1,), optional
            Play outputs before the first sample; the initial states by default.

        Returns
        -------
        z : ndarray of float, shape (N, n+1)
            Play outputs [A].
        z_end : ndarray of float, shape (n+1,)
            Play outputs after the last sample [A].

        """
        x_arr = np.ascontiguousarray(x, dtype=np.float64).reshape(-1)
        z = np.array(self.initial_states if state is None else state, dtype=np.float64)
        out = play_batch(x_arr, np.ascontiguousarray(self.thresholds), z)
        return out, z

    def apply(self, x: npt.ArrayLike,
              state: npt.ArrayLike | None = None) -> tuple[FloatArray, FloatArray]:
        """
        Apply H (5) to an input sequence.

        Parameters
        ----------
        x, state
            As for :meth:`play_outputs`: input [A], play outputs before it.

        Returns
        -------
        y : ndarray of float, shape (N,)
            ``H[x]`` [A].
        z_end : ndarray of float, shape (n+1,)
            Play outputs after the last sample [A].

        """
        z, z_end = self.play_outputs(x, state)
        return z @ self.weights, z_end

    def satisfies_constraints(self, epsilon: float = 0.0) -> bool:
        """
        Check the inequality constraints (8): ``w_H0 > epsilon``, ``w_Hi >= 0``.

        Parameters
        ----------
        epsilon : float
            The small positive bound of (8).

        Returns
        -------
        bool
            True when (8) holds (the generator function is convex).

        """
        return bool(self.weights[0] > epsilon and np.all(self.weights[1:] >= 0.0))
