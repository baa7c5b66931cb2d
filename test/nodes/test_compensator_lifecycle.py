# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
The single-axis compensator as a managed node, driven over DDS by the lifecycle services.

``change_state`` / ``get_state`` (lifecycle_msgs) and ``set_parameters_atomically`` /
``set_parameters`` (rcl_interfaces) are called from a client node; desired displacements
go through a real publisher and the commands come back through a real subscription.
Commands are compared with the core (:class:`mpi_ros.compensation.Compensator`) fed exactly
the inputs the node served, to 1e-12 A.  No timing is asserted; every wait is bounded.
"""

from diagnostic_msgs.msg import DiagnosticStatus
from lifecycle_msgs.msg import Transition
from lifecycle_msgs.srv import ChangeState, GetState
from mpi_ros.compensation import Compensator
from mpi_ros.nodes.compensator import CompensatorNode
from mpi_ros.operators.model import MPIModel
import numpy as np
import pytest
import rclpy
from rclpy.executors import SingleThreadedExecutor
from rclpy.parameter import Parameter
from std_msgs.msg import Float64

from .lifecycle_rig import LifecycleRig
from .processes import NodeProcess
from .test_compensator_node import as_parameters, limits, MODEL_A, MODEL_B, OUTPUT_MAX, OUTPUT_MIN

TOLERANCE = 1e-12


@pytest.fixture
def make_rig(ros_context):
    """Build a compensator (overrides given) with a client and a desired/command loop."""
    made = []

    def make(overrides=()):
        node = CompensatorNode(context=ros_context, parameter_overrides=list(overrides))
        rig = LifecycleRig(ros_context, node)
        rig.received = []
        rig.client.create_subscription(Float64, 'current_command',
                                       lambda msg: rig.received.append(msg.data), 10000)
        rig.publisher = rig.client.create_publisher(Float64, 'desired_displacement', 10000)
        made.append(rig)
        return rig

    yield make
    for rig in made:
        rig.close()
        rig.node.destroy_node()


def connected(rig):
    """Wait until the loop topics are matched both ways (the node is configured)."""
    return rig.loop_matched(rig.publisher)


def send(rig, values):
    """Publish desired displacements; wait until the node has taken all of them."""
    before = rig.node.counters['messages_in']
    for value in values:
        rig.publisher.publish(Float64(data=float(value)))
    assert rig.spin_until(lambda: rig.node.counters['messages_in'] >= before + len(values))


def commands(rig, count):
    """Wait for ``count`` commands in all; return them."""
    assert rig.spin_until(lambda: len(rig.received) >= count), rig.node.counters
    return np.array(rig.received)


def core(model=MODEL_A):
    return Compensator(MPIModel.from_params(model), output_min=OUTPUT_MIN,
                       output_max=OUTPUT_MAX)


def desired(count, phase, seed):
    """Desired displacements that reverse often inside the model's range [m]."""
    rng = np.random.default_rng(seed)
    return (2.0e-5 + 1.2e-5 * np.sin(np.linspace(phase, phase + 9.0, count))
            + rng.normal(0.0, 1.0e-7, count))


def status_of(rig):
    return rig.node.diagnostics().status[0]


def value_of(status, key):
    return next(item.value for item in status.values if item.key == key)


def test_deactivate_publishes_nothing_and_activate_resumes_bumplessly(make_rig):
    rig = make_rig(limits() + as_parameters(MODEL_A))          # autostart: active
    assert rig.state() == 'active'
    assert connected(rig)
    first, held, after = desired(120, 0.0, 1), desired(80, 2.0, 2), desired(60, 3.5, 3)
    after[0] = first[-1]                     # the same desired value as before the stop
    send(rig, first)
    before = commands(rig, len(first))

    assert rig.change_state('deactivate')
    assert rig.state() == 'inactive'
    assert value_of(status_of(rig), 'lifecycle_state') == 'inactive'
    out = rig.node.counters['messages_out']
    send(rig, held)                          # taken and dropped: would move the memory
    rig.spin_for(0.5)
    assert len(rig.received) == len(first)
    assert rig.node.counters['messages_out'] == out
    assert rig.node.counters['dropped_inactive'] == len(held)
    status = status_of(rig)
    assert status.message.startswith('lifecycle state inactive: no commands published')

    assert rig.change_state('activate')
    assert rig.state() == 'active'
    send(rig, after)
    resumed = commands(rig, len(first) + len(after))[len(first):]
    # No jump: the same desired value gives the same command as before the stop ...
    assert resumed[0] == pytest.approx(before[-1], abs=TOLERANCE)
    # ... and the memory continued from the held state: the core fed first + after.
    reference = core()
    expected = [reference.command(v) for v in np.concatenate([first, after])]
    np.testing.assert_allclose(np.concatenate([before, resumed]), expected, rtol=0,
                               atol=TOLERANCE)
    # The dropped inputs would have changed the commands (the test can tell).
    replayed = core()
    with_held = [replayed.command(v) for v in np.concatenate([first, held, after])]
    assert np.max(np.abs(np.array(with_held[-len(after):]) - resumed)) > 1e-3


