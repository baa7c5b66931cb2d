# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
The multi-axis compensator over DDS, in-process: 8 axes, one model each, array topics.

Blocks of desired displacements (one sample of every axis per message, chunks of K
samples with ``layout.dim``, chunks without it) go through a real publisher, the node's
raw subscription and publisher, and a real subscriber; every column of every command
block must equal the single-axis core (:class:`mpi_ros.compensation.Compensator`, one
``command`` per sample) with that axis's model to 1e-12 A.  Model updates: several axes
in one request apply together or not at all.  No timing is asserted; every wait is bounded.
"""

import time

from diagnostic_msgs.msg import DiagnosticStatus
from mpi_ros.compensation import Compensator
from mpi_ros.nodes.compensator import CompensatorNode, make_node
from mpi_ros.nodes.multi_axis import axis_key, MultiAxisCompensatorNode
from mpi_ros.nodes.spinning import events_executor
import numpy as np
import pytest
import rclpy
from rclpy.parameter import Parameter
from std_msgs.msg import Float64MultiArray, MultiArrayDimension

from ..core_models import random_model, random_walk

AXES = 8
OUTPUT_MIN, OUTPUT_MAX = -3.0, 3.0
#: Commands of the node and of the single-axis core agree to this [A].
TOLERANCE = 1e-12
TIMEOUT = 30.0


def axis_models(seed):
    rng = np.random.default_rng(seed)
    models = []
    for _ in range(AXES):
        model = random_model(rng, n=int(rng.integers(1, 8)), l=int(rng.integers(0, 4)),
                             initial_history=False)
        models.append(model)
    return models


def overrides_for(models):
    overrides = [Parameter('axes', value=len(models)),
                 Parameter('output.min', value=OUTPUT_MIN),
                 Parameter('output.max', value=OUTPUT_MAX),
                 Parameter('diagnostics_period', value=3600.0)]
    for axis, model in enumerate(models):
        overrides += [Parameter(axis_key(axis, key), value=value)
                      for key, value in _plain(model.to_params()).items()]
    return overrides


def desired_block(models, samples, seed):
    """Reachable desired displacements: each axis's model driven by a random walk [m]."""
    rng = np.random.default_rng(seed)
    columns = [model.simulate(np.clip(random_walk(rng, samples, 0.15), -2.5, 2.5))
               for model in models]
    return np.column_stack(columns)


def message(block, *, layout=True):
    msg = Float64MultiArray()
    samples, axes = block.shape
    if layout:
        msg.layout.dim = [MultiArrayDimension(label='samples', size=samples,
                                              stride=samples * axes),
                          MultiArrayDimension(label='axes', size=axes, stride=axes)]
    msg.data = block.reshape(-1).tolist()
    return msg


@pytest.fixture
def rig(ros_context):
    models = axis_models(7)
    node = MultiAxisCompensatorNode(context=ros_context,
                                    parameter_overrides=overrides_for(models))
    source = rclpy.create_node('array_source', context=ros_context)
    received = []
    publisher = source.create_publisher(Float64MultiArray, 'desired_displacements', 10000)
    source.create_subscription(
        Float64MultiArray, 'current_commands',
        lambda msg: received.append(np.array(msg.data).reshape(-1, AXES)), 10000)
    executor = events_executor(ros_context)
    executor.add_node(node)
    executor.add_node(source)
    spin_until(executor, lambda: publisher.get_subscription_count() > 0
               and node.count_subscribers('current_commands') > 0)
    yield models, node, publisher, executor, received
    executor.shutdown()
    source.destroy_node()
    node.destroy_node()


def spin_until(executor, condition):
    deadline = time.monotonic() + TIMEOUT
    while not condition() and time.monotonic() < deadline:
        executor.spin_once(timeout_sec=0.02)


def cores(models):
    return [Compensator(model, output_min=OUTPUT_MIN, output_max=OUTPUT_MAX)
            for model in models]


def reference(axis_cores, block):
    return np.column_stack([[core.command(float(v)) for v in block[:, axis]]
                            for axis, core in enumerate(axis_cores)])


