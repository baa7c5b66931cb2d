# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
The compensator's /diagnostics levels and its throttled warnings about bad inputs.

WARN while unconfigured ("no model") and after a diagnostics period with non-finite,
out-of-range or clamped inputs; OK after a clean period. The warning log lines come at
most once per 5 s: the node's clock (``time.monotonic`` in its modules) is replaced by a
counter the test advances, so nothing here depends on how fast the machine is.
"""

import math
import time as real_time
from types import SimpleNamespace

from diagnostic_msgs.msg import DiagnosticStatus
from mpi_ros.nodes import compensator as compensator_module
from mpi_ros.nodes import compensator_base
from mpi_ros.nodes.compensator import CompensatorNode
from mpi_ros.nodes.spinning import events_executor
from mpi_ros.operators.model import MODEL_KEYS
import pytest
import rclpy
from rclpy.parameter import Parameter
from std_msgs.msg import Float64

#: A valid forward model (input 0.2-1.8 A -> about 4-44 um).
MODEL = dict(zip(MODEL_KEYS, (
    [0.0, 0.3, 0.6], [1.0, 0.4, 0.2], [-0.5, 0.0, 0.8], [1.0e-5, 2.0e-5, -0.5e-5])))

#: Inside the model's displacement range, away from both limits [m].
GOOD = 2.0e-5


class FakeClock:
    """Stands in for the ``time`` module of the compensator: ``monotonic()`` is ``now``."""

    def __init__(self):
        self.now = 1000.0

    def monotonic(self):
        return self.now


class LogRecorder:
    """Collects what the node logs as warnings."""

    def __init__(self):
        self.warnings = []

    def warning(self, text, **kwargs):
        self.warnings.append(text)

    def info(self, text, **kwargs):
        pass


@pytest.fixture
def clock(monkeypatch):
    fake = FakeClock()
    # The node reads the clock in its module (message times) and in the shared base
    # (fault log throttle, diagnostics rate window).
    for module in (compensator_module, compensator_base):
        monkeypatch.setattr(module, 'time', SimpleNamespace(monotonic=fake.monotonic))
    return fake


@pytest.fixture
def make_node(ros_context, clock):
    nodes = []

    def make(with_model=True):
        overrides = [Parameter('output.min', value=0.2), Parameter('output.max', value=1.8)]
        if with_model:
            overrides += [Parameter(key, value=value) for key, value in MODEL.items()]
        node = CompensatorNode(context=ros_context, parameter_overrides=overrides)
        nodes.append(node)
        return node

    yield make
    for node in nodes:
        node.destroy_node()


def status_of(node):
    return node.diagnostics().status[0]


def test_unconfigured_is_warn_no_model_with_the_node_as_hardware_id(make_node):
    node = make_node(with_model=False)
    node.command(GOOD)
    status = status_of(node)
    assert status.level == DiagnosticStatus.WARN
    assert status.message.startswith('no model')
    assert status.hardware_id == '/compensator'
    assert status.hardware_id == node.get_fully_qualified_name()


def test_hardware_id_follows_the_namespace(ros_context, clock):
    node = CompensatorNode(context=ros_context, namespace='/rig_a')
    try:
        assert status_of(node).hardware_id == '/rig_a/compensator'
    finally:
        node.destroy_node()


@pytest.mark.parametrize('bad, counter', [
    (math.nan, 'nonfinite_input'),
    (math.inf, 'nonfinite_input'),
    (1.0, 'out_of_range'),
    (-1.0, 'out_of_range'),
])
def test_a_period_with_bad_input_is_warn_and_the_next_clean_one_ok(make_node, bad, counter):
    node = make_node()
    node.command(GOOD)
    assert status_of(node).level == DiagnosticStatus.OK
    before = node.counters[counter]
    node.command(bad)
    node.command(GOOD)
    assert node.counters[counter] == before + 1
    status = status_of(node)
    assert status.level == DiagnosticStatus.WARN
    assert 'in the last period' in status.message
    node.command(GOOD)
    assert status_of(node).level == DiagnosticStatus.OK


def test_clamping_alone_is_warn(make_node):
    node = make_node()
    # With S convex at the top, the best linear map (of the major loop) asks for more than
    # output.max at the top of the range: clamped, although the desired displacement is in
    # range and finite.
    assert node.set_parameters([
        Parameter('enabled', value=False),
        Parameter('model.superposition.weights', value=[1.0e-5, 2.0e-5, 2.0e-5])])[0].successful
    high = node.compensator.displacement_range[1]
    assert node.compensator.linear_map(high) > node.compensator.output_max
    status_of(node)
    node.command(high)
    counters = node.counters
    assert counters['clamped'] == 1
    assert counters['out_of_range'] == counters['nonfinite_input'] == 0
    status = status_of(node)
    assert status.level == DiagnosticStatus.WARN
    assert '1 clamped inputs' in status.message
    node.command(GOOD)
    assert status_of(node).level == DiagnosticStatus.OK


def test_bad_input_warnings_are_logged_at_most_every_5_s(make_node, clock, monkeypatch):
    node = make_node()
    log = LogRecorder()
    monkeypatch.setattr(node, 'get_logger', lambda: log)
    assert not node.log_faults()                       # nothing bad yet
    node.command(math.nan)
    node.command(1.0)
    assert node.log_faults()
    assert len(log.warnings) == 1
    assert '1 non-finite' in log.warnings[0]
    assert '1 out-of-range' in log.warnings[0]
    for _ in range(100):                               # a flood of bad input ...
        node.command(math.nan)
    clock.now += 4.9
    assert not node.log_faults()                       # ... is not logged within 5 s
    clock.now += 0.2
    assert node.log_faults()                           # then once, with the whole count
    assert '100 non-finite' in log.warnings[1]
    clock.now += 60.0
    assert not node.log_faults()                       # nothing new: nothing logged
    assert len(log.warnings) == 2


def test_no_fault_warnings_while_unconfigured(make_node, monkeypatch):
    node = make_node(with_model=False)
    log = LogRecorder()
    monkeypatch.setattr(node, 'get_logger', lambda: log)
    node.command(math.nan)
    assert not node.log_faults()
    assert log.warnings == []


def test_a_queue_longer_than_one_callback_serves_is_served_in_full(
        ros_context, make_node, monkeypatch):
    """At most _DRAIN_LIMIT messages per callback (a stop request gets a turn); none lost."""
    monkeypatch.setattr(compensator_module, '_DRAIN_LIMIT', 7)
    node = make_node()
    helper = rclpy.create_node('desired_source', context=ros_context)
    received = []
    publisher = helper.create_publisher(Float64, 'desired_displacement', 1000)
    helper.create_subscription(Float64, 'current_command', lambda m: received.append(m.data),
                               1000)
    executor = events_executor(ros_context)
    executor.add_node(node)
    executor.add_node(helper)
    try:
        deadline = real_time.monotonic() + 10.0
        while publisher.get_subscription_count() < 1 and real_time.monotonic() < deadline:
            executor.spin_once(timeout_sec=0.05)
        for _ in range(100):                     # queued up before the node gets a turn
            publisher.publish(Float64(data=GOOD))
        deadline = real_time.monotonic() + 10.0
        while len(received) < 100 and real_time.monotonic() < deadline:
            executor.spin_once(timeout_sec=0.05)
    finally:
        executor.shutdown()
        helper.destroy_node()
    assert node.counters['messages_in'] == 100
    assert node.counters['messages_out'] == 100
    assert len(received) == 100
