# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""``mpi-ros diagnose`` options: ``--window`` and ``--excitation`` (exit codes via main)."""

import json

from mpi_ros.app.cli import main
from mpi_ros.plant.actuator import ActuatorConfig, MagnetostrictiveActuator
from mpi_ros.plant.excitation import diagnostic_excitation, identification_excitation
from mpi_ros.recordings import read_csv_table, write_csv_columns
import numpy as np


def test_excitation_is_written_as_csv(tmp_path):
    out = tmp_path / 'excitation.csv'
    assert main(['diagnose', '--excitation', str(out), '--seed', '3']) == 0
    header, table = read_csv_table(out)
    t, current = diagnostic_excitation(sample_rate=1000.0, seed=3)
    assert header == ['time', 'current']
    np.testing.assert_array_equal(table[:, 0], t)
    np.testing.assert_array_equal(table[:, 1], current)


def test_excitation_with_too_low_a_rate_fails(tmp_path, capsys):
    out = tmp_path / 'excitation.csv'
    assert main(['diagnose', '--excitation', str(out), '--excitation-rate', '100']) == 1
    assert 'error: sample_rate' in capsys.readouterr().err
    assert not out.exists()


def test_usage_errors_exit_1(tmp_path, capsys):
    """Usage errors exit with status 1 (README), after the usage and one error line."""
    assert main(['diagnose']) == 1
    err = capsys.readouterr().err
    assert err.startswith('usage: mpi-ros diagnose')
    assert err.strip().splitlines()[-1] == ('error: mpi-ros diagnose: give DATA to diagnose, '
                                            'or --excitation OUT.csv')
    assert main(['diagnose', str(tmp_path / 'data.csv')]) == 1     # no --json/--report
    assert '--json and --report are required with DATA' in capsys.readouterr().err


def _write(path, t, x, cfg, seed):
    y = MagnetostrictiveActuator(cfg, seed=seed).simulate(t, x)
    write_csv_columns(path, {'time': t, 'current': x, 'displacement': y})


def test_window_diagnoses_only_the_window(tmp_path, capsys):
    """DATA starts with 3 s of a saturated sensor; the window keeps the good part."""
    cfg = ActuatorConfig(noise_std_m=2e-8, dead_time_s=0.01)
    t, x = identification_excitation(20.0, sample_rate=1000.0, seed=1)
    y = MagnetostrictiveActuator(cfg, seed=1).simulate(t, x)
    t_bad = np.arange(3000) * 1e-3
    x_bad = 1.0 + 0.5 * np.sin(2.0 * np.pi * t_bad)
    write_csv_columns(tmp_path / 'data.csv', {
        'time': np.concatenate([t_bad, t + 3.0]) + 5.0,           # need not start at 0
        'current': np.concatenate([x_bad, x]),
        'displacement': np.concatenate([np.full(3000, 4.0e-5), y])})
    tv, xv = diagnostic_excitation(sample_rate=1000.0, seed=2, repeats=1, hold_duration=1.5)
    _write(tmp_path / 'val.csv', tv, xv, cfg, 2)
    common = ['--validate', str(tmp_path / 'val.csv'), '--input-column', 'current',
              '--output-column', 'displacement', '--order', '8', '4',
              '--report', str(tmp_path / 'report')]
    argv = ['diagnose', str(tmp_path / 'data.csv'), '--window', '3', '23',
            '--json', str(tmp_path / 'report.json'), *common]
    assert main(argv) == 0
    report = json.loads((tmp_path / 'report.json').read_text())
    assert report['data']['samples'] == t.size
    assert report['data']['source'].endswith('[3 s, 23 s]')
    assert report['cause'] == 'dead_time'
    assert capsys.readouterr().out.strip() == 'dead_time'

    for window in (['10', '5'], ['100', '200']):
        argv = ['diagnose', str(tmp_path / 'data.csv'), '--window', *window,
                '--json', str(tmp_path / 'bad.json'), *common]
        assert main(argv) == 1
        assert 'error: --window' in capsys.readouterr().err
    assert not (tmp_path / 'bad.json').exists()


def test_rig_csv_with_a_falling_sensor_and_its_own_zero(tmp_path, capsys):
    """Volts, nm, a sensor that counts down from -123 um: a report, or a clear refusal."""
    cfg = ActuatorConfig(noise_std_m=2e-8, dead_time_s=0.01)
    t, x = identification_excitation(20.0, sample_rate=1000.0, seed=1)
    y = MagnetostrictiveActuator(cfg, seed=1).simulate(t, x)
    tv, xv = diagnostic_excitation(sample_rate=1000.0, seed=2, repeats=1, hold_duration=1.5)
    yv = MagnetostrictiveActuator(cfg, seed=2).simulate(tv, xv)
    write_csv_columns(tmp_path / 'data.csv', {'time': t, 'volts': 10.0 * x,
                                              'nm': (-123e-6 - y) * 1e9})
    write_csv_columns(tmp_path / 'val.csv', {'time': tv, 'volts': 10.0 * xv,
                                             'nm': (-116e-6 - yv) * 1e9})   # own zero
    common = ['--input-column', 'volts', '--output-column', 'nm', '--input-scale', '0.1',
              '--output-scale', '1e-9', '--order', '8', '4', '--report', str(tmp_path / 'r')]
    argv = ['diagnose', str(tmp_path / 'data.csv'), '--validate', str(tmp_path / 'val.csv'),
            '--json', str(tmp_path / 'report.json'), *common]
    assert main(argv) == 0
    report = json.loads((tmp_path / 'report.json').read_text())
    assert report['cause'] == 'dead_time'
    assert report['data']['output_sign'] == -1
    baseline = report['baseline']
    assert baseline['operating_point']['output_sign'] == -1
    assert baseline['rms_error'] < 0.1 * baseline['linear_rms_error']
    assert abs(baseline['validation_output_offset'] - 7e-6) < 1e-6   # -116 - (-123) um
    assert 'sensor zero' in report['evidence']
    capsys.readouterr()

    # The same rig's validation column swapped for an unrelated linear sensor: refused.
    write_csv_columns(tmp_path / 'line.csv', {'time': tv, 'volts': 10.0 * xv,
                                              'nm': -2e4 * xv - 1.2e5})
    argv = ['diagnose', str(tmp_path / 'data.csv'), '--validate', str(tmp_path / 'line.csv'),
            '--json', str(tmp_path / 'bad.json'), *common]
    assert main(argv) == 1
    assert 'error: the baseline MPI model (n=8, l=4) is no better than a straight line' in \
        capsys.readouterr().err
    assert not (tmp_path / 'bad.json').exists()


