# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
The compensator driven by the requests the ``ros2 param`` command line sends (issue 11).

- ``ros2 param load NODE FILE``: ``AsyncParameterClient.load_parameter_file``, i.e. every
  key of the file in ONE non-atomic ``set_parameters`` request (values re-parsed from
  their ``str()``);
- ``ros2 param set NODE KEY VALUE``: ``set_parameters`` with one key whose value is
  ``rclpy.parameter.get_parameter_value(VALUE)``;
- ``ros2 param dump NODE``: ``list_parameters``, ``get_parameters`` of every name, and the
  values nested and written with ``yaml.dump(default_flow_style=False)``; the file must
  start a node with ``--params-file``.

The compensator is spun in a background executor and reached through its real services.
"""

import threading
import time

from mpi_ros.compensation import Compensator
from mpi_ros.nodes.compensator import CompensatorNode
from mpi_ros.operators.model import MODEL_KEYS, MPIModel, OPERATING_POINT_KEYS, \
    RECORD_START_STATES
from mpi_ros.params import write_params_yaml
import numpy as np
import pytest
from rcl_interfaces.msg import Parameter as ParameterMsg
import rclpy
from rclpy.executors import SingleThreadedExecutor
from rclpy.parameter import get_parameter_value, parameter_value_to_python
from rclpy.parameter_client import AsyncParameterClient
import yaml

from .test_compensator_extensions import CREEP, typed
from .test_compensator_node import (
    as_parameters, limits, MODEL_A, MODEL_B, model_parameters, OUTPUT_MAX, OUTPUT_MIN,
)

R_H, W_H, R_S, W_S = MODEL_KEYS
Z_H0 = RECORD_START_STATES
X0, Y0, SIGN = OPERATING_POINT_KEYS

#: MODEL_B at an operating point: input bias, sensor zero and a falling sensor.
MODEL_B_OP = dict(MODEL_B, **{X0: 0.3, Y0: 5.0e-5, SIGN: -1})

#: Desired displacements [m] for MODEL_B_OP (y0 - S[H[...]] reaches about 5e-5 - 4e-5).
DESIRED_B = 5.0e-5 - 2.0e-5 - 1.2e-5 * np.sin(np.linspace(0.0, 12.0, 300))
DESIRED_A = 2.0e-5 + 1.2e-5 * np.sin(np.linspace(0.0, 9.0, 200))

#: Longest wait for one service answer [s] (a bound, not a timing assertion).
TIMEOUT = 30.0


class Cli:
    """The ``ros2 param`` requests, sent from a client node to ``/compensator``."""

    def __init__(self, context):
        self.node = rclpy.create_node('ros2param_cli', context=context)
        self.client = AsyncParameterClient(self.node, 'compensator')
        self.executor = SingleThreadedExecutor(context=context)
        self.executor.add_node(self.node)

    def add(self, node):
        self.executor.add_node(node)

    def __enter__(self):
        self.thread = threading.Thread(target=self.executor.spin, daemon=True)
        self.thread.start()
        assert self.client.wait_for_services(timeout_sec=TIMEOUT)
        return self

    def __exit__(self, *exc_info):
        self.executor.shutdown()
        self.thread.join(timeout=5.0)

    def wait(self, future):
        deadline = time.monotonic() + TIMEOUT
        while not future.done() and time.monotonic() < deadline:
            time.sleep(0.01)
        assert future.done(), 'no answer from the compensator'
        return future.result()

    def load(self, path):
        """``ros2 param load /compensator PATH``: {name: SetParametersResult}."""
        from rclpy.parameter import parameter_dict_from_yaml_file
        names = list(parameter_dict_from_yaml_file(str(path)))
        response = self.wait(self.client.load_parameter_file(str(path)))
        assert len(response.results) == len(names)
        return dict(zip(names, response.results))

    def set_one(self, name, text):
        """``ros2 param set /compensator NAME TEXT``: the SetParametersResult."""
        message = ParameterMsg(name=name, value=get_parameter_value(string_value=text))
        response = self.wait(self.client.set_parameters([message]))
        assert len(response.results) == 1
        return response.results[0]

    def dump(self, path):
        """``ros2 param dump /compensator > PATH``."""
        names = sorted(self.wait(self.client.list_parameters()).result.names)
        values = self.wait(self.client.get_parameters(names)).values
        tree = {}
        for name, value in zip(names, values):
            node = tree
            *parents, leaf = name.split('.')
            for part in parents:
                node = node.setdefault(part, {})
            node[leaf] = parameter_value_to_python(value)
        path.write_text(yaml.dump({'/compensator': {'ros__parameters': tree}},
                                  default_flow_style=False))


@pytest.fixture
def spun(ros_context):
    """Start compensators (given overrides) spun together with the CLI's client node."""
    started = []

    def start(overrides):
        node = CompensatorNode(context=ros_context, parameter_overrides=list(overrides))
        started.append(node)
        cli = Cli(ros_context)
        cli.add(node)
        started.append(cli)
        return node, cli

    yield start
    for item in reversed(started):
        (item.node if isinstance(item, Cli) else item).destroy_node()


