# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""Tests of the simulated magnetostrictive actuator (mpi_ros.plant.actuator)."""

from mpi_ros.errors import DataError, ModelError
from mpi_ros.plant.actuator import ActuatorConfig, MagnetostrictiveActuator
from mpi_ros.plant.excitation import identification_excitation
import numpy as np
import pytest

RATE = 1000.0  # Hz
SCALE = ActuatorConfig().displacement_scale_m
EXACT = 1e-12 * SCALE  # round-off tolerance on displacements [m]
ALL_EFFECTS = ActuatorConfig(creep_gain=0.05, eddy_time_constant_s=0.005,
                             thermal_gain_m_per_a2=2e-6, dead_time_s=0.0035, noise_std_m=1e-8)


def _sine(frequency, cycles, *, samples_per_cycle=400, bias=1.0, amplitude=0.6):
    """Return (time, current): a ramp-free sine around the bias, starting at its minimum."""
    n = cycles * samples_per_cycle + 1
    phase = 2 * np.pi * np.arange(n) / samples_per_cycle
    return np.arange(n) / (samples_per_cycle * frequency), bias - amplitude * np.cos(phase)


def _loop_area(current, displacement):
    """Area enclosed by one closed (current, displacement) loop [A m], by the shoelace rule."""
    return 0.5 * abs(np.sum(current[:-1] * displacement[1:] - current[1:] * displacement[:-1]))


@pytest.fixture(scope='module')
def excitation():
    return identification_excitation(20.0, sample_rate=RATE, seed=3)


def test_rest_state_is_zero():
    act = MagnetostrictiveActuator()
    assert np.all(act.simulate([0.0, 0.5, 1.0], [0.0, 0.0, 0.0]) == 0.0)
    assert act.step(0.0, 0.0) == 0.0


def test_batch_equals_streaming_and_chunks(excitation):
    t, i = excitation
    t = t + 3e-4 * np.sin(7 * t)  # non-uniform sampling
    batch = MagnetostrictiveActuator(ALL_EFFECTS, seed=5).simulate(t, i)
    act = MagnetostrictiveActuator(ALL_EFFECTS, seed=5)
    stream = np.array([act.step(tk, ik) for tk, ik in zip(t[:3000], i[:3000])])
    np.testing.assert_array_equal(stream, batch[:3000])
    cuts = [3000, 3001, 3017, 9000, t.size]
    chunks = [act.advance(t[a:b], i[a:b]) for a, b in zip(cuts[:-1], cuts[1:])]
    np.testing.assert_array_equal(np.concatenate([stream, *chunks]), batch)
    act.reset()
    np.testing.assert_array_equal(act.advance(t, i), batch)


def test_rate_independent_without_effects():
    t, i = _sine(1.0, 3)
    act = MagnetostrictiveActuator()
    slow = act.simulate(t, i)
    fast = act.simulate(t / 40.0, i)
    np.testing.assert_array_equal(slow, fast)
    lagged = MagnetostrictiveActuator(ActuatorConfig(eddy_time_constant_s=0.005))
    assert np.max(np.abs(lagged.simulate(t / 40.0, i) - slow)) > 0.02 * SCALE


def test_minor_loop_closes_at_its_reversal_point():
    # Return-point memory of the Preisach operator: 1.5 -> 0.6 -> 1.2 -> 0.6 A ends where
    # the first descent to 0.6 A ended, although the path in between differs.
    knots = [0.0, 1.5, 0.6, 1.2, 0.6]
    current = np.concatenate([np.linspace(a, b, 200, endpoint=False)
                              for a, b in zip(knots[:-1], knots[1:])] + [[0.6]])
    s = MagnetostrictiveActuator().simulate(np.arange(current.size) / RATE, current)
    first_visit = s[400]  # index of the first arrival at 0.6 A
    assert current[400] == 0.6 and current[-1] == 0.6
    assert s[-1] == pytest.approx(first_visit, abs=EXACT)
    assert abs(s[-2] - first_visit) > 1e-3 * SCALE
    inner = s[400:600]  # the ascent 0.6 -> 1.2 A lies below the descent 1.5 -> 0.6 A
    descent_at = np.interp(current[400:600], current[200:401][::-1], s[200:401][::-1])
    assert np.all(inner[1:] < descent_at[1:])


def test_static_map_strictly_increasing_non_convex_asymmetric():
    act = MagnetostrictiveActuator()
    y = np.linspace(-0.5, 2.0, 2501)
    g = act.static_map(y)
    assert act.static_map(0.0) == 0.0
    assert np.all(np.diff(g) > 0)
    curvature = np.diff(g[(y >= 0) & (y <= 1)], 2)
    assert curvature.max() > 0 > curvature.min()  # convex, then concave
    mid = act.static_map([0.0, 0.5, 1.0])
    assert abs((mid[1] - mid[0]) - (mid[2] - mid[1])) > 0.1 * mid[2]


