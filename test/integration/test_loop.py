# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
The three nodes as separate processes over DDS: closed loop, model push, rejection, swap.

Each test module runs on its own ``ROS_DOMAIN_ID`` (the ``ros_env`` fixture of
``test/conftest.py``) with ``ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST``; every process is
started and stopped here, by PID.
"""

from mpi_ros import identify, MPIModel
from mpi_ros.compensation import Compensator, operating_range
from mpi_ros.harness.driver import LoopDriver
from mpi_ros.harness.processes import NodeProcess
from mpi_ros.metrics import control_error
from mpi_ros.nodes.identifier import ParameterPushError, push_model_parameters
from mpi_ros.operators.inverse import invert_hysteresis_initial_states
from mpi_ros.plant.excitation import identification_excitation, tracking_trajectory
import numpy as np
import pytest
import rclpy

from ..core_models import hand_model

RATE = 200.0
LIMITS = (0.2, 1.8)


@pytest.fixture()
def loop(ros_env, tmp_path):
    context = rclpy.Context()
    rclpy.init(context=context)
    driver = LoopDriver(context=context)
    started = []

    def start(node, *ros_args):
        proc = NodeProcess(node, list(ros_args), tmp_path / f'{node}-{len(started)}.log')
        started.append(proc)
        return proc

    def stop_all():
        for proc in started:
            proc.stop()

    start.stop_all = stop_all
    try:
        yield driver, start
    finally:
        for proc in started:
            proc.stop()
        assert not any(p.running() for p in started)
        driver.destroy_node()
        rclpy.try_shutdown(context=context)


#: Issue 9's reconfigured actuator: its sensor was zeroed in operation, after rest -> 1.8 A
#: -> 0.2 A, so it reads 0 m at the lowest current of the range (not at the model's origin).
ZEROED = ('-p', 'actuator.sensor_zero_current_a:=0.2',
          '-p', 'actuator.sensor_zero_peak_current_a:=1.8')


def _record(driver, start, duration=20.0, plant_args=()):
    plant = start('plant-simulator', '-p', 'noise_std:=4e-08', '-p', 'seed:=3', *plant_args)
    driver.wait_for(lambda: driver.current_pub.get_subscription_count() > 0, 'plant', 60.0)
    t, current = identification_excitation(duration, sample_rate=RATE, seed=3, holds=False,
                                           bursts=False)
    driver.handshake(driver.current_pub, current[0])
    measured = np.array([driver.exchange(driver.current_pub, v) for v in current])
    plant.stop()
    return current, measured


def _push(driver, model_or_params, timeout=30.0):
    params = model_or_params.to_params() if isinstance(model_or_params, MPIModel) else \
        model_or_params
    with driver.detached():
        push_model_parameters(driver, '/compensator', params, timeout=timeout)


def _start_loop(driver, start, enabled=True, plant_args=()):
    # A fresh plant is where the identification record started: the record's start.
    start('plant-simulator', '-p', 'noise_std:=4e-08', '-p', 'seed:=4', *plant_args)
    start('compensator', '-p', f'output.min:={LIMITS[0]}', '-p', f'output.max:={LIMITS[1]}',
          '-p', f'enabled:={str(enabled).lower()}', '-p', 'start_state:=record')


def _track(driver, desired):
    driver.wait_for(lambda: driver.desired_pub.get_subscription_count() > 0, 'compensator',
                    60.0)
    driver.handshake(driver.desired_pub, desired[0])
    driver.commands.clear()
    return np.array([driver.exchange(driver.desired_pub, v) for v in desired])


def _trajectory(model, duration=6.0):
    lo, hi = operating_range(model, *LIMITS)
    span = hi - lo
    _, desired = tracking_trajectory(duration, sample_rate=RATE, low=lo + 0.1 * span,
                                     high=hi - 0.1 * span)
    return np.concatenate([np.linspace(0.0, desired[0], int(RATE)), desired]), int(RATE)


@pytest.mark.parametrize('plant_args', [(), ZEROED], ids=['origin', 'zeroed_in_operation'])
def test_closed_loop_reaches_the_papers_control_error(loop, plant_args):
    driver, start = loop
    current, measured = _record(driver, start, plant_args=plant_args)
    model = identify(current, measured, n=14, l=7).model
    desired, lead = _trajectory(model)
    errors = {}
    for enabled in (False, True):
        _start_loop(driver, start, enabled, plant_args)
        _push(driver, model)
        s = _track(driver, desired)
        errors[enabled] = control_error(desired[lead:], s[lead:])
        start.stop_all()
    print(f'control error (38): linear {100 * errors[False]:.2f} %,'
          f' MPI (14, 7) {100 * errors[True]:.2f} %')
    assert errors[False] >= 0.20          # best linear map (issue 9 asks >= 15 %)
    assert errors[True] <= 0.03           # the paper's ~3 %


def test_push_reject_and_bumpless_swap(loop):
    driver, start = loop
    params = hand_model()
    old = MPIModel.from_params(params)
    new = MPIModel.from_params(dict(params, **{
        'model.hysteresis.weights': [1.1, 0.25, 0.25, 0.05]}))
    _start_loop(driver, start)
    _push(driver, old)
    mirror = Compensator(old, output_min=LIMITS[0], output_max=LIMITS[1])
    desired, _ = _trajectory(old, duration=3.0)
    _track(driver, desired[:1])
    mirror.command(desired[0])
    # (a) the pushed model is applied: the node's commands are the core's, exactly.
    for v in desired[1:300]:
        driver.exchange(driver.desired_pub, v)
    expected = [mirror.command(v) for v in desired[1:300]]
    np.testing.assert_allclose(driver.commands[-299:], expected, rtol=0, atol=1e-12)
    # (b) a bad model is rejected with a reason naming the parameter; the old one runs on.
    bad = dict(params, **{'model.hysteresis.weights': [1.0, -0.3, 0.2, 0.1]})
    with pytest.raises(ParameterPushError, match=r'model\.hysteresis\.weights'):
        _push(driver, bad)
    for v in desired[300:400]:
        driver.exchange(driver.desired_pub, v)
    expected = [mirror.command(v) for v in desired[300:400]]
    np.testing.assert_allclose(driver.commands[-100:], expected, rtol=0, atol=1e-12)
    # (c) a good new model is swapped in bumplessly (as the core's swap, proven exact).
    applied = np.array(driver.commands)          # every command since the loop started
    _push(driver, new)
    mirror.install(new)
    for v in desired[400:]:
        driver.exchange(driver.desired_pub, v)
    expected = [mirror.command(v) for v in desired[400:]]
    np.testing.assert_allclose(driver.commands[-len(expected):], expected, rtol=0, atol=1e-12)
    # Independently: the first command after the swap is the new model's inverse started
    # from the state the applied current history leaves in the new model, by (14).
    _, z_h = new.hysteresis.apply(applied)
    z_inv = invert_hysteresis_initial_states(z_h, new.hysteresis.weights)
    implied = float(np.clip(new.inverse().run(desired[400:401], z_inv)[0][0], *LIMITS))
    assert driver.commands[-len(expected)] == pytest.approx(implied, abs=1e-12)
