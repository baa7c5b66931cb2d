# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
The compensator node with extended models (creep, rate dependence, thermal drift, dead time).

In-process on a private context, like ``test_compensator_node.py``: parameter updates go
through ``Node.set_parameters_atomically``, the function rclpy's parameter service calls.
"""

import math
import time

from mpi_ros.compensation import Compensator
from mpi_ros.extensions import extended_model_from_params
from mpi_ros.nodes.compensator import CompensatorNode
from mpi_ros.nodes.spinning import events_executor
from mpi_ros.operators.model import MODEL_KEYS
import numpy as np
import pytest
import rclpy
from rclpy.parameter import Parameter
from std_msgs.msg import Float64

from .test_compensator_node import MODEL_A, OPERATING_POINT, OUTPUT_MAX, OUTPUT_MIN

CREEP = {'model.creep.time_constants': [0.01, 0.1, 1.0],
         'model.creep.weights': [0.05, 0.05, 0.1]}
RATE = {'model.rate_dependence.time_constant': 0.005}
THERMAL = {'model.thermal_drift.time_constant': 5.0, 'model.thermal_drift.weight': 0.02}
DEAD = {'model.dead_time': 0.01}

#: Desired displacements [m] (inside the operating range) and their times [s] at 1 kHz.
DESIRED = 2.0e-5 + 1.2e-5 * np.sin(np.linspace(0.0, 12.0, 400))
STAMPS = 100.0 + 1.0e-3 * np.arange(DESIRED.size)


def typed(mapping):
    """Return rclpy Parameters with explicit types (lists: double arrays)."""
    out = []
    for name, value in mapping.items():
        if isinstance(value, list):
            out.append(Parameter(name, Parameter.Type.DOUBLE_ARRAY, [float(v) for v in value]))
        elif isinstance(value, int):
            out.append(Parameter(name, Parameter.Type.INTEGER, value))
        else:
            out.append(Parameter(name, Parameter.Type.DOUBLE, float(value)))
    return out


def limits():
    return typed({'output.min': OUTPUT_MIN, 'output.max': OUTPUT_MAX})


@pytest.fixture
def make_node(ros_context):
    nodes = []

    def make(overrides=()):
        node = CompensatorNode(context=ros_context, parameter_overrides=list(overrides))
        nodes.append(node)
        return node

    yield make
    for node in nodes:
        node.destroy_node()


def run(node, desired=DESIRED, stamps=STAMPS):
    return np.array([node.command(float(d), stamp=float(t)) for d, t in zip(desired, stamps)])


def core(params):
    comp = Compensator(extended_model_from_params(params), output_min=OUTPUT_MIN,
                       output_max=OUTPUT_MAX, sample_period=1e-3)
    if comp.has_effect:
        return np.array([comp.command(float(d), time=float(t))
                         for d, t in zip(DESIRED, STAMPS)])
    return np.array([comp.command(float(d)) for d in DESIRED])


@pytest.mark.parametrize('extension', [CREEP, RATE, THERMAL], ids=['creep', 'rate', 'thermal'])
def test_extended_set_is_accepted_and_used(make_node, extension):
    node = make_node(limits() + typed(MODEL_A))
    result = node.set_parameters_atomically(typed(dict(MODEL_A, **extension)))
    assert result.successful, result.reason
    assert node.compensator.has_effect      # the effect's per-step inverse is in use
    assert node.model_version == 2
    commands = run(node)
    assert np.all(np.isfinite(commands))
    assert np.all((commands >= OUTPUT_MIN) & (commands <= OUTPUT_MAX))
    # The node computes what the core's Compensator computes from the same
    # inputs and times (the node's swap replays the same start, so exactly equal) ...
    np.testing.assert_allclose(commands, core(dict(MODEL_A, **extension)), rtol=0, atol=1e-12)
    # ... which is not the plain compensator's answer.
    assert np.max(np.abs(commands - core(MODEL_A))) > 1e-3
    assert node.counters['bad_time'] == 0
    values = {kv.key: kv.value for kv in node.diagnostics().status[0].values}
    assert values['extension'] == next(iter(extension)).split('.')[1]
    assert values['bad_time'] == '0'
    assert len(values['slow_state'].split()) == node.compensator.slow_state.size


@pytest.mark.parametrize('extension', [CREEP, RATE, THERMAL], ids=['creep', 'rate', 'thermal'])
def test_extended_compensator_with_an_operating_point(make_node, extension):
    """Issue 9: input bias, sensor zero and sign -1 with an extension: the core's commands."""
    params = dict(MODEL_A, **extension, **OPERATING_POINT)
    node = make_node(limits() + typed(params))
    assert node.compensator.has_effect      # the effect's per-step inverse is in use
    desired = 1.0e-4 - DESIRED
    commands = run(node, desired)
    reference = Compensator(extended_model_from_params(params), output_min=OUTPUT_MIN,
                            output_max=OUTPUT_MAX, sample_period=1e-3)
    expected = [reference.command(float(d), time=float(t)) for d, t in zip(desired, STAMPS)]
    np.testing.assert_allclose(commands, expected, rtol=0, atol=1e-12)
    assert np.all((commands >= OUTPUT_MIN) & (commands <= OUTPUT_MAX))
    # The operating point is used: the origin model's commands are about x0 = 0.4 A lower.
    assert np.median(commands - core(dict(MODEL_A, **extension))) > 0.2
    # A swap within the kind, at the operating point: the same compensator, swapped.
    compensator = node.compensator
    assert node.set_parameters_atomically(typed(params)).successful
    assert node.compensator is compensator
    if extension is not RATE:
        # Bumpless (the rate inverse's derivative term restarts: not comparable this way).
        after = node.command(float(desired[-1]), stamp=float(STAMPS[-1]) + 1e-6)
        assert after == pytest.approx(commands[-1], abs=1e-6)


