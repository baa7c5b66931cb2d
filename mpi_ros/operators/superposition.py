# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Prandtl-Ishlinskii superposition operator S, equations (15)-(19) of Kuhnen's paper.

``S[x](t) = w_S^T . S_rS[x](t)`` (18): a weighted superposition of one-sided
dead-zone operators with thresholds ``r_S-l < ... < r_S0 = 0 < ... < r_Sl``.
It is a memory-free, piecewise linear, strictly increasing map when every
cumulative weight counted outwards from ``w_S0`` is positive (19).

Units (see ``docs/design.md``): inside the MPI model S maps H's output (A) to
the actuator output (m); thresholds in A, weights in m/A.  The number of
negative and positive thresholds may differ (the paper uses ``l`` of each).
"""

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from .deadzone import dead_zone_operator
from .vectors import frozen_vector
from ..errors import ModelError

__all__ = ['PISuperpositionOperator']

FloatArray = npt.NDArray[np.float64]


@dataclass(frozen=True, eq=False)
class PISuperpositionOperator:
    """
    Threshold-discrete Prandtl-Ishlinskii superposition operator S (18).

    Parameters
    ----------
    thresholds : array_like of float, shape (m,)
        Dead-zone thresholds ``r_S``, strictly ascending, containing exactly
        one 0 [unit of the input].
    weights : array_like of float, shape (m,)
        Weights ``w_S`` [output unit per input unit]; the slope of every
        linear piece (cumulative sums counted outwards from the 0 threshold)
        must be positive (19).

    Raises
    ------
    ModelError
        When lengths differ, values are not finite, thresholds are not strictly
        ascending or do not contain exactly one 0, or a piece is not strictly
        increasing.

    """

    thresholds: FloatArray
    weights: FloatArray

    def __init__(self, thresholds: npt.ArrayLike, weights: npt.ArrayLike) -> None:
        r = frozen_vector(thresholds, 'superposition thresholds')
        w = frozen_vector(weights, 'superposition weights')
        if r.size != w.size:
            msg = (f'superposition thresholds and weights must have equal lengths;'
                   f' found {r.size} and {w.size}')
            raise ModelError(msg)
        zeros = int(np.count_nonzero(r == 0.0))
        if zeros != 1:
            msg = (f'superposition thresholds must contain exactly one 0; found'
                   f' {"none" if zeros == 0 else zeros}')
            raise ModelError(msg)
        steps = np.diff(r)
        if np.any(steps <= 0.0):
            i = int(np.flatnonzero(steps <= 0.0)[0])
            msg = (f'superposition thresholds must be strictly ascending; found {r[i]!r} then'
                   f' {r[i + 1]!r} at indices {i} and {i + 1}')
            raise ModelError(msg)
        object.__setattr__(self, 'thresholds', r)
        object.__setattr__(self, 'weights', w)
        slopes = self.slopes
        if np.any(slopes <= 0.0):
            i = int(np.flatnonzero(slopes <= 0.0)[0])
            msg = (f'superposition weights must give every linear piece a positive slope (19);'
                   f' the piece at threshold {r[i]!r} has slope {slopes[i]!r}')
            raise ModelError(msg)

    @property
    def center(self) -> int:
        """Index of the zero threshold ``r_S0``."""
        return int(np.flatnonzero(self.thresholds == 0.0)[0])

    @property
    def slopes(self) -> FloatArray:
        """
        Slope of the piece that starts at each threshold, counted outwards (19).

        For index ``i >= 0`` (relative to the zero threshold) the slope on
        ``[r_Si, r_Si+1)`` is ``w_S0 + ... + w_Si``; for ``i < 0`` the slope on
        ``(r_Si-1, r_Si]`` is ``w_Si + ... + w_S0``.
        """
        c = self.center
        w = self.weights
        out = np.empty_like(w)
        out[c:] = np.cumsum(w[c:])
        out[:c + 1] = np.cumsum(w[:c + 1][::-1])[::-1]
        return out

    @property
    def order(self) -> int:
        """Model order ``l`` (the larger of the negative and positive counts)."""
        c = self.center
        return int(max(c, self.thresholds.size - 1 - c))

    def apply(self, x: npt.ArrayLike) -> FloatArray:
        """
        Apply S (18) to an input sequence.

        Parameters
        ----------
        x : array_like of float, shape (N,)
            Input.

        Returns
        -------
        ndarray of float, shape (N,)
            ``S[x]``.

        """
        return dead_zone_operator(x, self.thresholds) @ self.weights

    def satisfies_constraints(self, epsilon: float = 0.0) -> bool:
        """Check (19): every piece's slope is larger than ``epsilon``."""
        return bool(np.all(self.slopes > epsilon))
