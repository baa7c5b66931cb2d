# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""Diagnosis tests: hide one effect in the simulated actuator, diagnose must name it."""

import importlib
import json
from pathlib import Path

from mpi_ros.diagnosis import check_invertible_class, diagnose, write_report
from mpi_ros.diagnosis.report import write_extended_params, write_json
from mpi_ros.errors import DataError, IdentificationError
from mpi_ros.extensions import extended_model_from_params
from mpi_ros.params import read_params_yaml
from mpi_ros.plant.actuator import ActuatorConfig, MagnetostrictiveActuator
from mpi_ros.plant.excitation import diagnostic_excitation, identification_excitation
from mpi_ros.recordings import read_signals, Recording, write_bag_signals
import numpy as np
import pytest

# Identification-style excitation with long holds (creep) and fast bursts (lag vs delay).
EXCITATION = {'sample_rate': 1000.0, 'burst_frequency': 40.0, 'hold_duration': 5.0}
DURATION = 60.0
NOISE = 2e-8          # [m], 0.05 % of the 40 um stroke
ZERO_PEAK, ZERO_CURRENT = 1.8, 0.2      # [A] where issue 9's actuator's sensor was zeroed
VALIDATION_ZERO = 7e-6                  # [m] the validation record's own sensor zero
ZERO_TOLERANCE = 1e-6                   # [m] re-estimated zero vs VALIDATION_ZERO
REAL_DATA = Path(__file__).resolve().parents[2] / 'shared' / 'data' / 'measured' / \
    'pnzt-aixacct-tue' / 'csv'


def _strength(cause, rng):
    # Realistic, randomised strengths (seeded).
    if cause == 'creep':
        return {'creep_gain': rng.uniform(0.04, 0.08)}
    if cause == 'rate_dependence':
        return {'eddy_time_constant_s': rng.uniform(0.003, 0.008)}
    if cause == 'thermal_drift':
        return {'thermal_gain_m_per_a2': rng.uniform(0.8e-6, 1.5e-6)}
    if cause == 'dead_time':
        return {'dead_time_s': rng.uniform(0.005, 0.015)}
    return {}


def _zeroed_in_operation(cfg):
    # Issue 9's reconfigured actuator reads 0 m at the lowest current of its range on its
    # major loop: the sensor was zeroed after 0 A -> 1.8 A -> 0.2 A.  Returns the reading
    # there of the effect-free actuator, to subtract (a local helper: the actuator's own
    # sensor-zero option is another change).
    keep = ('displacement_scale_m', 'coercive_current_a', 'coercive_spread_a',
            'interaction_center_a', 'interaction_spread_a', 'reversible_fraction',
            'reversible_current_scale_a', 'map_linear_fraction', 'map_knee',
            'threshold_min_a', 'threshold_max_a', 'relay_grid_size')
    clean = ActuatorConfig(**{k: getattr(cfg, k) for k in keep})
    path = np.array([0.0, ZERO_PEAK, ZERO_CURRENT])
    return float(MagnetostrictiveActuator(clean).simulate(np.arange(3.0), path)[-1])


def _experiment(cause, seed, *, zeroed=False, validation_zero=0.0):
    # Training: identification excitation; validation: a separate experiment with the
    # diagnostic structure (paired holds, bursts at seven frequencies).  zeroed: the sensor
    # reads 0 at 0.2 A; validation_zero [m]: the validation record's own sensor zero.
    cfg = ActuatorConfig(noise_std_m=NOISE, **_strength(cause, np.random.default_rng(seed)))
    shift = _zeroed_in_operation(cfg) if zeroed else 0.0
    t, x = identification_excitation(DURATION, seed=seed, **EXCITATION)
    tv, xv = diagnostic_excitation(sample_rate=1000.0, seed=seed + 10)
    recs = []
    for k, (tk, xk) in enumerate(((t, x), (tv, xv))):
        y = MagnetostrictiveActuator(cfg, seed=seed + 100 + k).simulate(tk, xk) - shift
        recs.append(Recording(tk, xk, y + (validation_zero if k else 0.0),
                              source=f'{cause}-{k}'))
    return recs


