# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
The compensator nodes' ``start_state`` (issue 24, item 2).

Declared with a descriptor, validated when set, taken when the core is built, logged at
activation.
"""

from mpi_ros.compensation import Compensator
from mpi_ros.nodes.compensator import CompensatorNode
from mpi_ros.nodes.multi_axis import MultiAxisCompensatorNode
from mpi_ros.operators.model import MPIModel
from mpi_ros.operators.start import identified_ranges
import numpy as np
import pytest
from rclpy.parameter import Parameter

from .lifecycle_rig import LifecycleRig
from .test_compensator_node import as_parameters, limits, MODEL_A, OUTPUT_MAX, OUTPUT_MIN

#: Desired displacements inside MODEL_A's range [m] (MODEL_A tells its identified range:
#: one S' threshold on each side).
DESIRED = 2.0e-5 + 1.0e-5 * np.sin(np.linspace(0.0, 6.0, 60))


@pytest.fixture
def make_node(ros_context):
    """Build CompensatorNodes on the private context and destroy them afterwards."""
    nodes = []

    def make(overrides=()):
        node = CompensatorNode(context=ros_context, parameter_overrides=list(overrides))
        nodes.append(node)
        return node

    yield make
    for node in nodes:
        node.destroy_node()


class _Log:
    """A logger that keeps what the node says (rclpy's goes to the console)."""

    def __init__(self):
        self.lines = []

    def info(self, text, **kwargs):
        self.lines.append(text)

    warning = warn = error = debug = info


def test_start_state_is_declared_validated_and_logged_at_activation(make_node):
    node = make_node(limits() + as_parameters(MODEL_A)
                     + [Parameter('start_state', value='rest_high'),
                        Parameter('autostart', value=False)])
    described = node.describe_parameter('start_state')
    assert 'rest_low' in described.description and described.additional_constraints
    for bad in ('middle', '0.1, x', ''):
        result = node.set_parameters([Parameter('start_state', value=bad)])[0]
        assert not result.successful
        assert result.reason.startswith('start_state must be one of rest_low, rest_high')
    assert node.get_parameter('start_state').value == 'rest_high'
    log = _Log()
    node.get_logger = lambda: log
    rig = LifecycleRig(node.context, node)
    try:
        assert rig.change_state('configure') and rig.change_state('activate')
    finally:
        rig.close()
    gamma = MPIModel.from_params(MODEL_A)
    low, high = identified_ranges(gamma)[0]
    low, high = max(low, OUTPUT_MIN), min(high, OUTPUT_MAX)
    started = [line for line in log.lines if line.startswith('start state: ')]
    assert started == [f'start state: rest_high: at rest after a sweep down to the lowest '
                       f'identified input, {low:.6g} A, and up to the highest, {high:.6g} A']
    # The core starts there: the node's commands are the core's with the same start.
    core = Compensator(gamma, output_min=OUTPUT_MIN, output_max=OUTPUT_MAX, start='rest_high')
    assert core.last_command == high
    np.testing.assert_allclose([node.command(v) for v in DESIRED],
                               [core.command(v) for v in DESIRED], rtol=0.0, atol=1e-12)


def test_the_default_start_is_rest_low_and_record_is_the_record_start(make_node):
    record = dict(MODEL_A, **{'record_start.hysteresis.initial_states': [0.3, 0.1, -0.1]})
    for start, expected in (('rest_low', 'rest_low: at rest after a sweep up to'),
                            ('record', "record: the model's record start")):
        node = make_node(limits() + as_parameters(record)
                         + [Parameter('start_state', value=start)])
        assert node.compensator.start_description.startswith(expected)
        core = Compensator(MPIModel.from_params(record), output_min=OUTPUT_MIN,
                           output_max=OUTPUT_MAX, start=start)
        np.testing.assert_array_equal(node.compensator.state, core.state)
    np.testing.assert_array_equal(core.state, [0.3, 0.1, -0.1])


def test_multi_axis_node_starts_every_axis_where_start_state_says(ros_context):
    axes = {f'axis{k}.{key}': value for k in range(2) for key, value in MODEL_A.items()}
    node = MultiAxisCompensatorNode(
        context=ros_context, parameter_overrides=limits() + as_parameters(axes) + [
            Parameter('axes', value=2), Parameter('start_state', value='-0.5, -0.2, 0.1'),
            Parameter('axis1.model.input_quantity', value='voltage')])
    try:
        for axis, unit in zip(node.compensator.axes, ('A', 'V')):
            np.testing.assert_array_equal(axis.state, [-0.5, -0.2, 0.1])
            assert axis.start_description == f'explicit play states [-0.5, -0.2, 0.1] {unit}'
    finally:
        node.destroy_node()


def test_a_voltage_model_starts_in_volts(make_node):
    # The start's words carry the model's input unit (they said A for every model).
    node = make_node(limits() + as_parameters(MODEL_A)
                     + [Parameter('model.input_quantity', value='voltage')])
    low, high = identified_ranges(MPIModel.from_params(MODEL_A))[0]
    low, high = max(low, OUTPUT_MIN), min(high, OUTPUT_MAX)
    assert node.compensator.start_description == (
        f'rest_low: at rest after a sweep up to the highest identified input, {high:.6g} V,'
        f' and down to the lowest, {low:.6g} V')


@pytest.mark.parametrize('start', ['rest_low', 'record'])
def test_a_push_keeps_the_start_of_the_running_core(make_node, start):
    node = make_node(limits() + as_parameters(MODEL_A) + [Parameter('start_state', value=start)])
    before = node.compensator.state
    result = node.set_parameters_atomically(as_parameters(MODEL_A))
    assert result.successful, result.reason
    np.testing.assert_array_equal(node.compensator.state, before)
