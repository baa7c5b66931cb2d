# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""Float64MultiArray CDR bytes <-> samples x axes blocks, checked against rclpy's own CDR."""

from mpi_ros.nodes.arrays import (
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
