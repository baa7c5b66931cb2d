# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""The ``mpi-ros`` batch subcommands: identify, simulate, compensate (offline, no DDS)."""

import json
import re

from mpi_ros import identify, MPIModel
from mpi_ros.app.cli import main
from mpi_ros.params import read_params_yaml
from mpi_ros.recordings import read_csv_table, write_bag_signals, write_csv_columns
import numpy as np
import pytest
import yaml

from .core_models import hand_model

PARAMS = hand_model()


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
    assert model.n == 4                          # S' is centred on the output's operating
    assert model.superposition.thresholds.size == 5   # point: 2l+1 thresholds (issue 9)
    assert model.to_params()['model.output_offset'] != 0.0
    fit = json.loads((tmp / 'fit.json').read_text())
    assert fit['order'] == [4, 2] and fit['samples'] == current.size
    core = identify(current, displacement, n=4, l=2)        # the CLI reports the core's fit
    assert fit['nonlinearity_error'] == pytest.approx(core.nonlinearity_error, rel=1e-9)
    assert fit['rms_error'] == pytest.approx(core.rms_error, rel=1e-9)
    err = capsys.readouterr().err
    assert 'nonlinearity error (37)' in err and 'operating point: input offset' in err


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
    assert main([]) == 1                         # a usage error: exit status 1, as README says
    captured = capsys.readouterr()
    assert 'identify' in captured.out
    assert captured.err.strip().splitlines()[-1] == 'error: give a COMMAND (see the list above)'


# ------------------------------------------------------------------ data options, order


def _fit(tmp, source, *extra):
    out = tmp / f'{len(list(tmp.iterdir()))}.yaml'
    rc = main(['identify', str(source), '-o', str(out), *extra])
    return rc, out


def test_identify_from_joint_state_and_array_bags(recording, capsys):
    from .message_bags import write_array_signals, write_joint_state_signals
    tmp, t, current, displacement = recording
    core = MPIModel.from_params(read_params_yaml(_fit(tmp, tmp / 'bag', '--order', '4,2')[1]))
    write_joint_state_signals(tmp / 'js', t, current, displacement)
    rc, out = _fit(tmp, tmp / 'js', '--order', '4,2', '--input-topic', '/joint_states',
                   '--output-topic', '/joint_states', '--input-joint', 'actuator',
                   '--input-field', 'effort', '--output-joint', 'actuator')
    assert rc == 0, capsys.readouterr().err
    assert MPIModel.from_params(read_params_yaml(out)).to_params() == core.to_params()
    write_array_signals(tmp / 'arr', t, current, 1e9 * displacement, storage='mcap')
    rc, out = _fit(tmp, tmp / 'arr', '--order', '4', '2', '--input-topic', '/command',
                   '--output-topic', '/measurement', '--input-index', '1', '--output-index',
                   '0', '--output-scale', '1e-9')
    assert rc == 0, capsys.readouterr().err
    model = MPIModel.from_params(read_params_yaml(out))
    np.testing.assert_allclose(model.simulate(current), core.simulate(current), rtol=0,
                               atol=1e-6 * np.ptp(displacement))


@pytest.mark.parametrize('extra, needle', [
    (['--input-topic', '/joint_states', '--output-topic', '/joint_states', '--input-joint',
      'elbow', '--output-joint', 'actuator', '--input-field', 'effort'],
     "it has no joint 'elbow' (--input-joint); joints found: 'wrist', 'actuator'; set "
     '--input-joint to one of them'),
    (['--input-topic', '/joint_states', '--output-topic', '/joint_states', '--input-field',
      'effort', '--output-joint', 'actuator'],
     "it holds 2 joints ('wrist', 'actuator') and --input-joint is not set"),
    (['--input-topic', '/nope'], 'pass --input-topic <topic> with one of them'),
    (['--input-topic', '/joint_states', '--output-topic', '/joint_states', '--input-index',
      '0'], '--input-index does not apply to topic /joint_states'),
    (['--output-scale', '0'], '--output-scale must be a finite non-zero number; found 0.0'),
    (['--output-scale', 'nan'], '--output-scale must be a finite non-zero number; found nan'),
    (['--order', '4,0'], "--order takes 'auto' or two whole numbers N, L >= 1 written N,L or "
                         "N L (e.g. 14,7); found '4,0'"),
    (['--order', '4', '2', '1'], "found '4 2 1'"),
])
def test_identify_errors_name_the_command_line_options(recording, capsys, extra, needle):
    from .message_bags import write_joint_state_signals
    tmp, t, current, displacement = recording
    write_joint_state_signals(tmp / 'js', t, current, displacement)
    source = tmp / ('js' if '/joint_states' in extra else 'bag')
    rc, out = _fit(tmp, source, *extra)
    err = capsys.readouterr().err
    assert rc == 1
    last = err.strip().splitlines()[-1]
    assert last.startswith('error: ') and needle in last, err
    for keyword in ('np.', 'input_topic', 'input_joint', 'input_index', 'output_scale'):
        assert keyword not in last, last
    assert not re.search(r'\b[a-z_]{2,}=', last), last       # no Python keyword argument
    assert not out.exists()


