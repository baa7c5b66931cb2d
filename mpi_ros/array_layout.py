# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
The samples x axes layout of a ``std_msgs/msg/Float64MultiArray``: one rule for every reader.

A message whose ``layout.dim`` has two entries holds ``dim[0].size`` = K samples of
``dim[1].size`` = N axes, row-major, from ``layout.data_offset``, one row every
``dim[1].stride`` values (the ROS convention: ``dim[1].stride`` is the row stride,
``dim[0].stride`` the total; a stride below N is read as N).  The multi-axis nodes'
decoder (:func:`block_of`) and the bag reader's array reader
(:mod:`mpi_ros.recordings.messages.multi_array`) both read blocks through
:func:`chunk_layout`, and a message without ``dim`` of a known axis count through
:func:`consecutive_layout`; each
phrases its own errors (what the user has to change differs).

The multi-axis nodes take and publish their array topics serialized (rclpy's raw
subscriptions and ``publish_raw``): decoding a block is one ``numpy.frombuffer`` over the
message's bytes (:func:`block_of`) and encoding one ``tobytes``
(:func:`encode_float64_multiarray`), where rclpy would build a Python message object and
convert its ``data`` element by element.  Published blocks carry ``dim = [samples (K,
K*N), axes (N, N)]`` and ``data_offset = 0``; the flat form of ros2_control's
``forward_command_controller`` (one value per joint, empty ``layout.dim``,
``data_offset = 0``) is :func:`encode_flat_float64_multiarray`.