def test_branches_strictly_monotone_in_operating_range():
    knots = [0.0, 1.8, 0.2, 1.8, 0.6, 1.4, 0.2]
    pieces = [np.linspace(a, b, 300, endpoint=False) for a, b in zip(knots[:-1], knots[1:])]
    current = np.concatenate(pieces)
    s = MagnetostrictiveActuator().simulate(np.arange(current.size) / RATE, current)
    ds, di = np.diff(s), np.diff(current)
    operating = (current[1:] >= 0.2) & (current[:-1] >= 0.2)
    assert np.all(np.sign(ds[operating]) == np.sign(di[operating]))


def test_nonlinearity_error_like_the_paper():
    t, i = identification_excitation(60.0, sample_rate=500.0, seed=0)
    s = MagnetostrictiveActuator().simulate(t, i)
    gain = np.linalg.lstsq(i[:, None], s, rcond=None)[0]
    error = np.max(np.abs(i * gain[0] - s)) / np.max(np.abs(s))
    assert 0.30 <= error <= 0.50
    assert 1e-5 < s.max() < 1e-4  # tens of micrometres


def test_creep_keeps_moving_during_hold():
    t = np.arange(0, 60.0, 0.01)
    i = np.where(t < 0.5, 2 * t, 1.0)  # ramp to 1 A, then hold
    plain = MagnetostrictiveActuator().simulate(t, i)
    creep = MagnetostrictiveActuator(ActuatorConfig(creep_gain=0.1)).simulate(t, i)
    hold = t >= 0.5
    assert np.ptp(plain[hold]) == 0.0
    assert np.all(np.diff(creep[hold]) > 0)
    gained = creep - plain
    at = {s: np.interp(s + 0.5, t, gained) for s in (0.1, 1.0, 10.0)}
    # Logarithmic-type: comparable growth per decade of time, bounded by gamma * step.
    first, second = at[1.0] - at[0.1], at[10.0] - at[1.0]
    assert 0.3 < second / first < 3.0
    assert gained[-1] < 0.1 * plain[-1]


def test_rate_dependence_widens_loops_with_frequency():
    config = ActuatorConfig(eddy_time_constant_s=0.005)
    areas = []
    for frequency in (0.5, 5.0, 20.0):
        t, i = _sine(frequency, 3)
        s = MagnetostrictiveActuator(config).simulate(t, i)
        areas.append(_loop_area(i[-401:], s[-401:]))
    assert areas[0] < areas[1] < areas[2]
    assert areas[2] > 1.2 * areas[0]


def test_thermal_drift_follows_joule_heating():
    gain, tau = 2e-6, 30.0
    config = ActuatorConfig(thermal_gain_m_per_a2=gain, thermal_time_constant_s=tau)
    t = np.arange(0, 20.0, 0.01)
    i = np.full_like(t, 1.5)
    drift = (MagnetostrictiveActuator(config).simulate(t, i)
             - MagnetostrictiveActuator().simulate(t, i))
    np.testing.assert_allclose(drift, gain * 1.5 ** 2 * -np.expm1(-t / tau), rtol=1e-9,
                               atol=EXACT)
    # For t << tau the thermal state is the integral of the Joule heating: T ~ int i^2 dt / tau.
    tau = 300.0
    config = ActuatorConfig(thermal_gain_m_per_a2=gain, thermal_time_constant_s=tau)
    t, i = identification_excitation(10.0, sample_rate=200.0, seed=2, bursts=False)
    drift = (MagnetostrictiveActuator(config).simulate(t, i)
             - MagnetostrictiveActuator().simulate(t, i))
    heat = np.concatenate([[0.0], np.cumsum(0.5 * (i[1:] ** 2 + i[:-1] ** 2) * np.diff(t))])
    assert np.corrcoef(drift, heat)[0, 1] > 0.999
    assert drift[-1] == pytest.approx(gain * heat[-1] / tau, rel=0.03)


def test_dead_time_shifts_output_by_exactly_the_delay(excitation):
    t, i = excitation
    plain = MagnetostrictiveActuator().simulate(t, i)
    delayed = MagnetostrictiveActuator(ActuatorConfig(dead_time_s=0.012)).simulate(t, i)
    assert np.all(delayed[:12] == 0.0)
    np.testing.assert_allclose(delayed[12:], plain[:-12], rtol=0, atol=EXACT)


