# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""Dead-time compensation by prediction (mpi_ros.compensation.prediction)."""

from mpi_ros.compensation import Compensator
from mpi_ros.compensation.prediction import DeadTimePredictor, prediction_horizon, \
    prediction_weights
from mpi_ros.errors import ModelError
from mpi_ros.extensions.composite import CompositeModel
from mpi_ros.extensions.dead_time import DeadTimeModel
from mpi_ros.extensions.rate_dependence import RateDependentModel
from mpi_ros.operators.model import MPIModel
import numpy as np
import pytest

GAMMA = MPIModel.from_params({
    'model.hysteresis.thresholds': [0.0, 0.2, 0.5], 'model.hysteresis.weights': [1.0, 0.4, 0.2],
    'model.superposition.thresholds': [0.0, 0.3], 'model.superposition.weights': [2e-5, 5e-6],
    'model.input_offset': 0.1})
LIMITS = {'output_min': 0.1, 'output_max': 1.9}
PERIOD = 1e-3
#: Round-off of the least-squares weights on displacements of 1e-5 m.
EXACT = 1e-15


@pytest.mark.parametrize('window, horizon', [(2, 0.0), (8, 1.8), (21, 10.0), (61, 29.7)])
def test_weights_extrapolate_a_straight_line_exactly(window, horizon):
    c = prediction_weights(window, horizon)
    assert c.shape == (window,) and c.sum() == pytest.approx(1.0, abs=1e-12)
    k = np.arange(1 - window, 1, dtype=float)
    assert c @ (3.0 - 0.7 * k) == pytest.approx(3.0 - 0.7 * horizon, abs=1e-9)


def test_predictor_is_exact_on_a_ramp_and_holds_a_hold():
    p = DeadTimePredictor(0.0123, PERIOD)                 # 12.3 samples ahead
    assert p.window == 26
    assert p.predict(2e-5) == 2e-5                         # the first value fills the window
    for _ in range(40):
        assert p.predict(2e-5) == 2e-5
    ramp = 2e-5 + 1e-8 * np.arange(1, 200)
    out = np.array([p.predict(v) for v in ramp])
    # Once the ramp fills the window: the line 12.3 samples ahead, not cut by the bound.
    np.testing.assert_allclose(out[p.window:], ramp[p.window:] + 12.3e-8, rtol=0, atol=EXACT)
    assert np.all(out >= ramp) and np.all(out <= ramp + 12.3e-8 + EXACT)


def test_a_step_is_not_extrapolated():
    # A step of the desired value: the prediction is the value itself, before, at and
    # after the step (one large difference among small ones: median step 0).
    p = DeadTimePredictor(0.03, PERIOD)
    values = np.concatenate([np.full(100, 1e-5), np.full(200, 4e-5), np.full(50, 2e-5)])
    np.testing.assert_array_equal([p.predict(v) for v in values], values)


def test_prediction_of_noise_is_finite_and_bounded():
    rng = np.random.default_rng(5)
    p = DeadTimePredictor(0.01, PERIOD)
    noise = 1e-5 + 1e-8 * rng.standard_normal(20000)
    out = np.array([p.predict(v) for v in noise])
    assert np.all(np.isfinite(out))
    reach = 10.0 * np.max(np.abs(np.diff(noise)))
    assert np.all(np.abs(out - noise) <= reach)
    # The line over 21 samples averages: the prediction scatters less than the values.
    assert np.std(out[100:]) < np.std(noise[100:])


def test_bad_settings_are_refused():
    with pytest.raises(ModelError, match='finite dead time > 0 and sample period > 0'):
        DeadTimePredictor(0.0, PERIOD)
    with pytest.raises(ModelError, match='finite dead time > 0 and sample period > 0'):
        DeadTimePredictor(0.01, float('nan'))


def test_horizon_of_models():
    dead = DeadTimeModel(GAMMA, 0.01)
    assert prediction_horizon(GAMMA) == 0.0 and prediction_horizon(dead) == 0.01
    both = CompositeModel(GAMMA, (RateDependentModel(GAMMA, 0.003), dead))
    assert prediction_horizon(both) == 0.01


def _two_sines(n, frequencies=(0.7, 2.3)):
    t = np.arange(n) * PERIOD
    return t, (2.2e-5 + 6e-6 * np.sin(2 * np.pi * frequencies[0] * t)
               + 3e-6 * np.sin(2 * np.pi * frequencies[1] * t))


@pytest.mark.parametrize('model', [
    DeadTimeModel(GAMMA, 0.02),
    CompositeModel(GAMMA, (RateDependentModel(GAMMA, 0.003), DeadTimeModel(GAMMA, 0.02)))],
    ids=['dead time', 'lag + dead time'])
def test_prediction_tracks_a_dead_time_model_on_a_smooth_trajectory(model):
    # The exact plant (the model itself, started where the compensator starts): Gamma^-1
    # alone leaves the dead time's error; the prediction removes most of it (measured: 0.27
    # of it at 0.5 + 1.5 Hz and 20 ms, with a lag before it too; what is left is the
    # straight line's curvature error).
    t, desired = _two_sines(6000, (0.5, 1.5))
    errors = {}
    for predict in (True, False):
        comp = Compensator(model, **LIMITS, sample_period=PERIOD, start='record',
                           dead_time_prediction=predict)
        command = comp.command_batch(desired, t)
        assert np.all(np.isfinite(command))
        errors[predict] = np.sqrt(np.mean((model.simulate(t, command) - desired)[500:] ** 2))
    assert errors[True] < 0.35 * errors[False]


