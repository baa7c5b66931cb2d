# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""The nodes' logic that needs no ROS: specs, value checks, diagnostics, plant, identifier."""

from dataclasses import replace
import subprocess
import sys

from mpi_ros.compensation.multi_axis import JointOrder
from mpi_ros.compensation.status import (
    lifecycle_status, loss_problems, multi_axis_status, multi_axis_values, OK,
    single_axis_status, single_axis_values, status_values, WARN,
)
from mpi_ros.errors import DataError, MPIError, ParameterRejected
from mpi_ros.node_parameters import check_value, check_values, is_null, normalized, \
    specs_by_name
from mpi_ros.node_parameters.compensator import (
    axis_limit_parameters, axis_parameters, compensator_parameters, MODEL_PARAMETERS,
)
from mpi_ros.node_parameters.identifier import check_identifier_value
from mpi_ros.node_parameters.identifier import PARAMETERS as IDENTIFIER_PARAMETERS
from mpi_ros.node_parameters.plant_simulator import PARAMETERS as PLANT_PARAMETERS
from mpi_ros.operators.model import INPUT_OFFSET, MODEL_KEYS, OUTPUT_SIGN
from mpi_ros.pipeline import identify_bag as identify
from mpi_ros.plant.simulator import build_truth, describe_truth, excitation_schedule
import numpy as np
import pytest

SPECS = specs_by_name(compensator_parameters())
W_S = 'model.superposition.weights'
LOSSLESS = {'messages_lost': 0, 'incompatible_qos': 0}


def test_the_moved_modules_import_no_ros():
    code = ('import sys, mpi_ros.node_parameters.compensator, mpi_ros.compensation.status, '
            'mpi_ros.plant.simulator, mpi_ros.pipeline, mpi_ros.array_layout, '
            'mpi_ros.node_parameters.identifier, mpi_ros.node_parameters.plant_simulator; '
            "sys.exit(any(m.split('.')[0] in ('rclpy', 'rcl_interfaces', 'std_msgs', "
            "'diagnostic_msgs') for m in sys.modules))")
    assert subprocess.run([sys.executable, '-c', code], check=False).returncode == 0


def test_a_spec_checks_the_form_of_its_value_naming_the_key():
    # start_state's form is its spec's check (StartState.parse), not a name test in check_value.
    check_value(SPECS['start_state'], 'string', 'rest_high')
    check_value(SPECS['start_state'], 'string', '0.1, 0.2')
    with pytest.raises(ParameterRejected, match=r'start_state must be one of rest_low, rest_high, '
                                                r".*found 'sideways'"):
        check_value(SPECS['start_state'], 'string', 'sideways')
    # The check is no part of a spec's identity; a renamed spec keeps it.
    assert replace(SPECS['start_state'], check=None) == SPECS['start_state']
    renamed = replace(SPECS['start_state'], name='axis0.start_state')
    with pytest.raises(ParameterRejected, match=r'^axis0.start_state must be one of'):
        check_value(renamed, 'string', 'sideways')


def test_values_are_checked_as_plain_python_naming_the_key():
    check_value(SPECS[W_S], 'double_array', [1e-5, 0.0])
    with pytest.raises(ParameterRejected, match=r'model.superposition.weights must be an '
                                                r'array of doubles \(write \[0.0, 1.0\]'):
        check_value(SPECS[W_S], 'integer_array', [0, 1])
    with pytest.raises(ParameterRejected, match=r'weights\[1\] must be finite'):
        check_value(SPECS[W_S], 'double_array', [0.0, float('nan')])
    with pytest.raises(ParameterRejected, match='cannot be unset'):
        check_value(SPECS[W_S], 'string', 'null')
    check_value(SPECS[W_S], 'string', 'null', allow_unset=True)
    with pytest.raises(ParameterRejected, match=r'must lie in \[1, 1024\]'):
        check_value(SPECS['axes'], 'integer', 0)
    with pytest.raises(ParameterRejected, match='one of arrival, nominal'):
        check_value(SPECS['message_time'], 'string', 'later')
    with pytest.raises(ParameterRejected, match="use_sim_time is rclpy's own"):
        check_values(SPECS, [('use_sim_time', 'bool', True)])
    with pytest.raises(ParameterRejected, match='nope is not a parameter of this node'):
        check_values(SPECS, [('nope', 'bool', True)])


def test_null_and_the_forms_ros2_param_load_loses():
    assert is_null(SPECS[W_S], 'not_set', None)
    assert is_null(SPECS[W_S], 'string', '~')
    assert not is_null(SPECS['message_time'], 'string', 'null')
    assert normalized(SPECS[W_S], 'string_array', ['1e-05', '2e-05']) == (
        'double_array', [1e-05, 2e-05])
    assert normalized(SPECS[W_S], 'string', '[2.2e-05, -6e-06]') == (
        'double_array', [2.2e-05, -6e-06])
    assert normalized(SPECS[W_S], 'bool_array', []) == ('double_array', [])
    assert normalized(SPECS[INPUT_OFFSET], 'string', '1e-05') == ('double', 1e-05)
    assert normalized(SPECS[W_S], 'string', '[0.0, 1.0]') == ('string', '[0.0, 1.0]')


