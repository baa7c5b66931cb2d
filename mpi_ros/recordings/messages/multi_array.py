# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Reader of ``std_msgs/msg/Float64MultiArray``: one element, or one axis of a chunk.

Chunked arrays (the multi-axis nodes' layout, :mod:`mpi_ros.array_layout`)
    A ``Float64MultiArray`` whose ``layout.dim`` has two entries is a block of
    ``dim[0].size`` = K samples x ``dim[1].size`` = N axes, row-major from
    ``layout.data_offset`` with the row stride ``dim[1].stride`` (N when it is
    smaller). The selected index is the axis (column, < N); the reader returns
    the K samples of that column, oldest first. A message without ``dim``, or
    with one or more than two entries, is one sample whose elements are
    indexed as before (element k after ``data_offset``); so is a block with
    K = 1. With :attr:`Selection.axes` = N (the data option ``array_axes``,
    set by the identifier for ``axes`` > 1) such a message is read as the
    nodes read it: its values after ``data_offset`` are K x N samples x axes.
    When the samples were taken is the bag reader's business
    (:func:`mpi_ros.recordings.read_bag_signals`).
"""

from __future__ import annotations

from typing import Any

import numpy as np
import numpy.typing as npt

from .base import MessageReader, Selection, SelectionError
from ...array_layout import chunk_layout, consecutive_layout

__all__ = ['Float64MultiArrayReader']


class Float64MultiArrayReader(MessageReader):
    """
    ``std_msgs/msg/Float64MultiArray``: one element of ``data``, or one axis of a chunk.

    A message whose ``layout.dim`` has two entries is a chunk of samples x axes
    (module docstring); any other message is one sample.
    """

    msgtype = 'std_msgs/msg/Float64MultiArray'
    selectors = ('index',)

    def value(self, msg: Any, selection: Selection) -> float:
        """Return ``msg.data[layout.data_offset + index]`` (a one-sample chunk's element)."""
        if len(msg.layout.dim) == 2 or selection.axes is not None:
            samples = self.values(msg, selection)
            if samples.size != 1:
                msg_text = (f'it holds a chunk of {samples.size} samples (samples x axes), '
                            'not one number; read it with values()')
                raise SelectionError(msg_text)
            return float(samples[0])
        return self._element(msg, selection)

    def values(self, msg: Any, selection: Selection) -> npt.NDArray[np.float64]:
        """Return the selected axis of a chunk (K samples), or ``[value]`` for one sample."""
        dims = msg.layout.dim
        offset = int(msg.layout.data_offset)
        size = len(msg.data)
        option = selection.name('index')
        axes_option = selection.name('axes')
        layout = chunk_layout([(int(d.size), int(d.stride)) for d in dims], offset)
        if layout is not None:
            samples, axes, row = layout.samples, layout.axes, layout.row
            stride = f', row stride {row}' if row != axes else ''
            shape = (f'{samples} sample(s) x {axes} axes (layout.dim = samples x axes{stride}'
                     f'{_offset_note(offset, ", ")})')
            if samples < 1 or axes < 1:
                msg_text = (f'its layout announces {shape}: a chunk needs at least one sample '
                            'and one axis; fix layout.dim in the publisher (dim[0] = samples, '
                            'dim[1] = axes) or leave dim empty for one sample per message')
                raise SelectionError(msg_text)
            if not layout.fits(size):
                msg_text = (f'its layout announces {shape}, which needs {layout.needed} values,'
                            f' but data holds {size}; fix layout.dim in the publisher (dim[0] = '
                            'samples, dim[1] = axes) to match the data')
                raise SelectionError(msg_text)
            if selection.axes is not None and axes != selection.axes:
                msg_text = (f'it holds chunks of {shape}, but {axes_option} is '
                            f'{selection.axes}; set {axes_option} to {axes} (one column per '
                            'axis) or record the topic of the other actuators')
                raise SelectionError(msg_text)
        elif selection.axes is not None:
            axes = selection.axes
            layout = consecutive_layout(size, offset, axes)
            if layout is None:
                msg_text = (f'it holds {max(size - offset, 0)} value(s){_offset_note(offset)}'
                            f' and no layout.dim, not whole samples of {axes_option} {axes}'
                            ' axes (samples x axes, row-major); publish K x N values or set '
                            f'layout.dim, or set {axes_option} to the number of axes')
                raise SelectionError(msg_text)
            samples = layout.samples
            shape = (f'{samples} sample(s) x {axes} axes ({axes_option} {axes}, no '
                     f'layout.dim{_offset_note(offset, ", ")})')
        else:
            return np.array([self._element(msg, selection)], dtype=np.float64)
        index = _index(selection, axes, f'chunks of {shape}', 'the axis, ')
        if index >= axes:
            msg_text = (f'{option} {index} is out of range: the message holds {shape}; set '
                        f'{option} to an axis, one of 0 to {axes - 1}')
            raise SelectionError(msg_text)
        return layout.column(msg.data, index)

    def shape(self, msg: Any) -> tuple[str, int]:
        """Return ('chunk', axes) for a samples x axes block, ('flat', values) without dim."""
        dims = msg.layout.dim
        if len(dims) == 2:
            return 'chunk', int(dims[1].size)
        if not dims:
            return 'flat', len(msg.data) - int(msg.layout.data_offset)
        return 'other', 0

    @staticmethod
    def _element(msg: Any, selection: Selection) -> float:
        """Return ``msg.data[layout.data_offset + index]`` of a one-sample message."""
        offset = int(msg.layout.data_offset)
        size = len(msg.data) - offset
        option = selection.name('index')
        index = _index(selection, size, f'{size} elements', '')
        if not 0 <= index < size:
            fix = (f'set {option} to one of 0 to {size - 1}' if size > 0
                   else 'record a topic whose arrays hold the signal')
            msg_text = (f'{option} {index} is out of range: the array holds {max(size, 0)} '
                        f'element(s){_offset_note(offset)}; {fix}')
            raise SelectionError(msg_text)
        return float(msg.data[offset + index])


def _index(selection: Selection, count: int, holds: str, what: str) -> int:
    """Return the selected index; with none selected, 0 when `count` is 1, else refuse."""
    if selection.index is not None:
        return selection.index
    if count != 1:
        option = selection.name('index')
        msg_text = (f'it holds {holds} and {option} is not set; set {option} to {what}one of '
                    f'0 to {count - 1}')
        raise SelectionError(msg_text)
    return 0


def _offset_note(offset: int, lead: str = ' after ') -> str:
    return f'{lead}layout.data_offset {offset}' if offset else ''