def core_commands(compensator, desired):
    return [compensator.command(float(value)) for value in desired]


def test_load_of_a_valid_model_file_answers_with_that_model(spun, tmp_path):
    """Acceptance: the running compensator's commands are the core's with the loaded model."""
    node, cli = spun(limits() + as_parameters(MODEL_A))
    core = Compensator(MPIModel.from_params(MODEL_A), output_min=OUTPUT_MIN,
                       output_max=OUTPUT_MAX)
    assert core_commands(node, DESIRED_A) == core_commands(core, DESIRED_A)
    model_file = tmp_path / 'model.yaml'
    write_params_yaml(model_file, MODEL_B_OP)
    with cli:
        results = cli.load(model_file)
    assert set(results) == set(MODEL_B_OP)
    assert all(result.successful for result in results.values()), results
    assert node.model_version == 2  # the eight keys applied in one swap
    core.install(MPIModel.from_params(MODEL_B_OP))
    commands = core_commands(node, DESIRED_B)
    assert commands == core_commands(core, DESIRED_B)
    assert OUTPUT_MIN < min(commands) < max(commands) < OUTPUT_MAX  # not clamped
    assert model_parameters(node) == MODEL_B
    assert [node.get_parameter(key).value for key in OPERATING_POINT_KEYS] == [0.3, 5.0e-5, -1]


BROKEN = {
    '(19) violated': (W_S, dict(MODEL_B_OP, **{W_S: [2.2e-5, -3.0e-5]})),
    'lengths differ': (Z_H0, dict(MODEL_B_OP, **{Z_H0: [0.0, 0.0]})),
    'sign 0': (SIGN, dict(MODEL_B_OP, **{SIGN: 0})),
    'integer thresholds': (R_H, dict(MODEL_B_OP, **{R_H: [0, 1, 2, 3]})),
}


@pytest.mark.parametrize('case', sorted(BROKEN))
def test_load_of_a_broken_file_leaves_the_running_model(spun, tmp_path, case):
    """Acceptance: nothing applied, every model key's reply names the bad key."""
    key, broken = BROKEN[case]
    node, cli = spun(limits() + as_parameters(MODEL_A))
    old_model = node.compensator.model
    model_file = tmp_path / 'broken.yaml'
    write_params_yaml(model_file, broken)
    with cli:
        results = cli.load(model_file)
    assert [result.successful for result in results.values()] == [False] * len(broken)
    for result in results.values():
        assert key in result.reason and 'running model (version 1) stays' in result.reason
        assert 'np.' not in result.reason
    assert node.compensator.model is old_model
    assert model_parameters(node) == MODEL_A
    assert [node.get_parameter(k).value for k in OPERATING_POINT_KEYS] == [0.0, 0.0, 1]
    status = {kv.key: kv.value for kv in node.diagnostics().status[0].values}
    assert key in status['last_rejected_update']


