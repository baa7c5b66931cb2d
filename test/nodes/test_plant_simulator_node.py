# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""The plant simulator node in-process: truths, parameters, topics, excitation and recording."""

import math
import time

from mpi_ros.errors import ModelError
from mpi_ros.errors import ParameterRejected
from mpi_ros.nodes.plant_simulator import PlantSimulatorNode
from mpi_ros.operators.model import MODEL_KEYS, MPIModel, RECORD_START_STATES
from mpi_ros.plant.actuator import MagnetostrictiveActuator
from mpi_ros.plant.excitation import identification_excitation
from mpi_ros.recordings import read_bag_signals
import numpy as np
import pytest
import rclpy
from rclpy.exceptions import InvalidParameterValueException
from rclpy.executors import SingleThreadedExecutor
from rclpy.parameter import Parameter
from rclpy.qos import ReliabilityPolicy
from std_msgs.msg import Float64

MODEL = {
    MODEL_KEYS[0]: [0.0, 0.3, 0.6],
    MODEL_KEYS[1]: [1.0, 0.4, 0.2],
    RECORD_START_STATES: [0.0, 0.0, 0.0],
    MODEL_KEYS[2]: [-0.5, 0.0, 0.8],
    MODEL_KEYS[3]: [1.0e-5, 2.0e-5, -0.5e-5],
}


@pytest.fixture
def make_plant(ros_context):
    nodes = []

    def make(**overrides):
        parameters = [Parameter(name.replace('__', '.'), value=value)
                      for name, value in overrides.items()]
        node = PlantSimulatorNode(context=ros_context, parameter_overrides=parameters)
        nodes.append(node)
        return node

    yield make
    for node in nodes:
        node.destroy_node()


def test_builtin_truth_matches_the_actuator_simulation(make_plant):
    plant = make_plant()
    t = np.arange(200) * 1e-3
    current = 1.0 + 0.8 * np.sin(2 * np.pi * 5 * t)
    measured = [plant.measure(float(tk), float(ik)) for tk, ik in zip(t, current)]
    np.testing.assert_allclose(measured, MagnetostrictiveActuator().simulate(t, current),
                               rtol=0, atol=1e-15)


def test_mpi_truth_matches_the_model(make_plant):
    plant = make_plant(truth='mpi', **{key.replace('.', '__'): value
                                       for key, value in MODEL.items()})
    current = 1.0 + 0.8 * np.sin(np.linspace(0.0, 9.0, 300))
    measured = [plant.measure(0.0, float(i)) for i in current]
    np.testing.assert_allclose(measured, MPIModel.from_params(MODEL).simulate(current),
                               rtol=0, atol=1e-15)


def test_mpi_truth_reads_the_operating_point(make_plant):
    """Issue 9: the same three keys as the compensator: y = y0 + sign S[H[x - x0]]."""
    model = dict(MODEL, **{'model.input_offset': 0.5, 'model.output_offset': -2.0e-4,
                           'model.output_sign': -1})
    plant = make_plant(truth='mpi', **{key.replace('.', '__'): value
                                       for key, value in model.items()})
    current = 1.0 + 0.8 * np.sin(np.linspace(0.0, 9.0, 300))
    measured = [plant.measure(0.0, float(i)) for i in current]
    expected = MPIModel.from_params(model).simulate(current)
    np.testing.assert_allclose(measured, expected, rtol=0, atol=1e-15)
    origin = MPIModel.from_params(MODEL).simulate(current - 0.5)
    np.testing.assert_allclose(measured, -2.0e-4 - origin, rtol=0, atol=1e-15)


def test_noise_is_seeded(make_plant):
    first = make_plant(noise_std=1e-6, seed=5)
    second = make_plant(noise_std=1e-6, seed=5)
    a = [first.measure(k * 1e-3, 1.0) for k in range(1, 50)]
    b = [second.measure(k * 1e-3, 1.0) for k in range(1, 50)]
    assert a == b
    assert np.std(np.diff(a)) > 1e-7


