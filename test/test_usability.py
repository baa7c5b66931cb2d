# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
A model is accepted only when Gamma and Gamma^-1 run (mpi_ros.operators.usability).

The issue-25 pushes (subnormal weights, an offset of 1e308) are refused naming the key;
a non-finite inverse is never commanded; a property test pushes random and extreme values
into every model key of the compensator's specs through the node's validation rule (type
check, whole-model prepare): no other exception escapes, and every accepted model's
commands are finite and inside the limits.
"""

import math

from hypothesis import given, HealthCheck, seed, settings, strategies as st
from mpi_ros.compensation import Compensator
from mpi_ros.compensation.updates import apply, complete, model_keys, prepare, usable
from mpi_ros.errors import ModelError, MPIError
from mpi_ros.node_parameters import check_values, specs_by_name
from mpi_ros.node_parameters.compensator import compensator_parameters
from mpi_ros.operators.model import MODEL_KEYS, MPIModel, RECORD_START_STATES
from mpi_ros.operators.usability import check_usable, ROUND_TRIP, usability_sweep
import numpy as np
import pytest

from .core_models import random_model
from .hostile_values import pushes, type_name

R_H, W_H, R_S, W_S = MODEL_KEYS
Z_H0 = RECORD_START_STATES
LIMITS = (0.2, 1.8)
SPECS = specs_by_name(compensator_parameters())
#: Seeds fixed before the first run.
SEED = 2025


def _params(seed_=3):
    model = random_model(np.random.default_rng(seed_), n=6, l=3)
    params = model.to_params()
    params['model.input_offset'] = 1.0
    return params


def _values(params):
    values = dict.fromkeys(model_keys())
    values.update(params)
    values.update({'output.min': LIMITS[0], 'output.max': LIMITS[1]})
    return values


@pytest.mark.parametrize('change, key, words', [
    ({W_H: [5e-324] * 7}, W_H, 'subnormal'),
    ({W_H: [1e-200] * 7}, W_H, 'H^-1'),
    ({W_S: [1e300] * 4}, W_S, ''),
    ({'model.input_offset': 1e308}, 'model.input_offset', 'cannot be resolved'),
    ({'model.output_offset': 1e308}, 'model.output_offset', 'cannot be resolved'),
    ({Z_H0: [1e308] * 7}, Z_H0, 'initial states'),
])
def test_unusable_models_are_refused_naming_the_key(change, key, words):
    params = {**_params(), **change}
    if len(params[W_S]) != len(params[R_S]):
        params[W_S] = params[W_S][:len(params[R_S])]
    with pytest.raises(ModelError, match=key.replace('.', r'\.')) as caught:
        MPIModel.from_params(params)
    assert words in str(caught.value)
    # The node's rule (whole model over its output limits) refuses it the same way.
    with pytest.raises(MPIError, match=key.replace('.', r'\.')):
        prepare(_values(_params()), complete(_values(_params()), params))


def test_the_issue_cases_of_fifteen_plays():
    params = _params()
    params.update({R_H: [0.05 * i for i in range(15)], W_H: [5e-324] * 15,
                   Z_H0: [0.0] * 15})
    with pytest.raises(ModelError, match=r'model\.hysteresis\.weights item 0 is 5e-324'):
        MPIModel.from_params(params)


def test_an_offset_is_judged_against_the_range_of_use():
    # Resolved against the model's own range (2 A around x0: rounding step 1.2e-7 A of
    # 1e9), not against a range of 0.1 A.
    params = {**_params(), 'model.input_offset': 1e9}
    model = MPIModel.from_params(params)
    with pytest.raises(ModelError, match=r'model\.input_offset = 1000000000\.0 A cannot'):
        usable(model, model.inverse(), (0.2, 0.3))


@pytest.mark.parametrize('seed_', range(40))
def test_random_valid_models_pass(seed_):
    # No false refusal: random models of every order (initial histories, asymmetric S,
    # operating points) pass, over their own range and over a compensator's limits.
    rng = np.random.default_rng(1000 + seed_)
    model = random_model(rng).with_operating_point(
        input_offset=float(rng.uniform(-1.0, 1.0)), output_offset=float(rng.uniform(-1, 1)),
        output_sign=int(rng.choice([-1, 1])))
    again = MPIModel.from_params(model.to_params())
    h_inv, s_inv = check_usable(again.hysteresis, again.superposition,
                                input_offset=again.input_offset,
                                output_offset=again.output_offset,
                                output_sign=again.output_sign, current_range=(-2.0, 2.0))
    np.testing.assert_allclose(h_inv.weights, again.inverse().hysteresis.weights, rtol=1e-12)
    usable(again, again.inverse(), (-2.0, 2.0))


def test_the_round_trip_is_measured_not_assumed():
    # The sweep runs the model's own states: an exact inverse gives the currents back
    # far inside the tolerance; the sweep covers both ends of the range.
    model = random_model(np.random.default_rng(7), n=8, l=4)
    x = usability_sweep(-1.0, 1.0)
    assert x.min() == -1.0 and x.max() == 1.0
    back = model.inverse().simulate(model.simulate(x))
    assert np.max(np.abs(back - x)) < 1e-3 * ROUND_TRIP * 2.0


def _poisoned(compensator):
    """Bind a kernel whose input offset is NaN: every inverse is NaN."""
    kernel = list(compensator.kernel)
    kernel[8] = np.array([math.nan, 0.0, 1.0])
    compensator.bind(tuple(kernel))


def test_a_non_finite_inverse_is_never_commanded():
    model = random_model(np.random.default_rng(5), n=4, l=2)
    compensator = Compensator(model, output_min=LIMITS[0], output_max=LIMITS[1])
    first = compensator.command(float(np.mean(compensator.displacement_range)))
    _poisoned(compensator)
    held = [compensator.command(v) for v in np.linspace(*compensator.displacement_range, 5)]
    assert held == [first] * 5
    assert compensator.counters['nonfinite_command'] == 5
    assert compensator.counters['clamped'] == 0
    # The compiled block loop holds it too.
    batch = Compensator(model, output_min=LIMITS[0], output_max=LIMITS[1])
    batch.command_batch([float(np.mean(batch.displacement_range))])
    last = batch.last_command
    batch._own_pack = None
    _poisoned(batch)
    out = batch.command_batch(np.linspace(*batch.displacement_range, 7))
    np.testing.assert_array_equal(out, np.full(7, last))
    assert batch.counters['nonfinite_command'] == 7


# -- the property test: random and extreme values into every model key ----------------

def _validate(values, request):
    """Run the node's on-set rule on dicts: type check, then the whole model (prepare)."""
    check_values(SPECS, ((k, type_name(v), v) for k, v in request.items()))
    return prepare(values, complete(values, request))