def test_specs_are_plain_data_with_their_ros_texts():
    sign = SPECS[OUTPUT_SIGN]
    assert sign.type_ == 'integer' and '1 or -1' in sign.all_constraints()
    assert SPECS[INPUT_OFFSET].described().endswith('[A] (type: double)')
    assert SPECS['message_time'].all_constraints().startswith('one of: arrival, nominal.')
    assert [spec.name for spec in MODEL_PARAMETERS][:4] == list(MODEL_KEYS)
    per_axis = specs_by_name(axis_parameters(2) + axis_limit_parameters(2))
    assert 'axis1.model.hysteresis.weights' in per_axis
    assert per_axis['axis0.output.min'].default is None
    assert per_axis['axis1.model.hysteresis.weights'].description.startswith('Axis 1: ')


def test_losses_and_faults_make_a_period_warn():
    assert loss_problems(LOSSLESS, {}, 100, 10, 'desired displacements') == []
    lost = loss_problems(dict(LOSSLESS, messages_lost=3), {'messages_lost': 1}, 100, 0, 'x')
    assert len(lost) == 1 and lost[0].startswith('2 x lost in the last period (3 in all)')
    assert 'more than half full' in loss_problems(LOSSLESS, {}, 100, 51, 'x')[0]
    counters = {'clamped': 0, 'nonfinite_input': 0, 'out_of_range': 0}
    assert single_axis_status([], counters, {}, has_model=True, enabled=True) == (
        OK, 'compensating')
    assert single_axis_status([], counters, {}, has_model=True, enabled=False)[0] == OK
    assert single_axis_status([], counters, {}, has_model=False, enabled=True)[0] == WARN
    level, message = single_axis_status([], dict(counters, clamped=2), {}, has_model=True,
                                        enabled=True)
    assert level == WARN and 'in the last period' in message
    level, message = multi_axis_status(
        [], dict(counters, malformed=1), {}, what='arrays', last_malformed='short',
        last_missing='', missing_axes=[1])
    assert level == WARN and '1 malformed arrays' in message and 'axis 1' in message
    assert lifecycle_status(None, 'active') == (OK, 'no model loaded')
    assert lifecycle_status((WARN, 'bad'), 'inactive') == (
        WARN, 'lifecycle state inactive: no commands published; bad')
    values = status_values({'a': 1}, {'enabled': 'own'}, lifecycle_state='active', enabled=True)
    assert list(values) == ['a', 'lifecycle_state', 'enabled'] and values['enabled'] == 'own'


def test_the_plant_is_built_from_its_parameter_values():
    values = {spec.name: spec.default for spec in PLANT_PARAMETERS}
    assert describe_truth(values).startswith('the built-in magnetostrictive actuator')
    assert np.isfinite(build_truth(values).step(1.0e-3, 0.5))
    with pytest.raises(ParameterRejected, match='truth:=mpi needs the model parameters'):
        build_truth(dict(values, truth='mpi'))
    t, current = excitation_schedule(values)
    assert len(t) == len(current)                    # the defaults: 20 s at 1 kHz
    assert t[0] == 0.0 and t[-1] == pytest.approx(20.0)
    np.testing.assert_allclose(np.diff(t), 1e-3)
    assert current[0] == 0.0 and current.max() <= 1.0 + 0.8 + 1e-12   # from 0 A, <= bias + amp.


def test_the_identifier_checks_its_values_and_needs_a_bag():
    check_identifier_value('order', '3,2')
    with pytest.raises(MPIError):
        check_identifier_value('order', 'three')
    values = {spec.name: spec.default for spec in IDENTIFIER_PARAMETERS}
    with pytest.raises(DataError, match='no bag given'):
        identify(values, info=print, error=print)


def test_joint_states_are_put_in_axis_order_or_refused_with_a_reason():
    order = JointOrder(['a', 'b'])
    block, fault, reason = order.block(['b', 'x', 'a'], [2.0, 9.0, 1.0])
    assert fault == reason == '' and block.tolist() == [[1.0, 2.0]]
    block, fault, reason = order.block(['b'], [2.0])
    assert block is None and fault == 'missing_joints' and reason.startswith('JointState '
                                                                             'without a')
    assert order.block(['a', 'b', 'a'], [1.0, 2.0, 3.0])[1:] == (
        'malformed', 'JointState names a joint more than once')
    assert order.block(['a', 'b'], [1.0])[1] == 'malformed'


def test_the_nodes_own_diagnostics_values():
    assert single_axis_values('creep', [1e-7, 2.0]) == {'extension': 'creep',
                                                        'slow_state': '1e-07 2'}
    values = multi_axis_values([None, None], model_versions=[0, 0], joints=['j0', 'j1'],
                               flat=True, limits=([0.0, 0.0], [2.0, 1.5]),
                               slow_states=[None, [0.5]])
    assert values == {'axes': 2, 'model_versions': '0 0', 'joints': 'j0 j1',
                      'output_layout': 'flat', 'output_min': 0.0, 'output_max': '2.0 1.5',
                      'extension': '- -', 'axis1.slow_state': '0.5'}