CDR (XCDR1, as rmw_fastrtps writes it): a 4-byte encapsulation header (byte 1: 1 =
little-endian, 0 = big-endian), then the fields, each aligned to its size relative to
the end of the header; a string is a ``uint32`` length (with its NUL) and its bytes.
"""

from collections.abc import Sequence
from dataclasses import dataclass
import struct
from typing import List, Optional, Tuple

import numpy as np
import numpy.typing as npt

__all__ = ['ArrayLayoutError', 'ChunkLayout', 'FLOAT64_SIZE', 'block_of', 'chunk_layout',
           'consecutive_layout', 'decode_float64_multiarray', 'encode_flat_float64_multiarray',
           'encode_float64_multiarray', 'float64_of', 'malformed_float64']

#: Bytes of a CDR ``std_msgs/Float64``: the 4-byte header and the double (more are ignored).
FLOAT64_SIZE = 12

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


#: One dimension of ``layout.dim``: label, size, stride.
Dimension = Tuple[str, int, int]


class ArrayLayoutError(ValueError):
    """A Float64MultiArray whose bytes or layout do not give a samples x axes block."""


def decode_float64_multiarray(data: bytes) -> Tuple[List[Dimension], int, np.ndarray]:
    """
    Decode the CDR bytes of a ``Float64MultiArray``.

    Parameters
    ----------
    data : bytes
        The serialized message (as a raw subscription delivers it).

    Returns
    -------
    dims : list of (str, int, int)
        ``layout.dim``: label, size, stride.
    data_offset : int
        ``layout.data_offset``.
    values : ndarray of float, shape (M,)
        ``data`` (a read-only view of ``data``'s bytes, native byte order after a copy
        only when the message is big-endian).

    Raises
    ------
    ArrayLayoutError
        When the bytes are too short for what they announce.

    """
    if len(data) < 4:
        msg = f'Float64MultiArray: {len(data)} bytes, fewer than the 4-byte CDR header'
        raise ArrayLayoutError(msg)
    order = '<' if data[1] == 1 else '>'
    u32 = struct.Struct(order + 'I').unpack_from
    view = memoryview(data)[4:]
    pos = 0
    try:
        (count,), pos = u32(view, 0), 4
        dims: List[Dimension] = []
        for _ in range(count):
            (length,) = u32(view, pos)
            label = bytes(view[pos + 4:pos + 4 + max(length - 1, 0)]).decode('utf-8', 'replace')
            pos = _align(pos + 4 + length, 4)
            size, stride = struct.unpack_from(order + 'II', view, pos)
            pos += 8
            dims.append((label, size, stride))
        (data_offset,) = u32(view, pos)
        (length,) = u32(view, pos + 4)
    except struct.error as err:
        msg = f'Float64MultiArray: truncated message ({len(data)} bytes): {err}'
        raise ArrayLayoutError(msg) from err
    pos = _align(pos + 8, 8)
    end = pos + 8 * length
    if end > len(view):
        msg = (f'Float64MultiArray: announces {length} values but has bytes for '
               f'{max(len(view) - pos, 0) // 8}')
        raise ArrayLayoutError(msg)
    values = np.frombuffer(view[pos:end], dtype=order + 'f8')
    if order == '>':
        values = values.astype(np.float64)
    return dims, data_offset, values


def block_of(data: bytes, axes: int) -> npt.NDArray[np.float64]:
    """
    Return the ``samples x axes`` block a serialized ``Float64MultiArray`` carries.

    Parameters
    ----------
    data : bytes
        The serialized message.
    axes : int
        Number of axes (columns) expected.

    Returns
    -------
    ndarray of float, shape (K, axes)
        The block (K >= 1 samples).

    Raises
    ------
    ArrayLayoutError
        When the layout does not describe ``K x axes`` values that are there, naming
        what was found.

    Notes
    -----
    The bytes :func:`encode_float64_multiarray` writes (and rclpy writes for the same
    layout: labels ``samples`` and ``axes``, ``data_offset`` 0, row stride = axes,
    little-endian) are read by one ``struct`` call at fixed offsets and one
    ``numpy.frombuffer`` (about 0.6 us); any other message goes through the general
    parser (:func:`decode_float64_multiarray`, about 3 us), with the same result.

    """
    block = _fast_block(data, axes)
    return _general_block(data, axes) if block is None else block


def encode_float64_multiarray(block: npt.NDArray[np.float64]) -> bytes:
    """
    Encode a ``samples x axes`` block as the CDR bytes of a ``Float64MultiArray``.

    Parameters
    ----------
    block : ndarray of float, shape (K, N)
        Values, row-major.

    Returns
    -------
    bytes
        ``layout.dim = [samples (K, K*N), axes (N, N)]``, ``data_offset = 0``, ``data``.

    """
    samples, columns = block.shape
    values = samples * columns
    return (_HEADER_START
            + _LAYOUT(samples, values, 5, b'axes\x00', columns, columns, 0, values)
            + np.ascontiguousarray(block, dtype='<f8').tobytes())


def encode_flat_float64_multiarray(values: npt.NDArray[np.float64]) -> bytes:
    """
    Encode one value per axis as the CDR bytes of a ``Float64MultiArray`` without layout.

    What ros2_control's ``forward_command_controller`` takes on ``~/commands``: ``data``
    holds exactly one value per joint, in the controller's ``joints`` order; it reads
    ``data`` alone (a message of any other size is dropped).

    Parameters
    ----------
    values : ndarray of float, shape (N,)
        One command per axis.

    Returns
    -------
    bytes
        ``layout.dim = []``, ``layout.data_offset = 0``, ``data = values``.

    """
    flat = np.ascontiguousarray(values, dtype='<f8').reshape(-1)
    return _FLAT(_CDR_LE, 0, 0, flat.size) + flat.tobytes()


def malformed_float64(data: bytes) -> str:
    """
    Say why bytes are not the CDR of a ``std_msgs/Float64`` (the reason a node reports).

    Parameters
    ----------
    data : bytes
        The serialized message (raw subscription).

    Returns
    -------
    str
        What is wrong: too short, or not a CDR encapsulation.

    Examples
    --------
    >>> malformed_float64(bytes(1))
    '1 bytes, not a CDR Float64 (12 bytes: a 4-byte header, then the double)'
    >>> malformed_float64(bytes([0, 7]) + bytes(10))
    'encapsulation 0x0007 is not CDR (0x0000 or 0x0001)'

    """
    if len(data) < FLOAT64_SIZE:
        return (f'{len(data)} bytes, not a CDR Float64 (12 bytes: a 4-byte header, then the '
                'double)')
    return f'encapsulation 0x{data[0]:02x}{data[1]:02x} is not CDR (0x0000 or 0x0001)'


def float64_of(data: bytes) -> float:
    """
    Decode the CDR bytes of a ``std_msgs/Float64`` after checking them.

    Parameters
    ----------
    data : bytes
        The serialized message.

    Returns
    -------
    float
        Its ``data`` (any double, NaN and Inf included).

    Raises
    ------
    ArrayLayoutError
        When the bytes are not a CDR Float64 (:func:`malformed_float64` says why).

    Examples
    --------
    >>> float64_of(bytes([0, 1, 0, 0]) + struct.pack('<d', 2.5))
    2.5

    """
    if len(data) < FLOAT64_SIZE or data[0] != 0 or data[1] > 1:
        raise ArrayLayoutError(malformed_float64(data))
    return float(struct.unpack_from('<d' if data[1] == 1 else '>d', data, 4)[0])


def _fast_block(data: bytes, axes: int) -> Optional[npt.NDArray[np.float64]]:
    """
    Return the block of a message laid out as our encoder writes it, or None.

    The bytes qualify when they are little-endian, have two dims labelled ``samples`` and
    ``axes`` (so every field sits at a fixed offset), ``axes`` columns with a row stride
    of at most ``axes`` (read as ``axes``, as the general parser does), ``data_offset``
    0, at least ``K * axes`` values, K >= 1, and bytes for every announced value.  Then
    the block is the first ``K * axes`` doubles, from byte 60: exactly what
    :func:`_general_block` returns.  Anything else (big-endian, other labels, a data
    offset, padded rows, errors) returns None for the general parser to read or refuse.
    `data` and `axes` are those of :func:`block_of`; the block returned is a read-only view
    of ``data``.
    """
    if len(data) < _FAST_START or data[1] != 1:
        return None
    prefix, samples, _, label, columns, stride, offset, length = _FAST_FIELDS(data, 4)
    values = samples * columns
    if (prefix != _FAST_PREFIX or label != _FAST_AXES or columns != axes or stride > columns
            or offset or not 0 < values <= length
            or _FAST_START + 8 * length > len(data)):
        return None
    return np.frombuffer(data, _FLOAT64_LE, values, _FAST_START).reshape(samples, columns)


def _general_block(data: bytes, axes: int) -> npt.NDArray[np.float64]:
    """
    Return the block :func:`block_of` returns, from the fully parsed message.

    `data` and `axes` and the :class:`ArrayLayoutError` are those of :func:`block_of`.
    """
    dims, offset, values = decode_float64_multiarray(data)
    layout = chunk_layout([(size, stride) for _, size, stride in dims], offset)
    if layout is not None:
        if layout.axes != axes:
            msg = (f'layout.dim[1].size (axes) is {layout.axes}; this node has axes={axes}: '
                   'send one column per axis')
            raise ArrayLayoutError(msg)
        if not layout.fits(values.size):
            msg = (f'layout says {layout.samples} samples x {layout.axes} axes (row stride '
                   f'{layout.row}, data_offset {offset}), data has {values.size} values')
            raise ArrayLayoutError(msg)
        return layout.block(values)
    if dims and len(dims) != 2:
        msg = (f'layout.dim has {len(dims)} entries; expected none (consecutive samples '
               'of every axis) or two (samples, axes)')
        raise ArrayLayoutError(msg)
    layout = consecutive_layout(values.size, offset, axes)
    if layout is None:
        msg = (f'{max(values.size - offset, 0)} values are not whole samples of axes={axes}'
               ' (samples x axes, row-major); send a multiple of the axis count or set'
               ' layout.dim')
        raise ArrayLayoutError(msg)
    return layout.block(values)


def _align(pos: int, size: int) -> int:
    return (pos + size - 1) // size * size


# Fixed part of an encoded block: header; 2 dims; 'samples' (8 bytes with its NUL, so the
# size after it is aligned); 'axes' (5 bytes + 3 of padding); data_offset; the data's
# length; 4 bytes of padding: the doubles start at payload offset 56, aligned to 8.
_HEADER_START = b'\x00\x01\x00\x00' + struct.pack('<II', 2, 8) + b'samples\x00'
_LAYOUT = struct.Struct('<II I5s3x II II 4x').pack
#: The encapsulation header CDR_LE (bytes 00 01) as a little-endian unsigned short.
_CDR_LE = 0x0100
# A flat array: header; no dim; data_offset; the data's length; 4 bytes of padding (the
# doubles start at payload offset 16, aligned to 8).
_FLAT = struct.Struct('<H2x III 4x').pack

# The fast path of block_of (_fast_block): from byte 4 (after the encapsulation header),
# the dim count (2) and the first label's length (8) and bytes, K and the first stride,
# the second label's length (5) and bytes, 3 bytes of padding, N, the row stride,
# data_offset and the data's length; the doubles start at byte 60.
_FAST_PREFIX = struct.pack('<II', 2, 8) + b'samples\x00'
_FAST_AXES = struct.pack('<I', 5) + b'axes\x00'
_FAST_FIELDS = struct.Struct('<16sII9s3xIIII').unpack_from
_FAST_START = 60
_FLOAT64_LE = np.dtype('<f8')
