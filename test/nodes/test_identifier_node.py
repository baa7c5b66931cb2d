# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""The identifier in-process: bag -> fit -> atomic push, and its failures (exit status 1)."""

import threading

from mpi_ros import identify
from mpi_ros.errors import IdentificationError
from mpi_ros.errors import ParameterRejected
from mpi_ros.nodes import identifier
from mpi_ros.nodes.compensator import CompensatorNode
from mpi_ros.nodes.identifier import IdentifierNode, parse_order
from mpi_ros.operators.model import IDENTIFIED_INPUT_RANGE, MODEL_KEYS, OPERATING_POINT_KEYS, \
    RECORD_START_STATES
from mpi_ros.params import read_params_yaml
from mpi_ros.plant.actuator import MagnetostrictiveActuator
from mpi_ros.plant.excitation import identification_excitation
from mpi_ros.recordings import read_bag_signals, write_bag_signals
import numpy as np
import pytest
from rclpy.executors import SingleThreadedExecutor
from rclpy.parameter import Parameter

ORDER = '6,3'


@pytest.fixture(scope='module')
def excitation_bag(tmp_path_factory):
    """Return a bag of the built-in actuator driven by the identification excitation."""
    t, current = identification_excitation(12.0, sample_rate=250.0, seed=1)
    displacement = MagnetostrictiveActuator().simulate(t, current)
    path = tmp_path_factory.mktemp('bags') / 'excitation'
    write_bag_signals(path, t, current, displacement)
    return path


@pytest.fixture
def compensator(ros_context):
    """Spin a compensator node (unconfigured) in a background executor."""
    node = CompensatorNode(context=ros_context, parameter_overrides=[
        Parameter('output.min', value=0.2), Parameter('output.max', value=1.8)])
    executor = SingleThreadedExecutor(context=ros_context)
    executor.add_node(node)
    thread = threading.Thread(target=executor.spin, daemon=True)
    thread.start()
    yield node
    executor.shutdown()
    thread.join(timeout=5.0)
    node.destroy_node()


def test_parse_order():
    assert parse_order('auto') == 'auto'
    assert parse_order(' 14, 7 ') == (14, 7)
    assert parse_order('14 7') == (14, 7)
    for bad in ('', '14', '0,3', 'a,b', '1,2,3'):
        with pytest.raises(ParameterRejected, match='order must be'):
            parse_order(bad)


def test_fit_and_push_applies_the_model(ros_context, compensator, excitation_bag, tmp_path):
    params_file = tmp_path / 'params.yaml'
    node = IdentifierNode(context=ros_context, parameter_overrides=[
        Parameter('bag', value=str(excitation_bag)), Parameter('order', value=ORDER),
        Parameter('params_file', value=str(params_file)),
        Parameter('service_timeout', value=10.0)])
    try:
        fit = node.run()
    finally:
        node.destroy_node()
    assert fit.result.order == (6, 3)
    assert fit.result.nonlinearity_error < 0.2
    assert compensator.model_version == 1
    applied = compensator.compensator.model.to_params()
    assert applied == fit.parameters
    written = read_params_yaml(params_file)
    kept = MODEL_KEYS + OPERATING_POINT_KEYS + (RECORD_START_STATES, IDENTIFIED_INPUT_RANGE)
    for key in kept:
        assert written[key] == pytest.approx(fit.parameters[key], rel=1e-12, abs=0.0)
    assert set(fit.parameters) == set(kept)
    # The record's input range reaches the running node (its rest start and limits use it).
    assert compensator.get_parameter(IDENTIFIED_INPUT_RANGE).value.tolist() == \
        fit.parameters[IDENTIFIED_INPUT_RANGE]
    assert fit.parameters[IDENTIFIED_INPUT_RANGE] == [float(v) for v in
                                                      fit.result.model.identified_input_range]
    for key in OPERATING_POINT_KEYS:
        assert compensator.get_parameter(key).value == fit.parameters[key]


def _main(monkeypatch, capsys, *ros_args):
    from test.nodes.ros_env import run_domain_id
    monkeypatch.setenv('ROS_AUTOMATIC_DISCOVERY_RANGE', 'LOCALHOST')
    monkeypatch.setenv('ROS_DOMAIN_ID', str(run_domain_id()))
    status = identifier.main(['identifier', '--ros-args', *ros_args])
    return status, capsys.readouterr().err


def test_missing_bag_fails_cleanly(monkeypatch, capsys, tmp_path):
    status, err = _main(monkeypatch, capsys, '-p', f'bag:={tmp_path / "nope"}')
    assert status == 1
    assert 'error: identifier:' in err


