# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Hostile peers (issue 25): malformed messages and pushes never end a node or make it unsafe.

Each node runs as its own process on the module's ROS domain; this test process is
another participant that publishes raw bytes (one byte, truncated and oversized arrays,
unknown encapsulations), NaN and Inf values, and pushes through the standard parameter
services models that pass the form checks but do not run (subnormal weights, an input
offset of 1e308) and models with every key of the wrong type.  One process takes several
probes; after *each* probe the node must still run and answer valid inputs with finite
commands inside its limits, equal to the core compensator's.  A node started with an
unusable ``--params-file`` prints one ``error:`` line and exits 1.
"""

import math
import struct
import time

from diagnostic_msgs.msg import DiagnosticArray
from mpi_ros.array_layout import encode_float64_multiarray
from mpi_ros.compensation import Compensator
from mpi_ros.nodes.multi_axis import axis_key
from mpi_ros.operators.model import MODEL_KEYS, MPIModel, RECORD_START_STATES
from mpi_ros.params import write_params_yaml
import numpy as np
import pytest
from rcl_interfaces.srv import SetParametersAtomically
from rclpy.parameter import Parameter
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64, Float64MultiArray

from .helpers import call_service, commands_for, first_command, LIMITS, log_text, wait_exit

R_H, W_H, R_S, W_S = MODEL_KEYS
Z_H0 = RECORD_START_STATES
#: A valid model (0.2 to 1.8 A -> roughly 0 to 40 um), with an operating point.
MODEL = {
    R_H: [0.0, 0.3, 0.6], W_H: [1.0, 0.4, 0.2], Z_H0: [0.0, 0.1, 0.0],
    R_S: [-0.5, 0.0, 0.8], W_S: [1.0e-5, 2.0e-5, -0.5e-5],
    'model.input_offset': 0.4, 'model.output_offset': 1.0e-4, 'model.output_sign': 1,
}
TIMEOUT = 30.0


def _core():
    return Compensator(MPIModel.from_params(MODEL), output_min=LIMITS[0],
                       output_max=LIMITS[1])


def _desired(core, size, seed):
    low, high = core.displacement_range
    return np.random.default_rng(seed).uniform(low, high, size)


def _typed(name, value):
    return Parameter(name, value=value)


def _push(driver, parameters, node='/compensator'):
    """Push through set_parameters_atomically; return (successful, reason)."""
    request = SetParametersAtomically.Request(
        parameters=[parameter.to_parameter_msg() for parameter in parameters])
    result = call_service(driver, SetParametersAtomically,
                          f'{node}/set_parameters_atomically', request).result
    return result.successful, result.reason


def _unusable_pushes(prefix=''):
    """Return (probe name, parameters, key the refusal must name): form-valid, unusable."""
    def model(**changes):
        values = dict(MODEL, **changes)
        return [_typed(prefix + key, value) for key, value in values.items()]

    wrong = [Parameter(prefix + key, Parameter.Type.STRING, 'x') for key in MODEL]
    return [
        ('subnormal weights', model(**{W_H: [5e-324] * 3}), prefix + W_H),
        ('input offset 1e308', model(**{'model.input_offset': 1e308}),
         prefix + 'model.input_offset'),
        ('every key wrong-typed', wrong, prefix + R_H),
    ]


def _diagnostics(driver, name):
    """Return the values of the next /diagnostics status whose name starts with ``name``."""
    received = []
    subscription = driver.create_subscription(DiagnosticArray, '/diagnostics',
                                              received.append, 10)
    try:
        driver.wait_for(lambda: any(status.name.startswith(name) for array in received
                                    for status in array.status), '/diagnostics', TIMEOUT)
    finally:
        driver.destroy_subscription(subscription)
    for array in received:
        for status in array.status:
            if status.name.startswith(name):
                return {kv.key: kv.value for kv in status.values}
    raise AssertionError('no status')


def _publish_once(driver, message_type, topic, message, subscribers=1):
    """Publish one probe from a new writer of the driver once it is matched."""
    publisher = driver.create_publisher(message_type, topic, 10)
    try:
        driver.wait_for(lambda: publisher.get_subscription_count() >= subscribers,
                        f'{topic} to match', TIMEOUT)
        publisher.publish(message)
        driver.spin_for(0.3)
    finally:
        driver.destroy_publisher(publisher)


def test_single_axis_compensator_survives_every_probe(nodes, driver, tmp_path):
    params_file = tmp_path / 'model.yaml'
    write_params_yaml(params_file, MODEL)
    comp = nodes.compensator('--params-file', str(params_file))
    core = _core()
    values = _desired(core, 200, seed=25)
    assert first_command(driver, values[0]) == core.command(values[0])
    k = 1

    def answers_as_the_core(probe):
        nonlocal k
        assert comp.running(), f'{probe} ended the compensator:\n{log_text(comp)}'
        commands = commands_for(driver, values[k:k + 5])
        assert np.all(np.isfinite(commands)), probe
        assert np.all((commands >= LIMITS[0]) & (commands <= LIMITS[1])), probe
        np.testing.assert_allclose(commands, [core.command(v) for v in values[k:k + 5]],
                                   rtol=0, atol=1e-12, err_msg=probe)
        k += 5

    raw = [('one byte', b'\x00'), ('empty', b''), ('truncated double', bytes([0, 1, 0, 0, 7])),
           ('unknown encapsulation', bytes([0, 7, 0, 0]) + struct.pack('<d', 1e-5)),
           ('half a double', bytes([0, 1, 0, 0]) + bytes(4))]
    # Each probe comes from a writer of its own: Fast DDS never delivers an empty sample
    # (it stalls that writer's reliable stream, about 5 s here, not the node).
    for probe, data in raw:
        _publish_once(driver, Float64, 'desired_displacement', data)
        answers_as_the_core(probe)
    for value in (math.nan, math.inf, -math.inf, 1e308, -1e308, 5e-324):
        command = commands_for(driver, [value])[0]
        assert command == core.command(value) and LIMITS[0] <= command <= LIMITS[1], value
        answers_as_the_core(f'desired {value!r}')
    for probe, parameters, key in _unusable_pushes():
        successful, reason = _push(driver, parameters)
        assert not successful, probe
        assert key in reason, (probe, reason)
        answers_as_the_core(probe)
    values_now = _diagnostics(driver, 'compensator')
    assert int(values_now['malformed']) == len(raw) - 1        # the empty one never arrives
    assert int(values_now['nonfinite_command']) == 0
    assert int(values_now['rejected_updates']) == len(_unusable_pushes())
    assert int(values_now['model_version']) == 1
    assert 'not a CDR Float64' in values_now['last_malformed']


def _block_bytes(dims, data, offset=0):
    """Serialize a Float64MultiArray with any layout (rclpy), e.g. one that lies."""
    from rclpy.serialization import serialize_message
    from std_msgs.msg import MultiArrayDimension
    message = Float64MultiArray()
    message.layout.dim = [MultiArrayDimension(label=label, size=size, stride=stride)
                          for label, size, stride in dims]
    message.layout.data_offset = offset
    message.data = [float(v) for v in data]
    return serialize_message(message)


def test_multi_axis_compensator_survives_every_probe(nodes, driver, tmp_path):
    params = {'axes': 2, 'output.min': LIMITS[0], 'output.max': LIMITS[1]}
    for axis in range(2):
        params.update({axis_key(axis, key): value for key, value in MODEL.items()})
    params_file = tmp_path / 'axes.yaml'
    write_params_yaml(params_file, params)
    comp = nodes.compensator('--params-file', str(params_file))
    cores = [_core(), _core()]
    values = np.column_stack([_desired(cores[0], 80, seed=26), _desired(cores[1], 80, seed=27)])
    blocks = []
    publisher = driver.create_publisher(Float64MultiArray, 'desired_displacements', 100)
    driver.create_subscription(Float64MultiArray, 'current_commands',
                               lambda m: blocks.append(np.array(m.data).reshape(-1, 2)), 100)
    driver.wait_for(lambda: publisher.get_subscription_count() > 0
                    and driver.count_publishers('current_commands') > 0, 'matching', TIMEOUT)
    deadline = time.monotonic() + TIMEOUT
    while not blocks:                                  # handshake: repeat the first block
        assert time.monotonic() < deadline, 'no answer from the multi-axis compensator'
        publisher.publish(encode_float64_multiarray(values[:1]))
        driver.spin_for(0.5)
    driver.spin_for(0.3)
    expected = [core.command(v) for core, v in zip(cores, values[0])]
    assert all(np.array_equal(block[0], expected) for block in blocks)
    k = 1

    def answers_as_the_core(probe):
        nonlocal k
        assert comp.running(), f'{probe} ended the compensator:\n{log_text(comp)}'
        blocks.clear()
        publisher.publish(encode_float64_multiarray(values[k:k + 3]))
        driver.wait_for(lambda: blocks, f'an answer after {probe}', TIMEOUT)
        got = blocks[0]
        assert got.shape == (3, 2) and np.all(np.isfinite(got)), probe
        assert np.all((got >= LIMITS[0]) & (got <= LIMITS[1])), probe
        for axis, core in enumerate(cores):
            np.testing.assert_allclose(got[:, axis], [core.command(v) for v in
                                                      values[k:k + 3, axis]],
                                       rtol=0, atol=1e-12, err_msg=probe)
        k += 3

    two_by_two = [('samples', 2, 4), ('axes', 2, 2)]
    raw = [('one byte', b'\x00'),
           ('truncated array', _block_bytes(two_by_two, [1e-5] * 3)),
           ('oversized layout', _block_bytes([('samples', 1000000, 2000000), ('axes', 2, 2)],
                                             [1e-5] * 4)),
           ('rows of 3 values', _block_bytes([], [1e-5] * 5)),
           ('offset past the data', _block_bytes(two_by_two, [1e-5] * 4, offset=99))]
    for probe, data in raw:
        _publish_once(driver, Float64MultiArray, 'desired_displacements', data)
        answers_as_the_core(probe)
    for value in (math.nan, math.inf, -1e308):
        blocks.clear()
        block = np.array([[value, values[k, 1]]])
        publisher.publish(encode_float64_multiarray(block))
        driver.wait_for(lambda: blocks, f'an answer to {value!r}', TIMEOUT)
        expected = [core.command(v) for core, v in zip(cores, block[0])]
        np.testing.assert_array_equal(blocks[0][0], expected)
        answers_as_the_core(f'desired {value!r}')
    for axis in (0, 1):
        for probe, parameters, key in _unusable_pushes(prefix=f'axis{axis}.'):
            successful, reason = _push(driver, parameters)
            assert not successful, probe
            assert key in reason, (probe, reason)
            answers_as_the_core(f'axis {axis}: {probe}')
    values_now = _diagnostics(driver, 'compensator')
    assert int(values_now['malformed']) == len(raw)
    assert int(values_now['nonfinite_command']) == 0


def test_joint_state_input_and_plant_survive_malformed_messages(nodes, driver, tmp_path):
    # Two processes: a multi-axis compensator fed JointStates, and the plant simulator.
    params = {'axes': 2, 'joints': ['a', 'b'], 'input_message': 'joint_state',
              'output.min': LIMITS[0], 'output.max': LIMITS[1]}
    for axis in range(2):
        params.update({axis_key(axis, key): value for key, value in MODEL.items()})
    params_file = tmp_path / 'joints.yaml'
    write_params_yaml(params_file, params)
    comp = nodes.compensator('--params-file', str(params_file))
    plant = nodes.start('plant-simulator')
    cores = [_core(), _core()]
    blocks = []
    joints = driver.create_publisher(JointState, 'desired_joint_states', 100)
    driver.create_subscription(Float64MultiArray, 'current_commands',
                               lambda m: blocks.append(np.array(m.data)), 100)
    driver.wait_for(lambda: joints.get_subscription_count() > 0
                    and driver.count_publishers('current_commands') > 0, 'matching', TIMEOUT)
    values = np.column_stack([_desired(cores[0], 20, seed=28), _desired(cores[1], 20, seed=29)])
    deadline = time.monotonic() + TIMEOUT
    while not blocks:
        assert time.monotonic() < deadline, 'no answer to a JointState'
        joints.publish(JointState(name=['b', 'a'], position=[values[0, 1], values[0, 0]]))
        driver.spin_for(0.5)
    driver.spin_for(0.3)
    expected = [core.command(v) for core, v in zip(cores, values[0])]
    k = 1
    probes = [('one byte', b'\x00'), ('truncated', bytes([0, 1, 0, 0, 9, 0, 0])),
              ('NaN position', JointState(name=['a', 'b'], position=[math.nan, 1e-5]))]
    for probe, message in probes:
        _publish_once(driver, JointState, 'desired_joint_states', message)
        if probe == 'NaN position':
            expected = [core.command(v) for core, v in zip(cores, [math.nan, 1e-5])]
        assert comp.running(), f'{probe} ended the compensator:\n{log_text(comp)}'
        blocks.clear()
        joints.publish(JointState(name=['a', 'b'], position=list(values[k])))
        driver.wait_for(lambda: blocks, f'an answer after {probe}', TIMEOUT)
        expected = [core.command(v) for core, v in zip(cores, values[k])]
        got = blocks[-1]
        assert np.all(np.isfinite(got)) and np.all((got >= LIMITS[0]) & (got <= LIMITS[1]))
        np.testing.assert_allclose(got, expected, rtol=0, atol=1e-12, err_msg=probe)
        k += 1
    assert int(_diagnostics(driver, 'compensator')['malformed']) == 2

    driver.wait_for(lambda: driver.current_pub.get_subscription_count() > 1,
                    'the plant to subscribe', TIMEOUT)
    for probe, data in (('one byte', b'\x00'), ('truncated', bytes([0, 1, 0, 0, 1])),
                        ('unknown encapsulation', bytes([1, 1, 0, 0]) + bytes(8))):
        # The compensator subscribes to current_command too (its output topic: it only
        # publishes there), so the probe waits for both readers.
        _publish_once(driver, Float64, 'current_command', data, subscribers=1)
        assert plant.running(), f'{probe} ended the plant simulator:\n{log_text(plant)}'
        displacement = driver.handshake(driver.current_pub, 1.0, timeout=TIMEOUT)
        assert math.isfinite(displacement), probe
    assert 'ignoring current_command message' in log_text(plant)


#: (file content or None for a missing file, words of the error line); more cases run
#: in-process in test/nodes/test_params_file.py.
PARAMS_FILES = [
    (b'\x89PNG\r\n\x1a\n\x00\x00garbage: [', 'not valid YAML'),
    (b'compensator:\n  ros__parameters: 5\n', 'ros__parameters must be a mapping'),
    (None, 'cannot read it'),
]


@pytest.mark.parametrize('content, words', PARAMS_FILES)
def test_unusable_params_file_gives_one_error_line(nodes, tmp_path, content, words):
    path = tmp_path / 'params.yaml'
    if content is not None:
        path.write_bytes(content)
    comp = nodes.start('compensator', '--params-file', str(path))
    assert wait_exit(comp, timeout=TIMEOUT) == 1
    lines = [line for line in log_text(comp).splitlines() if line.strip()]
    assert 'Traceback' not in log_text(comp)
    errors = [line for line in lines if line.startswith('error:')]
    assert len(errors) == 1 and words in errors[0], lines
    assert lines == errors, lines
