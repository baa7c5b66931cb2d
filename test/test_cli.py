# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""The ``mpi-ros`` batch subcommands: identify, simulate, compensate (offline, no DDS)."""

import json

from mpi_ros import identify, MPIModel
from mpi_ros.cli import main
from mpi_ros.params import read_params_yaml
from mpi_ros.recordings import read_csv_table, write_bag_signals, write_csv_columns
import numpy as np
import pytest

PARAMS = {
    'model.hysteresis.thresholds': [0.0, 0.4, 0.8, 1.2],
    'model.hysteresis.weights': [1.0, 0.3, 0.2, 0.1],
    'model.hysteresis.initial_states': [0.0, 0.0, 0.0, 0.0],
    'model.superposition.thresholds': [0.0, 0.5, 1.0],
    'model.superposition.weights': [2e-5, -0.5e-5, 0.3e-5],
}


@pytest.fixture()
def recording(tmp_path):
    t = np.linspace(0.0, 20.0, 4001)
    current = 1.0 + 0.8 * np.sin(2 * np.pi * 0.5 * t) * np.exp(-t / 15.0)
    current[:200] = np.linspace(0.0, current[200], 200)
    displacement = MPIModel.from_params(PARAMS).simulate(current)
    write_csv_columns(tmp_path / 'rec.csv', {'time': t, 'current': current,
                                             'displacement': displacement})
    write_bag_signals(tmp_path / 'bag', t, current, displacement)
    return tmp_path, t, current, displacement


@pytest.mark.parametrize('source', ['rec.csv', 'bag'])
def test_identify_writes_params_and_json(recording, source, capsys):
    tmp, _, current, displacement = recording
    rc = main(['identify', str(tmp / source), '--order', '4', '2', '-o', str(tmp / 'p.yaml'),
               '--json', str(tmp / 'fit.json')])
    assert rc == 0
    model = MPIModel.from_params(read_params_yaml(tmp / 'p.yaml'))
    assert model.n == 4                          # the output never goes negative, so S has
    assert model.superposition.thresholds.size == 3   # only its 0 and positive thresholds
    fit = json.loads((tmp / 'fit.json').read_text())
    assert fit['order'] == [4, 2] and fit['samples'] == current.size
    core = identify(current, displacement, n=4, l=2)        # the CLI reports the core's fit
    assert fit['nonlinearity_error'] == pytest.approx(core.nonlinearity_error, rel=1e-9)
    assert fit['rms_error'] == pytest.approx(core.rms_error, rel=1e-9)
    assert 'nonlinearity error (37)' in capsys.readouterr().err


def test_simulate_then_compensate_round_trip(recording):
    tmp, t, current, _ = recording
    from mpi_ros.params import write_params_yaml
    write_params_yaml(tmp / 'model.yaml', PARAMS)
    write_csv_columns(tmp / 'in.csv', {'time': t, 'current': current})
    assert main(['simulate', str(tmp / 'model.yaml'), '--input', str(tmp / 'in.csv'),
                 '--output', str(tmp / 'sim.csv')]) == 0
    header, sim = read_csv_table(tmp / 'sim.csv')
    assert header == ['time', 'current', 'displacement']
    write_csv_columns(tmp / 'desired.csv', {'time': t, 'desired': sim[:, 2]})
    assert main(['compensate', str(tmp / 'model.yaml'), '--input', str(tmp / 'desired.csv'),
                 '--output', str(tmp / 'cmd.csv')]) == 0
    header, cmd = read_csv_table(tmp / 'cmd.csv')
    assert header == ['time', 'desired', 'current']
    np.testing.assert_array_equal(cmd[:, 0], t)                      # time passes through
    np.testing.assert_allclose(cmd[:, 2], current, atol=1e-12)       # Gamma^-1[Gamma[x]] = x


@pytest.mark.parametrize('argv, match', [
    (['identify', '{tmp}/missing.csv', '-o', '{tmp}/p.yaml'], 'does not exist'),
    (['identify', '{tmp}/rec.csv', '--order', '3', '-o', '{tmp}/p.yaml'], '--order takes'),
    (['identify', '{tmp}/rec.csv', '--order', '2000', '1000', '-o', '{tmp}/p.yaml'],
     'too few samples'),
    (['simulate', '{tmp}/rec.csv', '--input', '{tmp}/rec.csv', '--output', '{tmp}/o.csv'],
     'ros__parameters'),
])
def test_errors_exit_1_and_write_nothing(recording, argv, match, capsys):
    tmp = recording[0]
    rc = main([a.format(tmp=tmp) for a in argv])
    assert rc == 1
    assert match in capsys.readouterr().err
    assert not (tmp / 'p.yaml').exists() and not (tmp / 'o.csv').exists()


def test_no_command_prints_help(capsys):
    assert main([]) == 2
    assert 'identify' in capsys.readouterr().out
