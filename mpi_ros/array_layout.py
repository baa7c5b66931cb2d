# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
The samples x axes layout of a ``std_msgs/msg/Float64MultiArray``: one rule for every reader.

A message whose ``layout.dim`` has two entries holds ``dim[0].size`` = K samples of
``dim[1].size`` = N axes, row-major, from ``layout.data_offset``, one row every
``dim[1].stride`` values (the ROS convention: ``dim[1].stride`` is the row stride,
``dim[0].stride`` the total; a stride below N is read as N).  The multi-axis nodes'
decoder (:mod:`mpi_ros.nodes.arrays`) and the bag reader
(:mod:`mpi_ros.recordings.messages`) both read blocks through :func:`chunk_layout`, and a
message without ``dim`` of a known axis count through :func:`consecutive_layout`; each
phrases its own errors (what the user has to change differs).
"""

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

__all__ = ['ChunkLayout', 'chunk_layout', 'consecutive_layout']

FloatArray = npt.NDArray[np.float64]


@dataclass(frozen=True)
class ChunkLayout:
    """
    Where the K x N values of a chunk are in a message's ``data``.

    Attributes
    ----------
    samples : int
        K, rows.
    axes : int
        N, columns.
    row : int
        Values from one row's start to the next (>= N).
    offset : int
        ``layout.data_offset``: index of the first value.

    """

    samples: int
    axes: int
    row: int
    offset: int

    @property
    def needed(self) -> int:
        """Return how many values ``data`` must hold (the last row may stop after its axes)."""
        return self.offset + (self.samples - 1) * self.row + self.axes

    def fits(self, size: int) -> bool:
        """Tell whether at least one sample and one axis lie inside ``size`` values."""
        return self.samples >= 1 and self.axes >= 1 and self.needed <= size

    def block(self, values: FloatArray) -> FloatArray:
        """
        Return the K x N block of ``values`` (a view when every row is complete).

        Parameters
        ----------
        values : ndarray of float
            ``data`` of a message this layout fits.

        Returns
        -------
        ndarray of float, shape (K, N)

        """
        end = self.offset + self.samples * self.row
        if end > values.size:                    # the last row stops after its axes
            values = np.concatenate([values, np.zeros(end - values.size)])
        rows = values[self.offset:end].reshape(self.samples, self.row)
        return rows[:, :self.axes]

    def column(self, values: Sequence[float], axis: int) -> FloatArray:
        """Return the K samples of one axis (column) of ``values``, oldest first."""
        start = self.offset + axis
        return np.array(values[start:start + (self.samples - 1) * self.row + 1:self.row],
                        dtype=np.float64)


def chunk_layout(dims: Sequence[tuple[int, int]], data_offset: int) -> ChunkLayout | None:
    """
    Return the chunk a message's ``layout`` describes, or None when it is not samples x axes.

    Parameters
    ----------
    dims : sequence of (int, int)
        ``layout.dim`` as (size, stride) pairs.
    data_offset : int
        ``layout.data_offset``.

    Returns
    -------
    ChunkLayout or None
        For two dims (samples, axes); None for any other number (the caller decides:
        one sample per message, or an error).  Not checked against the data: see
        :meth:`ChunkLayout.fits`.

    Examples
    --------
    >>> layout = chunk_layout([(3, 12), (2, 4)], 1)
    >>> layout.row, layout.needed
    (4, 11)
    >>> layout.column(list(range(11)), 1).tolist()
    [2.0, 6.0, 10.0]

    """
    if len(dims) != 2:
        return None
    (samples, _), (axes, stride) = dims
    return ChunkLayout(int(samples), int(axes), max(int(stride), int(axes)), int(data_offset))


def consecutive_layout(size: int, data_offset: int, axes: int) -> ChunkLayout | None:
    """
    Return the chunk of a message without ``layout.dim``: consecutive samples of N axes.

    Parameters
    ----------
    size : int
        Number of values in ``data``.
    data_offset : int
        ``layout.data_offset``.
    axes : int
        N.

    Returns
    -------
    ChunkLayout or None
        K = (size - data_offset) / N samples, rows N apart; None when the values after
        the offset are not a positive whole number of samples.

    Examples
    --------
    >>> consecutive_layout(7, 1, 3).samples, consecutive_layout(7, 0, 3)
    (2, None)

    """
    flat = size - data_offset
    if axes < 1 or flat < axes or flat % axes:
        return None
    return ChunkLayout(flat // axes, axes, axes, data_offset)
