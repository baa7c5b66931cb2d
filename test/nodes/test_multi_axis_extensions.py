# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
The multi-axis compensator with extended models per axis, over DDS.

Three axes: axis 0 with creep, axis 1 plain, axis 2 with rate dependence
(``axis<k>.model.<extension key>``).  Blocks go through a real publisher, the node's raw
subscription and publisher and a real subscriber, and every column must equal a
single-axis core :class:`mpi_ros.compensation.Compensator` with that axis's model fed the
same values and times: ``message_time: nominal`` (``sample_period`` apart), and
``arrival`` with the node's clock replaced by a recorded one and the stream times of
:class:`mpi_ros.compensation.message_time.MessageClock`.  Parameter requests go through the node's
parameter services (``AsyncParameterClient``, what ``ros2 param`` uses).  Each test
holds a ROS_DOMAIN_ID of its own (:func:`test.ros_domain.claim_domain`): the node names
are the usual ``/compensator``, and another run on this machine must not answer.  No
timing is asserted; every wait is bounded.
"""

import itertools
import time

from mpi_ros.compensation import Compensator
from mpi_ros.compensation.message_time import MessageClock
from mpi_ros.errors import ParameterRejected
from mpi_ros.extensions import extended_model_from_params
from mpi_ros.nodes.multi_axis import axis_key, MultiAxisCompensatorNode
import numpy as np
import pytest
import rclpy
from rclpy.parameter import Parameter
from std_msgs.msg import Float64MultiArray

from .test_compensator_cli_requests import Cli
from .test_multi_axis_limits import _file
from .test_multi_axis_node import _plain, desired_block, message
from ..core_models import random_model
from ..ros_domain import claim_domain

AXES = 3
OUTPUT_MIN, OUTPUT_MAX = -3.0, 3.0
SAMPLE_PERIOD = 1.0e-3
#: Commands of the node and of the single-axis cores agree to this [A].
TOLERANCE = 1e-12
TIMEOUT = 30.0
CREEP = {'model.creep.time_constants': [0.01, 0.1, 1.0],
         'model.creep.weights': [0.05, 0.05, 0.1]}
RATE = {'model.rate_dependence.time_constant': 0.002}
#: A second material effect: it does not chain with creep (a composite has at most one).
THERMAL = {'model.thermal_drift.time_constant': 2.0, 'model.thermal_drift.weight': 0.05}
#: The extension of each axis at start: creep, none, rate dependence.
EXTENSIONS = (CREEP, {}, RATE)


def gammas(seed=7):
    rng = np.random.default_rng(seed)
    return [random_model(rng, n=int(rng.integers(1, 8)), l=int(rng.integers(0, 4)),
                         initial_history=False) for _ in range(AXES)]


def axis_parameters(axis, params):
    """Return ``axis<k>.`` parameters of a flat model dict (typed as ROS wants them)."""
    return [Parameter(axis_key(axis, key), value=value) for key, value in _plain(params).items()]


def overrides_for(models, extensions=EXTENSIONS, message_time='nominal', skip=()):
    overrides = [Parameter('axes', value=AXES),
                 Parameter('output.min', value=OUTPUT_MIN),
                 Parameter('output.max', value=OUTPUT_MAX),
                 Parameter('sample_period', value=SAMPLE_PERIOD),
                 Parameter('message_time', value=message_time),
                 Parameter('diagnostics_period', value=3600.0)]
    for axis, (model, extension) in enumerate(zip(models, extensions)):
        if axis not in skip:
            overrides += axis_parameters(axis, dict(model.to_params(), **extension))
    return overrides


def core(model, extension):
    return Compensator(extended_model_from_params(dict(model.to_params(), **extension)),
                       output_min=OUTPUT_MIN, output_max=OUTPUT_MAX,
                       sample_period=SAMPLE_PERIOD)


def reference(cores, block, times=None):
    """Each column through its own single-axis core, sample by sample."""
    stamps = [None] * block.shape[0] if times is None else list(times)
    return np.column_stack([[c.command(float(v), time=t) for v, t in zip(block[:, a], stamps)]
                            for a, c in enumerate(cores)])


class Rig:
    """The node, an array source/sink and a ros2-param-like client, spun in one thread."""

    def __init__(self, context, overrides):
        self.node = MultiAxisCompensatorNode(context=context, parameter_overrides=overrides)
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

    def send(self, chunks, *, layout=True):
        """Publish the chunks and return the command blocks, stacked."""
        count = len(self.received)
        for k, chunk in enumerate(chunks):
            self.publisher.publish(message(chunk, layout=layout or k % 2 == 0))
        assert self.wait_for(lambda: len(self.received) >= count + len(chunks)), 'no commands'
        blocks = self.received[count:count + len(chunks)]
        assert [b.shape for b in blocks] == [c.shape for c in chunks]
        return np.vstack(blocks)

    def atomically(self, parameters):
        messages = [parameter.to_parameter_msg() for parameter in parameters]
        return self.cli.wait(self.cli.client.set_parameters_atomically(messages)).result

    def value(self, name):
        return self.node.get_parameter(name).value

    def values(self):
        """Every axis<k>.* value, as plain lists and numbers."""
        return {(axis, name): (list(p.value) if isinstance(p.value, (list, tuple)) or hasattr(
                    p.value, 'tolist') else p.value)
                for axis in range(AXES)
                for name, p in self.node.get_parameters_by_prefix(f'axis{axis}').items()}

    def diagnostics(self):
        status = self.node.diagnostics().status[0]
        return status, {item.key: item.value for item in status.values}


@pytest.fixture
def ros_context(monkeypatch):
    """Yield an initialised private rclpy.Context on a local-only domain held by this test."""
    with claim_domain() as domain_id:
        monkeypatch.setenv('ROS_AUTOMATIC_DISCOVERY_RANGE', 'LOCALHOST')
        monkeypatch.setenv('ROS_DOMAIN_ID', str(domain_id))
        monkeypatch.delenv('ROS_LOCALHOST_ONLY', raising=False)
        context = rclpy.Context()
        rclpy.init(context=context)
        try:
            yield context
        finally:
            rclpy.try_shutdown(context=context)


@pytest.fixture
def rig(ros_context):
    rigs = []

    def start(overrides):
        made = Rig(ros_context, overrides)
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


def chunks_of(block, sizes):
    """Split a block into chunks of the given sizes, in turn (1-sample messages too)."""
    chunks, start, k = [], 0, 0
    while start < block.shape[0]:
        size = sizes[k % len(sizes)]
        chunks.append(block[start:start + size])
        start, k = start + size, k + 1
    return chunks


def assert_same(commands, expected):
    assert commands.shape == expected.shape
    assert np.max(np.abs(commands - expected)) <= TOLERANCE


def test_nominal_every_column_equals_its_single_axis_core(rig):
    models = gammas()
    started = rig(overrides_for(models))
    cores = [core(m, e) for m, e in zip(models, EXTENSIONS)]
    desired = desired_block(models, 300, seed=3)
    commands = started.send(chunks_of(desired, [1, 10, 1, 25]), layout=False)
    assert_same(commands, reference(cores, desired))
    assert np.all((commands >= OUTPUT_MIN) & (commands <= OUTPUT_MAX))
    # The effects are used: axes 0 and 2 differ from a plain core, axis 1 does not.
    plain = reference([core(m, {}) for m in models], desired)
    assert np.max(np.abs(commands[:, 0] - plain[:, 0])) > 1e-3
    assert np.max(np.abs(commands[:, 2] - plain[:, 2])) > 1e-3
    assert np.array_equal(commands[:, 1], plain[:, 1])
    _, values = started.diagnostics()
    assert values['messages_lost'] == values['malformed'] == '0'
    assert values['extension'] == 'creep none rate_dependence'
    assert 'not_compensated' not in values
    assert len(values['axis0.slow_state'].split()) == 3        # one lag per creep term
    assert len(values['axis2.slow_state'].split()) == 1        # the lagged current
    assert 'axis1.slow_state' not in values
    assert values['bad_time'] == '0'


def test_arrival_times_the_chunks_on_the_stream_not_on_the_jitter(rig):
    models = gammas()
    started = rig(overrides_for(models, message_time='arrival'))
    # The node's steady clock replaced by a recorded one: chunks of 5 samples that come
    # 5 sample periods apart, sooner (a burst), later (a busy executor) and, once, after
    # a pause of 0.5 s.
    steps = itertools.chain([0.005, 0.002, 0.0004, 0.03, 0.005, 0.001] * 3, [0.5],
                            itertools.cycle([0.005, 0.0004, 0.02]))
    stamps = []

    def clock():
        stamps.append((stamps[-1] if stamps else 100.0) + next(steps))
        return stamps[-1]

    started.node._arrival_clock = clock
    desired = desired_block(models, 200, seed=4)
    chunks = chunks_of(desired, [5])
    commands = started.send(chunks)
    assert len(stamps) == len(chunks)                      # one clock reading per message
    stream = MessageClock()
    times = np.concatenate([stream.times(t, 5, SAMPLE_PERIOD) for t in stamps])
    assert stream.pauses == 1
    # The 19th chunk (samples 90-94) came 0.5 s after the 18th: its last sample 0.5 s
    # after the 18th's last one; every other interval the sample period.
    intervals = np.diff(times)
    assert intervals[89] == pytest.approx(0.496, abs=1e-9)
    np.testing.assert_allclose(np.delete(intervals, 89), SAMPLE_PERIOD, rtol=0, atol=1e-9)
    cores = [core(m, e) for m, e in zip(models, EXTENSIONS)]
    assert_same(commands, reference(cores, desired, times))
    # Until the pause the jittered arrivals give the nominal commands; the pause matters.
    nominal = reference([core(m, e) for m, e in zip(models, EXTENSIONS)], desired)
    # (to the rounding of stream times near 100 s: 1e-14 s in a 1 ms interval)
    np.testing.assert_allclose(commands[:90], nominal[:90], rtol=0, atol=1e-9)
    assert np.max(np.abs(commands[90:, 0] - nominal[90:, 0])) > 1e-9
    assert started.node.counters['bad_time'] == 0


def test_extension_keys_alone_change_one_axis_only(rig):
    models = gammas()
    started = rig(overrides_for(models))
    cores = [core(m, e) for m, e in zip(models, EXTENSIONS)]
    first = desired_block(models, 60, seed=5)
    assert_same(started.send(chunks_of(first, [10])), reference(cores, first))
    axis0 = started.node.compensator.axes[0]
    slow = axis0.slow_state

    rate = {'model.rate_dependence.time_constant': 0.004}
    result = started.atomically(axis_parameters(1, rate))          # the running Gamma of axis 1
    assert result.successful, result.reason
    cores[1].install(extended_model_from_params(dict(models[1].to_params(), **rate)))
    assert started.node.compensator.axes[1].model.cause == 'rate_dependence'
    assert started.node.compensator.axes[0] is axis0                # axis 0 untouched
    np.testing.assert_array_equal(axis0.slow_state, slow)
    _, values = started.diagnostics()
    assert values['extension'] == 'creep rate_dependence rate_dependence'
    assert values['model_versions'] == '1 2 1'
    second = desired_block(models, 60, seed=6)
    assert_same(started.send(chunks_of(second, [1, 7])), reference(cores, second))

    # Same kind on axis 0 (new creep weights alone): swapped, slow states kept.
    creep = {'model.creep.weights': [0.02, 0.05, 0.1]}
    assert started.atomically(axis_parameters(0, creep)).successful
    cores[0].install(extended_model_from_params(dict(models[0].to_params(),
                                                     **dict(CREEP, **creep))))
    np.testing.assert_array_equal(started.node.compensator.axes[0].slow_state,
                                  cores[0].slow_state)
    third = desired_block(models, 40, seed=7)
    assert_same(started.send(chunks_of(third, [4])), reference(cores, third))


def test_an_input_stage_beside_a_running_creep_makes_a_composite(rig):
    # Rate-dependence keys pushed to the axis that runs creep: both effects chain (the lag
    # before the material, the creep in it); the axis compensates the composite exactly.
    models = gammas()
    started = rig(overrides_for(models))
    cores = [core(m, e) for m, e in zip(models, EXTENSIONS)]
    first = desired_block(models, 40, seed=13)
    assert_same(started.send(chunks_of(first, [8])), reference(cores, first))
    result = started.atomically(axis_parameters(0, RATE))
    assert result.successful, result.reason
    cores[0].install(extended_model_from_params(dict(models[0].to_params(),
                                                     **dict(CREEP, **RATE))))
    assert started.node.compensator.axes[0].model.cause == 'creep + rate_dependence'
    _, values = started.diagnostics()
    assert values['extension'] == 'creep+rate_dependence none rate_dependence'
    assert len(values['axis0.slow_state'].split()) == 4        # the lagged current, 3 lags
    second = desired_block(models, 60, seed=14)
    assert_same(started.send(chunks_of(second, [1, 9])), reference(cores, second))


def test_a_plain_push_and_a_null_switch_one_axis_extension_off(rig):
    models = gammas()
    started = rig(overrides_for(models))
    cores = [core(m, e) for m, e in zip(models, EXTENSIONS)]
    first = desired_block(models, 50, seed=8)
    assert_same(started.send(chunks_of(first, [5])), reference(cores, first))

    # The five Gamma keys of axis 0: its whole model, so its creep goes off.
    gamma_keys = {key: value for key, value in models[0].to_params().items()
                  if key.startswith('model.hysteresis') or key.startswith('model.superposition')}
    result = started.atomically(axis_parameters(0, gamma_keys))
    assert result.successful, result.reason
    assert started.value(axis_key(0, 'model.creep.weights')) == []
    assert started.value(axis_key(0, 'model.creep.time_constants')) == []
    assert not started.node.compensator.axes[0].has_effect
    cores[0].install(models[0])
    # A null for axis 2's extension key: its rate dependence goes off too.
    null = Parameter(axis_key(2, 'model.rate_dependence.time_constant'))
    assert null.type_ == Parameter.Type.NOT_SET
    result = started.atomically([null])
    assert result.successful, result.reason
    assert started.value(axis_key(2, 'model.rate_dependence.time_constant')) == 0.0
    cores[2].install(models[2])
    _, values = started.diagnostics()
    assert values['extension'] == 'none none none'
    assert values['model_versions'] == '2 1 2'
    second = desired_block(models, 50, seed=9)
    assert_same(started.send(chunks_of(second, [1, 9])), reference(cores, second))
    assert not started.node._timed                 # no lag left: the plain message path


REFUSED = {
    'two extensions on one axis': (
        lambda: axis_parameters(1, dict(CREEP, **THERMAL)),
        'axis 1 (axis1.model.*): parameters hold keys of several model extensions'),
    'a second extension beside a running one': (
        lambda: axis_parameters(0, THERMAL),
        'axis 0 (axis0.model.*): parameters hold keys of several model extensions'),
    'a bad extension beside a good axis': (
        lambda: (axis_parameters(2, {'model.rate_dependence.time_constant': 0.004})
                 + axis_parameters(1, {'model.creep.time_constants': [0.1, 1.0],
                                       'model.creep.weights': [0.05]})),
        'axis 1 (axis1.model.*): axis1.model.creep.weights must have one weight per time '
        'constant: expected 2, found 1'),
    'a negative time constant': (                   # refused by the declared range
        lambda: axis_parameters(2, {'model.rate_dependence.time_constant': -0.01}),
        'axis2.model.rate_dependence.time_constant'),
}


@pytest.mark.parametrize('case', sorted(REFUSED))
def test_a_refused_request_changes_nothing(rig, case):
    request, needle = REFUSED[case]
    models = gammas()
    started = rig(overrides_for(models))
    cores = [core(m, e) for m, e in zip(models, EXTENSIONS)]
    first = desired_block(models, 40, seed=10)
    assert_same(started.send(chunks_of(first, [8])), reference(cores, first))
    before = started.values()
    result = started.atomically(request())
    assert not result.successful
    assert needle in result.reason, result.reason
    assert started.values() == before
    _, values = started.diagnostics()
    assert values['model_versions'] == '1 1 1'
    assert values['extension'] == 'creep none rate_dependence'
    if 'negative' not in case:                        # rclpy's own range check comes first
        assert values['rejected_updates'] == '1'
        assert needle in values['last_rejected_update']
    second = desired_block(models, 40, seed=11)          # the old models run on
    assert_same(started.send(chunks_of(second, [3])), reference(cores, second))


def test_extension_keys_for_an_axis_without_gamma_are_refused(rig, ros_context):
    models = gammas()
    started = rig(overrides_for(models, skip=(2,)))
    assert started.node.compensator is None
    before = started.values()
    result = started.atomically(axis_parameters(2, RATE))
    assert not result.successful
    assert ('axis 2 has no model yet, so axis2.model.rate_dependence.time_constant cannot '
            'apply') in result.reason
    assert 'missing: axis2.model.hysteresis.thresholds' in result.reason
    assert started.values() == before
    assert started.node.compensator is None
    # The same at start: the node refuses to start rather than run without that axis.
    overrides = overrides_for(models, skip=(2,)) + axis_parameters(2, RATE)
    with pytest.raises(ParameterRejected, match='axis 2 has no model yet, so '
                       'axis2.model.rate_dependence.time_constant cannot apply'):
        MultiAxisCompensatorNode(context=ros_context, parameter_overrides=overrides)
    # Gamma and the extension together configure the axis.
    result = started.atomically(axis_parameters(2, dict(models[2].to_params(), **RATE)))
    assert result.successful, result.reason
    assert started.node.compensator.axes[2].model.cause == 'rate_dependence'


def test_ros2_param_load_of_axis_extension_keys(rig, tmp_path):
    models = gammas()
    started = rig(overrides_for(models))
    cores = [core(m, e) for m, e in zip(models, EXTENSIONS)]
    first = desired_block(models, 30, seed=12)
    assert_same(started.send(chunks_of(first, [6])), reference(cores, first))

    # Two material effects (creep, thermal drift) on axis 1: the file's model keys are refused
    # together.
    bad = _file(tmp_path, 'bad.yaml', {
        axis_key(1, 'model.creep.time_constants'): [0.02, 0.2],
        axis_key(1, 'model.creep.weights'): [0.05, 0.05],
        axis_key(1, 'model.thermal_drift.time_constant'): 2.0,
        axis_key(1, 'model.thermal_drift.weight'): 0.05,
        axis_key(0, 'model.creep.weights'): [0.01, 0.02, 0.03]})
    before = started.values()
    results = started.cli.load(bad)
    assert not any(result.successful for result in results.values())
    assert 'several model extensions' in results[axis_key(0, 'model.creep.weights')].reason
    assert started.values() == before

    # Creep weights on axis 0 (same kind), creep added to axis 1, a new rate on axis 2,
    # with the floats ros2 param load turns into strings (1e-05 written without a dot).
    changes = {axis_key(0, 'model.creep.weights'): [0.01, 0.02, 1e-05],
               axis_key(1, 'model.creep.time_constants'): [0.02, 0.2],
               axis_key(1, 'model.creep.weights'): [0.05, 0.05],
               axis_key(2, 'model.rate_dependence.time_constant'): 0.003}
    results = started.cli.load(_file(tmp_path, 'good.yaml', changes))
    assert all(result.successful for result in results.values()), results
    assert list(started.value(axis_key(0, 'model.creep.weights'))) == [0.01, 0.02, 1e-05]
    cores[0].install(extended_model_from_params(dict(
        models[0].to_params(), **{'model.creep.time_constants': [0.01, 0.1, 1.0],
                                  'model.creep.weights': [0.01, 0.02, 1e-05]})))
    cores[1].install(extended_model_from_params(dict(
        models[1].to_params(), **{'model.creep.time_constants': [0.02, 0.2],
                                  'model.creep.weights': [0.05, 0.05]})))
    cores[2].install(extended_model_from_params(dict(
        models[2].to_params(), **{'model.rate_dependence.time_constant': 0.003})))
    _, values = started.diagnostics()
    assert values['extension'] == 'creep creep rate_dependence'
    assert values['model_versions'] == '2 2 2'
    second = desired_block(models, 60, seed=13)
    assert_same(started.send(chunks_of(second, [1, 12])), reference(cores, second))


def test_dead_time_on_one_axis_compensates_its_gamma(rig):
    # dead_time_prediction false: the dead-time axis is Gamma^-1 alone, and said so.
    models = gammas()
    extensions = (CREEP, {'model.dead_time': 0.01}, {})
    started = rig(overrides_for(models, extensions)
                  + [Parameter('dead_time_prediction', value=False)])
    cores = [core(models[0], CREEP), core(models[1], {}), core(models[2], {})]
    desired = desired_block(models, 40, seed=14)
    assert_same(started.send(chunks_of(desired, [4])), reference(cores, desired))
    _, values = started.diagnostics()
    assert values['extension'] == 'creep dead_time none'
    assert values['not_compensated'] == '1'


def test_dead_time_on_one_axis_is_predicted_by_default(rig):
    # The default: the dead-time axis predicts (as its single-axis core does), the block
    # path serves it sample by sample, and no axis is reported not compensated.
    models = gammas()
    extensions = (CREEP, {'model.dead_time': 0.01}, {})
    started = rig(overrides_for(models, extensions))
    cores = [core(models[0], CREEP), core(models[1], {'model.dead_time': 0.01}),
             core(models[2], {})]
    assert cores[1].kind == 'dead_time (predicted)'
    desired = desired_block(models, 40, seed=14)
    commands = started.send(chunks_of(desired, [4]))
    assert_same(commands, reference(cores, desired))
    gamma_alone = reference([core(models[1], {})], desired[:, 1:2])
    assert np.max(np.abs(commands[:, 1] - gamma_alone[:, 0])) > 1e-9    # it does predict
    _, values = started.diagnostics()
    assert values['extension'] == 'creep dead_time none'
    assert 'not_compensated' not in values