def test_mpi_truth_without_model_refuses_to_start(make_plant):
    with pytest.raises(ParameterRejected, match='truth:=mpi needs the model parameters'):
        make_plant(truth='mpi')


def test_invalid_actuator_parameter_refuses_to_start(make_plant):
    with pytest.raises(ModelError, match='actuator.creep_gain'):
        make_plant(actuator__creep_gain=-0.5)


def test_parameters_are_read_only(make_plant):
    plant = make_plant()
    result = plant.set_parameters([Parameter('noise_std', value=1.0e-6)])[0]
    assert not result.successful and 'noise_std' in result.reason


@pytest.mark.parametrize('reliability, policy', [
    ('reliable', ReliabilityPolicy.RELIABLE), ('best_effort', ReliabilityPolicy.BEST_EFFORT)])
def test_qos_reliability_sets_the_loop_endpoints(make_plant, reliability, policy):
    plant = make_plant(qos_reliability=reliability)
    endpoints = (plant.get_publishers_info_by_topic('displacement')
                 + plant.get_subscriptions_info_by_topic('current_command'))
    assert [info.qos_profile.reliability for info in endpoints] == [policy] * 2


def test_unknown_qos_reliability_refuses_to_start(make_plant):
    with pytest.raises((InvalidParameterValueException, ParameterRejected),
                       match='qos_reliability'):
        make_plant(qos_reliability='sometimes')


def test_one_displacement_per_finite_command(ros_context, make_plant):
    plant = make_plant()
    driver = rclpy.create_node('driver', context=ros_context)
    received = []
    publisher = driver.create_publisher(Float64, 'current_command', 100)
    driver.create_subscription(Float64, 'displacement', lambda m: received.append(m.data), 100)
    executor = SingleThreadedExecutor(context=ros_context)
    executor.add_node(plant)
    executor.add_node(driver)
    try:
        _spin_until(executor, lambda: publisher.get_subscription_count() > 0
                    and plant.count_publishers('displacement') > 0
                    and driver.count_subscribers('displacement') > 0)
        commands = [0.5, 1.0, math.nan, 1.5, math.inf, 1.2]
        for value in commands:
            publisher.publish(Float64(data=value))
        _spin_until(executor, lambda: plant.counters['commands'] == len(commands)
                    and len(received) == 4)
    finally:
        executor.shutdown()
        driver.destroy_node()
    assert plant.counters == {'commands': 6, 'nonfinite_commands': 2, 'published': 4}
    assert len(received) == 4 and all(math.isfinite(v) for v in received)


def test_excitation_mode_records_a_bag_and_finishes(make_plant, tmp_path, ros_context):
    bag = tmp_path / 'excitation'
    plant = make_plant(excitation__enabled=True, excitation__duration=1.0,
                       excitation__sample_rate=400.0, excitation__holds=False,
                       excitation__bursts=False, record__path=str(bag))
    assert plant.exits_when_done and plant.exciting
    executor = SingleThreadedExecutor(context=ros_context)
    executor.add_node(plant)
    try:
        executor.spin_until_future_complete(plant.finished, timeout_sec=30.0)
    finally:
        executor.shutdown()
    assert plant.finished.done() and not plant.exciting
    t, current = identification_excitation(1.0, sample_rate=400.0, seed=0, holds=False,
                                           bursts=False)
    recording = read_bag_signals(bag)
    assert len(recording) == len(t)
    np.testing.assert_allclose(recording.current, current, rtol=0, atol=1e-12)
    np.testing.assert_allclose(recording.displacement,
                               MagnetostrictiveActuator().simulate(t, current),
                               rtol=0, atol=1e-15)


def _spin_until(executor, condition, timeout=10.0):
    deadline = time.monotonic() + timeout
    while not condition():
        assert time.monotonic() < deadline, 'timed out'
        executor.spin_once(timeout_sec=0.05)