def test_noise_is_seeded_and_has_the_requested_spread(excitation):
    t, i = excitation
    config = ActuatorConfig(noise_std_m=1e-7)
    first = MagnetostrictiveActuator(config, seed=1).simulate(t, i)
    np.testing.assert_array_equal(first, MagnetostrictiveActuator(config, seed=1).simulate(t, i))
    other = MagnetostrictiveActuator(config, seed=2).simulate(t, i)
    plain = MagnetostrictiveActuator().simulate(t, i)
    assert not np.array_equal(first, other)
    assert np.std(first - plain) == pytest.approx(1e-7, rel=0.05)


def test_deep_memory_does_not_overflow():
    n = 1000
    current = 1.0 + 0.8 * (-1.0) ** np.arange(n) * np.geomspace(1.0, 1e-6, n)
    s = MagnetostrictiveActuator().simulate(np.arange(n) / RATE, current)
    assert np.all(np.isfinite(s))


def test_config_mapping_round_trip():
    config = ActuatorConfig.from_mapping({'actuator.creep_gain': 0.05, 'dead_time_s': 1,
                                          'actuator.relay_grid_size': 81})
    assert config.creep_gain == 0.05 and config.dead_time_s == 1.0
    assert type(config.dead_time_s) is float and type(config.relay_grid_size) is int
    assert ActuatorConfig(relay_grid_size=81.0, creep_lag_count=np.int64(5)).relay_grid_size == 81
    assert ActuatorConfig.from_mapping(config.to_mapping(prefix='actuator.')) == config
    assert ActuatorConfig.from_mapping(config.to_mapping()) == config
    assert set(ActuatorConfig.descriptions()) == set(config.to_mapping())


@pytest.mark.parametrize(('mapping', 'match'), [
    ({'actuator.creep_gian': 0.1}, r"unknown actuator parameter 'actuator\.creep_gian'"),
    ({'creep_gain': 0.1, 'actuator.creep_gain': 0.2}, 'given twice'),
    ({'creep_gain': -0.1}, r'actuator\.creep_gain must be >= 0'),
    ({'noise_std_m': float('nan')}, r'actuator\.noise_std_m must be a finite number'),
    ({'eddy_time_constant_s': True}, r'eddy_time_constant_s must be a finite number'),
    ({'relay_grid_size': 10.5}, r'relay_grid_size must be an integer'),
    ({'relay_grid_size': 2}, r'relay_grid_size must be in \[3, 2001\]'),
    ({'map_linear_fraction': 0.0}, 'strictly increasing'),
    ({'threshold_min_a': 3.0}, r'threshold_min_a must be < threshold_max_a'),
    ({'creep_time_constant_max_s': 0.01}, 'creep_time_constant_max_s must be >='),
    ({'reversible_fraction': 1.0}, r'reversible_fraction must be in \[0, 1\)'),
    ({'interaction_center_a': -50.0}, 'no mass on the grid'),
])
def test_config_errors(mapping, match):
    with pytest.raises(ModelError, match=match):
        MagnetostrictiveActuator(ActuatorConfig.from_mapping(mapping))


def test_config_type_error():
    with pytest.raises(ModelError, match='config must be an ActuatorConfig'):
        MagnetostrictiveActuator({'creep_gain': 0.1})


@pytest.mark.parametrize(('time', 'current', 'match'), [
    ([0.0, 1.0], [0.0, np.nan], r'current must be finite; found nan at index 1'),
    ([0.0, np.inf], [0.0, 1.0], r'time must be finite'),
    ([0.0, 1.0, 2.0], [0.0, 1.0], 'same length; found 3 and 2'),
    ([[0.0, 1.0]], [[0.0, 1.0]], r'1-D sequence \[s\]; found shape \(1, 2\)'),
    ([], [], r'non-empty 1-D sequence'),
    ([0.0, 1.0, 1.0], [0.0, 1.0, 1.0], r'strictly increasing; found 1\.0 s after 1\.0 s'),
    (['a'], [1.0], r'time must be numbers \[s\]'),
])
def test_series_errors(time, current, match):
    with pytest.raises(DataError, match=match):
        MagnetostrictiveActuator().simulate(time, current)


def test_streaming_errors():
    act = MagnetostrictiveActuator()
    act.step(1.0, 0.5)
    with pytest.raises(DataError, match=r'after the last sample \(1\.0 s\); found 1\.0 s'):
        act.step(1.0, 0.6)
    with pytest.raises(DataError, match='current must be finite'):
        act.step(2.0, float('nan'))
    act.reset()
    assert act.step(0.0, 0.0) == 0.0