def test_no_bag_parameter_fails_cleanly(monkeypatch, capsys):
    status, err = _main(monkeypatch, capsys)
    assert status == 1
    assert 'no bag given' in err


def test_bad_order_fails_cleanly(monkeypatch, capsys, excitation_bag):
    status, err = _main(monkeypatch, capsys, '-p', f'bag:={excitation_bag}', '-p', 'order:=x')
    assert status == 1
    assert 'order must be' in err


def test_missing_target_fails_with_bounded_wait(monkeypatch, capsys, excitation_bag):
    status, err = _main(monkeypatch, capsys, '-p', f'bag:={excitation_bag}',
                        '-p', f'order:={ORDER}', '-p', 'target_node:=/nobody_here',
                        '-p', 'service_timeout:=0.5')
    assert status == 1
    assert 'no parameter service /nobody_here/set_parameters_atomically' in err


def test_refused_data_logs_the_reason_and_pushes_nothing(ros_context, compensator, tmp_path,
                                                         capfd):
    """Issue 9: identify refuses a displacement unrelated to the current: no file, no push."""
    t, current = identification_excitation(8.0, sample_rate=250.0, seed=2)
    displacement = 1.0e-5 * np.random.default_rng(3).standard_normal(t.size)
    bag = tmp_path / 'unrelated'
    write_bag_signals(bag, t, current, displacement)
    params_file = tmp_path / 'params.yaml'
    node = IdentifierNode(context=ros_context, parameter_overrides=[
        Parameter('bag', value=str(bag)), Parameter('order', value=ORDER),
        Parameter('params_file', value=str(params_file)),
        Parameter('service_timeout', value=10.0)])
    try:
        with pytest.raises(IdentificationError, match='monotone'):
            node.run()
    finally:
        node.destroy_node()
    assert compensator.model_version == 0
    assert compensator.counters['rejected_updates'] == 0
    assert not params_file.exists()
    assert 'identification refused the data' in capfd.readouterr().err


def test_pushes_the_operating_point(ros_context, compensator, excitation_bag):
    """Issue 9: a model with a sensor zero, an input bias and a falling sensor: all 8 keys."""
    recording = read_bag_signals(excitation_bag, input_topic='/current_command',
                                 output_topic='/displacement')
    fitted = identify(recording.current, recording.displacement, order=(6, 3)).model
    parameters = fitted.with_operating_point(
        input_offset=0.7, output_offset=-1.2e-4, output_sign=-1).to_params()
    node = IdentifierNode(context=ros_context)
    try:
        identifier.push_model_parameters(node, '/compensator', parameters, timeout=10.0)
    finally:
        node.destroy_node()
    applied = compensator.compensator.model
    assert (applied.input_offset, applied.output_offset, applied.output_sign) == (
        0.7, -1.2e-4, -1)
    assert compensator.get_parameter('model.output_sign').value == -1
    assert applied.to_params() == parameters


# ------------------------------------------------------------------ data parameters


@pytest.fixture(scope='module')
def message_bags(tmp_path_factory):
    """Return the excitation as a JointState bag and a Float64MultiArray bag, and the data."""
    from test.message_bags import write_array_signals, write_joint_state_signals
    t, current = identification_excitation(12.0, sample_rate=250.0, seed=1)
    displacement = MagnetostrictiveActuator().simulate(t, current)
    root = tmp_path_factory.mktemp('message_bags')
    write_joint_state_signals(root / 'joints', t, current, displacement)
    write_array_signals(root / 'arrays', t, current, 1e9 * displacement, storage='mcap')
    return root, current, displacement


JOINT_PARAMETERS = {'input_topic': '/joint_states', 'output_topic': '/joint_states',
                    'input_joint': 'actuator', 'input_field': 'effort',
                    'output_joint': 'actuator'}
ARRAY_PARAMETERS = {'input_topic': '/command', 'output_topic': '/measurement',
                    'input_index': 1, 'output_index': 0, 'output_scale': 1e-9}


@pytest.mark.parametrize('bag, parameters', [('joints', JOINT_PARAMETERS),
                                             ('arrays', ARRAY_PARAMETERS)])
def test_identifies_from_joint_state_and_array_bags(ros_context, message_bags, bag,
                                                    parameters):
    from mpi_ros import identify
    root, current, displacement = message_bags
    node = IdentifierNode(context=ros_context, parameter_overrides=[
        Parameter('bag', value=str(root / bag)), Parameter('order', value='6 3'),
        Parameter('push', value=False),
        *(Parameter(name, value=value) for name, value in parameters.items())])
    try:
        fit = node.run()
    finally:
        node.destroy_node()
    core = identify(current, displacement, n=6, l=3)
    assert fit.result.order == (6, 3)
    assert fit.result.samples == current.size
    assert fit.result.nonlinearity_error == pytest.approx(core.nonlinearity_error, rel=1e-6)


