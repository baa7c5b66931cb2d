# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""Feed-forward compensator core: exact inverse, clamping, bad input, bumpless swaps."""

from mpi_ros import MPIModel
from mpi_ros.compensation import Compensator
from mpi_ros.errors import ModelError
from mpi_ros.operators.hysteresis import PIHysteresisOperator
from mpi_ros.operators.memory import TurningPointMemory
import numpy as np
import pytest

from .core_models import hand_model, random_model

PARAMS = hand_model()


def _path(rng, size=600, lo=0.2, hi=1.8):
    steps = np.cumsum(rng.normal(0.0, 0.05, size))
    return np.concatenate([np.linspace(0.0, 1.0, 50), np.clip(1.0 + steps, lo, hi)])


@pytest.mark.parametrize('seed', range(6))
def test_memory_replay_equals_full_history(seed):
    rng = np.random.default_rng(seed)
    memory = TurningPointMemory()
    x = np.cumsum(rng.normal(0.0, 1.0, 2000)) * rng.uniform(0.1, 2.0)
    for v in x:
        memory.push(float(v))
    assert len(memory) < 200                               # wiping-out keeps it short
    for _ in range(5):
        r = np.sort(rng.uniform(0.0, 10.0, 9))
        r[0] = 0.0
        start = rng.uniform(-3.0, 3.0, 9)
        h = PIHysteresisOperator(r, np.ones(9))
        np.testing.assert_allclose(h.apply(memory.points, start)[1], h.apply(x, start)[1],
                                   atol=1e-12)


def test_compensator_inverts_model_exactly_inside_limits():
    model = MPIModel.from_params(PARAMS)
    comp = Compensator(model, output_min=0.0, output_max=1.8)
    x = _path(np.random.default_rng(0), lo=0.05, hi=1.75)
    commands = np.array([comp.command(s) for s in model.simulate(x)])
    np.testing.assert_allclose(commands, x, atol=1e-12)
    assert comp.counters['clamped'] == 0


def test_disabled_compensator_passes_best_linear_map():
    model = MPIModel.from_params(PARAMS)
    comp = Compensator(model, output_min=0.2, output_max=1.8, enabled=False)
    lin = comp.linear_map
    assert comp.command(2e-5) == pytest.approx(lin.gain * 2e-5 + lin.offset)
    assert lin.gain > 0


@pytest.mark.parametrize('seed', range(5))
def test_output_is_always_finite_and_inside_limits(seed):
    rng = np.random.default_rng(seed)
    comp = Compensator(random_model(rng, output_scale=1e-5), output_min=0.2,
                       output_max=1.8)
    specials = [np.nan, np.inf, -np.inf, 1e300, -1e300, 5e-308, 1e-3, -1e-3, 'text', None]
    values = list(rng.normal(0.0, 3e-5, 2000)) + specials * 20
    rng.shuffle(values)
    out = np.array([comp.command(v) for v in values])
    assert np.all(np.isfinite(out)) and out.min() >= 0.2 and out.max() <= 1.8
    c = comp.counters
    assert c['nonfinite_input'] == 20 * 5                  # nan, +-inf, 'text', None, x 20
    assert c['messages'] == len(values) and c['clamped'] > 0 and c['out_of_range'] > 0


def test_recovers_after_bad_input():
    model = MPIModel.from_params(PARAMS)
    ref = Compensator(model, output_min=0.0, output_max=1.8)
    comp = Compensator(model, output_min=0.0, output_max=1.8)
    s = model.simulate(_path(np.random.default_rng(3), lo=0.05, hi=1.75))
    for v in s[:300]:
        ref.command(v)
        comp.command(v)
    for v in [np.nan, np.inf, -np.inf]:
        assert comp.command(v) == comp.last_command
    np.testing.assert_array_equal([comp.command(v) for v in s[300:]],
                                  [ref.command(v) for v in s[300:]])


