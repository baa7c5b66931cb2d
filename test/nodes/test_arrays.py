# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""Float64MultiArray CDR bytes <-> samples x axes blocks, checked against rclpy's own CDR."""

import struct

from hypothesis import event, given, HealthCheck, settings, strategies as st
from mpi_ros import array_layout as arrays
from mpi_ros.array_layout import (
    ArrayLayoutError, block_of, decode_float64_multiarray, encode_float64_multiarray,
)
import numpy as np
import pytest
from rclpy.serialization import deserialize_message, serialize_message
from std_msgs.msg import Float64MultiArray, MultiArrayDimension


def array_message(data, dims=(), offset=0):
    msg = Float64MultiArray(data=[float(v) for v in data])
    msg.layout.dim = [MultiArrayDimension(label=label, size=size, stride=stride)
                      for label, size, stride in dims]
    msg.layout.data_offset = offset
    return msg


@pytest.mark.parametrize('samples, axes', [(1, 1), (1, 8), (10, 8), (3, 5)])
def test_encoded_blocks_are_what_rclpy_reads(samples, axes):
    block = np.random.default_rng(samples * axes).normal(size=(samples, axes))
    msg = deserialize_message(encode_float64_multiarray(block), Float64MultiArray)
    assert [(d.label, d.size, d.stride) for d in msg.layout.dim] == [
        ('samples', samples, samples * axes), ('axes', axes, axes)]
    assert msg.layout.data_offset == 0
    assert np.array_equal(np.array(msg.data).reshape(samples, axes), block)


def test_decoding_reads_what_rclpy_writes():
    msg = array_message(np.arange(7.0), dims=[('a', 7, 7)], offset=0)
    dims, offset, values = decode_float64_multiarray(serialize_message(msg))
    assert dims == [('a', 7, 7)] and offset == 0
    assert np.array_equal(values, np.arange(7.0))
    empty = decode_float64_multiarray(serialize_message(Float64MultiArray()))
    assert empty[0] == [] and empty[2].size == 0


def test_blocks_with_and_without_layout():
    flat = serialize_message(array_message(np.arange(24.0)))
    assert np.array_equal(block_of(flat, 8), np.arange(24.0).reshape(3, 8))
    # Row stride 10 for 8 axes, data_offset 3: the ROS layout convention.
    padded = array_message(np.arange(3 + 20.0), dims=[('s', 2, 20), ('x', 8, 10)], offset=3)
    assert np.array_equal(block_of(serialize_message(padded), 8),
                          [np.arange(3.0, 11.0), np.arange(13.0, 21.0)])
    short_last_row = array_message(np.arange(18.0), dims=[('s', 2, 20), ('x', 8, 10)])
    assert np.array_equal(block_of(serialize_message(short_last_row), 8),
                          [np.arange(8.0), np.arange(10.0, 18.0)])


@pytest.mark.parametrize('msg, needle', [
    (array_message(np.arange(12.0)), 'not whole samples of axes=8'),
    (array_message([]), 'not whole samples of axes=8'),
    (array_message(np.arange(16.0), dims=[('s', 2, 16), ('x', 4, 4)]), 'axes=8'),
    (array_message(np.arange(8.0), dims=[('s', 2, 16), ('x', 8, 8)]), 'data has 8 values'),
    (array_message(np.arange(8.0), dims=[('a', 8, 8)]), 'layout.dim has 1 entries'),
])
def test_bad_layouts_are_refused_naming_what_was_found(msg, needle):
    with pytest.raises(ArrayLayoutError, match=needle):
        block_of(serialize_message(msg), 8)


def test_truncated_bytes_are_refused():
    data = serialize_message(array_message(np.arange(8.0)))
    with pytest.raises(ArrayLayoutError, match='bytes for'):
        block_of(data[:-9], 8)
    with pytest.raises(ArrayLayoutError, match='truncated|header'):
        block_of(data[:6], 8)


# The fast path of block_of (bytes laid out as the encoder writes them) against the general
# parser: on every message, including near misses of the fast layout, big-endian and
# truncated bytes, both give the same block or the same error.