@pytest.mark.parametrize('parameter, value, needle', [
    ('input_field', 'torque', 'input_field'),
    ('output_scale', 0.0, 'output_scale must be a finite non-zero number; found 0.0'),
    ('input_index', -2, 'input_index out of range'),
    ('sample_period', -1e-3, 'sample_period must be a finite number >= 0 [s]'),
])
def test_bad_data_parameters_are_rejected(ros_context, parameter, value, needle):
    node = IdentifierNode(context=ros_context)
    try:
        result = node.set_parameters([Parameter(parameter, value=value)])[0]
    finally:
        node.destroy_node()
    assert not result.successful
    assert needle in result.reason


def test_data_errors_name_the_parameters(monkeypatch, capsys, message_bags):
    root = message_bags[0]
    args = [f'{name}:={value}' for name, value in dict(JOINT_PARAMETERS,
                                                       input_joint='elbow').items()]
    status, err = _main(monkeypatch, capsys, '-p', f'bag:={root / "joints"}',
                        *[a for arg in args for a in ('-p', arg)], '-p', 'push:=false')
    assert status == 1
    last = err.strip().splitlines()[-1]
    assert ("it has no joint 'elbow' (input_joint); joints found: 'wrist', 'actuator'; set "
            'input_joint to one of them') in last
    assert '--input-joint' not in last


# ------------------------------------------------------------------ a lost answer


class _LostAnswerTarget:
    """
    A target whose ``set_parameters_atomically`` never answers (rmw lost the response).

    With ``apply`` it applies the request first (what rmw's "failed to send response
    (timeout)" leaves behind under load), else it drops it.  ``get_parameters`` answers.
    """

    def __init__(self, context, parameters, *, apply):
        from rcl_interfaces.srv import GetParameters, SetParametersAtomically
        from rclpy.callback_groups import ReentrantCallbackGroup
        from rclpy.node import Node
        from rclpy.task import Future
        self.node = Node('lossy', context=context, start_parameter_services=False)
        for name, value in parameters.items():
            self.node.declare_parameter(name, value)
        self.requests = 0
        never = Future()

        async def set_atomically(request, response):
            self.requests += 1
            if apply:
                self.node.set_parameters_atomically(
                    [Parameter.from_parameter_msg(p) for p in request.parameters])
            await never
            return response

        def get(request, response):
            response.values = [self.node.get_parameter(name).get_parameter_value()
                               for name in request.names]
            return response

        # Its own group: the awaiting callback must not hold back get_parameters (rmw's
        # lost response leaves the target's callbacks free).
        self.node.create_service(SetParametersAtomically, '~/set_parameters_atomically',
                                 set_atomically, callback_group=ReentrantCallbackGroup())
        self.node.create_service(GetParameters, '~/get_parameters', get)
        self.executor = SingleThreadedExecutor(context=context)
        self.executor.add_node(self.node)
        self.thread = threading.Thread(target=self.executor.spin, daemon=True)
        self.thread.start()

    def close(self):
        self.executor.shutdown()
        self.thread.join(timeout=5.0)
        self.node.destroy_node()


@pytest.mark.parametrize('apply', [True, False])
def test_a_lost_answer_is_confirmed_by_reading_the_values_back(
        ros_context, excitation_bag, capfd, apply):
    """A push the target applied but whose answer was lost succeeds; one it dropped fails."""
    recording = read_bag_signals(excitation_bag, input_topic='/current_command',
                                 output_topic='/displacement')
    old = identify(recording.current, recording.displacement, order=(6, 3)).model
    new = old.with_operating_point(input_offset=0.3, output_offset=-2e-6).to_params()
    target = _LostAnswerTarget(ros_context, old.to_params(), apply=apply)
    node = IdentifierNode(context=ros_context)
    try:
        if apply:
            identifier.push_model_parameters(node, '/lossy', new, timeout=3.0)
        else:
            with pytest.raises(identifier.ParameterPushError,
                               match='did not answer.*read back with other values'):
                identifier.push_model_parameters(node, '/lossy', new, timeout=3.0)
    finally:
        node.destroy_node()
        target.close()
    assert target.requests == 1
    held = {name: np.asarray(target.node.get_parameter(name).value, dtype=float)
            for name in new}
    assert all(np.array_equal(held[name], new[name]) for name in new) == apply
    if apply:
        assert 'reads back from /lossy with the pushed value' in capfd.readouterr().err
