# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
The output mode (``mpi_ros.extensions.resonance``): model, parameter form, plant, compensator.

A lightly damped mechanical mode after Gamma, ``s = R_(f, T)[Gamma[x]]``: its exact
first-order-hold update, its parameter keys, its step in the simulated plant, the compensator
that inverts Gamma only (and says so), and the identification that fits it on records that
ring after steps and writes it into the model ``mpi-ros simulate`` runs.
"""

import json
import math

from mpi_ros.app.cli import main
from mpi_ros.compensation import Compensator
from mpi_ros.compensation.updates import uncompensated
from mpi_ros.diagnosis import diagnose
from mpi_ros.errors import ModelError
from mpi_ros.extensions import CompositeModel, EFFECTS, extended_model_from_params, \
    fit_resonance, RateDependentModel, ResonanceModel
from mpi_ros.extensions.resonance import mode_state, mode_stream, output_mode
from mpi_ros.model_fit import identify
from mpi_ros.params import read_params_yaml
from mpi_ros.plant.actuator import ActuatorConfig, MagnetostrictiveActuator
from mpi_ros.plant.synthetic import synthetic_record
from mpi_ros.recordings import read_csv_table, Recording, write_csv_columns
import numpy as np
import pytest
from scipy import signal
from scipy.integrate import solve_ivp

from .core_models import random_model

FREQUENCY, DECAY = 740.0, 0.013          # [Hz], [s]: the TUM rig's mode
EXACT = 1e-12                             # relative to the signal's range


def _rms(sim, y):
    return float(np.sqrt(np.mean((sim - y) ** 2)) / np.ptp(y))


def test_mode_is_exact_for_a_drive_linear_between_samples():
    rng = np.random.default_rng(1)
    t = np.arange(3000) * 1e-4
    g = np.cumsum(rng.normal(0.0, 1e-6, t.size))
    g[1500:] += 3e-5                                   # a step: the mode rings
    w = 2.0 * math.pi * FREQUENCY
    lti = signal.lti([w * w], [1.0, 2.0 / DECAY, w * w])
    _, reference, _ = signal.lsim(lti, g - g[0], t, interp=True)   # first-order hold
    p = output_mode(t, g, FREQUENCY, DECAY)
    assert np.max(np.abs(p - (reference + g[0]))) <= EXACT * np.ptp(g)
    assert np.ptp(p[1500:2000]) > 1.5 * 3e-5                      # it overshoots
    # Any sampling: against the ODE integrated finely, with a start deflection.
    tn = np.cumsum(rng.uniform(0.5e-4, 1.5e-4, 400))
    gn = np.sin(2 * math.pi * 90.0 * tn) + (tn > tn[200])
    deflection = 0.4
    ode = solve_ivp(lambda s, z: [z[1], w * w * (np.interp(s, tn, gn) - z[0]) - 2.0 / DECAY
                                  * z[1]], (tn[0], tn[-1]), [gn[0] + deflection, 0.0],
                    t_eval=tn, rtol=1e-10, atol=1e-12, max_step=2e-6)
    np.testing.assert_allclose(output_mode(tn, gn, FREQUENCY, DECAY, deflection), ode.y[0],
                               rtol=0, atol=1e-6)
    # Chunked streaming equals one pass (the plant simulator node's way).
    state = mode_state()
    state[3] = g[0]
    chunks = [mode_stream(t[a:b], g[a:b], w, 1.0 / DECAY, state)
              for a, b in ((0, 1), (1, 700), (700, 3000))]
    np.testing.assert_array_equal(np.concatenate(chunks), p)
    np.testing.assert_array_equal(output_mode(t, g, 0.0, 0.0), g)            # no mode


def test_parameter_form_round_trip_and_validation():
    rng = np.random.default_rng(2)
    gamma = random_model(rng).with_operating_point(input_offset=0.2, output_offset=3e-5)
    model = ResonanceModel(gamma, FREQUENCY, DECAY, 2e-6)
    params = model.to_params()
    again = extended_model_from_params(params)
    assert type(again) is ResonanceModel and again.cause == 'resonance'
    t = np.arange(2000) * 1e-4
    x = np.clip(1.0 + np.cumsum(rng.normal(0.0, 0.03, t.size)), 0.1, 1.9)
    x[1000:] = 1.8                                      # a step
    np.testing.assert_array_equal(again.simulate(t, x), model.simulate(t, x))
    np.testing.assert_array_equal(
        model.simulate(t, x), output_mode(t, gamma.simulate(x), FREQUENCY, DECAY, 2e-6))
    assert again.damping_ratio == pytest.approx(1.0 / (2 * math.pi * FREQUENCY * DECAY))
    # The deflection defaults to 0 (a hand-written file without it starts at rest).
    del params['record_start.resonance.initial_deflection']
    assert extended_model_from_params(params).initial_deflection == 0.0
    with pytest.raises(ModelError, match=r'model.resonance.decay must be above 1 / \(2 pi f\)'
                                         r' = 0.0002151 s'):
        ResonanceModel(gamma, FREQUENCY, 2e-4)
    with pytest.raises(ModelError, match=r'model.resonance.frequency must be finite and >= 0.0'
                                         r' \[Hz\]; found -1.0'):
        extended_model_from_params({**params, 'model.resonance.frequency': -1.0})
    with pytest.raises(ModelError, match=r'record_start.resonance.initial_deflection must be a'
                                         r' number \[m\]'):
        extended_model_from_params({**params, 'record_start.resonance.initial_deflection': 'x'})
    # With an input lag: a composite, the lag before Gamma, the mode after it.
    both = extended_model_from_params(
        {**model.to_params(), 'model.rate_dependence.time_constant': 0.002})
    assert isinstance(both, CompositeModel) and both.causes == ('rate_dependence', 'resonance')
    lagged = RateDependentModel(gamma, 0.002)
    np.testing.assert_allclose(both.simulate(t, x), output_mode(
        t, lagged.simulate(t, x), FREQUENCY, DECAY, 2e-6), rtol=0, atol=1e-18)
    assert EFFECTS['resonance'].stage == 'output'


def test_compensator_inverts_gamma_only_and_says_so():
    rng = np.random.default_rng(3)
    gamma = random_model(rng)
    limits = {'output_min': 0.0, 'output_max': 2.0}
    mode = ResonanceModel(gamma, FREQUENCY, DECAY)
    comp = Compensator(mode, **limits)
    assert not comp.has_effect and comp.kind == 'resonance (not compensated)'
    desired = gamma.simulate(np.clip(1.0 + np.cumsum(rng.normal(0.0, 0.02, 500)), 0.1, 1.9))
    t = np.arange(desired.size) * 1e-4
    plain = Compensator(gamma, **limits)
    np.testing.assert_array_equal([comp.command(v, time=s) for s, v in zip(t, desired)],
                                  [plain.command(v, time=s) for s, v in zip(t, desired)])
    warning = uncompensated(mode)
    assert warning is not None and warning.startswith(
        'resonance cannot be inverted causally: compensating Gamma only; the output rings at'
        ' about 740 Hz (decay 13 ms)')
    assert 'input shaper at 740 Hz' in warning
    # With a lag: the lag's lead is inverted, the mode is left out (and named).
    lag = RateDependentModel(gamma, 0.002)
    both = CompositeModel(gamma, (lag, mode))
    comp = Compensator(both, **limits)
    assert comp.has_effect and comp.kind == 'rate_dependence+resonance (resonance not' \
                                            ' compensated)'
    only_lag = Compensator(lag, **limits)
    np.testing.assert_array_equal([comp.command(v, time=s) for s, v in zip(t, desired)],
                                  [only_lag.command(v, time=s) for s, v in zip(t, desired)])
    assert uncompensated(both).startswith('resonance cannot be inverted causally:'
                                          ' compensating the other stages; the output rings')
    assert uncompensated(lag) is None and uncompensated(gamma) is None


def test_plant_step_rings_and_streams_like_one_run():
    t = np.arange(4000) * 1e-4
    x = np.where(t < 0.05, 0.0, 1.2)
    x[2000:] = 0.6
    config = ActuatorConfig(resonance_frequency_hz=FREQUENCY, resonance_decay_s=DECAY)
    ringing = MagnetostrictiveActuator(config).simulate(t, x)
    plain = MagnetostrictiveActuator().simulate(t, x)
    np.testing.assert_allclose(ringing, output_mode(t, plain, FREQUENCY, DECAY), rtol=0,
                               atol=EXACT * np.ptp(plain))
    assert np.max(ringing[500:2000]) > plain[1999] + 0.5 * (plain[1999] - plain[0])
    act = MagnetostrictiveActuator(config)
    chunks = [act.advance(t[a:b], x[a:b]) for a, b in ((0, 1), (1, 1234), (1234, 4000))]
    np.testing.assert_array_equal(np.concatenate(chunks), ringing)
    assert ActuatorConfig.descriptions()['resonance_frequency_hz'] == (
        'natural frequency of a lightly damped output mode, 0 = off [Hz]')
    with pytest.raises(ModelError, match=r'actuator\.resonance_decay_s must be > 1 / \(2 pi'
                                         r' f\) = 0.0002151 s'):
        ActuatorConfig(resonance_frequency_hz=FREQUENCY, resonance_decay_s=1e-4)


@pytest.mark.parametrize('kind', ['ringing 500 Hz', 'ringing 1000 Hz'])
def test_identify_models_the_ringing_and_simulate_reproduces_it(kind, tmp_path):
    record = synthetic_record(kind, 2)
    t, x, y, truth = record.time, record.current, record.displacement, record.truth
    result = identify(x, y, order=(10, 5), time=t)
    mode = result.resonance
    assert mode.modelled and mode.frequency == pytest.approx(truth['resonance_hz'], rel=0.01)
    assert mode.error < 0.5 * mode.static_error
    assert mode.error == pytest.approx(result.whole_record_rms_error, rel=1e-9)
    summary = json.loads(json.dumps(result.summary()))
    assert summary['resonance']['modelled'] and summary['resonance']['frequency'] == \
        pytest.approx(mode.frequency)
    assert f'rings at {mode.frequency:.4g} Hz, decay {1e3 * mode.decay:.3g} ms; modelled' in \
        result.findings
    # `mpi-ros identify` writes it into the parameter form; `mpi-ros simulate --start record`
    # of the same record reproduces the whole-record error (ringing included).
    write_csv_columns(tmp_path / 'rec.csv', {'time': t, 'current': x, 'displacement': y})
    assert main(['identify', str(tmp_path / 'rec.csv'), '--order', '10,5', '-o',
                 str(tmp_path / 'p.yaml'), '--quiet']) == 0
    params = read_params_yaml(tmp_path / 'p.yaml')
    assert params['model.resonance.frequency'] == pytest.approx(mode.frequency)
    assert main(['simulate', str(tmp_path / 'p.yaml'), '--input', str(tmp_path / 'rec.csv'),
                 '--time-column', 'time', '--input-column', 'current', '--column-name',
                 'simulated', '--output', str(tmp_path / 'sim.csv'), '--start', 'record']) == 0
    header, table = read_csv_table(tmp_path / 'sim.csv')
    assert _rms(table[:, header.index('simulated')], y) == pytest.approx(
        result.whole_record_rms_error, rel=1e-9)


def test_a_record_that_starts_ringing_gets_its_initial_deflection():
    # As the TUM captures: the input stepped just before the first sample, the output
    # still at its old level.  The mode starts deflected by the step (fitted), not at rest.
    record = synthetic_record('ringing 740 Hz', 3)
    t, x, y = record.time, record.current, record.displacement
    step = int(np.argmax(np.abs(np.diff(x)))) + 1            # the largest step: 1.64 -> 0.35 A
    t, x, y = t[step:] - t[step], x[step:], y[step:]
    result = identify(x, y, order=(10, 5), time=t)
    mode = result.resonance
    assert mode.modelled and mode.frequency == pytest.approx(FREQUENCY, rel=0.01)
    settled = float(np.median(y[300:600]))
    assert mode.deflection == pytest.approx(y[0] - settled, rel=0.1)
    bound = record.truth['noise'] * 0.034 / (np.ptp(y) / 1e-3) + 0.005
    assert result.whole_record_rms_error <= bound
    assert result.full_model.to_params()['record_start.resonance.initial_deflection'] == \
        mode.deflection


def test_the_effect_fit_finds_the_mode_or_none():
    record = synthetic_record('ringing 740 Hz', 1)
    model = fit_resonance(record.time, record.current, record.displacement, order=(8, 4))
    assert model.frequency == pytest.approx(FREQUENCY, rel=0.01)
    assert model.decay == pytest.approx(DECAY, rel=0.2)
    quiet = synthetic_record('at rest, rising-amplitude sine', 1)
    none = fit_resonance(quiet.time, quiet.current, quiet.displacement, order=(8, 4))
    assert none.frequency == 0.0
    np.testing.assert_array_equal(none.simulate(quiet.time, quiet.current),
                                  none.model.simulate(quiet.current))


def test_the_diagnosis_names_the_resonance_on_a_ringing_record():
    # A candidate like every registered effect: fitted on one record, validated on another
    # (same rising sensor); no signature test reads ringing (decided on the gain alone).
    train, validation = (synthetic_record('ringing 740 Hz', seed) for seed in (2, 3))
    report = diagnose(Recording(train.time, train.current, train.displacement, source='a'),
                      validation=Recording(validation.time, validation.current,
                                           validation.displacement, source='b'),
                      order=(10, 5))
    assert report.cause == 'resonance', report.decision['steps']
    assert report.gain > 0.5
    chosen = next(c for c in report.candidates if c.cause == 'resonance')
    assert chosen.signature == 'unavailable' and chosen.significant