#: What the property test saw (printed by the last test of the module, with -s).
TALLY = {'refused': 0, 'accepted': 0, 'commands': 0}


@seed(SEED)
@settings(max_examples=400, deadline=None, suppress_health_check=list(HealthCheck),
          database=None)
@given(pushes(SPECS, base=_params()), st.integers(0, 2**32 - 1))
def test_no_push_escapes_or_makes_a_bad_command(request, draw_seed):
    params = _params()
    values = _values(params)
    try:
        prepared = _validate(values, request)
    except MPIError as err:
        assert str(err)                            # refused, with a reason
        TALLY['refused'] += 1
        return
    TALLY['accepted'] += 1
    compensator = Compensator(MPIModel.from_params(params), output_min=LIMITS[0],
                              output_max=LIMITS[1])
    apply(prepared, compensator)
    rng = np.random.default_rng(draw_seed)
    low, high = compensator.displacement_range
    desired = np.concatenate([rng.uniform(low, high, 60), [math.nan, 1e308, -1e308, high]])
    commands = np.array([compensator.command(v) for v in desired])
    TALLY['commands'] += commands.size
    assert np.all(np.isfinite(commands)), request
    assert np.all((commands >= LIMITS[0]) & (commands <= LIMITS[1])), request
    assert compensator.counters['nonfinite_command'] == 0, request


def test_the_property_test_ran():
    # Runs after it (file order): both outcomes occurred, as drawn.
    print(f'core property test: {TALLY}')
    if sum(TALLY.values()):
        assert TALLY['refused'] > 0 and TALLY['accepted'] > 0