@pytest.mark.parametrize('cause, seed', [(c, s) for c in ('none', 'creep', 'rate_dependence',
                                                          'thermal_drift', 'dead_time')
                                         for s in (1, 2)])
def test_diagnose_names_the_hidden_effect(cause, seed):
    train, val = _experiment(cause, seed)
    report = diagnose(train, validation=val)
    assert report.cause == cause, report.decision['steps']
    if cause == 'none':
        assert report.gain == 0.0
    else:
        assert report.gain > 0.05
        assert report.extended.rms_error < report.baseline.rms_error
        chosen = next(c for c in report.candidates if c.cause == cause)
        assert chosen.signature == 'present' and chosen.significant
        assert report.extended.cause == cause and report.extended.parameters == chosen.parameters
    assert report.baseline['rms_error'] > 0.0       # the truth is not an MPI model
    json.dumps(report.to_json())


def test_an_effect_its_fit_switched_off_is_the_baseline_itself():
    # Each effect nests the baseline: a candidate whose fit switched its effect off (a lag
    # or a dead time of 0) is the baseline model, so its validation gain and its z are 0
    # exactly (the effect fit's own Gamma, another fit of the same record, gained down to
    # -0.36 on the wide sweep's Preisach plants).
    train, val = _experiment('none', 1)
    report = diagnose(train, validation=val)
    off = [c for c in report.candidates
           if c.parameters.get('model.rate_dependence.time_constant') == 0.0
           or c.parameters.get('model.dead_time') == 0.0]
    assert off, [c.parameters for c in report.candidates]
    for c in off:
        assert c.gain == 0.0 and c.z == 0.0, c
        assert c.rms_error == report.baseline.rms_error


@pytest.mark.parametrize('switched_off', [None, 'creep'])
def test_a_pair_whose_fit_switched_an_effect_off_is_not_that_pair(monkeypatch, switched_off):
    """
    A creep + lag plant: the pair is named; a pair fit with creep off is the lag alone.

    On a fresh plant of the wide sweep (seed 407, a lag on a Preisach core) the pair of the
    lag and a thermal drift was named with gain 0.34 while its fit had switched the drift
    off: the lag alone on another Gamma, a drift the plant does not have.  Here the pair's
    fit is made to switch creep off; the diagnosis must say so and not name the pair.
    """
    module = importlib.import_module('mpi_ros.diagnosis.diagnose')
    real = module.fit_composite

    def fit(t, x, y, names, **kwargs):
        model = real(t, x, y, names, **kwargs)
        if switched_off is None:
            return model
        params = model.to_params()
        params['model.creep.weights'] = [0.0] * len(params['model.creep.weights'])
        return extended_model_from_params(params)
    monkeypatch.setattr(module, 'fit_composite', fit)
    cfg = ActuatorConfig(noise_std_m=NOISE, creep_gain=0.06, eddy_time_constant_s=0.006)
    t, x = identification_excitation(DURATION, seed=5, **EXCITATION)
    tv, xv = diagnostic_excitation(sample_rate=1000.0, seed=15)
    train, val = (Recording(tk, xk, MagnetostrictiveActuator(cfg, seed=105 + k).simulate(tk, xk))
                  for k, (tk, xk) in enumerate(((t, x), (tv, xv))))
    report = diagnose(train, validation=val)
    pair = next(c for c in report.candidates if c.parts)
    said = [s for s in report.decision['steps'] if s.startswith(pair.cause)]
    if switched_off is None:
        assert report.cause == 'creep + rate_dependence' and pair.significant, said
        assert 'switched' not in said[0]
    else:
        assert report.cause != pair.cause and not pair.significant
        assert 'its fit switched creep off, so it is not this pair' in said[0], said


@pytest.mark.parametrize('cause', ['none', 'creep', 'rate_dependence', 'thermal_drift',
                                   'dead_time'])
