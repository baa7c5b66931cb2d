# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""Write bags of sensor_msgs/JointState and std_msgs/Float64MultiArray with rosbags (tests)."""

import numpy as np
from rosbags.rosbag2 import StoragePlugin, Writer
from rosbags.typesys import get_typestore, Stores

STORE = get_typestore(Stores.ROS2_JAZZY)
JOINT_STATE = 'sensor_msgs/msg/JointState'
ARRAY = 'std_msgs/msg/Float64MultiArray'
FLOAT64 = 'std_msgs/msg/Float64'
STORAGES = {'sqlite3': StoragePlugin.SQLITE3, 'mcap': StoragePlugin.MCAP}


def joint_state(names, position=(), velocity=(), effort=(), stamp_ns=0):
    """Return a JointState message; empty fields stay empty (as publishers leave them)."""
    types = STORE.types
    header = types['std_msgs/msg/Header'](
        stamp=types['builtin_interfaces/msg/Time'](sec=int(stamp_ns // 10**9),
                                                   nanosec=int(stamp_ns % 10**9)),
        frame_id='')
    return types[JOINT_STATE](
        header=header, name=list(names), position=np.asarray(position, dtype=np.float64),
        velocity=np.asarray(velocity, dtype=np.float64),
        effort=np.asarray(effort, dtype=np.float64))


def float64_array(values, data_offset=0):
    """Return a Float64MultiArray with one dimension over `values`."""
    types = STORE.types
    values = np.asarray(values, dtype=np.float64)
    dim = types['std_msgs/msg/MultiArrayDimension'](label='x', size=values.size - data_offset,
                                                    stride=values.size - data_offset)
    layout = types['std_msgs/msg/MultiArrayLayout'](dim=[dim], data_offset=data_offset)
    return types[ARRAY](layout=layout, data=values)


def float64(value):
    """Return a std_msgs/Float64."""
    return STORE.types[FLOAT64](data=float(value))


def write_bag(path, topics, storage='sqlite3'):
    """Write topics {name: (msgtype, [(stamp_ns, msg), ...])} to a new bag; return path."""
    with Writer(path, version=Writer.VERSION_LATEST, storage_plugin=STORAGES[storage]) as bag:
        for topic, (msgtype, messages) in topics.items():
            connection = bag.add_connection(topic, msgtype, typestore=STORE)
            for stamp, msg in messages:
                bag.write(connection, int(stamp), STORE.serialize_cdr(msg, msgtype))
    return path


def _stamps(t):
    return np.round(np.asarray(t, dtype=np.float64) * 1e9).astype(np.int64).tolist()


def write_joint_state_signals(path, t, current, displacement, storage='sqlite3'):
    """
    One /joint_states topic: joint 'actuator' effort = current, position = displacement.

    A second joint 'wrist' carries other numbers, so the joint must be selected.
    """
    messages = [
        (stamp, joint_state(['wrist', 'actuator'], position=[-1.0, s], velocity=[0.0, 0.0],
                            effort=[5.0, x], stamp_ns=stamp))
        for stamp, x, s in zip(_stamps(t), np.asarray(current).tolist(),
                               np.asarray(displacement).tolist())]
    return write_bag(path, {'/joint_states': (JOINT_STATE, messages)}, storage)


def write_array_signals(path, t, current, displacement, storage='sqlite3'):
    """
    Two Float64MultiArray topics: /command [0, current] and /measurement [displacement, 7].

    The output is logged 1 ns after the input, as :func:`write_bag_signals` does.
    """
    stamps = _stamps(t)
    commands = [(stamp, float64_array([0.0, x]))
                for stamp, x in zip(stamps, np.asarray(current).tolist())]
    measurements = [(stamp + 1, float64_array([s, 7.0]))
                    for stamp, s in zip(stamps, np.asarray(displacement).tolist())]
    return write_bag(path, {'/command': (ARRAY, commands),
                            '/measurement': (ARRAY, measurements)}, storage)


def float64_block(block, data_offset=0, row_stride=None, sizes=None, pad=0):
    """
    Return a Float64MultiArray chunk: `block` (K x N) row-major, as the multi-axis nodes send.

    ``layout.dim = [samples (K, K*row), axes (N, row)]``; `row_stride` > N pads every row,
    `data_offset` puts that many values (99.0) in front, `pad` that many after; `sizes`
    overrides the announced (K, N) to build bad layouts.
    """
    types = STORE.types
    block = np.asarray(block, dtype=np.float64)
    samples, axes = block.shape
    row = axes if row_stride is None else row_stride
    rows = np.full((samples, row), -7.0)
    rows[:, :axes] = block
    data = np.concatenate([np.full(data_offset, 99.0), rows.reshape(-1), np.full(pad, -8.0)])
    samples, axes = (samples, axes) if sizes is None else sizes
    dim = types['std_msgs/msg/MultiArrayDimension']
    layout = types['std_msgs/msg/MultiArrayLayout'](
        dim=[dim(label='samples', size=samples, stride=samples * row),
             dim(label='axes', size=axes, stride=row)], data_offset=data_offset)
    return types[ARRAY](layout=layout, data=data)


def chunked(stamps, block, sizes):
    """
    Cut `block` (samples x axes, one row per stamp) into chunks of the given sizes.

    Each chunk is logged at the stamp of its last sample, as a publisher sends a chunk
    when it is complete. `sizes` is one size (the last chunk may be shorter) or a
    sequence that is cycled. Returns [(stamp, message), ...].
    """
    block = np.asarray(block, dtype=np.float64)
    cycle = [sizes] if np.isscalar(sizes) else list(sizes)
    messages, start, k = [], 0, 0
    while start < len(block):
        stop = min(start + int(cycle[k % len(cycle)]), len(block))
        messages.append((stamps[stop - 1], float64_block(block[start:stop])))
        start, k = stop, k + 1
    return messages