def test_clamping_keeps_inverse_in_step_with_applied_current():
    model = MPIModel.from_params(PARAMS)
    comp = Compensator(model, output_min=0.3, output_max=1.5)
    rng = np.random.default_rng(4)
    desired = model.simulate(_path(rng, lo=0.0, hi=1.8))     # goes beyond the limits
    applied = np.array([comp.command(v) for v in desired])
    assert comp.counters['clamped'] > 0
    # The compensator's forward state is the model's state under the applied current.
    _, state = model.hysteresis.apply(applied)
    np.testing.assert_allclose(comp.state, state, atol=1e-12)


def test_bumpless_swap_starts_new_model_at_the_operating_point():
    rng = np.random.default_rng(5)
    old = MPIModel.from_params(PARAMS)
    new_params = dict(PARAMS, **{'model.hysteresis.weights': [1.1, 0.25, 0.25, 0.05]})
    new = MPIModel.from_params(new_params)
    comp = Compensator(old, output_min=0.0, output_max=1.8)
    x = _path(rng, lo=0.05, hi=1.75)
    desired = old.simulate(x)
    applied = [comp.command(v) for v in desired[:400]]
    comp.install(new)
    assert comp.version == 2
    after = [comp.command(v) for v in desired[400:]]
    # What the new model itself implies: its inverse driven from the state the applied
    # current history leaves in the new model.
    _, z_h = new.hysteresis.apply(np.array(applied))
    expected = new.inverse().run(desired[400:], _inverse_state(new, z_h))[0]
    np.testing.assert_allclose(after, np.clip(expected, 0.0, 1.8), atol=1e-12)
    assert abs(after[0] - applied[-1]) < 0.05              # no jump at the switch


def _inverse_state(model, z_h):
    from mpi_ros.operators.inverse import invert_hysteresis_initial_states
    return invert_hysteresis_initial_states(z_h, model.hysteresis.weights)


def test_swap_to_same_model_is_seamless():
    model = MPIModel.from_params(PARAMS)
    ref = Compensator(model, output_min=0.0, output_max=1.8)
    comp = Compensator(model, output_min=0.0, output_max=1.8)
    desired = model.simulate(_path(np.random.default_rng(6), lo=0.05, hi=1.75))
    out_ref = [ref.command(v) for v in desired]
    out = [comp.command(v) for v in desired[:333]]
    comp.install(model)
    out += [comp.command(v) for v in desired[333:]]
    np.testing.assert_allclose(out, out_ref, atol=1e-12)


@pytest.mark.parametrize('lo, hi', [(1.0, 1.0), (2.0, 1.0), (np.nan, 1.0), (0.0, np.inf)])
def test_bad_limits_rejected(lo, hi):
    with pytest.raises(ModelError, match='output.min must be finite and below output.max'):
        Compensator(MPIModel.from_params(PARAMS), output_min=lo, output_max=hi)


@pytest.mark.parametrize('desired', [1e308, -1e308, 1.7976931348623157e308, 1e200, -5e305])
def test_extreme_finite_input_gives_clamped_finite_command(desired):
    comp = Compensator(MPIModel.from_params(PARAMS), output_min=0.2, output_max=1.8)
    current = comp.command(desired)
    assert np.isfinite(current) and current == (1.8 if desired > 0 else 0.2)
    assert np.all(np.isfinite(comp.state))


