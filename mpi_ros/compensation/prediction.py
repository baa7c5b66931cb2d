# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Dead-time compensation by prediction: the desired displacement extrapolated a dead time ahead.

A dead time ``L`` has no causal inverse: ``s(t) = Gamma[x](t - L)`` needs the command
``x(t) = Gamma^-1[s_c](t + L)``, the desired displacement of the future.  On a smooth
desired trajectory the future is predictable: a straight line fitted by least squares to
the last ``N`` desired values, evaluated ``L`` ahead, ``p_k = sum_j c_j s_c(k - j)``
(:func:`prediction_weights`), is exact on ramps and averages noise over the window.

The time base is the stream's own: ``N`` samples ``sample_period`` apart, the horizon
``L / sample_period`` samples; no clock is read, so a late or bunched message changes
nothing (:mod:`mpi_ros.compensation.message_time`).

The bound: the prediction moves from the newest value by at most the horizon times the
median step of the window, ``|p_k - s_c(k)| <= (L / T) median_j |s_c(j) - s_c(j - 1)|``.
On a ramp every step is the same, so a straight line is never cut; a step of the desired
displacement is one large difference among small ones, so the prediction stays at the new
value (the command is Gamma^-1 of the desired value itself, as without prediction), and
neither a late nor a bunched message changes it.  The compensator then keeps the
prediction inside the model's displacement range.

A desired stream held in stairs (a slower planner's values repeated at the stream's rate)
has median step 0 and is not predicted: send it at its own rate (``sample_period``) or
smooth it.  Measured numbers: docs/diagnosis.md (issue 24, the loop).
"""

import bisect
from collections import deque
import math

import numpy as np
import numpy.typing as npt

from ..errors import ModelError

__all__ = ['DeadTimePredictor', 'prediction_horizon', 'prediction_weights', 'MAX_WINDOW',
           'MIN_WINDOW', 'WINDOW_FACTOR']

FloatArray = npt.NDArray[np.float64]

#: The window spans at least this many horizons (``N - 1 >= WINDOW_FACTOR L / T``): two
#: tracked closest to the oracle (three: 1.03 % where two gave 0.89 % at 29 ms).
WINDOW_FACTOR = 2.0
#: ... and at least this many samples (noise gain below 1 for short dead times) ...
MIN_WINDOW = 8
#: ... and at most this many (a long dead time on a fast stream).
MAX_WINDOW = 4001


def prediction_weights(window: int, horizon: float) -> FloatArray:
    """
    Return the weights of the least-squares straight line evaluated ``horizon`` ahead.

    Parameters
    ----------
    window : int
        Samples ``N`` >= 2 of the fit, the newest last.
    horizon : float
        How far ahead [samples], >= 0.

    Returns
    -------
    ndarray of float, shape (N,)
        ``c`` with ``p = c @ s`` for the window ``s`` (oldest first); ``sum(c) = 1``.

    Examples
    --------
    >>> c = prediction_weights(4, 2.0)
    >>> float(round(c @ [0.0, 1.0, 2.0, 3.0], 12))      # a ramp: exact
    5.0

    """
    k = np.arange(1 - window, 1, dtype=np.float64)
    design = np.vstack([np.ones(window), k]).T
    weights: FloatArray = np.array([1.0, horizon]) @ np.linalg.pinv(design)
    return weights


def prediction_horizon(model: object) -> float:
    """
    Return the dead time [s] a model's compensator predicts over (0: none).

    A dead-time model's ``dead_time``; a composite's, the sum of its dead-time parts'.

    Parameters
    ----------
    model : MPIModel or extended model
        A model.

    Returns
    -------
    float
        The dead time [s], >= 0.

    """
    parts = getattr(model, 'parts', None) or (model,)
    return float(sum(float(getattr(part, 'dead_time', 0.0)) for part in parts))


class DeadTimePredictor:
    """
    The desired displacement extrapolated a dead time ahead, bounded (see the module).

    Parameters
    ----------
    dead_time : float
        ``L`` [s], > 0.
    sample_period : float
        ``T`` [s] between two desired values (the stream's nominal spacing), > 0.

    Attributes
    ----------
    window : int
        Samples ``N`` of the fit.
    horizon : float
        ``L / T`` [samples].

    """

    def __init__(self, dead_time: float, sample_period: float) -> None:
        if not (math.isfinite(dead_time) and dead_time > 0.0
                and math.isfinite(sample_period) and sample_period > 0.0):
            msg = (f'a dead-time prediction needs a finite dead time > 0 and sample period'
                   f' > 0 [s]; found {dead_time!r} and {sample_period!r}')
            raise ModelError(msg)
        self.horizon = float(dead_time) / float(sample_period)
        self.window = min(max(MIN_WINDOW, int(math.ceil(WINDOW_FACTOR * self.horizon)) + 1),
                          MAX_WINDOW)
        self._weights = prediction_weights(self.window, self.horizon)
        self._values = np.zeros(self.window)
        self._count = 0
        # The window's steps |s_j - s_(j-1)|, in order and sorted (the median in O(N)).
        self._steps: deque[float] = deque()
        self._sorted: list[float] = []

    def _fill(self, values: FloatArray) -> None:
        self._values[:] = values
        steps = np.abs(np.diff(values)).tolist()
        self._steps = deque(steps)
        self._sorted = sorted(steps)
        self._count = self.window

    @property
    def values(self) -> FloatArray:
        """Return the desired values in the window [m], oldest first (a copy)."""
        return self._values.copy() if self._count else np.zeros(0)

    def seed(self, values: npt.ArrayLike) -> None:
        """
        Fill the window with earlier desired values [m] (oldest first; e.g. a handover).

        Fewer values than the window repeat the oldest; none leave it empty.

        """
        given = np.asarray(values, dtype=np.float64).reshape(-1)[-self.window:]
        if given.size == 0:
            self._count = 0
            return
        window = np.full(self.window, given[0])
        window[self.window - given.size:] = given
        self._fill(window)

    def predict(self, desired: float) -> float:
        """
        Take the newest desired displacement [m]; return it predicted a dead time ahead.

        The first value fills the window (a hold: its prediction is itself).

        """
        s = self._values
        if self._count == 0:
            self._fill(np.full(self.window, desired))
        else:
            step = abs(desired - float(s[-1]))
            s[:-1] = s[1:]
            s[-1] = desired
            ordered = self._sorted
            del ordered[bisect.bisect_left(ordered, self._steps.popleft())]
            bisect.insort(ordered, step)
            self._steps.append(step)
        p = float(self._weights @ s)
        ordered = self._sorted
        half = len(ordered) // 2
        median = ordered[half] if len(ordered) % 2 else 0.5 * (ordered[half - 1] + ordered[half])
        reach = self.horizon * median
        return min(max(p, desired - reach), desired + reach)