def test_diagnose_with_the_sensor_zeroed_in_operation(cause):
    # Issue 9: the actuator reads 0 um at its lowest current, the validation record has its
    # own sensor zero (+7 um).  Only that offset is re-estimated (reported); every cause
    # is named with gain >= 0.2, none on noise only.  Seed 3 here; seeds 1-3 in
    # benchmarks/eval_diagnosis.py (docs/diagnosis.md).
    train, val = _experiment(cause, 3, zeroed=True, validation_zero=VALIDATION_ZERO)
    report = diagnose(train, validation=val)
    assert report.cause == cause, report.decision['steps']
    assert report.gain == 0.0 if cause == 'none' else report.gain >= 0.2
    assert report.data['output_offset_reestimated']
    shift = report.baseline['validation_output_offset']
    assert abs(shift - VALIDATION_ZERO) < ZERO_TOLERANCE, shift
    for c in report.candidates:
        assert abs(c.validation_output_offset - VALIDATION_ZERO) < ZERO_TOLERANCE
    assert 'sensor zero' in report.evidence and f'{shift:+.3g} m' in report.evidence
    assert report.baseline['rms_error'] < 0.1 * report.baseline['linear_rms_error']


def test_verdict_does_not_depend_on_the_zero_or_the_sign():
    # Another validation zero changes only the re-estimated offset; a falling sensor with
    # another zero in both records gives the same verdict and gains (same model up to the
    # operating point).
    train, val = _experiment('dead_time', 5, zeroed=True)
    options = {'order': (8, 4), 'causes': ('rate_dependence', 'dead_time')}
    reference = diagnose(train, validation=val, **options)
    assert reference.cause == 'dead_time'
    moved = diagnose(train, validation=Recording(val.time, val.current,
                                                 val.displacement - 2e-5), **options)
    assert moved.baseline['validation_output_offset'] == pytest.approx(
        reference.baseline['validation_output_offset'] - 2e-5, abs=1e-12)
    falling = diagnose(Recording(train.time, train.current, 1e-4 - train.displacement),
                       validation=Recording(val.time, val.current, 3e-4 - val.displacement),
                       **options)
    assert falling.data['output_sign'] == -1 and falling.model.model.output_sign == -1
    for report in (moved, falling):
        assert report.cause == reference.cause
        for a, b in zip(report.candidates, reference.candidates):
            assert a.gain == pytest.approx(b.gain, abs=1e-6)
            assert a.rms_error == pytest.approx(b.rms_error, rel=1e-6)


def test_validation_from_another_device_is_refused():
    # A validation record that a straight line explains better than the training
    # data's MPI model (here a linear sensor) is refused, not diagnosed.
    train, val = _experiment('none', 6)
    line = Recording(val.time, val.current, 2e-5 * val.current)
    with pytest.raises(IdentificationError, match='no better than a straight line'):
        diagnose(train, validation=line, order=(8, 4), causes=('dead_time',))


def test_bag_to_diagnose_report_and_params(tmp_path):
    train, val = _experiment('dead_time', 5)
    for name, rec in (('train', train), ('val', val)):
        write_bag_signals(tmp_path / name, rec.time, rec.current, rec.displacement)
    report = diagnose(read_signals(tmp_path / 'train'), validation=read_signals(
        tmp_path / 'val'))
    assert report.cause == 'dead_time'
    files = write_report(report, tmp_path / 'report')
    names = {p.name for p in files}
    assert {'summary.md', 'loops.png', 'residual.png', 'signature_dead_time.png'} <= names
    write_json(report, tmp_path / 'report.json')
    assert json.loads((tmp_path / 'report.json').read_text())['cause'] == 'dead_time'
    write_extended_params(report, tmp_path / 'extended.yaml')
    model = extended_model_from_params(read_params_yaml(tmp_path / 'extended.yaml'))
    assert model.cause == 'dead_time'
    assert abs(model.dead_time - report.extended.parameters['model.dead_time']) < 1e-12


def test_split_without_validation_scores_only_the_tail():
    train, _ = _experiment('none', 6)
    report = diagnose(train, split=0.6, causes=('dead_time',))
    assert report.data['training_samples'] == int(round(0.6 * len(train)))
    assert report.cause == 'none'


