"""The model-update policy on plain dicts (mpi_ros.compensation.updates), without ROS."""

import subprocess
import sys

from mpi_ros.compensation import Compensator, MultiAxisCompensator
from mpi_ros.compensation.updates import (
    apply, axis_key, complete, limits_of, load, model_keys, prepare, refusal,
)
from mpi_ros.errors import ModelError, ParameterRejected
from mpi_ros.extensions.effect import effect_off_values
from mpi_ros.operators.model import MODEL_KEYS, MPIModel
import numpy as np
import pytest

from .core_models import hand_model

GAMMA = hand_model()
OTHER = dict(GAMMA, **{'model.hysteresis.weights': [1.2, 0.2, 0.2, 0.1]})
CREEP = {'model.creep.time_constants': [0.01, 0.1, 1.0],
         'model.creep.weights': [0.05, 0.05, 0.1]}
LIMITS = {'output.min': 0.0, 'output.max': 2.0}


def values(params=None, prefix=''):
    """Return a node's current values: every model key (unset), the limits, ``params``."""
    current = {prefix + key: None for key in model_keys()}
    current.update({prefix + key: value for key, value in (params or {}).items()})
    current.update(LIMITS)
    current[prefix + 'model.input_offset'] = (params or {}).get('model.input_offset', 0.0)
    current[prefix + 'model.output_offset'] = (params or {}).get('model.output_offset', 0.0)
    current[prefix + 'model.output_sign'] = (params or {}).get('model.output_sign', 1)
    return current


def prefixed(params, prefix):
    return {prefix + key: value for key, value in params.items()}


def test_the_policy_imports_no_ros():
    code = ('import sys, mpi_ros.compensation.updates; '
            'sys.exit(any(m == "rclpy" or m.startswith("rclpy.") for m in sys.modules))')
    assert subprocess.run([sys.executable, '-c', code], check=False).returncode == 0


def test_a_whole_model_is_accepted_with_its_inverse():
    prepared = prepare(values(), dict(GAMMA), running=False)
    assert isinstance(prepared.model, MPIModel) and not prepared.model.is_inverse
    assert prepared.inverse is not None and prepared.inverse.is_inverse
    np.testing.assert_allclose(prepared.inverse.inverse().hysteresis.weights,
                               GAMMA['model.hysteresis.weights'])
    assert prepared.limits is None and prepared.switches == {}


def test_one_key_without_a_model_is_refused_naming_what_is_missing():
    with pytest.raises(ParameterRejected, match='the node has no model yet, and a model needs '
                       'all four keys of Gamma; missing: model.hysteresis.thresholds'):
        prepare(values(), {'model.hysteresis.weights': [1.0]}, running=False)
    with pytest.raises(ParameterRejected, match=r'axis 1 has no model yet, so '
                       r'axis1\.model\.dead_time cannot apply: .* missing: '
                       r'axis1\.model\.hysteresis\.thresholds'):
        prepare(values(prefix='axis1.'), {'axis1.model.dead_time': 0.01}, 'axis1.',
                running=False)


def test_an_invalid_model_is_refused_naming_the_key():
    bad = dict(GAMMA, **{'model.hysteresis.weights': [-1.0, 0.3, 0.2, 0.1]})
    with pytest.raises(ModelError, match='model.hysteresis.weights'):
        prepare(values(GAMMA), bad)
    with pytest.raises(ParameterRejected, match=r'axis 2 \(axis2\.model\.\*\): '
                       r'.*axis2\.model\.hysteresis\.weights'):
        prepare(values(GAMMA, 'axis2.'), prefixed(bad, 'axis2.'), 'axis2.')


def test_a_dump_loaded_back_without_a_model_prepares_nothing():
    current = values()
    request = {'model.hysteresis.thresholds': None, 'model.dead_time': None}
    assert complete(current, request) == {}
    unchanged = prepare(current, {'output.min': 0.0}, running=False)
    assert unchanged.model is None and unchanged.limits == (0.0, 2.0)
    # With a running model the same keys are checked whole (and pass).
    assert prepare(values(GAMMA), dict(GAMMA)).model is not None


