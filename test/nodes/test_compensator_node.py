# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
The compensator node in-process on a private context: parameters, model swaps, bad input.

Parameter updates go through ``Node.set_parameters_atomically`` / ``set_parameters``,
the functions rclpy's parameter services call; one test also pushes through the real
``set_parameters_atomically`` service.
"""

import math
import threading

from diagnostic_msgs.msg import DiagnosticStatus
from mpi_ros.compensation import Compensator
from mpi_ros.errors import ModelError
from mpi_ros.errors import ParameterRejected
from mpi_ros.nodes.compensator import CompensatorNode
from mpi_ros.nodes.identifier import ParameterPushError, push_model_parameters
from mpi_ros.operators.model import MODEL_KEYS, MPIModel, RECORD_START_STATES
import numpy as np
import pytest
import rclpy
from rclpy.exceptions import InvalidParameterValueException, ParameterNotDeclaredException
from rclpy.executors import SingleThreadedExecutor
from rclpy.parameter import Parameter
from rclpy.qos import ReliabilityPolicy

R_H, W_H, R_S, W_S = MODEL_KEYS
Z_H0 = RECORD_START_STATES

OUTPUT_MIN, OUTPUT_MAX = 0.2, 1.8

#: A valid forward model with asymmetric S (input 0.2-1.8 A -> roughly 0-40 um).
MODEL_A = {
    R_H: [0.0, 0.3, 0.6],
    W_H: [1.0, 0.4, 0.2],
    Z_H0: [0.0, 0.0, 0.0],
    R_S: [-0.5, 0.0, 0.8],
    W_S: [1.0e-5, 2.0e-5, -0.5e-5],
}

#: Another valid model (different orders), used as the update.
MODEL_B = {
    R_H: [0.0, 0.2, 0.5, 0.9],
    W_H: [0.8, 0.3, 0.3, 0.1],
    Z_H0: [0.0, 0.0, 0.0, 0.0],
    R_S: [0.0, 1.0],
    W_S: [2.2e-5, -0.6e-5],
}


#: An operating point: input bias 0.4 A, sensor zero 100 um, a sensor that falls as the
#: actuator extends (y = y0 - S[H[x - x0]]).
OPERATING_POINT = {'model.input_offset': 0.4, 'model.output_offset': 1.0e-4,
                   'model.output_sign': -1}
MODEL_A_OP = dict(MODEL_A, **OPERATING_POINT)


def as_parameters(mapping):
    """Return rclpy Parameters for a {name: value} mapping (types inferred)."""
    return [Parameter(name, value=value) for name, value in mapping.items()]


def limits():
    return [Parameter('output.min', value=OUTPUT_MIN), Parameter('output.max', value=OUTPUT_MAX)]


@pytest.fixture
def make_node(ros_context):
    """Build CompensatorNodes on the private context and destroy them afterwards."""
    nodes = []

    def make(overrides=(), **kwargs):
        node = CompensatorNode(context=ros_context, parameter_overrides=list(overrides),
                               **kwargs)
        nodes.append(node)
        return node

    yield make
    for node in nodes:
        node.destroy_node()


@pytest.fixture
def configured(make_node):
    """Return a compensator started with MODEL_A and the 0.2-1.8 A range."""
    return make_node(limits() + as_parameters(MODEL_A))


def model_parameters(node):
    return {key: list(node.get_parameter(key).value) for key in MODEL_KEYS + (Z_H0,)}


def test_starts_unconfigured_and_publishes_nothing(make_node):
    node = make_node(limits())
    assert node.compensator is None
    assert node.model_version == 0
    assert node.command(1e-5) is None
    assert node.counters['dropped_unconfigured'] == 1
    status = node.diagnostics().status[0]
    assert status.level == DiagnosticStatus.WARN
    assert 'unconfigured' in status.message


def test_model_from_parameter_overrides_is_applied(configured):
    assert configured.model_version == 1
    assert configured.compensator is not None
    current = configured.command(2.0e-5)
    assert OUTPUT_MIN <= current <= OUTPUT_MAX


def test_valid_model_pushed_atomically_is_applied(make_node):
    node = make_node(limits())
    result = node.set_parameters_atomically(as_parameters(MODEL_A))
    assert result.successful, result.reason
    assert node.model_version == 1
    assert model_parameters(node) == MODEL_A
    result = node.set_parameters_atomically(as_parameters(MODEL_B))
    assert result.successful, result.reason
    assert node.model_version == 2
    assert node.compensator.model.to_params()[R_H] == MODEL_B[R_H]


def test_model_swap_keeps_the_command_continuous(configured):
    """Bumpless: after a swap to the same model the next command does not jump."""
    rng = np.random.default_rng(3)
    desired = 2.0e-5 + 1.0e-5 * np.sin(np.linspace(0.0, 6.0, 200)) + rng.normal(0, 1e-7, 200)
    for value in desired:
        before = configured.command(float(value))
    result = configured.set_parameters_atomically(as_parameters(MODEL_A))
    assert result.successful, result.reason
    after = configured.command(float(desired[-1]))
    assert after == pytest.approx(before, abs=1e-9)


def test_operating_point_commands_are_the_shifted_origin_ones(make_node):
    """Issue 9: x = x0 + Gamma0^-1[sign (y - y0)], clamped to the same (shifted) range."""
    node = make_node(limits() + as_parameters(MODEL_A_OP))
    assert node.compensator.model.to_params() == MODEL_A_OP
    desired = 2.0e-5 + 3.0e-5 * np.sin(np.linspace(0.0, 12.0, 400))  # beyond the range
    commands = [node.command(1.0e-4 - float(value)) for value in desired]
    origin = Compensator(MPIModel.from_params(MODEL_A), output_min=OUTPUT_MIN - 0.4,
                         output_max=OUTPUT_MAX - 0.4)
    expected = [0.4 + origin.command(float(value)) for value in desired]
    np.testing.assert_allclose(commands, expected, rtol=0, atol=1e-12)
    assert node.counters['clamped'] > 0
    assert min(commands) == OUTPUT_MIN and max(commands) <= OUTPUT_MAX


def test_operating_point_swaps_are_bumpless(make_node):
    """A swap to the same model, and a new sensor zero with the desired moved by as much."""
    node = make_node(limits() + as_parameters(MODEL_A_OP))
    desired = 1.0e-4 - 2.0e-5 - 1.0e-5 * np.sin(np.linspace(0.0, 6.0, 200))
    for value in desired:
        before = node.command(float(value))
    assert node.set_parameters_atomically(as_parameters(MODEL_A_OP)).successful
    assert node.command(float(desired[-1])) == pytest.approx(before, abs=1e-9)
    results = node.set_parameters([Parameter('model.output_offset', value=1.0e-4 + 3.0e-6)])
    assert results[0].successful, results[0].reason
    assert node.model_version == 3
    assert node.command(float(desired[-1]) + 3.0e-6) == pytest.approx(before, abs=1e-9)


def _mutated(key, value):
    bad = {name: list(values) for name, values in MODEL_A.items()}
    bad[key] = value
    return bad


BAD_MODELS = {
    'weights shorter than thresholds': (W_H, _mutated(W_H, [1.0, 0.4])),
    'initial states longer than thresholds': (Z_H0, _mutated(Z_H0, [0.0] * 4)),
    'superposition weights shorter': (W_S, _mutated(W_S, [1.0e-5, 2.0e-5])),
    'unsorted hysteresis thresholds': (R_H, _mutated(R_H, [0.0, 0.6, 0.3])),
    'duplicate superposition thresholds': (R_S, _mutated(R_S, [-0.5, 0.0, 0.0])),
    'first play threshold not 0': (R_H, _mutated(R_H, [0.1, 0.3, 0.6])),
    'no zero dead-zone threshold': (R_S, _mutated(R_S, [-0.5, 0.1, 0.8])),
    'negative hysteresis weight': (W_H, _mutated(W_H, [1.0, -0.4, 0.2])),
    'zero first hysteresis weight': (W_H, _mutated(W_H, [0.0, 0.4, 0.2])),
    'decreasing static map (19)': (W_S, _mutated(W_S, [1.0e-5, 2.0e-5, -3.0e-5])),
    'NaN weight': (W_H, _mutated(W_H, [1.0, math.nan, 0.2])),
    'infinite threshold': (R_S, _mutated(R_S, [-0.5, 0.0, math.inf])),
    'integer array': (R_H, _mutated(R_H, [0, 1, 2])),
    'string instead of array': (W_S, _mutated(W_S, 'oops')),
    'scalar instead of array': (Z_H0, _mutated(Z_H0, 0.0)),
    'empty array': (W_H, _mutated(W_H, [])),
}


@pytest.mark.parametrize('case', sorted(BAD_MODELS))
def test_bad_model_is_rejected_and_old_model_kept(configured, case):
    key, bad = BAD_MODELS[case]
    old_model = configured.compensator.model
    before = configured.command(2.0e-5)
    result = configured.set_parameters_atomically(as_parameters(bad))
    assert not result.successful
    assert key in result.reason
    assert configured.compensator.model is old_model
    assert configured.model_version == 1
    assert model_parameters(configured) == MODEL_A
    assert configured.counters['rejected_updates'] == 1
    assert configured.command(2.0e-5) == pytest.approx(before, abs=1e-9)


def test_partial_update_applies_when_the_whole_model_is_valid(configured):
    """Issue 11: a request is laid over the running model; a valid whole model applies."""
    partial = {key: MODEL_B[key] for key in (R_H, W_H, Z_H0)}
    result = configured.set_parameters_atomically(as_parameters(partial))
    assert result.successful, result.reason
    assert configured.model_version == 2
    params = configured.compensator.model.to_params()
    assert params[R_H] == MODEL_B[R_H] and params[R_S] == MODEL_A[R_S]


def test_partial_update_giving_an_invalid_model_is_rejected(configured):
    old_model = configured.compensator.model
    partial = {key: MODEL_B[key] for key in (R_H, W_H)}
    result = configured.set_parameters_atomically(as_parameters(partial))
    assert not result.successful
    assert Z_H0 in result.reason and 'running model (version 1) stays' in result.reason
    assert configured.compensator.model is old_model
    assert model_parameters(configured) == MODEL_A


def test_non_atomic_set_parameters_applies_the_model_keys_together(configured):
    """Issue 11: set_parameters (ros2 param load) sets a request's model keys in one step."""
    results = configured.set_parameters(as_parameters(MODEL_B) + limits())
    assert all(r.successful for r in results), [r.reason for r in results]
    assert configured.model_version == 2  # one swap, never a mixed model
    assert model_parameters(configured) == MODEL_B
    bad = dict(MODEL_A, **{W_S: [1.0e-5, 2.0e-5, -3.0e-5]})
    old_model = configured.compensator.model
    results = configured.set_parameters(as_parameters(bad))
    assert [r.successful for r in results] == [False] * len(bad)
    for result in results:
        assert W_S in result.reason and '(19)' in result.reason
    assert configured.compensator.model is old_model
    assert model_parameters(configured) == MODEL_B