def test_butterfly_is_outside_the_invertible_class():
    t = np.linspace(0.0, 4.0, 1601)
    v = np.interp(t, [0, 1, 3, 4], [0.0, 1.0, -1.0, 0.0])          # bipolar triangle
    d = np.abs(v) ** 1.5 + 0.1 * np.gradient(v, t) * np.abs(v)     # butterfly-like
    check = check_invertible_class(v, d)
    assert not check.inside and 0.2 < check.reversal_ratio < 0.8
    report = diagnose(Recording(t, v, d), split=0.5)
    assert report.cause == 'outside_invertible_class'
    assert 'butterfly' in report.evidence


def test_falling_output_is_reported_with_the_sign_hint():
    t = np.linspace(0.0, 4.0, 1601)
    v = np.interp(t, [0, 1, 3, 4], [0.0, 1.0, -1.0, 0.0])
    check = check_invertible_class(v, -v)
    assert not check.inside and check.reversal_ratio > 0.8
    assert 'flip the sign' in check.reason


def test_bad_options_raise():
    train, _ = _experiment('none', 7)
    with pytest.raises(DataError, match='unknown cause'):
        diagnose(train, causes=('magic',))
    with pytest.raises(DataError, match='split must be'):
        diagnose(train, split=0.99)


@pytest.mark.skipif(not REAL_DATA.is_dir(), reason='shared measured data not present')
def test_real_butterfly_data_is_outside_the_class():
    from mpi_ros.recordings import read_csv_signals
    rec = read_csv_signals(REAL_DATA / 'Serie1_butterfly_0p5Hz.csv', time_column=None,
                           input_column='V_1600V_V', output_column='D1_1600V_nm',
                           output_scale=1e-9)
    report = diagnose(Recording(rec.time * 0.005, rec.current, rec.displacement), split=0.5)
    assert report.cause == 'outside_invertible_class'


def test_time_base_warning_names_only_the_implausible_values():
    from mpi_ros.diagnosis.time_base import implausible_time_constants, time_base_warning
    candidates = [
        {'cause': 'creep', 'parameters': {'model.creep.time_constants': [0.01, 2e4],
                                          'model.creep.weights': [0.0, 0.1]}},
        {'cause': 'rate_dependence', 'parameters': {'model.rate_dependence.time_constant': 0.004}},
        {'cause': 'thermal_drift', 'parameters': {'model.thermal_drift.time_constant': 900.0,
                                                  'model.thermal_drift.weight': 1.0}},
        {'cause': 'dead_time', 'parameters': {'model.dead_time': 20.6}}]
    residual = {'lag_of_best_correlation': -3.0,
                'burst_signature': {'delay': 0.01, 'lag_time_constant': 0.002}}
    found = implausible_time_constants(candidates, residual)
    assert found == [('model.creep.time_constants (largest) of the creep candidate', 2e4, 1e4),
                     ('model.dead_time of the dead_time candidate', 20.6, 1.0),
                     ('lag of the best rate correlation', 3.0, 1.0)]
    text = time_base_warning(found, [('record', np.arange(60001.0))])
    assert 'model.dead_time of the dead_time candidate 20.6 s (plausible: up to 1 s)' in text
    assert 'the record has a sample period of 1 s and lasts 6e+04 s (60001 samples)' in text
    assert 'pass --time-scale 1e-3' in text and '\n' not in text
    plausible = [{'cause': 'dead_time', 'parameters': {'model.dead_time': 0.0206}}]
    assert implausible_time_constants(plausible, {'lag_of_best_correlation': 0.02}) == []
    assert time_base_warning([], [('record', np.arange(10.0))]) is None


def test_validation_below_the_arithmetic_is_refused_not_divided_by_zero():
    """A subnormal validation record: its squared residuals were 0, the gain 0/0 (a crash)."""
    t, x = identification_excitation(1.5, sample_rate=400.0, seed=1, holds=False,
                                     bursts=False, ramp_duration=0.05)
    y = MagnetostrictiveActuator().simulate(t, x)
    with pytest.raises(DataError, match=r'validation: the current spans only 1.8e-310 A, too '
                                        r'small to compute with'):
        diagnose(Recording(t, x, y), validation=Recording(t, 1e-310 * x, 1e-310 * y),
                 order=(4, 2))