def test_null_is_resolved_per_kind_of_key():
    current = values(dict(GAMMA, **CREEP, **{'model.input_offset': 0.4}))
    request = {'model.creep.weights': None, 'model.input_offset': None,
               'model.dead_time': None, 'model.hysteresis.weights': None}
    completed = complete(current, request)
    assert completed == {'model.creep.weights': effect_off_values()['model.creep.weights'],
                         'model.input_offset': 0.0, 'model.hysteresis.weights': None}
    assert list(completed) == ['model.creep.weights', 'model.input_offset',
                               'model.hysteresis.weights']


def test_all_four_gamma_keys_describe_the_whole_model():
    current = values(dict(GAMMA, **CREEP, **{'model.output_sign': -1}))
    completed = complete(current, dict(OTHER))
    off = effect_off_values()
    assert completed == dict(OTHER, **{'model.output_sign': 1,
                                       'model.creep.time_constants':
                                           off['model.creep.time_constants'],
                                       'model.creep.weights': off['model.creep.weights']})
    # Three keys of Gamma are not a whole model: nothing is added.
    three = {key: OTHER[key] for key in MODEL_KEYS[:3]}
    assert complete(current, three) == three
    # The completed request prepares the plain model (the creep switched off).
    assert isinstance(prepare(current, completed).model, MPIModel)


def test_effect_keys_alone_extend_the_running_gamma_and_switch_off():
    current = values(GAMMA)
    creep = prepare(current, dict(CREEP))
    assert creep.model.cause == 'creep'
    with_creep = dict(current, **CREEP)
    off = complete(with_creep, dict.fromkeys(CREEP))
    assert isinstance(prepare(with_creep, off).model, MPIModel)


def test_each_axis_prefix_is_prepared_alone():
    current = dict(values(GAMMA, 'axis0.'), **values(prefix='axis1.'))
    current.update(dict.fromkeys(axis_key(k, key) for k in range(2)
                                 for key in ('output.min', 'output.max')))
    request = dict(prefixed(OTHER, 'axis0.'), **prefixed(GAMMA, 'axis1.'))
    completed = complete(current, request, 'axis0.')
    assert completed == request          # axis1's keys pass; axis0's whole model is complete
    first = prepare(current, completed, 'axis0.')
    second = prepare(current, completed, 'axis1.', running=False)
    assert first.prefix == 'axis0.' and second.prefix == 'axis1.'
    np.testing.assert_allclose(first.model.hysteresis.weights, OTHER[
        'model.hysteresis.weights'])
    np.testing.assert_allclose(second.model.hysteresis.weights, GAMMA[
        'model.hysteresis.weights'])
    # An axis's own limits, else the node-wide ones; the refusal names the keys used.
    assert prepare(current, {'axis1.output.max': 1.5}, 'axis1.').limits == (0.0, 1.5)
    assert prepare(current, {'output.max': 1.5}, 'axis0.').limits == (0.0, 1.5)
    with pytest.raises(ParameterRejected, match='axis1.output.min must be below output.max'):
        prepare(current, {'axis1.output.min': 3.0}, 'axis1.')
    assert limits_of(dict(current, **{'axis0.output.min': 0.5}), 'axis0.') == (0.5, 2.0)


def test_load_reads_declared_values():
    assert load(values()) is None
    assert isinstance(load(values(GAMMA)), MPIModel)
    with pytest.raises(ParameterRejected, match='model.creep.time_constants: a model '
                       'extension needs the four model.* keys of Gamma'):
        load(dict(values(), **CREEP))
    partial = dict(values(), **{'model.hysteresis.thresholds': [0.0]})
    with pytest.raises(ParameterRejected, match='incomplete model in the parameters: missing '
                       'model.hysteresis.weights'):
        load(partial)


def _counting_inverse(monkeypatch):
    calls = []
    inverse = MPIModel.inverse

    def counted(self):
        calls.append(self)
        return inverse(self)

    monkeypatch.setattr(MPIModel, 'inverse', counted)
    return calls