def test_compensator_with_prediction_is_gamma_inverse_of_the_prediction():
    # The wiring: the compensator's command is Gamma^-1 of the predictor's output.
    model = DeadTimeModel(GAMMA, 0.0137)
    _, desired = _two_sines(3000)
    comp = Compensator(model, **LIMITS, sample_period=PERIOD)
    plain = Compensator(GAMMA, **LIMITS, sample_period=PERIOD)
    p = DeadTimePredictor(0.0137, PERIOD)
    lo, hi = plain.displacement_range
    shifted = [min(max(p.predict(float(v)), lo), hi) for v in desired]
    np.testing.assert_array_equal(comp.command_batch(desired), plain.command_batch(shifted))


def test_a_step_across_the_range_does_not_swing_the_command():
    # Holds and steps across the whole range: with prediction the commands are exactly
    # those of Gamma^-1 alone (no overshoot), inside the limits, finite.
    model = DeadTimeModel(GAMMA, 0.03)
    ref = Compensator(model, **LIMITS, dead_time_prediction=False)
    lo, hi = ref.displacement_range
    desired = np.repeat([lo, hi, lo + 0.3 * (hi - lo), hi, lo], 200)
    predicted = Compensator(model, **LIMITS).command_batch(desired)
    np.testing.assert_array_equal(predicted, ref.command_batch(desired))
    assert np.all((predicted >= LIMITS['output_min']) & (predicted <= LIMITS['output_max']))


def test_bad_inputs_and_range_keep_the_commands_finite_and_inside():
    rng = np.random.default_rng(11)
    model = DeadTimeModel(GAMMA, 0.008)
    comp = Compensator(model, **LIMITS)
    lo, hi = comp.displacement_range
    desired = rng.uniform(lo - 0.5 * (hi - lo), hi + 0.5 * (hi - lo), 3000)
    desired[rng.integers(0, desired.size, 60)] = np.nan
    desired[rng.integers(0, desired.size, 20)] = np.inf
    desired[2000:2500] = np.linspace(lo, 2.0 * hi, 500)     # a ramp out of the range
    command = comp.command_batch(desired)
    assert np.all(np.isfinite(command))
    assert np.all((command >= LIMITS['output_min']) & (command <= LIMITS['output_max']))
    assert comp.counters['nonfinite_input'] > 0 and comp.counters['nonfinite_command'] == 0


def test_installing_the_same_model_mid_stream_is_bumpless():
    model = DeadTimeModel(GAMMA, 0.012)
    _, desired = _two_sines(2000)
    whole = Compensator(model, **LIMITS).command_batch(desired)
    comp = Compensator(model, **LIMITS)
    first = comp.command_batch(desired[:1234])
    comp.install(DeadTimeModel(GAMMA, 0.012))
    second = comp.command_batch(desired[1234:])
    np.testing.assert_allclose(np.concatenate([first, second]), whole, rtol=0, atol=1e-12)


def test_kind_and_warning_follow_the_option():
    from mpi_ros.compensation import kind_of
    from mpi_ros.compensation.updates import uncompensated
    model = DeadTimeModel(GAMMA, 0.01)
    assert Compensator(model, **LIMITS).kind == kind_of(model) == 'dead_time (predicted)'
    assert uncompensated(model) is None
    off = Compensator(model, **LIMITS, dead_time_prediction=False)
    assert off.kind == 'dead_time (not compensated)'
    assert uncompensated(model, dead_time_prediction=False).startswith(
        'dead_time cannot be inverted causally')
    both = CompositeModel(GAMMA, (RateDependentModel(GAMMA, 0.003), model))
    assert kind_of(both) == 'dead_time+rate_dependence (dead_time predicted)'
    assert kind_of(both, dead_time_prediction=False) == (
        'dead_time+rate_dependence (dead_time not compensated)')


def test_a_ramp_is_tracked_exactly_through_the_dead_time_model():
    # Exactness: on a ramp (the dead time a whole number of samples), once the ramp fills
    # the window the model's output through the dead time is the desired displacement.
    model = DeadTimeModel(GAMMA, 0.012)
    t = np.arange(1000) * PERIOD
    desired = 1.5e-5 + 3.5e-5 * t / t[-1]
    comp = Compensator(model, **LIMITS, sample_period=PERIOD, start='record')
    output = model.simulate(t, comp.command_batch(desired))
    settled = DeadTimePredictor(0.012, PERIOD).window + 12
    np.testing.assert_allclose(output[settled:], desired[settled:], rtol=0, atol=1e-17)
    off = Compensator(model, **LIMITS, sample_period=PERIOD, start='record',
                      dead_time_prediction=False)
    lag = model.simulate(t, off.command_batch(desired)) - desired
    assert np.min(np.abs(lag[settled:])) > 0.4e-6          # 12 samples behind the ramp


def test_the_running_median_is_the_window_median():
    # The predictor keeps the window's steps sorted as it slides (and after a seed): its
    # output equals the definition, line and median recomputed over every window.
    rng = np.random.default_rng(2)
    x = np.cumsum(rng.standard_normal(3000)) * 1e-7 + np.repeat(rng.uniform(0, 1e-5, 30), 100)
    p = DeadTimePredictor(0.0123, PERIOD)
    p.seed(x[:7])                                        # fewer values than the window
    n, h = p.window, p.horizon
    c = prediction_weights(n, h)
    window = np.concatenate([np.full(n - 7, x[0]), x[:7]])
    for v in x[7:]:
        window = np.append(window[1:], v)
        reach = h * np.median(np.abs(np.diff(window)))
        assert p.predict(float(v)) == min(max(float(c @ window), v - reach), v + reach)