def test_identify_nonfinite_hint_and_drop_option(recording, capsys):
    tmp, t, current, displacement = recording
    broken = displacement.copy()
    broken[1000] = np.nan
    write_bag_signals(tmp / 'nan', t, current, broken)
    rc, out = _fit(tmp, tmp / 'nan', '--order', '4,2')
    assert rc == 1
    last = capsys.readouterr().err.strip().splitlines()[-1]
    assert 'fix the publisher or pass --drop-nonfinite' in last
    assert 'drop_nonfinite' not in last
    rc, out = _fit(tmp, tmp / 'nan', '--order', '4,2', '--drop-nonfinite')
    assert rc == 0 and out.exists()


def test_identify_drops_empty_csv_fields_with_the_option(recording, capsys):
    """Empty fields (how pandas writes NaN): --drop-nonfinite drops the rows, with a note."""
    tmp, t, current, displacement = recording
    lines = (tmp / 'rec.csv').read_text().splitlines()        # line k + 2: sample k
    for k, column in ((700, 1), (1500, 2), (2500, 0)):
        fields = lines[k + 1].split(',')
        fields[column] = ''
        lines[k + 1] = ','.join(fields)
    (tmp / 'pandas.csv').write_text('\n'.join(lines) + '\n')
    rc, out = _fit(tmp, tmp / 'pandas.csv', '--order', '4,2')
    assert rc == 1 and not out.exists()
    last = capsys.readouterr().err.strip().splitlines()[-1]
    assert last.startswith('error: CSV file ') and "the first at line 702, column 'current' " \
        '(an empty field); fix the data or pass --drop-nonfinite to drop those rows' in last
    rc, out = _fit(tmp, tmp / 'pandas.csv', '--order', '4,2', '--drop-nonfinite')
    assert rc == 0 and out.exists()
    err = capsys.readouterr().err
    assert 'note: dropped 3 row(s) with non-finite values (NaN, Inf or empty fields)' in err
    assert f'identifying from {t.size - 3} samples' in err


@pytest.mark.parametrize('argv, needle', [
    (['identify', '{tmp}/rec.csv'], 'error: mpi-ros identify: the following arguments are '
                                    'required: -o/--output'),
    (['identify', '{tmp}/rec.csv', '-o', '{tmp}/p.yaml', '--bogus'],
     'error: mpi-ros: unrecognized arguments: --bogus'),
    (['identify', '{tmp}/rec.csv', '-o', '{tmp}/p.yaml', '--input-field', 'torque'],
     "error: mpi-ros identify: argument --input-field: invalid choice: 'torque'"),
    (['identify', '{tmp}/rec.csv', '-o', '{tmp}/p.yaml', '--input-index', 'x'],
     "error: mpi-ros identify: argument --input-index: invalid int value: 'x'"),
    (['simulate', '{tmp}/p.yaml'],
     'error: mpi-ros simulate: the following arguments are required: --input, --output'),
    (['nonsense'], "error: mpi-ros: argument COMMAND: invalid choice: 'nonsense'"),
    (['demo', '--effect', 'x'], "error: mpi-ros demo: argument --effect: invalid choice: 'x'"),
])
def test_usage_errors_exit_1(recording, capsys, argv, needle):
    tmp = recording[0]
    assert main([a.format(tmp=tmp) for a in argv]) == 1
    err = capsys.readouterr().err
    assert err.startswith('usage: mpi-ros')
    assert err.strip().splitlines()[-1].startswith(needle), err
    assert not (tmp / 'p.yaml').exists()


def test_diagnose_shares_the_data_options(recording, capsys):
    tmp = recording[0]
    argv = ['diagnose', str(tmp / 'rec.csv'), '--json', str(tmp / 'r.json'), '--report',
            str(tmp / 'r')]
    assert main([*argv, '--input-index', '-1']) == 1
    assert capsys.readouterr().err.strip().splitlines()[-1] == (
        'error: --input-index must be a whole number >= 0 (0 is the first element); found -1')
    assert main([*argv, '--input-topic', '/nope', '--order', '4,0']) == 1
    assert "error: --order takes 'auto'" in capsys.readouterr().err
    assert not (tmp / 'r.json').exists()


