# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Per-axis output limits of the multi-axis compensator, over DDS (issue 12).

``axis<k>.output.min`` / ``axis<k>.output.max`` (unset: the node-wide ``output.min`` /
``output.max``) reach the node through its real parameter services
(``AsyncParameterClient.set_parameters_atomically`` and ``load_parameter_file``, what
``ros2 param load`` sends); blocks go through a real publisher, the node's raw topics and a
real subscriber.  Every column of every command block must equal the single-axis core
(:class:`mpi_ros.compensation.Compensator`) with that axis's model and range to 1e-12 A.  A
request with a model and its limits is applied whole or refused whole; a refused one leaves
the parameters, the running models and the commands as they were.  No timing is asserted;
every wait is bounded.
"""

import re
import time

from diagnostic_msgs.msg import DiagnosticStatus
from mpi_ros.compensation import Compensator
from mpi_ros.errors import ParameterRejected
from mpi_ros.nodes.multi_axis import axis_key, MultiAxisCompensatorNode
import numpy as np
import pytest
import rclpy
from rclpy.parameter import Parameter
from std_msgs.msg import Float64MultiArray
import yaml

from .test_compensator_cli_requests import Cli
from .test_multi_axis_node import _plain, desired_block, message
from ..core_models import random_model

AXES = 3
OUTPUT_MIN, OUTPUT_MAX = -3.0, 3.0
#: Commands of the node and of the single-axis core agree to this [A].
TOLERANCE = 1e-12
TIMEOUT = 30.0
#: Axis 1 has a range of its own, axis 2 only its own maximum [A].
AXIS_LIMITS = {axis_key(1, 'output.min'): -0.5, axis_key(1, 'output.max'): 0.8,
               axis_key(2, 'output.max'): 1.5}
LOWS, HIGHS = [-3.0, -0.5, -3.0], [3.0, 0.8, 1.5]


def axis_models(seed):
    rng = np.random.default_rng(seed)
    return [random_model(rng, n=int(rng.integers(1, 8)), l=int(rng.integers(0, 4)),
                         initial_history=False) for _ in range(AXES)]


def model_parameters(axis, model):
    return [Parameter(axis_key(axis, key), value=value)
            for key, value in _plain(model.to_params()).items()]


def overrides_for(models, limits=AXIS_LIMITS):
    overrides = [Parameter('axes', value=AXES),
                 Parameter('output.min', value=OUTPUT_MIN),
                 Parameter('output.max', value=OUTPUT_MAX),
                 Parameter('diagnostics_period', value=3600.0)]
    for axis, model in enumerate(models):
        overrides += model_parameters(axis, model)
    return overrides + [Parameter(name, value=value) for name, value in limits.items()]


class Rig:
    """The node, a source/sink node and a ros2-param-like client, spun in one thread."""

    def __init__(self, context, models, limits=AXIS_LIMITS):
        self.models = models
        self.node = MultiAxisCompensatorNode(context=context,
                                             parameter_overrides=overrides_for(models, limits))
        self.source = rclpy.create_node('array_source', context=context)
        self.received = []
        self.publisher = self.source.create_publisher(
            Float64MultiArray, 'desired_displacements', 1000)
        self.source.create_subscription(
            Float64MultiArray, 'current_commands',
            lambda msg: self.received.append(np.array(msg.data).reshape(-1, AXES)), 1000)
        self.cli = Cli(context)
        self.cli.add(self.node)
        self.cli.add(self.source)

    def wait_for(self, condition):
        deadline = time.monotonic() + TIMEOUT
        while not condition() and time.monotonic() < deadline:
            time.sleep(0.01)
        return condition()

    def commands(self, block):
        count = len(self.received)
        self.publisher.publish(message(block))
        assert self.wait_for(lambda: len(self.received) > count), 'no command block'
        return self.received[count]

    def atomically(self, parameters):
        messages = [parameter.to_parameter_msg() for parameter in parameters]
        return self.cli.wait(self.cli.client.set_parameters_atomically(messages)).result

    def value(self, name):
        return self.node.get_parameter(name).value

    def diagnostics(self):
        status = self.node.diagnostics().status[0]
        return status, {item.key: item.value for item in status.values}


@pytest.fixture
def rig(ros_context):
    rigs = []

    def start(models=None, limits=AXIS_LIMITS):
        made = Rig(ros_context, axis_models(7) if models is None else models, limits)
        rigs.append(made)
        made.cli.__enter__()
        assert made.wait_for(lambda: made.publisher.get_subscription_count() > 0
                             and made.node.count_subscribers('current_commands') > 0)
        return made

    yield start
    for made in reversed(rigs):
        made.cli.__exit__(None, None, None)
        made.cli.node.destroy_node()
        made.source.destroy_node()
        made.node.destroy_node()


def cores(models, lows=LOWS, highs=HIGHS):
    return [Compensator(model, output_min=low, output_max=high)
            for model, low, high in zip(models, lows, highs)]


def reference(axis_cores, block):
    return np.column_stack([[core.command(float(v)) for v in block[:, axis]]
                            for axis, core in enumerate(axis_cores)])


def assert_same(commands, expected):
    assert commands.shape == expected.shape
    assert np.max(np.abs(commands - expected)) <= TOLERANCE


def test_axis_limits_at_start_bound_their_axis_only_and_show_on_diagnostics(rig):
    started = rig()
    axis_cores = cores(started.models)
    block = desired_block(started.models, 120, seed=3)
    commands = started.commands(block)
    assert_same(commands, reference(axis_cores, block))
    assert np.all((commands >= LOWS) & (commands <= HIGHS))
    assert np.any(commands[:, 1] == 0.8)             # axis 1 is held by its own maximum
    assert started.node.counters['clamped'] > 0
    status, values = started.diagnostics()
    assert values['output_min'] == '-3.0 -0.5 -3.0'
    assert values['output_max'] == '3.0 0.8 1.5'
    assert status.level == DiagnosticStatus.WARN and 'clamped' in status.message


def test_axes_without_limits_of_their_own_report_the_node_wide_range(rig):
    started = rig(limits={})
    _, values = started.diagnostics()
    assert values['output_min'] == '-3.0' and values['output_max'] == '3.0'
    assert started.node.get_parameter(axis_key(0, 'output.min')).type_ == Parameter.Type.NOT_SET


def test_a_model_and_its_limits_in_one_atomic_request_apply_together(rig):
    started = rig()
    axis_cores = cores(started.models)
    first = desired_block(started.models, 60, seed=4)
    assert_same(started.commands(first), reference(axis_cores, first))
    new = axis_models(11)[2]
    limits = {axis_key(2, 'output.min'): -1.0, axis_key(2, 'output.max'): 1.2}
    result = started.atomically(model_parameters(2, new)
                                + [Parameter(n, value=v) for n, v in limits.items()])
    assert result.successful, result.reason
    axis_cores[2].set_limits(-1.0, 1.2)               # the node's order: limits, then model
    axis_cores[2].install(new)
    models = started.models[:2] + [new]
    second = desired_block(models, 60, seed=5)
    commands = started.commands(second)
    assert_same(commands, reference(axis_cores, second))
    assert np.all((commands[:, 2] >= -1.0) & (commands[:, 2] <= 1.2))
    assert started.value(axis_key(2, 'output.min')) == -1.0
    _, values = started.diagnostics()
    assert values['output_min'] == '-3.0 -0.5 -1.0'
    assert values['output_max'] == '3.0 0.8 1.2'
    assert values['model_versions'] == '1 1 2'


@pytest.mark.parametrize('bad, needle', [
    ({axis_key(0, 'output.min'): 1.0, axis_key(0, 'output.max'): 0.5},
     'axis0.output.min must be below axis0.output.max; found axis0.output.min=1.0 A'),
    ({axis_key(0, 'output.min'): 3.5},
     'axis0.output.min must be below output.max; found axis0.output.min=3.5 A and '
     'output.max=3.0 A'),
    ({'output.min': 2.0},                            # axis 2 falls back to output.min
     'output.min must be below axis2.output.max; found output.min=2.0 A and '
     'axis2.output.max=1.5 A'),
])
def test_a_refused_request_changes_nothing(rig, bad, needle):
    started = rig()
    axis_cores = cores(started.models)
    first = desired_block(started.models, 60, seed=6)
    assert_same(started.commands(first), reference(axis_cores, first))
    new = axis_models(13)[0]
    names = [p.name for p in overrides_for(started.models)] + list(bad)
    before = {name: started.value(name) for name in names}
    result = started.atomically(model_parameters(0, new)
                                + [Parameter(n, value=v) for n, v in bad.items()])
    assert not result.successful
    assert re.search(needle, result.reason), result.reason
    assert {name: started.value(name) for name in names} == before
    assert started.node.counters['rejected_updates'] == 1
    _, values = started.diagnostics()
    assert re.search(needle, values['last_rejected_update'])
    assert values['model_versions'] == '1 1 1'
    assert values['output_min'] == '-3.0 -0.5 -3.0'
    second = desired_block(started.models, 60, seed=7)    # the old models, the old ranges
    assert_same(started.commands(second), reference(axis_cores, second))


def test_an_axis_limit_out_of_its_range_is_refused_with_the_model(rig):
    started = rig()
    axis_cores = cores(started.models)
    weights = list(started.value(axis_key(0, 'model.hysteresis.weights')))
    result = started.atomically(model_parameters(0, axis_models(13)[0])
                                + [Parameter(axis_key(0, 'output.max'), value=2000.0)])
    assert not result.successful                     # rclpy's descriptor range, by name
    assert 'axis0.output.max' in result.reason and '1000.0' in result.reason
    assert list(started.value(axis_key(0, 'model.hysteresis.weights'))) == weights
    assert started.node.get_parameter(axis_key(0, 'output.max')).type_ == (
        Parameter.Type.NOT_SET)
    block = desired_block(started.models, 60, seed=9)
    assert_same(started.commands(block), reference(axis_cores, block))


def _file(tmp_path, name, parameters):
    tree = {}
    for key, value in parameters.items():
        node = tree
        *parents, leaf = key.split('.')
        for part in parents:
            node = node.setdefault(part, {})
        node[leaf] = value
    path = tmp_path / name
    path.write_text(yaml.dump({'/compensator': {'ros__parameters': tree}},
                              default_flow_style=False), encoding='utf-8')
    return path


def test_ros2_param_load_sets_a_model_and_its_limits_as_one_group(rig, tmp_path):
    started = rig()
    axis_cores = cores(started.models)
    new = axis_models(17)[1]
    keys = {axis_key(1, key): value for key, value in _plain(new.to_params()).items()}
    bad = _file(tmp_path, 'bad.yaml', dict(keys, **{axis_key(1, 'output.max'): -0.7}))
    results = started.cli.load(bad)
    assert not any(result.successful for result in results.values())
    reason = results[axis_key(1, 'model.hysteresis.weights')].reason
    assert 'axis1.output.min must be below axis1.output.max' in reason
    assert list(started.value(axis_key(1, 'model.hysteresis.weights'))) == list(
        started.models[1].hysteresis.weights)
    assert started.value(axis_key(1, 'output.max')) == 0.8

    changes = {axis_key(1, 'output.max'): 1.1, 'output.min': -2.0}
    good = _file(tmp_path, 'good.yaml', dict(keys, **changes))
    results = started.cli.load(good)
    assert all(result.successful for result in results.values()), results
    axis_cores[0].set_limits(-2.0, 3.0)               # node-wide minimum: axes 0 and 2
    axis_cores[2].set_limits(-2.0, 1.5)
    axis_cores[1].set_limits(-0.5, 1.1)
    axis_cores[1].install(new)
    models = [started.models[0], new, started.models[2]]
    block = desired_block(models, 80, seed=8)
    assert_same(started.commands(block), reference(axis_cores, block))
    _, values = started.diagnostics()
    assert values['output_min'] == '-2.0 -0.5 -2.0'
    assert values['output_max'] == '3.0 1.1 1.5'


def test_unordered_axis_limits_at_start_refuse_to_start(ros_context):
    limits = {axis_key(2, 'output.min'): 1.0, axis_key(2, 'output.max'): -1.0}
    with pytest.raises(ParameterRejected,
                       match='axis2.output.min must be below axis2.output.max'):
        MultiAxisCompensatorNode(context=ros_context,
                                 parameter_overrides=overrides_for(axis_models(7), limits))
