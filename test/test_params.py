# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""Parameter form of the model: validation with precise messages, YAML round trip."""

import math

from mpi_ros import MPIModel
from mpi_ros.errors import DataError, ModelError
from mpi_ros.params import closest_key, load_params_document, MAX_DEPTH, \
    read_params_yaml, unknown_keys, write_params_yaml
import numpy as np
import pytest

from .core_models import random_model, random_walk

VALID = {
    'model.hysteresis.thresholds': [0.0, 0.4, 0.8],
    'model.hysteresis.weights': [1.0, 0.3, 0.2],
    'record_start.hysteresis.initial_states': [0.0, 0.0, 0.0],
    'model.superposition.thresholds': [-0.5, 0.0, 0.5],
    'model.superposition.weights': [1e-5, 2e-5, -1e-5],
}


def _with(**changes):
    p = dict(VALID)
    for k, v in changes.items():
        p[k.replace('__', '.')] = v
    return p


def test_valid_parameters_load():
    model = MPIModel.from_params(VALID)
    assert (model.n, model.l) == (2, 1)
    # The parameter form: Gamma's four arrays, the operating point (defaults: origin) and
    # the record start.
    assert model.to_params() == {**VALID, 'model.input_offset': 0.0,
                                 'model.output_offset': 0.0, 'model.output_sign': 1}


@pytest.mark.parametrize('params, match', [
    ({k: v for k, v in VALID.items() if k != 'model.hysteresis.weights'},
     r'model\.hysteresis\.weights is missing'),
    (_with(model__hysteresis__weights=[1.0, 0.3]), r'model\.hysteresis\.weights must have one'),
    (_with(record_start__hysteresis__initial_states=[0.0]), r'initial_states must have one'),
    (_with(model__superposition__weights=[1e-5]), r'superposition\.weights must have one'),
    (_with(model__hysteresis__thresholds=[0.1, 0.4, 0.8]), r'start at exactly 0\.0'),
    (_with(model__hysteresis__thresholds=[0.0, 0.8, 0.4]),
     r'thresholds must be strictly.*unsorted'),
    (_with(model__hysteresis__thresholds=[0.0, 0.4, 0.4]), r'duplicate'),
    (_with(model__superposition__thresholds=[-0.5, 0.1, 0.5]), r'exactly one 0; found none'),
    (_with(model__superposition__thresholds=[0.5, 0.0, -0.5]),
     r'superposition\.thresholds must be'),
    (_with(model__hysteresis__weights=[0.0, 0.3, 0.2]), r'violates \(8\).*w_H0'),
    (_with(model__hysteresis__weights=[1.0, -0.3, 0.2]), r'violates \(8\).*item 1'),
    (_with(model__superposition__weights=[1e-5, 2e-5, -3e-5]), r'violates \(19\).*item 2'),
    (_with(model__superposition__weights=[-3e-5, 2e-5, 1e-5]), r'violates \(19\).*item 0'),
    (_with(model__hysteresis__weights=[1.0, math.nan, 0.2]), r'weights must be finite'),
    (_with(record_start__hysteresis__initial_states=[0.0, math.inf, 0.0]),
     r'record_start\.hysteresis\.initial_states must be'),
    (_with(model__hysteresis__weights='1.0, 0.3'), r'must be a list of floats'),
    (_with(model__hysteresis__weights=[1.0, 'a', 0.2]), r'item 1 is str'),
    (_with(model__hysteresis__weights=[True, 0.3, 0.2]), r'item 0 is bool'),
    (_with(model__hysteresis__weights=[]), r'must not be empty'),
])
def test_invalid_parameters_name_the_key(params, match):
    with pytest.raises(ModelError, match=match):
        MPIModel.from_params(params)


def test_yaml_round_trip(tmp_path):
    rng = np.random.default_rng(4)
    model = random_model(rng, n=14, l=7)
    path = tmp_path / 'params.yaml'
    write_params_yaml(path, model.to_params(), header='identified by a test')
    text = path.read_text()
    assert text.startswith('# identified by a test\ncompensator:\n  ros__parameters:\n')
    loaded = MPIModel.from_params(read_params_yaml(path))
    x = random_walk(rng, 500)
    np.testing.assert_array_equal(loaded.simulate(x), model.simulate(x))


def test_yaml_floats_stay_floats(tmp_path):
    # ROS parameter types are strict: 0 would be read as an integer, not a double.
    path = tmp_path / 'p.yaml'
    write_params_yaml(path, VALID)
    assert '[0.0, 0.0, 0.0]' in path.read_text()


def test_yaml_errors(tmp_path):
    with pytest.raises(DataError, match='does not exist'):
        read_params_yaml(tmp_path / 'missing.yaml')
    bad = tmp_path / 'bad.yaml'
    bad.write_text('a: [1, 2\n')
    with pytest.raises(DataError, match='cannot read'):
        read_params_yaml(bad)
    other = tmp_path / 'other.yaml'
    other.write_text('a:\n  ros__parameters: {x: 1}\nb:\n  ros__parameters: {y: 1}\n')
    with pytest.raises(DataError, match="no ros__parameters for node 'compensator'"):
        read_params_yaml(other)
    with pytest.raises(ModelError, match='non-finite'):
        write_params_yaml(tmp_path / 'nan.yaml', {'model.hysteresis.weights': [math.nan]})
    assert not (tmp_path / 'nan.yaml').exists()


def test_the_loader_refuses_aliases_and_deep_nesting_in_one_line(tmp_path):
    anchored = tmp_path / 'alias.yaml'
    anchored.write_text('a: &x [1.0, 2.0]\nb: *x\n')
    with pytest.raises(DataError, match=r'alias \*x; YAML aliases are not allowed.* line 2'):
        load_params_document(anchored)
    at_limit = tmp_path / 'limit.yaml'
    at_limit.write_text('[' * MAX_DEPTH + ']' * MAX_DEPTH + '\n')
    assert load_params_document(at_limit) is not None
    deeper = tmp_path / 'deep.yaml'
    deeper.write_text('[' * (MAX_DEPTH + 1) + ']' * (MAX_DEPTH + 1) + '\n')
    with pytest.raises(DataError, match=f'nested more than {MAX_DEPTH} deep') as raised:
        load_params_document(deeper)
    assert '\n' not in str(raised.value)
    broken = tmp_path / 'broken.yaml'
    broken.write_text('a:\n\tb: 1\n')
    with pytest.raises(DataError, match='not valid YAML: .* at line 2, column 1') as raised:
        load_params_document(broken)
    assert '\n' not in str(raised.value)


def test_unknown_keys_and_the_closest_known_one():
    known = ['model.output_offset', 'model.input_offset', 'output.min', 'output.max']
    given = ['model.output_ofset', 'output.min', 'qos_overrides./x.depth', 'zzz']
    assert unknown_keys(given, known, prefixes=('qos_overrides.',)) == [
        'model.output_ofset', 'zzz']
    assert closest_key('model.output_ofset', known) == 'model.output_offset'
    assert closest_key('zzz', known) is None
