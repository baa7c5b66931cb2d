# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
No silent loss: the compensator counts the desired displacements it never got.

The node is overloaded on purpose, never by timing: a publisher in the same context sends
bursts while the node is not spun (a blocked node), into a short input queue
(``qos_depth`` 10); the queue keeps only the newest messages.  The jump of the publisher's
sequence number between the messages the node then takes is counted as
``messages_lost``, and the next diagnostics period is WARN saying so.  A clean stream
counts nothing.  An incompatible peer (a best-effort publisher on the reliable input) is
counted and WARN too.  Every wait is bounded; nothing here depends on the machine's speed.
"""

import time

from diagnostic_msgs.msg import DiagnosticStatus
from mpi_ros.nodes.compensator import CompensatorNode
from mpi_ros.nodes.spinning import events_executor
from mpi_ros.operators.model import MODEL_KEYS
import pytest
import rclpy
from rclpy.parameter import Parameter
from rclpy.qos import QoSProfile, ReliabilityPolicy
from std_msgs.msg import Float64

#: A valid forward model (input 0.2-1.8 A -> about 4-44 um).
MODEL = dict(zip(MODEL_KEYS, (
    [0.0, 0.3, 0.6], [1.0, 0.4, 0.2], [-0.5, 0.0, 0.8], [1.0e-5, 2.0e-5, -0.5e-5])))

#: Inside the model's displacement range [m].
GOOD = 2.0e-5

#: Longest wait for anything over DDS [s] (never reached unless something is broken).
TIMEOUT = 20.0


@pytest.fixture
def rig(ros_context):
    """Build a compensator with a 10-deep input queue, a source node and an executor."""
    overrides = [Parameter('qos_depth', value=10), Parameter('output.min', value=0.2),
                 Parameter('output.max', value=1.8),
                 Parameter('diagnostics_period', value=3600.0)]   # periods end by hand
    overrides += [Parameter(key, value=value) for key, value in MODEL.items()]
    node = CompensatorNode(context=ros_context, parameter_overrides=overrides)
    source = rclpy.create_node('desired_source', context=ros_context)
    received = []
    publisher = source.create_publisher(Float64, 'desired_displacement', 10000)
    source.create_subscription(Float64, 'current_command',
                               lambda msg: received.append(msg.data), 10000)
    executor = events_executor(ros_context)
    executor.add_node(node)
    executor.add_node(source)
    deadline = time.monotonic() + TIMEOUT
    while ((publisher.get_subscription_count() < 1
            or node.count_subscribers('current_command') < 1)
           and time.monotonic() < deadline):
        executor.spin_once(timeout_sec=0.05)
    yield node, source, publisher, executor, received
    executor.shutdown()
    source.destroy_node()
    node.destroy_node()


def burst(publisher, count):
    """Publish ``count`` desired displacements at once (the node is not spun meanwhile)."""
    for _ in range(count):
        publisher.publish(Float64(data=GOOD))


def spin_until(executor, condition):
    deadline = time.monotonic() + TIMEOUT
    while not condition() and time.monotonic() < deadline:
        executor.spin_once(timeout_sec=0.02)


def settle(executor, node):
    """Spin until the node has served everything that reached its queue."""
    deadline = time.monotonic() + TIMEOUT
    last = -1
    while node.counters['messages_in'] != last and time.monotonic() < deadline:
        last = node.counters['messages_in']
        end = time.monotonic() + 0.3
        while time.monotonic() < end:
            executor.spin_once(timeout_sec=0.02)


def test_a_blocked_node_counts_what_its_queue_dropped_and_warns(rig):
    node, _, publisher, executor, received = rig
    burst(publisher, 5)                                  # a reference sequence number
    settle(executor, node)
    assert node.counters['messages_lost'] == 0
    node.diagnostics()                                   # start a clean period
    served = node.counters['messages_in']
    burst(publisher, 500)                                # 500 into a 10-deep queue
    settle(executor, node)
    taken = node.counters['messages_in'] - served
    assert taken <= 10 + 1                               # the queue kept the newest
    lost = node.counters['messages_lost']
    assert lost > 0
    assert taken + lost <= 500
    assert node.counters['lost_sequence_gaps'] == lost or node.counters['lost_dds_events']
    status = node.diagnostics().status[0]
    assert status.level == DiagnosticStatus.WARN
    assert 'lost' in status.message
    assert f'{lost} desired displacements lost' in status.message
    values = {kv.key: kv.value for kv in status.values}
    assert int(values['messages_lost']) == lost
    # The next period without loss is OK again.
    burst(publisher, 3)
    settle(executor, node)
    assert node.counters['messages_lost'] == lost
    assert node.diagnostics().status[0].level == DiagnosticStatus.OK


def test_a_stream_the_node_keeps_up_with_counts_nothing(rig):
    node, _, publisher, executor, received = rig
    for _ in range(12):
        burst(publisher, 5)                              # half the queue at most
        settle(executor, node)
    assert node.counters['messages_in'] == 60
    assert node.counters['messages_lost'] == 0
    spin_until(executor, lambda: len(received) >= 60)
    assert len(received) == 60
    assert node.diagnostics().status[0].level == DiagnosticStatus.OK


def test_a_queue_more_than_half_full_is_warn(rig):
    node, _, publisher, executor, _ = rig
    node.diagnostics()
    burst(publisher, 9)                                  # 9 of 10 wait at once
    settle(executor, node)
    assert node.counters['messages_lost'] == 0
    status = node.diagnostics().status[0]
    assert status.level == DiagnosticStatus.WARN
    assert 'more than half full' in status.message


def test_incompatible_qos_peer_is_counted_and_warn(rig):
    node, source, _, executor, _ = rig
    best_effort = QoSProfile(depth=10, reliability=ReliabilityPolicy.BEST_EFFORT)
    source.create_publisher(Float64, 'desired_displacement', best_effort)
    spin_until(executor, lambda: node.counters['incompatible_qos'] > 0)
    assert node.counters['incompatible_qos'] > 0
    status = node.diagnostics().status[0]
    assert status.level == DiagnosticStatus.WARN
    assert 'incompatible QoS' in status.message


def test_two_publishers_interleaving_their_numbers_count_nothing(rig):
    node, source, publisher, executor, _ = rig
    other = source.create_publisher(Float64, 'desired_displacement', 10000)
    spin_until(executor, lambda: node._subscription.get_publisher_count() == 2)
    for _ in range(4):
        burst(other, 5)                                  # other's numbers run ahead
        settle(executor, node)
    for _ in range(3):
        for _ in range(2):                               # then both, interleaved
            publisher.publish(Float64(data=GOOD))
            other.publish(Float64(data=GOOD))
        settle(executor, node)
    assert node.counters['messages_in'] == 32
    assert node.counters['messages_lost'] == 0


def test_a_blocked_multi_axis_node_counts_the_arrays_its_queue_dropped(ros_context):
    # The same overload for the multi-axis node: 500 one-sample arrays of 8 axes into a
    # 10-deep queue while it is not spun.
    from mpi_ros.nodes.multi_axis import axis_key, MultiAxisCompensatorNode
    from std_msgs.msg import Float64MultiArray
    axes = 8
    overrides = [Parameter('axes', value=axes), Parameter('qos_depth', value=10),
                 Parameter('output.min', value=0.2), Parameter('output.max', value=1.8),
                 Parameter('diagnostics_period', value=3600.0)]
    overrides += [Parameter(axis_key(k, key), value=value)
                  for k in range(axes) for key, value in MODEL.items()]
    node = MultiAxisCompensatorNode(context=ros_context, parameter_overrides=overrides)
    source = rclpy.create_node('desired_source', context=ros_context)
    publisher = source.create_publisher(Float64MultiArray, 'desired_displacements', 10000)
    executor = events_executor(ros_context)
    executor.add_node(node)
    executor.add_node(source)
    try:
        spin_until(executor, lambda: publisher.get_subscription_count() >= 1)

        def arrays(count):
            for _ in range(count):
                publisher.publish(Float64MultiArray(data=[GOOD] * axes))

        arrays(5)
        settle(executor, node)
        assert node.counters['messages_lost'] == 0
        node.diagnostics()
        served = node.counters['messages_in']
        arrays(500)
        settle(executor, node)
        taken = node.counters['messages_in'] - served
        lost = node.counters['messages_lost']
        assert taken <= 10 + 1 and lost > 0 and taken + lost <= 500
        status = node.diagnostics().status[0]
        assert status.level == DiagnosticStatus.WARN
        assert f'{lost} desired displacement arrays lost' in status.message
        assert int({kv.key: kv.value for kv in status.values}['messages_lost']) == lost
    finally:
        executor.shutdown()
        source.destroy_node()
        node.destroy_node()
