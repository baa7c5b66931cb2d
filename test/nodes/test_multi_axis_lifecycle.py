# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
The multi-axis compensator as a managed node, driven over DDS by the lifecycle services.

As ``test_compensator_lifecycle`` for the single-axis node: ``change_state`` / ``get_state``
and the parameter services from a client node, array blocks through real topics, commands
compared column by column with the single-axis core fed exactly what the node served.
"""

from mpi_ros.compensation import Compensator
from mpi_ros.nodes.multi_axis import axis_key, MultiAxisCompensatorNode
import numpy as np
import pytest
from rclpy.parameter import Parameter
from std_msgs.msg import Float64MultiArray

from .lifecycle_rig import LifecycleRig
from .test_multi_axis_node import (_plain, axis_models, desired_block, message, OUTPUT_MAX,
                                   OUTPUT_MIN, overrides_for)

AXES = 8
TOLERANCE = 1e-12


@pytest.fixture
def make_rig(ros_context):
    """Build a multi-axis compensator with a client and an array loop."""
    made = []

    def make(overrides):
        node = MultiAxisCompensatorNode(context=ros_context,
                                        parameter_overrides=list(overrides))
        rig = LifecycleRig(ros_context, node)
        rig.received = []
        rig.client.create_subscription(
            Float64MultiArray, 'current_commands',
            lambda msg: rig.received.append(np.array(msg.data).reshape(-1, AXES)), 10000)
        rig.publisher = rig.client.create_publisher(Float64MultiArray,
                                                    'desired_displacements', 10000)
        made.append(rig)
        return rig

    yield make
    for rig in made:
        rig.close()
        rig.node.destroy_node()


def connected(rig):
    return rig.loop_matched(rig.publisher)


def send(rig, block):
    """Publish one message per sample; wait until the node has taken them all."""
    before = rig.node.counters['messages_in']
    for k in range(block.shape[0]):
        rig.publisher.publish(message(block[k:k + 1]))
    assert rig.spin_until(
        lambda: rig.node.counters['messages_in'] >= before + block.shape[0])


def commands(rig, count):
    assert rig.spin_until(lambda: len(rig.received) >= count), rig.node.counters
    return np.vstack(rig.received)


def cores(models):
    return [Compensator(model, output_min=OUTPUT_MIN, output_max=OUTPUT_MAX)
            for model in models]


def feed(axis_cores, block):
    return np.column_stack([[core.command(float(v)) for v in block[:, axis]]
                            for axis, core in enumerate(axis_cores)])


def test_deactivate_publishes_nothing_and_activate_resumes_bumplessly(make_rig):
    models = axis_models(7)
    rig = make_rig(overrides_for(models))
    assert rig.state() == 'active'
    assert connected(rig)
    first = desired_block(models, 60, seed=1)
    held = desired_block(models, 40, seed=2)
    after = desired_block(models, 40, seed=3)
    after[0] = first[-1]
    send(rig, first)
    before = commands(rig, 60)

    assert rig.change_state('deactivate')
    assert rig.state() == 'inactive'
    send(rig, held)
    rig.spin_for(0.5)
    assert len(rig.received) == 60
    assert rig.node.counters['messages_out'] == 60
    assert rig.node.counters['dropped_inactive'] == 40
    status = rig.node.diagnostics().status[0]
    assert status.message.startswith('lifecycle state inactive: no commands published')

    assert rig.change_state('activate')
    send(rig, after)
    resumed = commands(rig, 100)[60:]
    np.testing.assert_allclose(resumed[0], before[-1], rtol=0, atol=TOLERANCE)   # no jump
    expected = feed(cores(models), np.vstack([first, after]))
    np.testing.assert_allclose(np.vstack([before, resumed]), expected, rtol=0, atol=TOLERANCE)
    with_held = feed(cores(models), np.vstack([first, held, after]))[-40:]
    assert np.max(np.abs(with_held - resumed)) > 1e-3       # the dropped inputs mattered


def test_pushes_follow_the_same_rule_in_every_state(make_rig):
    models = axis_models(7)
    new = axis_models(11)
    rig = make_rig(overrides_for(models) + [Parameter('autostart', value=False)])
    assert rig.state() == 'unconfigured'
    assert rig.node.count_subscribers('desired_displacements') == 0
    bad = _plain(new[5].to_params())
    bad['model.hysteresis.weights'] = [-1.0] * len(bad['model.hysteresis.weights'])
    bad_request = {axis_key(5, key): value for key, value in bad.items()}
    good_request = {axis_key(2, key): value for key, value in _plain(new[2].to_params()).items()}

    reasons = []
    refused = rig.push(bad_request)                      # unconfigured
    assert not refused.successful
    reasons.append(refused.reason)
    assert rig.push(good_request).successful             # stored, loaded by configure
    assert rig.node.compensator is None
    assert rig.change_state('configure')
    assert rig.node.compensator is not None
    refused = rig.push(bad_request)                      # inactive
    reasons.append(refused.reason)
    assert rig.change_state('activate')
    refused = rig.push(bad_request)                      # active
    reasons.append(refused.reason)
    assert reasons[0] == reasons[1] == reasons[2]
    assert reasons[0].startswith('axis 5 (axis5.model.*): axis5.model.hysteresis.weights')

    # configure loaded the pushed axis 2, with the memory at each model's start state.
    assert connected(rig)
    loaded = models[:2] + [new[2]] + models[3:]
    block = desired_block(loaded, 50, seed=4)
    send(rig, block)
    np.testing.assert_allclose(commands(rig, 50), feed(cores(loaded), block), rtol=0,
                               atol=TOLERANCE)

    # A push while inactive is installed into the running core, bumplessly.
    assert rig.change_state('deactivate')
    replacement = {axis_key(6, key): value
                   for key, value in _plain(new[6].to_params()).items()}
    assert rig.push(replacement).successful
    assert rig.node.counters['messages_out'] == 50
    assert rig.change_state('activate')
    reference = cores(loaded)
    feed(reference, block)
    reference[6].install(new[6])
    final = loaded[:6] + [new[6]] + loaded[7:]
    later = desired_block(final, 30, seed=5)
    send(rig, later)
    np.testing.assert_allclose(commands(rig, 80)[50:], feed(reference, later), rtol=0,
                               atol=TOLERANCE)


def test_cleanup_and_shutdown(make_rig):
    models = axis_models(7)
    rig = make_rig(overrides_for(models))
    assert connected(rig)
    assert rig.change_state('deactivate') and rig.change_state('cleanup')
    assert rig.state() == 'unconfigured'
    assert rig.node.compensator is None
    assert rig.spin_until(lambda: rig.publisher.get_subscription_count() == 0)
    status = rig.node.diagnostics().status[0]
    assert status.message == 'lifecycle state unconfigured: no commands published'
    assert rig.change_state('shutdown')
    assert rig.state() == 'finalized'
    assert rig.node.finalized.done()