def test_unknown_model_key_is_not_accepted(configured):
    """Undeclared keys are refused by rclpy before the validator (message omits the name)."""
    old_model = configured.compensator.model
    with pytest.raises(ParameterNotDeclaredException, match='undeclared'):
        configured.set_parameters_atomically(
            as_parameters(dict(MODEL_B, **{'model.hysteresis.extra': [1.0]})))
    assert configured.compensator.model is old_model
    assert model_parameters(configured) == MODEL_A


def test_fuzzed_malformed_updates_never_get_through(configured):
    """1,000 seeded random malformations: each rejected, naming a model key, model kept."""
    rng = np.random.default_rng(20260521)
    old_model = configured.compensator.model
    for trial in range(1000):
        bad, key = _random_malformation(rng)
        result = configured.set_parameters_atomically(as_parameters(bad))
        assert not result.successful, (trial, bad)
        assert key in result.reason, (trial, key, result.reason)
        assert configured.compensator.model is old_model
    assert model_parameters(configured) == MODEL_A
    assert configured.model_version == 1


def test_output_limits(configured):
    result = configured.set_parameters([Parameter('output.min', value=1.9)])[0]
    assert not result.successful and 'output.min' in result.reason
    result = configured.set_parameters([Parameter('output.max', value=math.nan)])[0]
    assert not result.successful and 'output.max' in result.reason
    result = configured.set_parameters([Parameter('output.max', value=2)])[0]
    assert not result.successful and 'output.max' in result.reason
    result = configured.set_parameters_atomically(
        [Parameter('output.min', value=0.5), Parameter('output.max', value=1.0)])
    assert result.successful, result.reason
    for desired in (-1.0, 0.0, 1.0e-5, 4.0e-5, 1.0):
        assert 0.5 <= configured.command(desired) <= 1.0