def test_autostart_false_waits_unconfigured_and_pushes_follow_the_same_rule(make_rig):
    rig = make_rig(limits() + [Parameter('autostart', value=False)])
    assert rig.state() == 'unconfigured'
    assert rig.node.count_subscribers('desired_displacement') == 0   # no loop topics yet
    status = status_of(rig)
    assert status.level == DiagnosticStatus.OK
    assert status.message == 'lifecycle state unconfigured: no commands published'
    assert value_of(status, 'lifecycle_state') == 'unconfigured'
    assert not rig.transition(Transition.TRANSITION_ACTIVATE)     # not from unconfigured
    assert rig.state() == 'unconfigured'

    # A bad model is refused for the same reason in every state (compared below).
    bad = dict(MODEL_A, **{'model.hysteresis.weights': [1.0, -0.4, 0.2]})
    refused_unconfigured = rig.push(bad)
    assert not refused_unconfigured.successful
    assert 'model.hysteresis.weights' in refused_unconfigured.reason
    # One key without Gamma: refused as while active without a model.
    alone = rig.set_each({'model.output_offset': 1.0e-6})
    assert not alone[0].successful and 'missing' in alone[0].reason
    # A valid model is stored, not loaded: no core until configure.
    assert rig.push(MODEL_A).successful
    assert rig.node.compensator is None and rig.node.model_version == 0
    assert list(rig.node.get_parameter('model.hysteresis.weights').value) == MODEL_A[
        'model.hysteresis.weights']

    assert rig.change_state('configure')
    assert rig.state() == 'inactive'
    assert rig.node.model_version == 1
    assert rig.node.compensator.model.to_params() == dict(
        MODEL_A, **{'model.input_offset': 0.0, 'model.output_offset': 0.0,
                    'model.output_sign': 1})
    refused_inactive = rig.push(bad)
    assert rig.change_state('activate')
    assert connected(rig)
    refused_active = rig.push(bad)
    reasons = [r.reason.split('. Nothing was applied')[0]
               for r in (refused_unconfigured, refused_inactive, refused_active)]
    assert not refused_inactive.successful and not refused_active.successful
    assert reasons[0] == reasons[1] == reasons[2]
    assert rig.node.counters['rejected_updates'] == 4
    # Activated from a fresh configure: the memory is the model's start state.
    values = desired(100, 0.5, 4)
    send(rig, values)
    reference = core()
    np.testing.assert_allclose(commands(rig, len(values)),
                               [reference.command(v) for v in values], rtol=0, atol=TOLERANCE)


def test_a_push_while_inactive_is_installed_bumplessly(make_rig):
    rig = make_rig(limits() + as_parameters(MODEL_A))
    assert connected(rig)
    first, after = desired(90, 0.0, 5), desired(70, 1.0, 6)
    send(rig, first)
    commands(rig, len(first))
    assert rig.change_state('deactivate')
    assert rig.push(MODEL_B).successful                  # validated and installed
    assert rig.node.model_version == 2
    bad = dict(MODEL_B, **{'model.superposition.weights': [2.2e-5, -3.0e-5]})
    result = rig.push(bad)
    assert not result.successful and 'model.superposition.weights' in result.reason
    assert rig.node.model_version == 2
    # A grouped set_parameters (ros2 param load) of one key is served the same way.
    assert all(r.successful for r in rig.set_each({'model.output_offset': 0.0}))
    assert rig.node.counters['messages_out'] == len(first)
    assert rig.change_state('activate')
    send(rig, after)
    resumed = commands(rig, len(first) + len(after))[len(first):]
    reference = core()
    for value in first:
        reference.command(value)
    reference.install(MPIModel.from_params(MODEL_B))
    np.testing.assert_allclose(resumed, [reference.command(v) for v in after], rtol=0,
                               atol=TOLERANCE)


