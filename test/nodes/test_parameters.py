# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""The shared parameter helpers: the forms `ros2 param load/set` and a dump send (issue 11)."""

from mpi_ros.errors import ModelError, ParameterRejected
from mpi_ros.node_parameters import specs_by_name
from mpi_ros.nodes.compensator import PARAMETERS
from mpi_ros.nodes.parameters import answer_request, check_parameter, descriptor, is_null, \
    normalized
from mpi_ros.operators.model import INPUT_OFFSET, OPERATING_POINT_DEFAULTS, OUTPUT_SIGN
import pytest
from rcl_interfaces.msg import Parameter as ParameterMsg
from rclpy.parameter import get_parameter_value, Parameter

SPECS = specs_by_name(PARAMETERS)
Type = Parameter.Type
W_S = 'model.superposition.weights'
CREEP = 'model.creep.time_constants'


def from_text(name, text):
    """Return the parameter `ros2 param set NODE name text` sends (and load, per value)."""
    return Parameter.from_parameter_msg(
        ParameterMsg(name=name, value=get_parameter_value(string_value=text)))


@pytest.mark.parametrize('name, text, expected', [
    (W_S, str([1e-05, 2e-05]), [1e-05, 2e-05]),          # all dot-less: a string array
    (W_S, str([2.2e-05, -6e-06]), [2.2e-05, -6e-06]),    # mixed: one string
    (W_S, str([1.5e-05, 0.5]), [1.5e-05, 0.5]),          # plain doubles
    (CREEP, str([]), []),                                # [] arrives as a bool array
    (INPUT_OFFSET, str(1e-05), 1e-05),                   # a dot-less scalar: a string
    (INPUT_OFFSET, '0.25', 0.25),
])
def test_normalized_restores_what_the_cli_text_loses(name, text, expected):
    parameter = normalized(SPECS[name], from_text(name, text))
    assert parameter.type_.name.lower() == SPECS[name].type_
    value = list(parameter.value) if isinstance(expected, list) else parameter.value
    assert value == expected
    check_parameter(SPECS[name], parameter)


@pytest.mark.parametrize('name, text, found', [
    (W_S, '[0, 1]', 'integer_array'),                    # integers stay refused
    (W_S, '[0.0, 1.0e-5, x]', 'string'),
    (W_S, "'[0.0, 0.5]'", 'string'),                     # a quoted list is a string
    (INPUT_OFFSET, '2', 'integer'),
    (INPUT_OFFSET, 'nan', 'string'),
    (OUTPUT_SIGN, '-1.0', 'double'),
])
def test_other_forms_are_refused_naming_the_key(name, text, found):
    parameter = normalized(SPECS[name], from_text(name, text))
    with pytest.raises(ParameterRejected, match=rf'^{name} must be .*; found {found}'):
        check_parameter(SPECS[name], parameter)


def test_integer_hint_only_for_integers():
    with pytest.raises(ParameterRejected, match=r'write \[0.0, 1.0\], not \[0, 1\]'):
        check_parameter(SPECS[W_S], Parameter(W_S, Type.INTEGER_ARRAY, [0, 1]))
    with pytest.raises(ParameterRejected) as err:
        check_parameter(SPECS[W_S], Parameter(W_S, Type.STRING, 'oops'))
    assert 'write' not in str(err.value)


@pytest.mark.parametrize('text', ['null', '~', 'None', 'NULL'])
def test_null_is_unset_for_non_string_parameters(text):
    null = Parameter(W_S, Type.STRING, text)
    assert is_null(SPECS[W_S], null)
    assert is_null(SPECS[W_S], Parameter(W_S, Type.NOT_SET, None))
    check_parameter(SPECS[W_S], null, allow_unset=True)
    with pytest.raises(ParameterRejected, match=rf'^{W_S} cannot be unset \(null\)'):
        check_parameter(SPECS[W_S], null)
    assert not is_null(SPECS['message_time'], Parameter('message_time', Type.STRING, text))


def test_operating_point_specs():
    for key, default in OPERATING_POINT_DEFAULTS.items():
        spec = SPECS[key]
        assert spec.default == default and not spec.read_only
        described = descriptor(spec)
        assert 'model' in described.additional_constraints
    assert SPECS[OUTPUT_SIGN].type_ == 'integer'
    assert '[A]' in descriptor(SPECS[INPUT_OFFSET]).description
    assert '[m]' in descriptor(SPECS['model.output_offset']).description
    assert '1 or -1' in descriptor(SPECS[OUTPUT_SIGN]).additional_constraints


def test_a_request_is_answered_with_the_refusal_or_the_error_named():
    def raising(err):
        def check():
            raise err
        return check

    assert answer_request(lambda: None).successful
    refused = answer_request(raising(ParameterRejected('order must be auto')))
    assert not refused.successful and refused.reason == 'order must be auto'
    model = answer_request(raising(ModelError('model.x must be finite')))
    assert not model.successful and model.reason == 'model.x must be finite'
    other = answer_request(raising(KeyError('axes')))
    assert not other.successful
    assert other.reason == "the request could not be checked (KeyError: 'axes')"