def test_extended_model_from_the_params_file(make_node):
    node = make_node(limits() + typed(dict(MODEL_A, **RATE)))
    assert node.compensator.has_effect      # the effect's per-step inverse is in use
    np.testing.assert_allclose(run(node), core(dict(MODEL_A, **RATE)), rtol=0, atol=1e-12)


def test_extended_compensator_survives_extreme_input(make_node):
    node = make_node(limits() + typed(dict(MODEL_A, **CREEP)))
    for k, desired in enumerate((math.nan, math.inf, -math.inf, 1e300, -1e300, 1.0, 2e-5)):
        current = node.command(desired, stamp=k * 1e-3)
        assert math.isfinite(current) and OUTPUT_MIN <= current <= OUTPUT_MAX
    node.command(2e-5, stamp=0.0)       # time going back: counted, nominal interval used
    assert node.counters['bad_time'] == 1


def _old_running(node, old_compensator, old_model):
    assert node.compensator is old_compensator
    assert node.compensator.model is old_model
    assert node.model_version == 1


BAD_EXTENSIONS = {
    'negative creep weight': ('model.creep.weights',
                              dict(CREEP, **{'model.creep.weights': [0.05, -0.1, 0.1]})),
    'creep weights shorter': ('model.creep.weights',
                              dict(CREEP, **{'model.creep.weights': [0.05, 0.1]})),
    'zero creep time constant': ('model.creep.time_constants',
                                 dict(CREEP, **{'model.creep.time_constants': [0.0, 0.1, 1.0]})),
    'creep weights missing': ('model.creep.weights',
                              {'model.creep.time_constants': [0.1, 1.0]}),
    'negative rate time constant': ('model.rate_dependence.time_constant',
                                    {'model.rate_dependence.time_constant': -0.005}),
    'thermal time constant 0 with a weight': ('model.thermal_drift.time_constant',
                                              {'model.thermal_drift.time_constant': 0.0,
                                               'model.thermal_drift.weight': 0.02}),
    'two extensions': ('creep, thermal_drift', dict(CREEP, **THERMAL)),
}


@pytest.mark.parametrize('case', sorted(BAD_EXTENSIONS))
def test_bad_extension_is_rejected_and_old_model_kept(make_node, case):
    key, bad = BAD_EXTENSIONS[case]
    node = make_node(limits() + typed(MODEL_A))
    old_compensator, old_model = node.compensator, node.compensator.model
    before = node.command(2.0e-5)
    result = node.set_parameters_atomically(typed(dict(MODEL_A, **bad)))
    assert not result.successful
    assert key in result.reason
    _old_running(node, old_compensator, old_model)
    assert node.command(2.0e-5) == pytest.approx(before, abs=1e-12)
    # The same extension keys alone (on the running Gamma) are rejected as well.
    result = node.set_parameters_atomically(typed(bad))
    assert not result.successful and key in result.reason
    _old_running(node, old_compensator, old_model)