def test_compensate_then_simulate_needs_the_right_column(recording, capsys):
    """Simulate on compensate's output (time, desired, current) must not take 'desired'."""
    from mpi_ros.params import write_params_yaml
    tmp, t, current, _ = recording
    write_params_yaml(tmp / 'model.yaml', PARAMS)
    desired = MPIModel.from_params(PARAMS).simulate(current)
    write_csv_columns(tmp / 'desired.csv', {'time': t, 'desired': desired})
    assert main(['compensate', str(tmp / 'model.yaml'), '--input', str(tmp / 'desired.csv'),
                 '--output', str(tmp / 'cmd.csv')]) == 0
    capsys.readouterr()
    assert main(['simulate', str(tmp / 'model.yaml'), '--input', str(tmp / 'cmd.csv'),
                 '--output', str(tmp / 'sim.csv')]) == 1
    last = capsys.readouterr().err.strip().splitlines()[-1]
    assert last == (f'error: --input {tmp / "cmd.csv"} has 2 columns besides the time '
                    '(desired, current); pass --input-column with the one holding the current')
    assert not (tmp / 'sim.csv').exists()
    assert main(['simulate', str(tmp / 'model.yaml'), '--input', str(tmp / 'cmd.csv'),
                 '--input-column', 'current', '--output', str(tmp / 'sim.csv')]) == 0
    header, sim = read_csv_table(tmp / 'sim.csv')
    assert header == ['time', 'current', 'displacement']
    np.testing.assert_allclose(sim[:, 2], desired, rtol=0, atol=1e-12 * np.ptp(desired))
    for argv, needle in (
            (['--input-column', 'volts'], '--input-column volts: --input'),
            (['--input-column', 'current', '--column-name', 'current'],
             '--column-name current: the result column would replace the input column'),
            (['--input-column', 'current', '--time-column', 'T'],
             '--time-column T: --input'),
    ):
        assert main(['simulate', str(tmp / 'model.yaml'), '--input', str(tmp / 'cmd.csv'),
                     '--output', str(tmp / 'o.csv'), *argv]) == 1
        assert needle in capsys.readouterr().err
    assert not (tmp / 'o.csv').exists()


def test_node_name_is_honoured(recording, capsys):
    tmp, t, current, _ = recording
    write_csv_columns(tmp / 'in.csv', {'time': t, 'current': current})
    assert main(['identify', str(tmp / 'rec.csv'), '--order', '4,2', '--node-name', 'foo',
                 '-o', str(tmp / 'foo.yaml')]) == 0
    assert list(yaml.safe_load((tmp / 'foo.yaml').read_text())) == ['foo']
    args = ['--input', str(tmp / 'in.csv'), '--output', str(tmp / 'sim.csv')]
    assert main(['simulate', str(tmp / 'foo.yaml'), '--node-name', 'foo', *args]) == 0
    capsys.readouterr()
    assert main(['simulate', str(tmp / 'foo.yaml'), '--node-name', 'bar', *args]) == 1
    assert capsys.readouterr().err.strip().splitlines()[-1] == (
        f"error: --node-name bar: parameter file {tmp / 'foo.yaml'} has no entry for node "
        "'bar'; entries found: foo; pass --node-name with one of them, or leave it out")


def test_identify_cli_and_pipeline_give_the_same_model(recording):
    # One pipeline: the CLI's model is fit_recording's, key for key.
    from mpi_ros.pipeline import fit_recording
    tmp, _, _, _ = recording
    assert main(['identify', str(tmp / 'rec.csv'), '--order', '4,2', '-o',
                 str(tmp / 'p.yaml')]) == 0
    from mpi_ros.pipeline import identified_parameters
    from mpi_ros.recordings import DataOptions
    fit = fit_recording(tmp / 'rec.csv', DataOptions(), order=(4, 2))
    # Issue 27: what identify writes is identified_parameters (the identifier pushes it).
    written = read_params_yaml(tmp / 'p.yaml')
    fitted = identified_parameters(fit.result, fit.recording)
    assert set(written) == set(fitted)
    assert set(fit.result.model.to_params()) <= set(fitted)
    assert written['model.input_quantity'] == fitted['model.input_quantity'] == 'current'
    for key, value in fitted.items():
        if key != 'model.input_quantity':
            np.testing.assert_allclose(written[key], value, rtol=1e-12, err_msg=key)