def test_eight_axes_one_sample_per_message_and_chunks_equal_the_single_axis_core(rig):
    models, node, publisher, executor, received = rig
    desired = desired_block(models, 600, seed=3)
    chunks = [desired[k:k + 1] for k in range(200)]                 # one sample each
    chunks += [desired[200 + 10 * k:210 + 10 * k] for k in range(30)]   # K = 10
    chunks += [desired[500 + 25 * k:525 + 25 * k] for k in range(4)]    # K = 25
    for k, chunk in enumerate(chunks):
        publisher.publish(message(chunk, layout=k % 3 != 2))         # some without dim
    spin_until(executor, lambda: len(received) >= len(chunks))
    assert len(received) == len(chunks)
    assert [block.shape for block in received] == [chunk.shape for chunk in chunks]
    commands = np.vstack(received)
    expected = reference(cores(models), desired)
    assert np.max(np.abs(commands - expected)) <= TOLERANCE
    assert np.all((commands >= OUTPUT_MIN) & (commands <= OUTPUT_MAX))
    counters = node.counters
    assert counters['messages_in'] == counters['messages_out'] == len(chunks)
    assert counters['samples_in'] == 600
    assert counters['messages_lost'] == counters['malformed'] == 0
    assert node.diagnostics().status[0].level == DiagnosticStatus.OK


def test_several_axes_change_together_or_not_at_all(rig):
    models, node, publisher, executor, received = rig
    axis_cores = cores(models)
    first = desired_block(models, 50, seed=4)
    new = axis_models(11)
    bad = _plain(new[5].to_params())
    bad['model.hysteresis.weights'] = [-1.0] * len(bad['model.hysteresis.weights'])
    request = ([Parameter(axis_key(2, key), value=value)
                for key, value in _plain(new[2].to_params()).items()]
               + [Parameter(axis_key(5, key), value=value) for key, value in bad.items()])
    result = node.set_parameters_atomically(request)
    assert not result.successful
    assert 'axis 5' in result.reason
    assert node.counters['rejected_updates'] == 1
    assert list(node.get_parameter(axis_key(2, 'model.hysteresis.weights')).value) == list(
        models[2].hysteresis.weights)                               # axis 2 untouched
    publisher.publish(message(first))
    spin_until(executor, lambda: len(received) >= 1)
    assert np.max(np.abs(received[0] - reference(axis_cores, first))) <= TOLERANCE

    good = ([Parameter(axis_key(2, key), value=value)
             for key, value in _plain(new[2].to_params()).items()]
            + [Parameter(axis_key(5, key), value=value)
               for key, value in _plain(new[5].to_params()).items()])
    assert node.set_parameters_atomically(good).successful
    axis_cores[2].install(new[2])
    axis_cores[5].install(new[5])
    second = desired_block(models[:2] + [new[2]] + models[3:5] + [new[5]] + models[6:], 50,
                           seed=5)
    publisher.publish(message(second))
    spin_until(executor, lambda: len(received) >= 2)
    assert np.max(np.abs(received[1] - reference(axis_cores, second))) <= TOLERANCE


def test_a_block_with_the_wrong_axis_count_is_counted_and_warn(rig):
    _, node, publisher, executor, received = rig
    node.diagnostics()
    publisher.publish(Float64MultiArray(data=[1e-6] * 12))      # 12 values, 8 axes
    spin_until(executor, lambda: node.counters['malformed'] > 0)
    assert node.counters['malformed'] == 1
    assert not received
    status = node.diagnostics().status[0]
    assert status.level == DiagnosticStatus.WARN
    assert 'malformed' in status.message and 'axes=8' in status.message


def test_an_axis_without_a_model_leaves_the_node_unconfigured(ros_context):
    models = axis_models(7)
    overrides = [p for p in overrides_for(models) if not p.name.startswith('axis3.')]
    node = MultiAxisCompensatorNode(context=ros_context, parameter_overrides=overrides)
    try:
        assert node.compensator is None
        status = node.diagnostics().status[0]
        assert status.level == DiagnosticStatus.WARN
        assert 'no model for axis 3' in status.message
        keys = [Parameter(axis_key(3, key), value=value)
                for key, value in _plain(models[3].to_params()).items()]
        assert node.set_parameters_atomically(keys).successful
        assert node.compensator is not None
        assert len(node.compensator) == AXES
    finally:
        node.destroy_node()


def test_make_node_picks_the_node_by_axes(ros_context):
    single = make_node(context=ros_context)
    multi = make_node(context=ros_context, parameter_overrides=overrides_for(axis_models(1)))
    try:
        assert isinstance(single, CompensatorNode)
        assert single.get_parameter('axes').value == 1
        assert isinstance(multi, MultiAxisCompensatorNode)
        assert multi.axes == AXES
    finally:
        single.destroy_node()
        multi.destroy_node()


def _plain(params):
    """Turn a model's parameter dict into ROS-typed values (float lists, int sign)."""
    out = {}
    for key, value in params.items():
        if isinstance(value, (list, tuple, np.ndarray)):
            out[key] = [float(v) for v in value]
        elif key.endswith('output_sign'):
            out[key] = int(value)
        else:
            out[key] = float(value)
    return out