def test_integer_creep_array_is_rejected_naming_the_key(make_node):
    node = make_node(limits() + typed(MODEL_A))
    result = node.set_parameters_atomically(
        typed(MODEL_A) + [Parameter('model.creep.time_constants', value=[1, 2])])
    assert not result.successful and 'model.creep.time_constants' in result.reason
    assert not node.compensator.has_effect  # Gamma's inverse alone


def test_extension_without_a_model_is_rejected(make_node):
    node = make_node(limits())
    result = node.set_parameters_atomically(typed(RATE))
    assert not result.successful
    assert 'model.rate_dependence.time_constant' in result.reason
    assert node.compensator is None


def test_plain_creep_plain_switching(make_node):
    node = make_node(limits() + typed(MODEL_A))
    run(node, DESIRED[:200], STAMPS[:200])
    desired = float(DESIRED[200])
    reference = node.compensator.state.copy()

    # plain -> creep: the creep's per-step inverse taking over the operating point.
    assert node.set_parameters_atomically(typed(dict(MODEL_A, **CREEP))).successful
    assert node.compensator.has_effect      # the effect's per-step inverse is in use
    np.testing.assert_allclose(node.compensator.state, reference, atol=1e-12)
    assert node.counters['messages'] == 200                 # counters go on

    # creep -> plain (the five core keys only): creep switched off, parameters say so.
    assert node.set_parameters_atomically(typed(MODEL_A)).successful
    assert not node.compensator.has_effect  # Gamma's inverse alone
    assert list(node.get_parameter('model.creep.weights').value) == []
    assert node.model_version == 3
    # No message in between: the round trip gives back the plain operating point.
    np.testing.assert_allclose(node.compensator.state, reference, atol=1e-12)
    plain_reference = make_node(limits() + typed(MODEL_A))
    run(plain_reference, DESIRED[:200], STAMPS[:200])
    assert node.command(desired) == pytest.approx(plain_reference.command(desired), abs=1e-12)

    # plain -> creep -> creep (same kind): install, bumpless.
    assert node.set_parameters_atomically(typed(dict(MODEL_A, **CREEP))).successful
    commands = run(node, DESIRED[201:300], STAMPS[201:300])
    compensator = node.compensator
    assert node.set_parameters_atomically(typed(dict(MODEL_A, **CREEP))).successful
    assert node.compensator is compensator                  # swapped, not rebuilt
    after = node.command(float(DESIRED[299]), stamp=float(STAMPS[299]) + 1e-6)
    assert after == pytest.approx(commands[-1], abs=1e-6)
    # creep -> rate: pushing another extension replaces the creep one.
    assert node.set_parameters_atomically(typed(dict(MODEL_A, **RATE))).successful
    assert node.compensator.model.cause == 'rate_dependence'
    assert list(node.get_parameter('model.creep.time_constants').value) == []


def test_dead_time_compensates_gamma_and_warns(make_node):
    # dead_time_prediction false: Gamma's inverse alone, said so.
    node = make_node(limits() + typed(MODEL_A)
                     + [Parameter('dead_time_prediction', value=False)])
    result = node.set_parameters_atomically(typed(dict(MODEL_A, **DEAD)))
    assert result.successful, result.reason
    assert not node.compensator.has_effect  # Gamma's inverse alone
    values = {kv.key: kv.value for kv in node.diagnostics().status[0].values}
    assert values['extension'] == 'dead_time (not compensated)'
    np.testing.assert_allclose(run(node), core(MODEL_A), rtol=0, atol=1e-12)
    assert node.set_parameters_atomically(typed(MODEL_A)).successful
    assert node.get_parameter('model.dead_time').value == 0.0


