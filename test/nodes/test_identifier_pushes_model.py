# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Issue 27: the identifier delivers the model ``identify`` writes, over DDS.

A bag from a plant with an input lag (the built-in actuator's eddy-current lag, 5 ms) goes
through the identifier node to a compensator node; the pushed model carries the lag (read
back through the compensator's ``get_parameters`` service, as ``ros2 param get`` does) and
the output limits ``identify`` writes.  A second compensator gets Gamma alone (the static
model the identifier pushed before).  Both are driven over DDS on a new trajectory (two
sines, not the identification excitation), their commands applied to the plant: the
pushed model tracks better.
"""

import threading

from mpi_ros.harness.driver import LoopDriver
from mpi_ros.nodes import identifier
from mpi_ros.nodes.compensator import CompensatorNode
from mpi_ros.nodes.identifier import IdentifierNode
from mpi_ros.plant.actuator import ActuatorConfig, MagnetostrictiveActuator
from mpi_ros.plant.excitation import identification_excitation
from mpi_ros.recordings import write_bag_signals
import numpy as np
import pytest
from rcl_interfaces.srv import GetParameters
from rclpy.executors import SingleThreadedExecutor
from rclpy.parameter import Parameter, parameter_value_to_python
from std_msgs.msg import Float64

LAG = 0.005                      # the plant's eddy-current lag [s]
RATE = 1000.0                    # samples per second
LAG_KEY = 'model.rate_dependence.time_constant'


def _plant(seed):
    return MagnetostrictiveActuator(ActuatorConfig(eddy_time_constant_s=LAG), seed=seed)


@pytest.fixture(scope='module')
def lagged_bag(tmp_path_factory):
    """Return a bag of the lagged plant under a 5 Hz identification excitation."""
    t, current = identification_excitation(12.0, sample_rate=RATE, seed=1, main_frequency=5.0)
    displacement = _plant(1).simulate(t, current)
    path = tmp_path_factory.mktemp('bags') / 'lagged'
    write_bag_signals(path, t, current, displacement)
    return path


@pytest.fixture
def compensators(ros_context):
    """Spin two compensator nodes, /full and /static, stamping samples 1 ms apart."""
    nodes = {name: CompensatorNode(context=ros_context, namespace=name, parameter_overrides=[
        Parameter('message_time', value='nominal'), Parameter('sample_period', value=1e-3)])
        for name in ('full', 'static')}
    executor = SingleThreadedExecutor(context=ros_context)
    for node in nodes.values():
        executor.add_node(node)
    thread = threading.Thread(target=executor.spin, daemon=True)
    thread.start()
    yield nodes
    executor.shutdown()
    thread.join(timeout=5.0)
    for node in nodes.values():
        node.destroy_node()


def _get_parameters(node, target, names):
    """Read parameters through the target's get_parameters service (ros2 param get)."""
    client = node.create_client(GetParameters, f'{target}/get_parameters')
    try:
        assert client.wait_for_service(timeout_sec=10.0)
        future = client.call_async(GetParameters.Request(names=list(names)))
        executor = SingleThreadedExecutor(context=node.context)
        executor.add_node(node)
        try:
            executor.spin_until_future_complete(future, timeout_sec=10.0)
        finally:
            executor.remove_node(node)
            executor.shutdown()
        assert future.done()
        return {name: parameter_value_to_python(value)
                for name, value in zip(names, future.result().values)}
    finally:
        node.destroy_client(client)


def _drive(driver, desired):
    """Publish each desired displacement over DDS and wait for its command."""
    for k, value in enumerate(desired):
        driver.desired_pub.publish(Float64(data=float(value)))
        driver.wait_for(lambda k=k: len(driver.commands) > k, 'a command', 10.0)
    return np.array(driver.commands[:len(desired)])


def test_the_pushed_model_carries_the_lag_and_tracks_better(ros_context, compensators,
                                                            lagged_bag):
    node = IdentifierNode(context=ros_context, parameter_overrides=[
        Parameter('bag', value=str(lagged_bag)), Parameter('order', value='6,3'),
        Parameter('target_node', value='/full/compensator'),
        Parameter('service_timeout', value=10.0)])
    try:
        fit = node.run()
        # The static model: Gamma and its operating point alone, as pushed before issue 27.
        identifier.push_model_parameters(node, '/static/compensator',
                                         fit.result.model.to_params(), timeout=10.0)
        read = _get_parameters(node, '/full/compensator',
                               [LAG_KEY, 'output.min', 'output.max'])
        static = _get_parameters(node, '/static/compensator', [LAG_KEY])
    finally:
        node.destroy_node()
    # What identify writes is what was pushed: the lag, and the identified input range.
    assert fit.written[LAG_KEY] == fit.parameters[LAG_KEY]
    assert read[LAG_KEY] == fit.written[LAG_KEY]
    assert read[LAG_KEY] == pytest.approx(LAG, rel=0.1)
    assert (read['output.min'], read['output.max']) == (fit.written['output.min'],
                                                        fit.written['output.max'])
    assert static[LAG_KEY] is None
    assert compensators['full'].compensator.model.to_params() == fit.parameters

    # A new trajectory: two sines (8 and 13 Hz) over 70 % of the reachable displacement.
    from mpi_ros.compensation import operating_range
    low, high = operating_range(fit.result.model, read['output.min'], read['output.max'])
    t = np.arange(2000) / RATE
    desired = 0.5 * (low + high) + 0.35 * (high - low) * (
        0.6 * np.sin(2.0 * np.pi * 8.0 * t) + 0.4 * np.sin(2.0 * np.pi * 13.0 * t + 1.0))
    errors = {}
    for name in ('full', 'static'):
        driver = LoopDriver(f'driver_{name}', namespace=name, context=ros_context)
        try:
            commands = _drive(driver, desired)
        finally:
            driver.destroy_node()
        reached = _plant(2).simulate(t, commands)
        settled = slice(200, None)
        errors[name] = float(np.sqrt(np.mean((reached[settled] - desired[settled]) ** 2))
                             / (high - low))
    # Measured on this trajectory: about 0.6 % (lag modelled) against 5.4 % (static).
    assert errors['full'] < 0.5 * errors['static'], errors


def test_diagnose_delivers_the_extension_it_names_clearly(ros_context, compensators,
                                                          tmp_path):
    """``diagnose: true``: the extension the diagnosis names with a clear gain is pushed."""
    t, current = identification_excitation(10.0, sample_rate=RATE, seed=1)
    # Creep (10 % of each change): the effect fits chosen out of sample (issue 24) no longer
    # name a 30 s thermal drift in a 10 s record, as they should not.
    config = ActuatorConfig(noise_std_m=2e-8, creep_gain=0.1)
    displacement = MagnetostrictiveActuator(config, seed=1).simulate(t, current)
    bag = tmp_path / 'creep'
    write_bag_signals(bag, t, current, displacement)
    node = IdentifierNode(context=ros_context, parameter_overrides=[
        Parameter('bag', value=str(bag)), Parameter('order', value='6,3'),
        Parameter('diagnose', value=True), Parameter('target_node', value='/full/compensator'),
        Parameter('service_timeout', value=120.0)])     # the first creep model compiles
    try:
        fit = node.run()
    finally:
        node.destroy_node()
    assert ', clear (validation gain' in fit.diagnosis, fit.diagnosis
    cause = fit.diagnosis.split()[1].rstrip(',')
    from mpi_ros.extensions import EFFECTS
    keys = EFFECTS[cause].keys
    assert all(key in fit.written for key in keys)
    applied = compensators['full'].compensator.model
    assert applied.to_params() == fit.parameters
    assert compensators['full'].compensator.kind == cause
    for key in keys:
        assert compensators['full'].get_parameter(key).value == pytest.approx(
            fit.written[key], rel=1e-12)