@pytest.mark.parametrize('desired', [math.nan, math.inf, -math.inf, 1e300, -1e300, 1.0, -1.0])
def test_extreme_input_gives_finite_in_range_command(configured, desired):
    for _ in range(3):
        current = configured.command(desired)
        assert math.isfinite(current)
        assert OUTPUT_MIN <= current <= OUTPUT_MAX
    assert configured.counters['messages_in'] == 3


def test_random_input_stream_stays_safe_and_is_counted(configured):
    rng = np.random.default_rng(7)
    specials = np.array([math.nan, math.inf, -math.inf, 1e308, -1e308])
    stream = rng.normal(2e-5, 3e-5, 5000)
    mask = rng.random(5000) < 0.05
    stream[mask] = rng.choice(specials, int(mask.sum()))
    outputs = np.array([configured.command(float(value)) for value in stream])
    assert np.all(np.isfinite(outputs))
    assert np.all((outputs >= OUTPUT_MIN) & (outputs <= OUTPUT_MAX))
    counters = configured.counters
    assert counters['nonfinite_input'] == int(np.sum(~np.isfinite(stream)))
    assert counters['out_of_range'] > 0
    assert counters['clamped'] > 0
    status = configured.diagnostics().status[0]
    assert status.level == DiagnosticStatus.WARN
    values = {kv.key: kv.value for kv in status.values}
    assert values['nonfinite_input'] == str(counters['nonfinite_input'])
    assert values['model_version'] == '1'
    # Valid input resumes: back to OK, commands inside the range.
    configured.command(2.0e-5)
    assert configured.diagnostics().status[0].level == DiagnosticStatus.OK