def test_gamma_inverse_is_built_once_per_push(monkeypatch):
    comp = Compensator(MPIModel.from_params(GAMMA), **{'output_min': 0.0, 'output_max': 2.0})
    for desired in np.linspace(0.0, 2e-5, 20):
        comp.command(desired)
    calls = _counting_inverse(monkeypatch)
    prepared = prepare(values(GAMMA), dict(OTHER))
    assert apply(prepared, comp) is None
    assert len(calls) == 1
    assert comp.version == 2 and comp.model is prepared.model
    # A core built for a pushed model takes the prepared inverse too (single and multi-axis).
    fresh = prepare(values(), dict(GAMMA), running=False)
    Compensator(apply(fresh, None), output_min=0.0, output_max=2.0, inverse=fresh.inverse)
    MultiAxisCompensator([fresh.model, prepared.model], output_min=0.0, output_max=2.0,
                         inverses=[fresh.inverse, prepared.inverse])
    assert len(calls) == 2


def test_gamma_inverse_is_built_once_per_push_of_a_creep_model(monkeypatch):
    # The creep's per-step inverse takes the Gamma^-1 prepare built (issue 19).
    comp = Compensator(MPIModel.from_params(GAMMA), output_min=0.0, output_max=2.0)
    comp.command(1e-5)
    calls = _counting_inverse(monkeypatch)
    prepared = prepare(values(GAMMA), dict(OTHER, **CREEP))
    assert prepared.model.cause == 'creep'
    assert apply(prepared, comp) is None
    assert len(calls) == 1
    assert comp.model is prepared.model and comp.has_effect
    # Fed the prepared inverse or none, the creep step commands the same currents.
    again = Compensator(prepared.model, output_min=0.0, output_max=2.0)
    assert len(calls) == 2
    built = Compensator(prepared.model, output_min=0.0, output_max=2.0,
                        inverse=prepared.inverse)
    assert len(calls) == 2
    for k, desired in enumerate(np.linspace(0.0, 2e-5, 20)):
        assert again.command(desired, time=1e-3 * k) == built.command(desired, time=1e-3 * k)


def test_apply_swaps_limits_switches_and_model():
    comp = Compensator(MPIModel.from_params(GAMMA), output_min=0.0, output_max=2.0)
    request = dict(OTHER, **{'output.min': 0.2, 'output.max': 1.5, 'enabled': False,
                             'sample_period': 0.002, 'diagnostics_period': 2.0})
    prepared = prepare(values(GAMMA), request)
    assert prepared.switches == {'enabled': False, 'sample_period': 0.002,
                                 'diagnostics_period': 2.0}
    apply(prepared, comp)
    assert (comp.output_min, comp.output_max) == (0.2, 1.5)
    assert not comp.enabled and comp.sample_period == 0.002
    assert comp.model is prepared.model
    assert not prepare(values(GAMMA), {'qos_depth': 10})


def test_nothing_is_half_applied_on_rejection():
    comp = Compensator(MPIModel.from_params(GAMMA), output_min=0.0, output_max=2.0)
    current = values(GAMMA)
    before = {key: list(value) if isinstance(value, list) else value
              for key, value in current.items()}
    model, state = comp.model, comp.state
    request = dict(OTHER, **{'output.min': 2.5})        # a valid model, unordered limits
    with pytest.raises(ParameterRejected, match='output.min must be below output.max'):
        prepare(current, request)
    assert current == before and request['output.min'] == 2.5
    assert comp.model is model and comp.version == 1
    assert (comp.output_min, comp.output_max) == (0.0, 2.0)
    np.testing.assert_array_equal(comp.state, state)


def test_refusal_says_what_stays():
    err = ParameterRejected('bad')
    assert refusal(['enabled'], err, version=3) == 'bad'
    text = refusal(list(GAMMA), err, version=3)
    assert text.startswith('model update (5 model.* keys) rejected, the whole model was '
                           'checked: bad. Nothing was applied; the running model (version 3) '
                           'stays.')
    assert 'the node stays unconfigured' in refusal(['model.dead_time'], err, version=None)
    assert refusal(['axis0.model.dead_time'], err, version=None, axes=True).startswith(
        'bad. Nothing was applied; the running models stay.')