def _late_sweep_validation(path, tail, cfg, rate=1000.0, idle=4000):
    """Write a 1 kHz validation: `idle` samples at rest, a sweep over the range, `tail` more."""
    n = idle + 300 + tail
    t = np.arange(n) / rate
    k = np.arange(n - idle)
    x = np.full(n, 1.0)
    sweep = np.interp(k, [0, 75, 225, 300], [1.0, 1.8, 0.2, 1.0])
    loops = 1.0 + 0.6 * np.sin(2.0 * np.pi * (k - 300) / 150.0)
    x[idle:] = np.where(k < 300, sweep, loops)
    _write(path, t, x, cfg, 4)


def test_validation_shorter_than_the_lag_window_is_diagnosed(tmp_path, capsys):
    """
    A validation scored on 190 samples at 1 kHz: the lag window shrinks to what they allow.

    The residual's lag window (0.2 s = 200 samples) was longer than the scored samples and
    np.corrcoef got slices of different lengths (a ValueError traceback, no report).  Since
    issue 17 a validation record that covers its range late is scored from its first
    sample (its start state estimated), so the short record here is most of one sweep,
    190 samples, scored whole.
    """
    cfg = ActuatorConfig(noise_std_m=1e-9)
    t, x = identification_excitation(3.0, sample_rate=400.0, seed=1, holds=False,
                                     bursts=False, ramp_duration=0.05)
    _write(tmp_path / 'train.csv', t, x, cfg, 3)
    _late_sweep_validation(tmp_path / 'val.csv', -110, cfg, idle=0)
    argv = ['diagnose', str(tmp_path / 'train.csv'), '--validate', str(tmp_path / 'val.csv'),
            '--order', '4', '2', '--json', str(tmp_path / 'r.json'),
            '--report', str(tmp_path / 'report')]
    assert main(argv) == 0, capsys.readouterr().err
    report = json.loads((tmp_path / 'r.json').read_text())
    scored = report['data']['validation_samples'] - report['data']['validation_burn_in']
    assert 100 <= scored < 200
    # The lag of the best rate correlation lies inside the shrunk window (half the samples).
    assert abs(report['residual']['lag_of_best_correlation']) <= (scored // 2) * 1e-3 + 1e-12
    assert (tmp_path / 'report' / 'summary.md').exists()
    assert (tmp_path / 'report' / 'signature_dead_time.png').exists()


def test_time_in_ms_read_as_s_is_warned_about(tmp_path, capsys):
    """
    A 19 ms dead time in a time column in ms: '19 s' gets a warning, --time-scale fixes it.

    The column's name says no unit (a name ending in _ms is read in ms, issue 27).
    """
    cfg = ActuatorConfig(noise_std_m=2e-8, dead_time_s=0.0206)
    t, x = identification_excitation(10.0, sample_rate=1000.0, seed=1)
    y = MagnetostrictiveActuator(cfg, seed=1).simulate(t, x)
    write_csv_columns(tmp_path / 'ms.csv', {'t': 1e3 * t, 'current': x, 'displacement': y})
    argv = ['diagnose', str(tmp_path / 'ms.csv'), '--time-column', 't', '--order', '6',
            '3', '--json', str(tmp_path / 'r.json'), '--report', str(tmp_path / 'report')]
    assert main(argv) == 0
    err = capsys.readouterr().err
    report = json.loads((tmp_path / 'r.json').read_text())
    dead_time = next(c for c in report['candidates'] if c['cause'] == 'dead_time')
    assert dead_time['parameters']['model.dead_time'] > 10.0           # "seconds"
    [warning] = report['warnings']
    assert f'warning: {warning}' in err.splitlines()
    assert (f'model.dead_time of the dead_time candidate '
            f'{dead_time["parameters"]["model.dead_time"]:.3g} s') in warning
    assert 'the record has a sample period of 1 s and lasts 1e+04 s (10001 samples)' in warning
    assert 'pass --time-scale 1e-3' in warning
    assert warning in (tmp_path / 'report' / 'summary.md').read_text()
    # The reading's own check (mpi_ros.units) names the unit option.
    assert any(line.startswith('warning: the samples are 1 s apart') and
               '--time-unit ms' in line for line in err.splitlines())

    assert main([*argv, '--time-scale', '1e-3']) == 0
    assert 'warning:' not in capsys.readouterr().err
    report = json.loads((tmp_path / 'r.json').read_text())
    assert report['warnings'] == []
    dead_time = next(c for c in report['candidates'] if c['cause'] == 'dead_time')
    assert 0.015 < dead_time['parameters']['model.dead_time'] < 0.025
