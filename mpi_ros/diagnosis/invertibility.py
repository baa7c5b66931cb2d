# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Check whether recorded data can belong to the invertible MPI class at all.

The MPI operator (26) with (8) and (19) is monotone along every branch: while the input
rises, the output rises.  Butterfly loops (ferroelectric switching of a piezoceramic under
bipolar drive) and actuators whose output falls with the input violate this.  The check
splits the record into monotone input branches, bins each long branch (at least half the
input range) into 20 input bins, and measures on the binned mean output the
*reversal ratio* ``sum of output steps against the branch direction / sum of |steps|``:
about 0 for an MPI-like loop, 1 for a decreasing map, and clearly in between for a
butterfly.  The verdict name for failing data is ``outside_invertible_class``.
"""

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

__all__ = ['monotone_branches', 'InvertibilityCheck', 'check_invertible_class',
           'OUTSIDE_INVERTIBLE_CLASS']

FloatArray = npt.NDArray[np.float64]

#: Verdict (``DiagnosisReport.cause``) for data the invertible MPI class cannot describe.
OUTSIDE_INVERTIBLE_CLASS = 'outside_invertible_class'


@dataclass(frozen=True)
class InvertibilityCheck:
    """
    Result of :func:`check_invertible_class`.

    Attributes
    ----------
    inside : bool
        True when the data may be described by an invertible MPI model.
    reversal_ratio : float
        Output travel against the branch direction / total travel on long branches (0..1).
    branches : int
        Number of long monotone input branches examined.
    reason : str
        One sentence for people.

    """

    inside: bool
    reversal_ratio: float
    branches: int
    reason: str


def monotone_branches(x: FloatArray, band: float) -> list[tuple[int, int]]:
    """
    Return the input's monotone branches between zig-zag turning points.

    A reversal counts once the input moved back by more than ``band`` from the running
    extremum (noise does not split a branch).

    Parameters
    ----------
    x : ndarray of float, shape (N,)
        Input [A].
    band : float
        Smallest move back that counts as a reversal [A].

    Returns
    -------
    list of (int, int)
        ``(start, stop)`` sample indices of each branch.

    """
    turns = [0]
    ext, direction = 0, 0
    for k in range(1, x.size):
        if direction == 0:
            if abs(x[k] - x[0]) > band:
                direction, ext = (1 if x[k] > x[0] else -1), k
        elif direction * (x[k] - x[ext]) > 0.0:
            ext = k
        elif direction * (x[ext] - x[k]) > band:
            turns.append(ext)
            direction, ext = -direction, k
    if ext != turns[-1]:
        turns.append(ext)
    return list(zip(turns[:-1], turns[1:]))


def check_invertible_class(current: npt.ArrayLike, displacement: npt.ArrayLike, *,
                           threshold: float = 0.2, bins: int = 20) -> InvertibilityCheck:
    """
    Test whether the output is a rising function of the input along long input branches.

    Parameters
    ----------
    current : array_like of float, shape (N,)
        Input [A].
    displacement : array_like of float, shape (N,)
        Output [m].
    threshold : float
        Largest reversal ratio still accepted.
    bins : int
        Input bins per branch.

    Returns
    -------
    InvertibilityCheck
        The verdict and the measured ratio.

    """
    x = np.asarray(current, dtype=np.float64)
    y = np.asarray(displacement, dtype=np.float64)
    span = float(np.ptp(x))
    against = 0.0
    total = 0.0
    used = 0
    for a, b in monotone_branches(x, 0.05 * span):
        lo, hi = sorted((a, b))
        seg_x, seg_y = x[lo:hi + 1], y[lo:hi + 1]
        if seg_x.size < 2 * bins or np.ptp(seg_x) < 0.5 * span:
            continue
        edges = np.linspace(seg_x.min(), seg_x.max(), bins + 1)
        idx = np.clip(np.searchsorted(edges, seg_x, side='right') - 1, 0, bins - 1)
        counts = np.bincount(idx, minlength=bins)
        means = np.bincount(idx, weights=seg_y, minlength=bins)[counts > 0] / counts[
            counts > 0]
        steps = np.diff(means)             # ordered by rising input
        against += float(np.sum(np.maximum(-steps, 0.0)))
        total += float(np.sum(np.abs(steps)))
        used += 1
    if used == 0 or total == 0.0:
        return InvertibilityCheck(True, 0.0, used, 'no long input branch to check')
    ratio = against / total
    if ratio <= threshold:
        reason = (f'the output rises with the input along {used} long branch(es)'
                  f' (reversal ratio {ratio:.2f} <= {threshold})')
        return InvertibilityCheck(True, ratio, used, reason)
    if ratio >= 1.0 - threshold:
        reason = (f'the output falls as the input rises along {used} long branch(es)'
                  f' (reversal ratio {ratio:.2f}); the MPI model needs a rising map: flip the'
                  ' sign of the output (e.g. a negative --output-scale)')
    else:
        reason = (f'the output is not a monotone function of the input along {used} long'
                  f' branch(es) (reversal ratio {ratio:.2f} > {threshold}): butterfly-like'
                  ' loops, e.g. ferroelectric switching; no invertible MPI model fits them')
    return InvertibilityCheck(False, ratio, used, reason)
