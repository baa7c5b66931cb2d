# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
The compensator node's online adaptation (issue 29), in-process on a private context.

The node computes the commands (``CompensatorNode.command``, which records them as the
message path does); the test plays the drifting actuator and hands each reading to the
node's adaptation, steps it once per simulated second (the worker thread is not started,
so the steps are the test's) and spins the node, whose timer applies a candidate through
its own ``set_parameters``: the validation every push goes through.  The node's default,
the adaptation in a child process, is run with the readings published on ``displacement``,
which the child takes itself (the node's process has no subscription there), each second
sent once the child has paired the one before.
"""

import os
import signal
import struct
import time

from mpi_ros import identify
from mpi_ros.compensation import Compensator
from mpi_ros.compensation.adaptation import (
    AdaptationProcess, AdaptationSettings, AdaptationWorker, CHILD_NICE, ReadingSource,
)
from mpi_ros.extensions.thermal_drift import ThermalDriftModel
from mpi_ros.nodes import adaptation_readings
from mpi_ros.nodes.compensator import CompensatorNode
from mpi_ros.nodes.qos import loop_qos
from mpi_ros.nodes.spinning import events_executor
from mpi_ros.operators.model import MPIModel
from mpi_ros.plant.actuator import ActuatorConfig, MagnetostrictiveActuator
from mpi_ros.plant.excitation import identification_excitation, tracking_trajectory
import numpy as np
import pytest
import rclpy
from rclpy.parameter import Parameter
from std_msgs.msg import Float64

RATE = 500.0


def _adaptive_node(ros_context, model, process):
    # A compensator node with MODEL, adapting (in a child process or not), on its executor.
    overrides = [Parameter(k, value=v) for k, v in model.to_params().items()] + [
        Parameter('output.min', value=0.0), Parameter('output.max', value=2.0),
        Parameter('sample_period', value=1 / RATE),
        Parameter('adaptation.enabled', value=True),
        Parameter('adaptation.process', value=process)]
    node = CompensatorNode(context=ros_context, parameter_overrides=overrides)
    executor = events_executor(ros_context)
    executor.add_node(node)
    return node, executor


@pytest.fixture(params=[False])
def node_and_plant(ros_context, monkeypatch, request):
    process = request.param
    if not process:
        monkeypatch.setattr(AdaptationWorker, 'start', lambda self: None)
    t, x = identification_excitation(30.0, sample_rate=RATE, seed=11)
    config = {'noise_std_m': 2e-8, 'sensor_zero_current_a': 0.2}
    y = MagnetostrictiveActuator(ActuatorConfig(**config), seed=11).simulate(t, x)
    node, executor = _adaptive_node(ros_context, identify(x, y, n=10, l=5).model, process)
    plant = MagnetostrictiveActuator(ActuatorConfig(
        thermal_gain_m_per_a2=3e-6, thermal_time_constant_s=30.0, **config), seed=111)
    yield node, executor, plant, (float(np.min(y)), float(np.max(y)))
    executor.remove_node(node)
    executor.shutdown()
    node.destroy_node()


def test_adapted_model_is_the_nodes_parameters_and_a_dump_loads_back(
        node_and_plant, ros_context):
    node, executor, plant, (lo, hi) = node_and_plant
    assert node.adaptation is not None
    span = hi - lo
    t, desired = tracking_trajectory(90.0, sample_rate=RATE, low=lo + 0.15 * span,
                                     high=hi - 0.15 * span, final_envelope=1.0)
    commands = []
    for k in range(t.size):
        current = node.command(float(desired[k]))
        commands.append(current)
        node.adaptation.record_measurement(plant.step(float(t[k]), current))
        if k and k % int(RATE) == 0:
            node.adaptation.step()
            for _ in range(3):
                executor.spin_once(timeout_sec=0.05)
    assert np.all(np.isfinite(commands))
    status = node.adaptation.status()
    assert status['adaptation_updates_accepted'] >= 1, status
    assert node.model_version == 1 + status['adaptation_updates_accepted']
    values = node.diagnostics().status[0].values
    shown = {kv.key: kv.value for kv in values}
    assert shown['adaptation_updates_accepted'] == str(status['adaptation_updates_accepted'])
    # The running model is what the parameters say (what ros2 param dump writes) ...
    running = node.compensator.model
    dumped = {key: node.get_parameter(key).value for key in running.to_params()}
    assert MPIModel.from_params(dumped).to_params() == running.to_params()
    # ... and a fresh compensator loaded from that dump commands what the adapted model
    # does on a new trajectory.
    fresh = CompensatorNode(
        node_name='fresh', context=ros_context,
        parameter_overrides=[Parameter(k, value=v) for k, v in dumped.items()] + [
            Parameter('output.min', value=0.0), Parameter('output.max', value=2.0)])
    try:
        core = Compensator(running, output_min=0.0, output_max=2.0)
        new = lo + span * (0.3 + 0.2 * np.sin(np.linspace(0.0, 20.0, 2000)))
        np.testing.assert_allclose([fresh.command(float(d)) for d in new],
                                   [core.command(float(d)) for d in new], rtol=0, atol=1e-12)
    finally:
        fresh.destroy_node()


def test_in_thread_mode_the_node_itself_subscribes_to_the_readings(node_and_plant):
    node, _, _, _ = node_and_plant
    assert '/displacement' in [s.topic_name for s in node.subscriptions]


def test_a_push_from_outside_restarts_the_adaptation(node_and_plant):
    node, executor, plant, _ = node_and_plant
    adaptation = node.adaptation
    params = node.compensator.model.to_params()
    params['model.output_offset'] = params['model.output_offset'] + 1e-7
    result = node.set_parameters_atomically([Parameter(k, value=v) for k, v in params.items()])
    assert result.successful, result.reason
    assert node.adaptation is adaptation       # the same object, reset to the new model
    assert adaptation.model.to_params() == MPIModel.from_params(params).to_params()
    assert node.model_version == 2


@pytest.mark.parametrize('node_and_plant', [True], indirect=True)
def test_the_adaptation_process_takes_the_readings_itself_and_updates_the_node(
        node_and_plant, ros_context):
    # The readings go out on displacement as an actuator publishes them: the child process
    # subscribes, the node's process does not (its executor never serves a reading), and
    # the adaptation still improves the model on the drifting plant, through the node's
    # set_parameters.  A malformed reading is dropped and counted by the node.
    node, executor, plant, (lo, hi) = node_and_plant
    adaptation = node.adaptation
    assert isinstance(adaptation, AdaptationProcess)
    assert '/displacement' not in [s.topic_name for s in node.subscriptions]
    sensor = rclpy.create_node('sensor', context=ros_context)
    publisher = sensor.create_publisher(Float64, 'displacement', loop_qos(10000, 'reliable'))
    try:
        # The one reader of displacement is the child's node (the graph learns its name
        # a moment after the reader itself).
        deadline = time.monotonic() + 60.0
        readers = []
        while (publisher.get_subscription_count() < 1 or not readers
               or '_NODE_NAME_UNKNOWN_' in [r.node_name for r in readers]):
            assert time.monotonic() < deadline, readers
            executor.spin_once(timeout_sec=0.05)
            readers = node.get_subscriptions_info_by_topic('displacement')
        assert [(r.node_name, r.node_namespace) for r in readers] == [
            (f'{node.get_name()}_adaptation', '/')]
        span = hi - lo
        t, desired = tracking_trajectory(40.0, sample_rate=RATE, low=lo + 0.15 * span,
                                         high=hi - 0.15 * span, final_envelope=1.0)
        block = int(RATE)
        message = Float64()
        for start in range(0, t.size - block + 1, block):
            for k in range(start, start + block):
                current = node.command(float(desired[k]))
                assert np.isfinite(current)
                message.data = plant.step(float(t[k]), current)
                publisher.publish(message)
            deadline = time.monotonic() + 120.0
            while adaptation.status().get('adaptation_pairs') != start + block:
                assert time.monotonic() < deadline, adaptation.status()
                executor.spin_once(timeout_sec=0.05)
        for _ in range(5):                          # the last candidate, if any, is applied
            executor.spin_once(timeout_sec=0.05)
        status = adaptation.status()
        assert status['adaptation_updates_accepted'] >= 1, status
        assert status['adaptation_lost_readings'] == 0, status
        assert status['adaptation_reading_publishers'] == 1, status
        assert node.model_version == 1 + status['adaptation_updates_accepted']
        running = node.compensator.model
        assert adaptation.model.to_params() == running.to_params()
        dumped = {key: node.get_parameter(key).value for key in running.to_params()}
        assert MPIModel.from_params(dumped).to_params() == running.to_params()
        # Three bytes are no CDR Float64: dropped in the child, counted by the node.
        publisher.handle.publish_raw(struct.pack('<3B', 0, 1, 0))
        deadline = time.monotonic() + 60.0
        while node.counters['malformed'] != 1:
            assert time.monotonic() < deadline, adaptation.status()
            executor.spin_once(timeout_sec=0.05)
        assert adaptation.status()['adaptation_malformed_readings'] == 1
        assert adaptation.status()['adaptation_pairs'] == t.size // block * block
    finally:
        sensor.destroy_node()
    node.destroy_node()
    assert not adaptation.running


def test_a_thermal_drift_model_is_adapted_with_its_weight(ros_context, monkeypatch):
    # The node adapts Gamma with a thermal drift too: a model whose w_T is a sixth of the
    # plant's drift (tau_T right) on a plant drifting 3 um/A^2; the node applies whole
    # thermal models through its own set_parameters, w_T grows, tau_T stays.
    monkeypatch.setattr(AdaptationWorker, 'start', lambda self: None)
    t, x = identification_excitation(30.0, sample_rate=RATE, seed=12)
    config = {'noise_std_m': 2e-8}
    y = MagnetostrictiveActuator(ActuatorConfig(**config), seed=12).simulate(t, x)
    model = ThermalDriftModel(identify(x, y, n=10, l=5).model, 30.0, 0.02)
    node, executor = _adaptive_node(ros_context, model, False)
    plant = MagnetostrictiveActuator(ActuatorConfig(
        thermal_gain_m_per_a2=3e-6, thermal_time_constant_s=30.0, **config), seed=112)
    try:
        adaptation = node.adaptation
        assert adaptation is not None and isinstance(adaptation.model, ThermalDriftModel)
        lo, hi = float(np.min(y)), float(np.max(y))
        span = hi - lo
        t, desired = tracking_trajectory(60.0, sample_rate=RATE, low=lo + 0.15 * span,
                                         high=hi - 0.15 * span, final_envelope=1.0)
        for k in range(t.size):
            current = node.command(float(desired[k]))
            adaptation.record_measurement(plant.step(float(t[k]), current))
            if k and k % int(RATE) == 0:
                adaptation.step()
                for _ in range(3):
                    executor.spin_once(timeout_sec=0.05)
        status = adaptation.status()
        assert status['adaptation_updates_accepted'] >= 1, status
        running = node.compensator.model
        assert isinstance(running, ThermalDriftModel)
        assert running.time_constant == 30.0
        assert node.get_parameter('model.thermal_drift.weight').value == running.weight
        assert running.weight > model.weight
    finally:
        executor.remove_node(node)
        executor.shutdown()
        node.destroy_node()


def _started_child(name, priority):
    # An adaptation child taking the readings on /displacement itself (holdout 0.1 s: 50
    # commands at 500 Hz), started; with the list its errors go to.
    t, x = identification_excitation(10.0, sample_rate=RATE, seed=11)
    y = MagnetostrictiveActuator(ActuatorConfig(noise_std_m=2e-8), seed=11).simulate(t, x)
    settings = AdaptationSettings(sample_period=1 / RATE, holdout=0.1, priority=priority)
    source = ReadingSource(topic='/displacement', depth=10000, reliability='reliable',
                           sample_period=1 / RATE, node_name=name)
    errors = []
    process = AdaptationProcess(identify(x, y, n=6, l=3).model, settings,
                                on_error=errors.append, readings=source,
                                entry=adaptation_readings.__name__)
    process.start()
    return process, errors


def _state(pid):
    # The process's state letter from /proc ('T': stopped; '' where there is no /proc).
    try:
        with open(f'/proc/{pid}/stat') as stat:
            return stat.read().rpartition(')')[2].split()[0]
    except OSError:
        return ''


def _stop(pid):
    # SIGSTOP, then wait (bounded) until the process is seen stopped where /proc shows it.
    os.kill(pid, signal.SIGSTOP)
    deadline = time.monotonic() + 10.0
    while _state(pid) not in ('T', '') and time.monotonic() < deadline:
        time.sleep(0.01)
    assert _state(pid) in ('T', ''), _state(pid)


def test_a_child_that_stops_taking_the_commands_is_stopped(ros_context):
    # The child takes the readings itself: one that has not taken 20 held-out windows of
    # commands has lost its readings too, so the node stops it and says so once, rather
    # than pair what no longer pairs (holdout 0.1 s: 1000 commands at 500 Hz).  At
    # priority low (one at idle priority is restarted instead: the next test).
    process, errors = _started_child('stalled_adaptation', 'low')
    try:
        assert process.wait_ready(60.0)
        _stop(process.pid)
        seen = []
        for _ in range(10):
            for _ in range(1000):
                process.record_command(1.0)
            process.exchange()
            seen.append((process.pending[0], _state(process.pid)))
        # What each exchange left waiting and the child's state: a flake names its cause.
        assert not process.running, (seen, process.status())
    finally:
        process.stop()
    state = 'stopped: the adaptation process did not take the commands (stalled)'
    assert process.status()['adaptation_state'] == state
    assert errors == [state]
    assert process.pending == (0, 0)


def test_an_idle_child_that_falls_behind_is_restarted_at_low_priority(ros_context):
    # The default child runs at idle priority; one the machine leaves behind (here: stopped)
    # is not stopped for good but restarted at niceness CHILD_NICE from the running model,
    # with its own subscription, and says so; the old one is ended, nothing is half-kept.
    assert AdaptationSettings().priority == 'idle'
    process, errors = _started_child('idle_adaptation', 'idle')
    first = process.pid
    try:
        assert process.wait_ready(60.0)
        if process.priority != 'idle':
            pytest.skip('this platform has no SCHED_IDLE')
        _stop(first)
        for _ in range(20):
            for _ in range(1000):
                process.record_command(1.0)
            process.exchange()
            if process.pid != first:
                break
        assert process.pid != first
        events = process.events()
        assert len(events) == 1 and 'fell behind' in events[0], events
        assert f'at niceness {CHILD_NICE} as process {process.pid}' in events[0]
        assert process.settings.priority == 'low'
        assert process.status()['adaptation_restarts'] == 1
        assert process.wait_ready(60.0)
        assert process.priority == 'low' and process.running
        os.kill(first, signal.SIGCONT)      # asked to end; ended by stop() at the latest
    finally:
        process.stop()
    with pytest.raises(ProcessLookupError):
        os.kill(first, 0)
    assert not process.running
    assert errors == []


def test_the_childs_subscription_lives_from_configure_to_cleanup(ros_context):
    # The readings' subscriber lives in the child, which the node starts at configure and
    # stops at cleanup (as its own subscription did): after cleanup nothing reads
    # displacement, after a new configure a new child does, and none outlives the node.
    t, x = identification_excitation(10.0, sample_rate=RATE, seed=11)
    y = MagnetostrictiveActuator(ActuatorConfig(noise_std_m=2e-8), seed=11).simulate(t, x)
    node, executor = _adaptive_node(ros_context, identify(x, y, n=6, l=3).model, True)
    second = None
    try:
        first = node.adaptation
        assert isinstance(first, AdaptationProcess) and first.running
        node.trigger_deactivate()
        assert first.running                      # inactive: the memory and the child stay
        node.trigger_cleanup()
        assert node.adaptation is None and not first.running
        node.trigger_configure()
        second = node.adaptation
        assert isinstance(second, AdaptationProcess) and second.running
        assert second.pid != first.pid
        assert '/displacement' not in [s.topic_name for s in node.subscriptions]
    finally:
        executor.remove_node(node)
        executor.shutdown()
        node.destroy_node()
    assert second is not None and not second.running
