# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Blocked folds of a record: contiguous blocks held out in turn, for out-of-sample choices.

A choice the in-sample error cannot judge (an effect's time constant, a bank of creep lags,
whether an effect is there at all) is made on the error of fits that did not see the
samples they are scored on.  The folds are made of contiguous blocks, not scattered
samples: the residual of a record is correlated over time, and a held-out sample between
two fitted neighbours is no test.  The record is cut into many blocks (30 by default), dealt
to the folds in turn, so every fold's training part still holds every kind of excitation
the record has: measured on the wide diagnosis sweep, three folds of one third each let
the fold without the record's large first loops miss by 12 um (40 % of the stroke) whatever
the effect's parameter, and that fold decided every choice.  The states of the plays and of
an effect's lags are functions of the input alone, so each fold's model is simulated over
the whole record and scored on its own blocks.
"""

import numpy as np
import numpy.typing as npt

from ..errors import DataError

__all__ = ['blocked_folds', 'FOLDS']

#: Folds of the out-of-sample choices.
FOLDS = 3
#: Contiguous blocks the record is cut into (dealt to the folds in turn).
BLOCKS = 30


def blocked_folds(size: int, count: int = FOLDS, *, start: int = 0,
                  blocks: int = BLOCKS) -> list[npt.NDArray[np.bool_]]:
    """
    Return the held-out rows of each fold: every ``count``-th contiguous block after ``start``.

    Parameters
    ----------
    size : int
        Samples in the record.
    count : int
        Folds (>= 2).
    start : int
        First sample that may be held out (the ones before are in no block: samples no
        fit uses, e.g. a burn-in).
    blocks : int
        Contiguous blocks of equal length (as integer edges allow) after ``start``; fold
        ``k`` holds blocks ``k, k + count, ...``.  At least ``count``, at most one per
        sample.

    Returns
    -------
    list of ndarray of bool, shape (size,)
        One mask per fold, True on its held-out blocks; the folds are disjoint and cover
        ``start..size - 1``.

    Raises
    ------
    DataError
        When ``count < 2`` or fewer than ``count`` samples follow ``start``.

    Examples
    --------
    >>> [np.flatnonzero(m).tolist() for m in blocked_folds(13, 2, start=1, blocks=4)]
    [[1, 2, 3, 7, 8, 9], [4, 5, 6, 10, 11, 12]]

    """
    if count < 2:
        msg = f'blocked folds need count >= 2; found {count}'
        raise DataError(msg)
    start = max(int(start), 0)
    if size - start < count:
        msg = (f'too few samples for {count} folds: {size - start} after sample {start};'
               ' record a longer excitation')
        raise DataError(msg)
    blocks = int(min(max(blocks, count), size - start))
    edges = np.linspace(start, size, blocks + 1).round().astype(int)
    masks = [np.zeros(size, dtype=bool) for _ in range(count)]
    for b, (lo, hi) in enumerate(zip(edges[:-1], edges[1:])):
        masks[b % count][lo:hi] = True
    return masks