def test_set_of_one_key_applies_when_the_model_stays_valid(spun):
    node, cli = spun(limits() + as_parameters(MODEL_A))
    with cli:
        result = cli.set_one(Y0, '1e-05')  # Python's str() of a float without a dot
        assert result.successful, result.reason
        assert node.model_version == 2
        assert node.compensator.model.output_offset == 1e-05
        result = cli.set_one(SIGN, '-1')
        assert result.successful, result.reason
        assert node.compensator.model.output_sign == -1
        result = cli.set_one(W_H, '[1.0, 0.5, 0.1]')
        assert result.successful, result.reason
        assert node.compensator.model.to_params()[W_H] == [1.0, 0.5, 0.1]
        assert node.model_version == 4
        model = node.compensator.model
        for key, text in ((W_H, '[1.0, 0.5]'), (R_H, '[0.0, 0.3, 0.6, 0.9]'),
                          (SIGN, '2'), (X0, 'nan'), (W_S, '[1.0e-5, 2.0e-5, -4.0e-5]')):
            result = cli.set_one(key, text)
            assert not result.successful, (key, text)
            assert key in result.reason, result.reason
            assert node.compensator.model is model
    assert node.model_version == 4


def test_set_of_a_key_of_an_unconfigured_node_says_what_is_missing(spun):
    node, cli = spun(limits())
    with cli:
        result = cli.set_one(R_H, '[0.0, 0.3]')
    assert not result.successful
    assert R_H in result.reason and W_S in result.reason and 'no model yet' in result.reason
    assert node.compensator is None


@pytest.mark.parametrize('configured', [True, False], ids=['configured', 'unconfigured'])
def test_dump_starts_a_node_and_loads_back(spun, tmp_path, configured):
    """``ros2 param dump`` output starts a node (--params-file) and loads back."""
    overrides = limits() + (as_parameters(MODEL_B_OP) if configured else [])
    node, cli = spun(overrides)
    dump = tmp_path / 'dump.yaml'
    with cli:
        if configured:
            # An extension switched on, then off: its keys hold [] and 0.0; the dead-time
            # key was never set: null.
            assert node.set_parameters_atomically(typed(CREEP)).successful
            assert node.set_parameters_atomically(as_parameters(MODEL_B_OP)).successful
        version = node.model_version
        cli.dump(dump)
        text = dump.read_text()
        assert 'null' in text
        if configured:
            assert '[]' in text
        results = cli.load(dump)
    model_results = {name: result for name, result in results.items()
                     if name.startswith('model.')}
    assert all(result.successful for result in model_results.values()), model_results
    assert results['use_sim_time'].successful, results['use_sim_time'].reason
    # Configured: the same model swapped in again (bumpless); unconfigured: nothing to do.
    assert node.model_version == version + (1 if configured else 0)
    expected = model_parameters(node) if configured else None

    context = rclpy.Context()
    rclpy.init(context=context, args=['compensator', '--ros-args', '--params-file', str(dump)])
    restarted = None
    try:
        restarted = CompensatorNode(context=context)
        if configured:
            assert restarted.model_version == 1
            assert model_parameters(restarted) == expected
            assert restarted.compensator.model.to_params() == node.compensator.model.to_params()
        else:
            assert restarted.compensator is None
        assert restarted.get_parameter('output.max').value == OUTPUT_MAX
    finally:
        if restarted is not None:
            restarted.destroy_node()
        rclpy.try_shutdown(context=context)


def test_null_at_start_means_unset(ros_context, tmp_path):
    """A hand-written file with null for the model keys starts an unconfigured node."""
    params = tmp_path / 'nulls.yaml'
    params.write_text('compensator:\n  ros__parameters:\n'
                      '    output: {min: 0.2, max: 1.8}\n'
                      '    model:\n      hysteresis: {thresholds: null, weights: ~}\n'
                      '      creep: {time_constants: null}\n      output_sign: null\n')
    context = rclpy.Context()
    rclpy.init(context=context, args=['compensator', '--ros-args', '--params-file', str(params)])
    node = None
    try:
        node = CompensatorNode(context=context)
        assert node.compensator is None
        assert node.get_parameter(SIGN).value == 1
    finally:
        if node is not None:
            node.destroy_node()
        rclpy.try_shutdown(context=context)
