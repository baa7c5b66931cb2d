# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Turning-point memory of an input history (the wiping-out property of play operators).

A play operator's output depends on the input history only through its
alternating sequence of dominant extrema (turning points): a closed minor loop
is wiped out once the input passes the extremum that opened it.  Replaying the
stored turning points through *any* Prandtl-Ishlinskii hysteresis operator
gives exactly the play states the full history would give.  The compensator
uses this to start a newly pushed model from the operating point (bumpless
swap).

The first stored point is the first input after the start state and is never
wiped (the start state is arbitrary); a pair of later turning points is wiped
when the input passes the first of them and the pair is nested inside the
preceding segment.
"""

import numba
import numpy as np
import numpy.typing as npt

__all__ = ['TurningPointMemory', 'memory_push']

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]


@numba.njit(cache=True, nogil=True)
def memory_push(points: FloatArray, state: IntArray,
                x: float) -> None:  # pragma: no cover - compiled
    """
    Record one input sample in a turning-point buffer (the one rule, compiled).

    Parameters
    ----------
    points : ndarray of float, shape (capacity + 1,)
        The stored points in ``points[:state[0]]``.
    state : ndarray of int, shape (2,)
        Number of stored points; 1 once the capacity was exceeded.
    x : float
        Input sample (finite).

    """
    n = state[0]
    if n >= 2 and (points[n - 1] - points[n - 2]) * (x - points[n - 1]) >= 0.0:
        points[n - 1] = x                   # the current monotone segment goes on
    elif n >= 1 and x == points[n - 1]:
        return
    else:
        points[n] = x                       # a reversal: the last input is a turning point
        n += 1
    while n >= 4:
        a, b, c, cur = points[n - 4], points[n - 3], points[n - 2], points[n - 1]
        nested = (c - a) * (b - c) >= 0.0
        passed = (cur - b) * (b - c) >= 0.0
        if not (nested and passed):
            break
        points[n - 3] = cur                 # the minor loop b -> c is wiped out
        n -= 2
    if n > points.shape[0] - 1:             # over capacity: forget the oldest interior pair
        for i in range(1, n - 2):
            points[i] = points[i + 2]
        n -= 2
        state[1] = 1
    state[0] = n


@numba.njit(cache=True, nogil=True)
def _memory_extend(points: FloatArray, state: IntArray,
                   values: FloatArray) -> None:  # pragma: no cover - compiled
    for k in range(values.shape[0]):
        memory_push(points, state, values[k])


class TurningPointMemory:
    """
    Bounded record of the turning points of an input sequence.

    The points live in a numpy buffer updated by the compiled :func:`memory_push`, so
    the compensators' compiled loops record them too (a multi-axis compensator keeps
    every axis's buffer as one row of a block: ``points`` and ``state`` may be views).

    Parameters
    ----------
    capacity : int
        Largest number of stored points.  When exceeded (only possible for
        growing oscillations around the first point), the oldest interior
        points are dropped and the replay is no longer exact for the widest
        thresholds; ``overflowed`` tells.
    points, state : ndarray, optional
        Storage to use: ``capacity + 1`` floats and 2 integers (number of points,
        overflow flag), e.g. rows of a multi-axis block; new arrays by default.

    """

    def __init__(self, capacity: int = 4096, *, points: FloatArray | None = None,
                 state: IntArray | None = None) -> None:
        self.capacity = int(capacity)
        self.buffer = np.zeros(self.capacity + 1) if points is None else points
        self.state = np.zeros(2, dtype=np.int64) if state is None else state
        if self.buffer.shape != (self.capacity + 1,) or self.state.shape != (2,):
            msg = (f'a turning-point memory of capacity {self.capacity} needs'
                   f' {self.capacity + 1} points and 2 state entries')
            raise ValueError(msg)

    def __len__(self) -> int:
        """Return the number of stored turning points (including the current input)."""
        return int(self.state[0])

    @property
    def overflowed(self) -> bool:
        """Tell whether the capacity was exceeded (the replay is no longer exact)."""
        return bool(self.state[1])

    @property
    def points(self) -> FloatArray:
        """Return the stored points: first input, turning points, current input (a copy)."""
        return self.buffer[:len(self)].copy()

    def clear(self) -> None:
        """Forget the history (back to the start state)."""
        self.state[:] = 0

    def push(self, x: float) -> None:
        """
        Record one input sample.

        Parameters
        ----------
        x : float
            Input sample (finite).

        """
        memory_push(self.buffer, self.state, float(x))

    def extend(self, values: npt.ArrayLike) -> None:
        """
        Record a sequence of input samples, as :meth:`push` on each would.

        Parameters
        ----------
        values : array_like of float, shape (K,)
            Input samples (finite).

        """
        _memory_extend(self.buffer, self.state,
                       np.ascontiguousarray(values, dtype=np.float64).reshape(-1))