def cdr_message(dims, offset, values, *, big_endian=False, padding=0, padded=None):
    """
    Serialize a Float64MultiArray as XCDR1 in either byte order (a test-side writer).

    Alignment padding is filled with the byte ``padding`` (rclpy leaves whatever was in
    its buffer there) and its positions are appended to the list ``padded`` if given.

    """
    order = '>' if big_endian else '<'
    out = bytearray(b'\x00' + (b'\x00' if big_endian else b'\x01') + b'\x00\x00')

    def align(size):
        gap = -(len(out) - 4) % size
        if padded is not None:
            padded.extend(range(len(out), len(out) + gap))
        out.extend(bytes([padding]) * gap)

    out += struct.pack(order + 'I', len(dims))
    for label, size, stride in dims:
        align(4)
        text = label.encode() + b'\x00'
        out += struct.pack(order + 'I', len(text)) + text
        align(4)
        out += struct.pack(order + 'II', size, stride)
    align(4)
    out += struct.pack(order + 'II', offset, len(values))
    if len(values):
        align(8)
        out += np.asarray(values, dtype=order + 'f8').tobytes()
    return bytes(out)


def outcome(parse, data, axes):
    """Return ('block', shape, bytes) or ('error', message) of one parse."""
    try:
        block = parse(data, axes)
    except ArrayLayoutError as err:
        return ('error', str(err))
    assert block.dtype == np.float64
    return ('block', block.shape, np.ascontiguousarray(block, dtype='<f8').tobytes())


@st.composite
def messages(draw):
    """Messages around the encoder's layout: often exactly it, else one field or more off."""
    def usually(canonical, *others):
        return draw(st.sampled_from([canonical] * 7 + list(others)))

    axes = draw(st.integers(1, 9))
    samples = usually(draw(st.integers(1, 5)), 0)
    columns = usually(axes, axes + 1, axes - 1)
    row_stride = usually(columns, columns + 2, max(columns - 1, 0))
    offset = usually(0, 1, 3)
    labels = usually(('samples', 'axes'), ('sample', 'axes'), ('samples', 'axis'), ('s', 'x'),
                     ('samples', 'x'), ('samples', 'columns'), ('samples', 'axes_'),
                     ('', ''), ('Samples', 'Axes'))
    dims = [(labels[0], samples, usually(samples * row_stride, 0, 7)),
            (labels[1], columns, row_stride)]
    dims = usually(dims, [], dims[:1], dims + [('z', 1, 1)])
    needed = offset + samples * max(row_stride, columns)
    count = max(usually(needed, needed - 1, needed + 2, samples * columns), 0)
    values = draw(st.lists(st.floats(allow_nan=True, width=64), min_size=count,
                           max_size=count))
    data = bytearray(cdr_message(dims, offset, values, big_endian=usually(False, True),
                                 padding=draw(st.sampled_from([0, 0x76, 0xff]))))
    data[1] = usually(data[1], 0, 2, 3)         # a header that does not say little-endian
    cut = usually(len(data), draw(st.integers(0, len(data))))
    return bytes(data[:cut]), axes


@settings(max_examples=1500, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(messages())
def test_fast_path_and_general_parser_agree(message):
    data, axes = message
    general = outcome(arrays._general_block, data, axes)
    assert outcome(block_of, data, axes) == general
    fast = arrays._fast_block(data, axes)
    event('fast path' if fast is not None else f'general parser: {general[0]}')
    if fast is not None:
        assert general[0] == 'block'
        assert outcome(lambda d, a: fast, data, axes) == general


@settings(max_examples=200, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.integers(1, 6), st.integers(1, 9), st.integers(0, 2**31))
def test_the_fast_path_reads_the_encoders_and_rclpys_bytes(samples, axes, seed):
    block = np.random.default_rng(seed).normal(size=(samples, axes))
    msg = array_message(block.reshape(-1), dims=[('samples', samples, samples * axes),
                                                 ('axes', axes, axes)])
    for data in (encode_float64_multiarray(block), serialize_message(msg)):
        fast = arrays._fast_block(data, axes)
        assert fast is not None and np.array_equal(fast, block)
        assert np.array_equal(arrays._general_block(data, axes), block)
        assert arrays._fast_block(data, axes + 1) is None      # axes mismatch: general


@settings(max_examples=200, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(messages())
def test_the_test_writer_writes_what_rclpy_writes(message):
    data, _ = message
    try:
        dims, offset, values = decode_float64_multiarray(data)
    except ArrayLayoutError:
        return
    if data[1] != 1 or not values.size:
        return
    padded = []
    written = bytearray(cdr_message(dims, offset, values, padded=padded))
    rclpys = bytearray(serialize_message(array_message(values, dims=dims, offset=offset)))
    for position in padded:                     # rclpy leaves its padding uninitialised
        written[position] = rclpys[position]
    assert rclpys == written