def test_cleanup_closes_the_topics_and_configure_restarts_from_the_start_state(make_rig):
    rig = make_rig(limits() + as_parameters(MODEL_A))
    assert connected(rig)
    first, after = desired(80, 0.0, 7), desired(80, 4.0, 8)
    send(rig, first)
    commands(rig, len(first))
    assert rig.change_state('deactivate')
    assert rig.change_state('cleanup')
    assert rig.state() == 'unconfigured'
    assert rig.node.compensator is None
    assert rig.spin_until(lambda: rig.publisher.get_subscription_count() == 0)
    assert rig.change_state('configure')
    assert rig.change_state('activate')
    assert connected(rig)
    send(rig, after)
    reference = core()                                   # fresh: the model's start state
    np.testing.assert_allclose(commands(rig, len(first) + len(after))[len(first):],
                               [reference.command(v) for v in after], rtol=0, atol=TOLERANCE)
    assert rig.node.model_version == 2                   # loaded again by configure


def test_shutdown_finalizes_the_node(make_rig):
    rig = make_rig(limits() + as_parameters(MODEL_A))
    assert connected(rig)
    assert not rig.node.finalized.done()
    assert rig.change_state('shutdown')
    assert rig.state() == 'finalized'
    assert rig.node.finalized.done()
    assert rig.node.compensator is None
    assert rig.spin_until(lambda: rig.publisher.get_subscription_count() == 0)
    assert value_of(status_of(rig), 'lifecycle_state') == 'finalized'


def test_configure_fails_on_a_bad_model_without_autostart_and_a_push_repairs_it(make_rig):
    bad = dict(MODEL_A, **{'model.hysteresis.weights': [1.0, -0.4, 0.2]})
    rig = make_rig(limits() + as_parameters(bad) + [Parameter('autostart', value=False)])
    assert not rig.change_state('configure')
    assert rig.state() == 'unconfigured'
    assert rig.node.compensator is None
    assert rig.node.count_subscribers('desired_displacement') == 0
    assert rig.push(MODEL_A).successful                  # the whole model: valid
    assert rig.change_state('configure')
    assert rig.change_state('activate')
    assert rig.node.compensator is not None


@pytest.mark.slow
def test_mpi_ros_compensator_process_is_driven_by_lifecycle_and_exits_on_shutdown(
        ros_context):
    """`mpi-ros compensator -p autostart:=false`: configure, activate, shutdown -> exit 0."""
    args = ['compensator', '--ros-args', '-r', '__node:=lifecycle_process',
            '-p', 'autostart:=false', '-p', 'output.min:=0.2', '-p', 'output.max:=1.8']
    for key, value in MODEL_A.items():
        args += ['-p', f'{key}:={value}']
    client = rclpy.create_node('lifecycle_process_client', context=ros_context)
    executor = SingleThreadedExecutor(context=ros_context)
    executor.add_node(client)
    change = client.create_client(ChangeState, '/lifecycle_process/change_state')
    get = client.create_client(GetState, '/lifecycle_process/get_state')

    def call(service, request):
        future = service.call_async(request)
        executor.spin_until_future_complete(future, timeout_sec=60.0)
        assert future.done(), f'{service.srv_name} did not answer'
        return future.result()

    try:
        with NodeProcess(args) as process:
            assert get.wait_for_service(timeout_sec=90.0), process.output
            assert call(get, GetState.Request()).current_state.label == 'unconfigured'
            for label in ('configure', 'activate'):
                request = ChangeState.Request(transition=Transition(label=label))
                assert call(change, request).success, process.output
            assert call(get, GetState.Request()).current_state.label == 'active'
            request = ChangeState.Request(transition=Transition(label='shutdown'))
            assert call(change, request).success, process.output
            status = process.process.wait(timeout=60.0)
    finally:
        executor.shutdown()
        client.destroy_node()
    assert status == 0, process.output
    assert 'lifecycle: shutdown done, state finalized' in process.output
    assert 'Traceback' not in process.output


def test_an_unexpected_error_in_a_transition_is_logged_and_leaves_unconfigured(make_rig):
    rig = make_rig(limits() + as_parameters(MODEL_A) + [Parameter('autostart', value=False)])

    def broken():
        raise RuntimeError('disk on fire')

    rig.node._load = broken                                # shadows the method
    assert not rig.change_state('configure')               # ERROR -> error processing
    assert rig.state() == 'unconfigured'
    assert isinstance(rig.node._transition_error, RuntimeError)
    assert rig.node.compensator is None
    assert rig.node.count_subscribers('desired_displacement') == 0
    del rig.node._load
    assert rig.change_state('configure') and rig.change_state('activate')
    assert rig.node.compensator is not None