def test_disabled_uses_the_best_linear_map(configured):
    result = configured.set_parameters([Parameter('enabled', value=False)])[0]
    assert result.successful, result.reason
    linear = configured.compensator.linear_map
    current = configured.command(2.0e-5)
    assert current == pytest.approx(min(max(linear(2.0e-5), OUTPUT_MIN), OUTPUT_MAX))
    status = configured.diagnostics().status[0]
    assert 'linear' in status.message


@pytest.mark.parametrize('override, key', [
    (dict(MODEL_A, **{W_H: [1.0, -0.4, 0.2]}), W_H),
    (dict(MODEL_A, **{R_H: [0, 1, 2]}), R_H),
    ({R_H: MODEL_A[R_H], W_H: MODEL_A[W_H]}, R_S),
])
def test_bad_params_file_refuses_to_start(make_node, override, key):
    with pytest.raises((InvalidParameterValueException, ModelError, ParameterRejected),
                       match=key):
        make_node(limits() + as_parameters(override))


def test_unordered_limits_in_params_file_refuse_to_start(make_node):
    with pytest.raises(ParameterRejected, match='output.min must be below output.max'):
        make_node([Parameter('output.min', value=1.0), Parameter('output.max', value=0.5)])


@pytest.mark.parametrize('reliability, policy', [
    ('reliable', ReliabilityPolicy.RELIABLE), ('best_effort', ReliabilityPolicy.BEST_EFFORT)])
def test_qos_reliability_sets_both_loop_endpoints(make_node, reliability, policy):
    node = make_node([Parameter('qos_reliability', value=reliability)])
    publishers = node.get_publishers_info_by_topic('current_command')
    subscriptions = node.get_subscriptions_info_by_topic('desired_displacement')
    assert [info.qos_profile.reliability for info in publishers + subscriptions] == [policy] * 2


def test_unknown_qos_reliability_refuses_to_start(make_node):
    with pytest.raises((InvalidParameterValueException, ParameterRejected),
                       match='qos_reliability'):
        make_node([Parameter('qos_reliability', value='sometimes')])