def test_one_compensator_installs_every_kind_bumplessly():
    # One Compensator serves plain and extended models; install() switches kinds, keeps
    # the counters and the turning-point memory, and stays exact for the new model.
    from mpi_ros.compensation import Compensator
    from mpi_ros.extensions import CreepModel, RateDependentModel
    rng = np.random.default_rng(11)
    gamma = random_model(rng, n=6, l=3, initial_history=False)
    x = 0.5 + 0.4 * np.sin(np.linspace(0.0, 12.0, 400))
    lo, hi = gamma.simulate(x).min(), gamma.simulate(x).max()
    desired = lo + (hi - lo) * (0.5 + 0.4 * np.sin(np.linspace(0.0, 9.0, 300)))
    comp = Compensator(gamma, output_min=-5.0, output_max=5.0)
    assert comp.kind == 'none' and comp.slow_state.size == 0
    for s in desired[:100]:
        comp.command(s)
    creep = CreepModel(gamma, np.array([0.05, 0.5]), np.array([0.1, 0.05]))
    comp.install(creep)
    assert comp.kind == 'creep' and comp.version == 2
    # The creep lags settle at the displacement G = sign (s - y0) of the last command.
    settled = gamma.output_sign * (desired[99] - gamma.output_offset)
    np.testing.assert_allclose(comp.slow_state, settled, rtol=1e-9, atol=0.0)
    times = np.arange(100, 200) * 1e-3
    commands = [comp.command(s, time=t) for s, t in zip(desired[100:200], times)]
    rate = RateDependentModel(gamma, 0.01)
    comp.install(rate)
    assert comp.kind == 'rate_dependence' and comp.counters['messages'] == 200
    comp.install(gamma)
    assert comp.kind == 'none' and comp.slow_state.size == 0
    assert np.all(np.isfinite(commands)) and comp.counters['clamped'] == 0


def test_command_batch_equals_command_per_sample():
    # The compiled chunk path gives the per-sample results, counters, memory and state.
    rng = np.random.default_rng(5)
    model = random_model(rng, n=8, l=4)
    one = Compensator(model, output_min=-1.0, output_max=2.0)
    chunked = Compensator(model, output_min=-1.0, output_max=2.0)
    lo, hi = one.displacement_range
    desired = lo + (hi - lo) * (np.cumsum(rng.normal(0.0, 0.15, 600)) % 1.6 - 0.3)
    desired[[10, 200]] = np.nan
    desired[300] = np.inf
    expected = np.array([one.command(v) for v in desired])
    got = np.concatenate([chunked.command_batch(part)
                          for part in np.array_split(desired, [1, 7, 100, 401])])
    np.testing.assert_array_equal(got, expected)
    assert chunked.counters == one.counters
    assert one.counters['out_of_range'] > 0 and one.counters['clamped'] > 0
    np.testing.assert_array_equal(chunked.memory.points, one.memory.points)
    np.testing.assert_array_equal(chunked.state, one.state)


def test_turning_point_memory_extend_equals_push():
    rng = np.random.default_rng(9)
    for _ in range(50):
        x = np.round(np.cumsum(rng.normal(0.0, 1.0, int(rng.integers(1, 80)))), 1)
        a, b = TurningPointMemory(), TurningPointMemory()
        for v in x:
            a.push(float(v))
        b.extend(x)
        np.testing.assert_array_equal(a.points, b.points)


def test_multi_axis_block_equals_single_axis_compensators():
    from mpi_ros.compensation import MultiAxisCompensator
    from mpi_ros.errors import DataError
    rng = np.random.default_rng(21)
    models = [random_model(rng, n=6, l=3) for _ in range(4)]
    multi = MultiAxisCompensator(models, output_min=-1.0, output_max=[1.5, 2.0, 2.5, 3.0])
    singles = [Compensator(m, output_min=-1.0, output_max=hi)
               for m, hi in zip(models, [1.5, 2.0, 2.5, 3.0])]
    ranges = np.array([c.displacement_range for c in singles])
    block = ranges[:, 0] + (ranges[:, 1] - ranges[:, 0]) * rng.uniform(0.0, 1.0, (50, 4))
    got = np.vstack([multi.command(block[:10]), multi.command(block[10])[None, :],
                     multi.command(block[11:])])
    expected = np.array([[c.command(v) for c, v in zip(singles, row)] for row in block])
    np.testing.assert_allclose(got, expected, rtol=0.0, atol=1e-12)
    with pytest.raises(DataError, match='samples x axes with 4 axes; found shape'):
        multi.command(block[:, :3])
