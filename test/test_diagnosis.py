# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""Diagnosis tests: hide one effect in the simulated actuator, diagnose must name it."""

import json
from pathlib import Path

from mpi_ros.actuator import ActuatorConfig, MagnetostrictiveActuator
from mpi_ros.diagnosis import check_invertible_class, diagnose, write_report
from mpi_ros.diagnosis.report import write_extended_params, write_json
from mpi_ros.diagnosis.signatures import diagnostic_excitation
from mpi_ros.errors import DataError
from mpi_ros.excitation import identification_excitation
from mpi_ros.extensions import extended_model_from_params
from mpi_ros.params import read_params_yaml
from mpi_ros.recordings import read_signals, Recording, write_bag_signals
import numpy as np
import pytest

# Identification-style excitation with long holds (creep) and fast bursts (lag vs delay).
EXCITATION = {'sample_rate': 1000.0, 'burst_frequency': 40.0, 'hold_duration': 5.0}
DURATION = 60.0
NOISE = 2e-8          # [m], 0.05 % of the 40 um stroke
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


def _experiment(cause, seed):
    # Training: identification excitation; validation: a separate experiment with the
    # diagnostic structure (paired holds, bursts at seven frequencies).
    cfg = ActuatorConfig(noise_std_m=NOISE, **_strength(cause, np.random.default_rng(seed)))
    t, x = identification_excitation(DURATION, seed=seed, **EXCITATION)
    tv, xv = diagnostic_excitation(sample_rate=1000.0, seed=seed + 10)
    recs = []
    for k, (tk, xk) in enumerate(((t, x), (tv, xv))):
        y = MagnetostrictiveActuator(cfg, seed=seed + 100 + k).simulate(tk, xk)
        recs.append(Recording(tk, xk, y, source=f'{cause}-{k}'))
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
        assert report.extended['rms_error'] < report.baseline['rms_error']
        chosen = next(c for c in report.candidates if c['cause'] == cause)
        assert chosen['signature'] == 'present' and chosen['significant']
    assert report.baseline['rms_error'] > 0.0       # the truth is not an MPI model
    json.dumps(report.to_json())


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
    assert abs(model.dead_time - report.extended['parameters']['model.dead_time']) < 1e-12


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
