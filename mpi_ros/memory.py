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

import numpy as np
import numpy.typing as npt

__all__ = ['TurningPointMemory']


class TurningPointMemory:
    """
    Bounded record of the turning points of an input sequence.

    Parameters
    ----------
    capacity : int
        Largest number of stored points.  When exceeded (only possible for
        growing oscillations around the first point), the oldest interior
        points are dropped and the replay is no longer exact for the widest
        thresholds; ``overflowed`` tells.

    """

    def __init__(self, capacity: int = 4096) -> None:
        self.capacity = int(capacity)
        self._points: list[float] = []
        self.overflowed = False

    def __len__(self) -> int:
        """Return the number of stored turning points (including the current input)."""
        return len(self._points)

    @property
    def points(self) -> npt.NDArray[np.float64]:
        """Return the stored points: first input, turning points, current input (a copy)."""
        return np.array(self._points, dtype=np.float64)

    def clear(self) -> None:
        """Forget the history (back to the start state)."""
        self._points.clear()
        self.overflowed = False

    def push(self, x: float) -> None:
        """
        Record one input sample.

        Parameters
        ----------
        x : float
            Input sample (finite).

        """
        p = self._points
        if len(p) >= 2 and (p[-1] - p[-2]) * (x - p[-1]) >= 0.0:
            p[-1] = x                       # the current monotone segment goes on
        elif len(p) >= 1 and x == p[-1]:
            return
        else:
            p.append(x)                     # a reversal: the last input is a turning point
        while len(p) >= 4:
            a, b, c, cur = p[-4], p[-3], p[-2], p[-1]
            nested = (c - a) * (b - c) >= 0.0
            passed = (cur - b) * (b - c) >= 0.0
            if not (nested and passed):
                break
            del p[-3:-1]                    # the minor loop b -> c is wiped out
        if len(p) > self.capacity:
            del p[1:3]
            self.overflowed = True

    def extend(self, values: npt.ArrayLike) -> None:
        """
        Record a sequence of input samples, as :meth:`push` on each would.

        Only the ends of monotone runs are pushed: an interior point of a run only
        replaces the run's last point, and a wipe-out it triggers the run's end triggers
        too (passing an extremum further still passes it).

        Parameters
        ----------
        values : array_like of float, shape (K,)
            Input samples (finite).

        """
        x = np.asarray(values, dtype=np.float64).reshape(-1)
        if x.size <= 2:
            for v in x:
                self.push(float(v))
            return
        direction = np.sign(np.diff(x))
        nonzero = np.flatnonzero(direction)
        keep = [0]
        if nonzero.size:
            d = direction[nonzero]
            turns = nonzero[1:][d[1:] != d[:-1]]          # first step of a new run
            keep.extend(int(i) for i in turns)
        keep.append(x.size - 1)
        for i in sorted(set(keep)):
            self.push(float(x[i]))
