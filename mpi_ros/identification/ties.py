# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Two models' held-out errors compared within their statistical noise: a tie or a difference.

Both models are scored on the same held-out blocks of one record (short contiguous blocks
spread over it, :func:`~mpi_ros.identification.folds.held_out_rows`).  Their RMS errors
differ by chance as well as by their physics: noise, and misfit both share, vary from block
to block.  The test pairs them per block and treats the blocks as independent replicates of
the difference (*batch means*: the blocks are far apart, so the residual's autocorrelation,
which a per-sample test would have to model, stays inside each block).

The difference per block is the log ratio of the two mean squared errors,
``d_b = log(mse1_b / mse2_b)``: the error's scale changes along a record by a factor of 10-100
(small loops and large sweeps, a slow and a fast part), and a difference of squared errors
would let the one or two largest blocks decide alone (a 2 ms lag on sines at 20 and 100 Hz:
the 100 Hz block's squared error is 10^4 times the quiet blocks'); the ratio makes the blocks
comparable.  With weights ``w_b = n_b / N`` (``n_b`` samples), ``D = sum_b w_b d_b``, its
variance from the blocks' scatter ``var D = B / (B - 1) sum_b w_b^2 (d_b - D)^2``, and
``t = D / sqrt(var D)`` is compared with Student's t with ``B - 1`` degrees of freedom,
two-sided at :data:`TIE_LEVEL`.  The two models **tie** when ``|t|`` is below the critical
value: the record cannot tell them apart.

Why blocks and not a fixed fraction: a 3 % relative rule ties two models on a record whose
blocks disagree by 10 % either way, and separates them on a long clean record where a 2 %
difference holds on every block.  Why not the per-sample Diebold-Mariano test of the
diagnosis: the held-out rows are blocks with gaps between them, which a HAC window over the
joined rows would straddle; the blocks themselves are the natural replicates.
"""

from dataclasses import dataclass
import math

import numpy as np
import numpy.typing as npt

__all__ = ['BlockComparison', 'block_errors', 'compare_on_blocks', 'TIE_LEVEL']

FloatArray = npt.NDArray[np.float64]

#: Two-sided level of the paired block test: a difference whose ``|t|`` stays below the
#: Student-t quantile ``1 - TIE_LEVEL / 2`` is within the noise.
TIE_LEVEL = 0.05


@dataclass(frozen=True)
class BlockComparison:
    """
    A paired comparison of two models on the same held-out blocks.

    Attributes
    ----------
    ratio : float
        The first model's RMS error over the second's, the blocks' weighted geometric mean
        (below 1: the first is better).
    t : float
        The mean log ratio over its standard error (``inf`` when every block has the same
        ratio and it is not 1; ``nan`` with fewer than 3 blocks).
    critical : float
        Student's t quantile at ``1 - level / 2`` with ``blocks - 1`` degrees of freedom.
    blocks : int
        Held-out blocks both models were scored on.

    """

    ratio: float
    t: float
    critical: float
    blocks: int

    @property
    def tie(self) -> bool:
        """Tell whether the difference is within the noise (too few blocks: a tie)."""
        return not abs(self.t) >= self.critical

    @property
    def first_better(self) -> bool:
        """Tell whether the first model is better beyond the noise."""
        return not self.tie and self.ratio < 1.0

    def describe(self) -> str:
        """Return the test in words, e.g. ``t -4.1 over 9 blocks, |t| >= 2.31``."""
        if not math.isfinite(self.critical):
            return f'{self.blocks} held-out blocks: too few to estimate the noise'
        relation = '<' if self.tie else '>='
        return (f'RMS ratio {self.ratio:.3g}, t {self.t:.3g} over {self.blocks} held-out'
                f' blocks, |t| {relation} {self.critical:.3g}')


def block_errors(error: FloatArray, held: npt.NDArray[np.bool_]) -> tuple[
        tuple[float, ...], tuple[int, ...]]:
    """
    Return the mean squared error and the size of each held-out block.

    Parameters
    ----------
    error : ndarray of float, shape (N,)
        Model output minus the measured output, over the output's range.
    held : ndarray of bool, shape (N,)
        The held-out rows; each contiguous run is a block.

    Returns
    -------
    mse : tuple of float
        Mean squared error per block.
    sizes : tuple of int
        Samples per block.

    """
    mask = np.asarray(held, dtype=bool)
    edges = np.flatnonzero(np.diff(np.concatenate([[0], mask.astype(np.int8), [0]])))
    mse, sizes = [], []
    for start, stop in zip(edges[::2].tolist(), edges[1::2].tolist()):
        part = np.asarray(error[start:stop], dtype=np.float64)
        mse.append(float(np.mean(part * part)))
        sizes.append(int(stop - start))
    return tuple(mse), tuple(sizes)


def compare_on_blocks(first: tuple[float, ...], second: tuple[float, ...],
                      sizes: tuple[int, ...], *, level: float = TIE_LEVEL) -> BlockComparison:
    """
    Compare two models' per-block mean squared errors by a paired test over the blocks.

    Parameters
    ----------
    first, second : tuple of float
        Mean squared error per held-out block of each model (:func:`block_errors`, on the
        same blocks).
    sizes : tuple of int
        Samples per block.
    level : float
        Two-sided level of the test.

    Returns
    -------
    BlockComparison
        The RMS ratio (first over second), its t and the critical value; ``tie`` tells
        whether they are within the noise of each other.

    Examples
    --------
    >>> compare_on_blocks((1.0, 1.2, 0.9), (1.1, 1.0, 1.0), (10, 10, 10)).tie
    True
    >>> compare_on_blocks((1.0, 1.2, 0.9, 1.1), (2.0, 2.3, 1.8, 2.1), (5, 5, 5, 5)).first_better
    True

    """
    from scipy.stats import t as student
    a = np.asarray(first, dtype=np.float64)
    b = np.asarray(second, dtype=np.float64)
    n = np.asarray(sizes, dtype=np.float64)
    blocks = int(n.size)
    if blocks == 0 or a.size != blocks or b.size != blocks:
        return BlockComparison(math.nan, math.nan, math.inf, blocks)
    w = n / n.sum()
    tiny = 1e-300 + 1e-24 * max(float(np.max(a)), float(np.max(b)))
    d = np.log(np.maximum(a, tiny)) - np.log(np.maximum(b, tiny))
    mean = float(np.dot(w, d))
    ratio = math.exp(0.5 * mean)
    if blocks < 3:
        return BlockComparison(ratio, math.nan, math.inf, blocks)
    variance = blocks / (blocks - 1) * float(np.dot(w * w, (d - mean) ** 2))
    if variance <= 1e-24:
        t = 0.0 if abs(mean) <= 1e-12 else math.copysign(math.inf, mean)
    else:
        t = mean / math.sqrt(variance)
    return BlockComparison(ratio, t, float(student.ppf(1.0 - level / 2.0, blocks - 1)), blocks)