def test_dead_time_is_predicted_by_default(make_node):
    # The default: the desired displacement predicted the dead time ahead, as the core.
    node = make_node(limits() + typed(MODEL_A))
    assert node.get_parameter('dead_time_prediction').value is True
    assert node.describe_parameter('dead_time_prediction').read_only
    result = node.set_parameters_atomically(typed(dict(MODEL_A, **DEAD)))
    assert result.successful, result.reason
    values = {kv.key: kv.value for kv in node.diagnostics().status[0].values}
    assert values['extension'] == 'dead_time (predicted)'
    commands = run(node)
    np.testing.assert_allclose(commands, core(dict(MODEL_A, **DEAD)), rtol=0, atol=1e-12)
    assert np.max(np.abs(commands - core(MODEL_A))) > 1e-6       # not Gamma^-1 alone


def _exchange(ros_context, node, values, *, pause, wait):
    # Publish VALUES on desired_displacement (PAUSE s apart) and collect the commands, on an
    # events executor; up to WAIT s for the last command.
    helper = rclpy.create_node('desired_source', context=ros_context)
    received = []
    publisher = helper.create_publisher(Float64, 'desired_displacement', 1000)
    helper.create_subscription(Float64, 'current_command', lambda m: received.append(m.data),
                               1000)
    executor = events_executor(ros_context)
    executor.add_node(node)
    executor.add_node(helper)
    try:
        deadline = time.monotonic() + 5.0
        while publisher.get_subscription_count() < 1 and time.monotonic() < deadline:
            executor.spin_once(timeout_sec=0.05)
        for value in values:
            publisher.publish(Float64(data=float(value)))
            if pause:
                time.sleep(pause)
            executor.spin_once(timeout_sec=0.0)
        deadline = time.monotonic() + wait
        while len(received) < len(values) and time.monotonic() < deadline:
            executor.spin_once(timeout_sec=0.05)
    finally:
        executor.shutdown()
        helper.destroy_node()
    return received


def test_messages_through_the_events_executor(ros_context, make_node):
    """The message path (callback with message info, drained queue) feeds the time stamps."""
    node = make_node(limits() + typed(dict(MODEL_A, **RATE)))
    received = _exchange(ros_context, node, DESIRED[:100], pause=1e-3, wait=5.0)
    assert len(received) == 100
    assert np.all(np.isfinite(received))
    assert np.all((np.array(received) >= OUTPUT_MIN) & (np.array(received) <= OUTPUT_MAX))
    assert node.counters['bad_time'] == 0
    assert node.counters['messages_out'] == 100


def test_model_keys_declared_with_units(make_node):
    node = make_node(limits())
    for key in ('model.creep.time_constants', 'model.rate_dependence.time_constant',
                'model.thermal_drift.time_constant', 'model.dead_time'):
        assert '[s]' in node.describe_parameter(key).description
    assert '[1/A]' in node.describe_parameter('model.thermal_drift.weight').description
    assert all(node.has_parameter(key) for key in MODEL_KEYS)


@pytest.mark.parametrize('message_time', ['default', 'arrival'])
def test_message_path_does_not_depend_on_when_messages_arrive(ros_context, make_node,
                                                              message_time):
    """Jittered, bunched, late arrivals: the lagged model's commands of nominal spacing."""
    overrides = limits() + typed(dict(MODEL_A, **RATE))
    if message_time != 'default':
        overrides.append(Parameter('message_time', value=message_time))
    node = make_node(overrides)
    # The node's steady clock replaced by a recorded one (read only with arrival).
    rng = np.random.default_rng(3)
    gaps = iter(np.where(rng.random(200) < 0.2, 1e-6, rng.lognormal(math.log(1e-3), 1.0, 200)))
    readings = []

    def clock():
        readings.append((readings[-1] if readings else 50.0) + float(next(gaps)))
        return readings[-1]

    node._arrival_clock = clock
    received = _exchange(ros_context, node, DESIRED[:200], pause=0.0, wait=10.0)
    assert len(received) == 200
    assert len(readings) == (200 if message_time == 'arrival' else 0)
    nominal = Compensator(extended_model_from_params(dict(MODEL_A, **RATE)),
                          output_min=OUTPUT_MIN, output_max=OUTPUT_MAX, sample_period=1e-3)
    expected = [nominal.command(float(d)) for d in DESIRED[:200]]
    # (to the rounding of the stream times near 50 s: 1e-14 s in a 1 ms interval)
    np.testing.assert_allclose(received, expected, rtol=0.0, atol=1e-9)
    assert node.counters['bad_time'] == 0