def test_push_through_the_parameter_service(ros_context, configured):
    """The identifier's push: accepted, rejected with the reason, or missing target."""
    client = rclpy.create_node('push_client', context=ros_context)
    executor = SingleThreadedExecutor(context=ros_context)
    executor.add_node(configured)
    spinner = threading.Thread(target=executor.spin, daemon=True)
    spinner.start()
    try:
        push_model_parameters(client, '/compensator', MODEL_B, timeout=10.0)
        assert configured.model_version == 2
        bad = dict(MODEL_A, **{W_H: [1.0, -0.4, 0.2]})
        with pytest.raises(ParameterPushError, match=W_H):
            push_model_parameters(client, '/compensator', bad, timeout=10.0)
        assert configured.model_version == 2
        with pytest.raises(ParameterPushError, match='no parameter service'):
            push_model_parameters(client, '/nobody_here', MODEL_B, timeout=0.5)
    finally:
        executor.shutdown()
        spinner.join(timeout=5.0)
        client.destroy_node()


def _random_malformation(rng):
    """Return (malformed model mapping, the key its reason must name)."""
    bad = {name: list(values) for name, values in MODEL_B.items()}
    kind = rng.integers(0, 10)
    key = MODEL_KEYS[rng.integers(0, len(MODEL_KEYS))]
    values = bad[key]
    if kind == 0:                                   # one array of the wrong length
        key = (W_H, Z_H0, W_S)[rng.integers(0, 3)]
        values = bad[key]
        if rng.random() < 0.5:
            del values[rng.integers(0, len(values))]
        else:
            values.insert(int(rng.integers(0, len(values) + 1)), float(rng.normal()))
    elif kind == 1:                                 # non-finite value
        values[rng.integers(0, len(values))] = float(rng.choice([math.nan, math.inf, -math.inf]))
    elif kind == 2:                                 # wrong type
        # (Not str(values): '[2.2e-05, -6e-06]' is how `ros2 param load` sends that very
        # list, since PyYAML reads 6e-06 as a string; the node accepts it, issue 11.)
        bad[key] = [int(v) for v in rng.integers(-3, 4, len(values))] if rng.random() < 0.5 \
            else 'values ' + str(values)
    elif kind == 3:                                 # empty
        bad[key] = []
    elif kind == 4:                                 # unsorted or duplicate thresholds
        key = R_H
        i = int(rng.integers(1, len(bad[R_H]) - 1))
        bad[R_H][i + 1] = bad[R_H][i] if rng.random() < 0.5 else bad[R_H][i] - 0.05
    elif kind == 5:                                 # first play threshold not 0
        key = R_H
        bad[R_H][0] = float(rng.uniform(0.001, 0.19))
    elif kind == 6:                                 # dead-zone thresholds without one 0
        key = R_S
        bad[R_S] = [float(rng.uniform(0.01, 0.5)), 1.0]
    elif kind == 7:                                 # weights violating (8)
        key = W_H
        i = int(rng.integers(0, len(bad[W_H])))
        bad[W_H][i] = -float(rng.uniform(0.001, 2.0)) if i else 0.0
    elif kind == 8:                                 # weights violating (19)
        key = W_S
        bad[W_S][-1] = -float(rng.uniform(2.3e-5, 1e-3))
    else:                                           # a model key missing (partial update)
        missing = MODEL_KEYS[rng.integers(0, len(MODEL_KEYS))]
        del bad[missing]
        key = missing
    return bad, key


def test_config_and_identify_yaml_load_through_params_files(monkeypatch, tmp_path):
    """`--params-file config/compensator.yaml --params-file params.yaml` configures the node."""
    from pathlib import Path

    from mpi_ros.params import write_params_yaml

    from .ros_env import run_domain_id
    monkeypatch.setenv('ROS_AUTOMATIC_DISCOVERY_RANGE', 'LOCALHOST')
    monkeypatch.setenv('ROS_DOMAIN_ID', str(run_domain_id()))
    config = Path(__file__).resolve().parents[2] / 'config' / 'compensator.yaml'
    model_yaml = tmp_path / 'params.yaml'
    write_params_yaml(model_yaml, MODEL_A)
    context = rclpy.Context()
    rclpy.init(context=context, args=['compensator', '--ros-args', '--params-file', str(config),
                                      '--params-file', str(model_yaml)])
    node = None
    try:
        node = CompensatorNode(context=context)
        assert node.get_parameter('output.min').value == OUTPUT_MIN
        assert node.get_parameter('output.max').value == OUTPUT_MAX
        assert node.model_version == 1
        assert model_parameters(node) == MODEL_A
    finally:
        if node is not None:
            node.destroy_node()
        rclpy.try_shutdown(context=context)
