# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Fuzz the command line: ``mpi-ros identify|diagnose|simulate|compensate`` on odd records.

Each run of a command either exits 0 with a sane result (files that read back, finite
numbers) or exits 1 with exactly one ``error: ...`` line, the last on stderr; never a
traceback, never another status (issue 17).  The records are generated from one good,
seeded actuator record: empty files, a header only, 1-5 rows, constant columns, NaN, Inf
and empty fields, text in numeric columns, non-increasing and duplicated time, magnitudes
from 1e-12 to 1e12 (and 1e+-300), one spike, noise without relation between input and
output, reversed signs, extra columns, other delimiters, a BOM, CRLF, time in ms or us,
... and `diagnose --validate` gets validation records of every length from 0 past the
diagnosis' minimum, and across its residual lag window.

The commands run in-process through :func:`mpi_ros.app.cli.main` (as the console script does)
so that several hundred runs take seconds.  The diagnosis' report plots are not rendered
there (``report._save`` only closes the figure; the plotting code itself still runs):
rendering six PNGs takes about 1.3 s per report.  A few cases run as real processes of
``python -m mpi_ros.app.cli`` with the plots rendered.
"""

import contextlib
import io
import json
import math
from pathlib import Path
import shutil
import subprocess
import sys
import traceback

from hypothesis import given, HealthCheck, settings, strategies as st
from mpi_ros.app.cli import main
from mpi_ros.diagnosis import report as diagnosis_report
from mpi_ros.diagnosis.diagnose import CAUSES
from mpi_ros.errors import DataError
from mpi_ros.extensions import EFFECTS
from mpi_ros.operators.model import MPIModel
from mpi_ros.params import read_params_yaml
from mpi_ros.plant.actuator import ActuatorConfig, MagnetostrictiveActuator
from mpi_ros.plant.excitation import identification_excitation
from mpi_ros.recordings import read_csv_table, read_recording, write_bag_signals, \
    write_csv_columns
import numpy as np
import pytest

#: Verdicts a diagnosis may give.
VERDICTS = {*CAUSES, 'none', 'outside_invertible_class'}
#: Order of every fit here: small, so that hundreds of runs stay quick.
ORDER = ['--order', '4', '2']
HEADER = ['time', 'current', 'displacement']
SEED = 17


def _signals(seconds=3.0, rate=400.0, seed=1):
    """Return a good record: time [s], current [A], displacement [m] (noise 1 nm)."""
    t, x = identification_excitation(seconds, sample_rate=rate, seed=seed, holds=False,
                                     bursts=False, ramp_duration=0.05)
    y = MagnetostrictiveActuator(ActuatorConfig(noise_std_m=1e-9), seed=seed).simulate(t, x)
    return t, x, y


def _text(header, rows, sep=',', newline='\n'):
    return newline.join([sep.join(header)] + [sep.join(row) for row in rows]) + newline


def _rows(*columns):
    return [[repr(float(v)) for v in row] for row in zip(*columns)]


def _edited(rows, edits):
    """Return a copy of `rows` with {(row, column): text} applied."""
    out = [list(row) for row in rows]
    for (row, column), value in edits.items():
        out[row][column] = value
    return out


def bad_records(rng, t, x, y):
    """
    Return (name, bytes) of odd CSV records derived from a good one.

    Parameters
    ----------
    rng : numpy.random.Generator
        Picks the rows and columns that are spoiled.
    t, x, y : ndarray of float, shape (N,)
        The good record.

    Returns
    -------
    list of (str, bytes)
        The records, each a CSV file's content.

    """
    n = t.size
    good = _rows(t, x, y)
    cases = [('empty', b''), ('blank lines', b'\n \n\t\n'), ('comments only', b'# a\n# b\n'),
             ('header only', _text(HEADER, [])),
             *[(f'{k} row(s)', _text(HEADER, good[:k])) for k in (1, 2, 3, 4, 5, 9, 10, 50)],
             ('constant current', _text(HEADER, _rows(t, np.full(n, 1.0), y))),
             ('constant displacement', _text(HEADER, _rows(t, x, np.full(n, 2e-6)))),
             ('constant time', _text(HEADER, _rows(np.full(n, 1.0), x, y))),
             ('all zero', _text(HEADER, _rows(t, 0.0 * x, 0.0 * y)))]
    for field in ('nan', 'NaN', 'inf', '-inf', '', ' ', 'abc', '1e400', '0x10', '--1', '1_0',
                  '"3"', '1,5'):
        row, column = int(rng.integers(1, n - 1)), int(rng.integers(0, 3))
        cases.append((f'{field!r} in {HEADER[column]}',
                      _text(HEADER, _edited(good, {(row, column): field}))))
    empties = {(int(k), 1): '' for k in rng.choice(n, 5, replace=False)}
    cases += [
        ('5 empty currents', _text(HEADER, _edited(good, empties))),
        ('every other displacement NaN',
         _text(HEADER, _edited(good, {(k, 2): 'nan' for k in range(0, n, 2)}))),
        ('all displacements NaN',
         _text(HEADER, _edited(good, {(k, 2): 'nan' for k in range(n)}))),
        ('time reversed', _text(HEADER, _rows(t[::-1], x, y))),
        ('time jumps back', _text(HEADER, _rows(np.where(t > t[n // 2], t - 0.5, t), x, y))),
        ('time duplicated once', _text(HEADER, _rows(np.r_[t[:100], t[99:-1]], x, y))),
        ('time in pairs', _text(HEADER, _rows(np.repeat(t[::2], 2)[:n], x, y))),
        ('time in ms', _text(HEADER, _rows(1e3 * t, x, y))),
        ('time in us', _text(HEADER, _rows(1e6 * t, x, y))),
        ('time since the epoch', _text(HEADER, _rows(1.7e9 + t, x, y))),
        ('time in ns since the epoch', _text(HEADER, _rows(1.7e18 + 1e9 * t, x, y))),
        ('negative time', _text(HEADER, _rows(t - 100.0, x, y))),
        ('time x 1e-12', _text(HEADER, _rows(1e-12 * t, x, y))),
        ('time x 1e12', _text(HEADER, _rows(1e12 * t, x, y))),
        ('irregular time', _text(HEADER, _rows(np.cumsum(rng.exponential(2.5e-3, n)), x, y))),
    ]
    for scale in (1e-12, 1e12, 1e-300, 1e300):
        cases += [(f'current x {scale:g}', _text(HEADER, _rows(t, scale * x, y))),
                  (f'displacement x {scale:g}', _text(HEADER, _rows(t, x, scale * y))),
                  (f'both x {scale:g}', _text(HEADER, _rows(t, scale * x, scale * y)))]
    spike_y, spike_x = y.copy(), x.copy()
    spike_y[n // 2] += 1e3 * np.ptp(y)
    spike_x[n // 2] += 1e3
    cases += [
        ('subnormal', _text(HEADER, _rows(t, 1e-310 * x, 1e-310 * y))),
        ('offset 1e12, span 1e-12', _text(HEADER, _rows(t, x, 1.0 + 1e-12 * y))),
        ('current offset 1e12', _text(HEADER, _rows(t, x + 1e12, y))),
        ('displacement spike', _text(HEADER, _rows(t, x, spike_y))),
        ('current spike', _text(HEADER, _rows(t, spike_x, y))),
        ('normal noise', _text(HEADER, _rows(t, rng.normal(size=n), rng.normal(size=n)))),
        ('uniform noise', _text(HEADER, _rows(t, rng.uniform(0.2, 1.8, n),
                                              rng.uniform(0.0, 4e-5, n)))),
        ('reversed sign', _text(HEADER, _rows(t, x, -y))),
        ('reversed input', _text(HEADER, _rows(t, -x, y))),
        ('straight line', _text(HEADER, _rows(t, x, 3e-5 * x))),
        ('swapped columns', _text(HEADER, _rows(t, y, x))),
        ('one step', _text(HEADER, _rows(t, (t > t[n // 2]).astype(float), y))),
        ('two levels', _text(HEADER, _rows(t, np.where(np.arange(n) % 2, 0.2, 1.8), y))),
        ('rounded', _text(HEADER, _rows(t, np.round(x), np.round(y, 5)))),
        ('integers', _text(HEADER, [[str(k), str(k % 7), str(k % 5)] for k in range(n)])),
        ('extra columns', _text(HEADER + ['note', 'temperature'],
                                [row + ['ok', '21.5'] for row in good])),
        ('text column first', _text(['note'] + HEADER, [['x'] + row for row in good])),
        ('semicolons', _text(HEADER, good, sep=';')),
        ('tabs', _text(HEADER, good, sep='\t')),
        ('spaces', _text(HEADER, good, sep=' ')),
        ('decimal commas', _text(HEADER, [[v.replace('.', ',') for v in row] for row in good],
                                 sep=';')),
        ('BOM', '\ufeff' + _text(HEADER, good)),
        ('UTF-16', _text(HEADER, good).encode('utf-16')),
        ('CRLF', _text(HEADER, good, newline='\r\n')),
        ('CR only', _text(HEADER, good, newline='\r')),
        ('Latin-1', ('# \xb5m\n' + _text(HEADER, good)).encode('latin-1')),
        ('NUL bytes', _text(HEADER, good).replace('\n', '\x00\n', 3)),
        ('no header', _text(HEADER, good).split('\n', 1)[1]),
        ('repeated column name', _text(['time', 'current', 'current'], good)),
        ('empty column name', _text(['time', '', 'displacement'], good)),
        ('quoted header', _text([f'"{name}"' for name in HEADER], good)),
        ('padded header', _text([f' {name} ' for name in HEADER], good)),
        ('capitalised header', _text([name.title() for name in HEADER], good)),
        ('short row', _text(HEADER, good[:100] + [good[100][:2]] + good[101:])),
        ('long row', _text(HEADER, good[:100] + [good[100] + ['1']] + good[101:])),
        ('open quote', _text(HEADER, good[:100] + [['"1', '2', '3']] + good[101:])),
        ('two columns', _text(HEADER[:2], [row[:2] for row in good])),
        ('one column', _text(HEADER[:1], [row[:1] for row in good])),
        ('no time column', _text(HEADER[1:], [row[1:] for row in good])),
        ('padded fields', _text(HEADER, [[f'  {v}  ' for v in row] for row in good])),
        ('plus signs', _text(HEADER, [[v if v.startswith('-') else '+' + v for v in row]
                                      for row in good])),
        ('a 100000-character field', _text(HEADER, _edited(good, {(50, 0): '1' * 100000}))),
        ('blank line between rows', _text(HEADER, good).replace('\n', '\n\n')),
        ('trailing commas', _text(HEADER, [row + [''] for row in good])),
        ('first 300 rows, time in ks', _text(HEADER, _rows(1e-3 * t[:300], x[:300],
                                                           y[:300]))),
    ]
    return [(name, content.encode() if isinstance(content, str) else content)
            for name, content in cases]


class Runs:
    """Run ``mpi-ros`` in-process and collect every breach of the exit contract."""

    def __init__(self, directory):
        self.directory = Path(directory)
        self.count = 0
        self.problems = []

    def run(self, name, argv, outputs=()):
        """Run `argv`; check the contract; return (status, stdout, stderr)."""
        self.count += 1
        out, err = io.StringIO(), io.StringIO()
        for path in map(Path, outputs):
            if path.is_dir():
                shutil.rmtree(path)
            path.unlink(missing_ok=True)
        try:
            with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
                status = main(argv)
        except BaseException as exc:  # noqa: B902 - the contract: nothing escapes main
            self.problems.append(f'{name}: {argv[0]} raised\n'
                                 + ''.join(traceback.format_exception(exc)))
            return None, out.getvalue(), err.getvalue()
        problem = contract_breach(status, err.getvalue())
        if problem is None and status == 0:
            problem = insane_result(argv, out.getvalue(), outputs)
        if problem is None and status == 1 and any(Path(p).exists() for p in outputs):
            problem = 'exit 1, but an output was written'
        if problem is not None:
            self.problems.append(f'{name}: {" ".join(argv)}\n  {problem}\n'
                                 f'  stderr: {err.getvalue()[-1500:]}')
        return status, out.getvalue(), err.getvalue()


def contract_breach(status, err):
    """Return what breaks 'exit 0, or exit 1 with one last error: line', or None."""
    lines = err.strip().splitlines()
    if 'Traceback' in err:
        return 'a traceback on stderr'
    if status not in (0, 1):
        return f'exit status {status}'
    errors = [line for line in lines if 'error:' in line]
    if status == 1 and (not lines or not lines[-1].startswith('error: ') or len(errors) != 1):
        return 'exit 1 without exactly one error: line, the last one'
    if status == 0 and errors:
        return 'exit 0 with an error: line'
    return None


def insane_result(argv, out, outputs):
    """Return what is wrong with the files of a successful run, or None."""
    command = argv[0]
    if command == 'identify':
        params, fit = outputs
        model = MPIModel.from_params(read_params_yaml(params))
        summary = json.loads(Path(fit).read_text())
        errors = [summary['rms_error'], summary['linear_rms_error'],
                  summary['nonlinearity_error']]
        if not all(math.isfinite(e) for e in errors):
            return f'non-finite errors {errors}'
        if not summary['rms_error'] < summary['linear_rms_error']:
            return 'a fit no better than the straight line was written'
        if not np.all(np.isfinite(model.simulate(np.linspace(-2.0, 2.0, 50)))):
            return 'the written model simulates to non-finite values'
    elif command == 'diagnose':
        report = json.loads(Path(outputs[0]).read_text())
        if report['cause'] not in VERDICTS or out.strip().splitlines()[-1] != report['cause']:
            return f'verdict {report["cause"]!r}, stdout {out!r}'
        if not isinstance(report.get('warnings', []), list):
            return 'no warnings list in the JSON'
        if report['baseline'] and not math.isfinite(report['baseline']['rms_error']):
            return 'a non-finite baseline error'
        if not (Path(outputs[1]) / 'summary.md').exists():
            return 'no summary.md'
    else:
        header, table = read_csv_table(outputs[0])
        if not np.all(np.isfinite(table)):
            return f'{command} wrote non-finite values'
    return None


@pytest.fixture
def unrendered(monkeypatch):
    """Run the report's plotting code but do not render the figures (see the module)."""
    def close(fig, path, plt):
        plt.close(fig)
        path.touch()
        return path
    monkeypatch.setattr(diagnosis_report, '_save', close)


def _commands(directory, data, good, params):
    out = Path(directory)
    report = [str(out / 'report.json'), str(out / 'report')]
    return {
        'identify': (['identify', str(data), *ORDER, '-o', str(out / 'p.yaml'), '--json',
                      str(out / 'fit.json')], [out / 'p.yaml', out / 'fit.json']),
        'diagnose': (['diagnose', str(data), *ORDER, '--json', report[0], '--report',
                      report[1]], report),
        'diagnose --validate': (['diagnose', str(good), '--validate', str(data), *ORDER,
                                 '--json', report[0], '--report', report[1]], report),
        'simulate': (['simulate', str(params), '--input', str(data), '--input-column',
                      'current', '--output', str(out / 'sim.csv')], [out / 'sim.csv']),
        'compensate': (['compensate', str(params), '--input', str(data), '--input-column',
                        'displacement', '--output', str(out / 'comp.csv')],
                       [out / 'comp.csv']),
    }


def _reads_as(path, reference):
    """Tell whether a CSV file reads as the same samples as `reference`."""
    try:
        a, b = read_recording(path), read_recording(reference)
    except DataError:
        return False
    return all(np.array_equal(getattr(a, name), getattr(b, name))
               for name in ('time', 'current', 'displacement'))


@pytest.fixture(scope='module')
def good_record(tmp_path_factory):
    """Write the good record and the model identified from it; return their paths."""
    directory = tmp_path_factory.mktemp('good')
    t, x, y = _signals()
    write_csv_columns(directory / 'good.csv', {'time': t, 'current': x, 'displacement': y})
    assert main(['identify', str(directory / 'good.csv'), *ORDER, '-o',
                 str(directory / 'params.yaml')]) == 0
    return directory / 'good.csv', directory / 'params.yaml', (t, x, y)


def test_fuzz_every_command_in_process(tmp_path, good_record, unrendered):
    good, params, (t, x, y) = good_record
    runs = Runs(tmp_path)
    statuses = {}
    records = [('the good record', good.read_bytes()),
               *bad_records(np.random.default_rng(SEED), t, x, y)]
    alike = 0
    for number, (name, content) in enumerate(records):
        data = tmp_path / f'case{number}.csv'
        data.write_bytes(content)
        # A diagnosis depends on the samples only: a record that reads as the good one's
        # samples (a BOM, CRLF, padding, ...) is diagnosed once, as the good record.
        same = number > 0 and _reads_as(data, good)
        alike += same
        for command, (argv, outputs) in _commands(tmp_path, data, good, params).items():
            if same and command.startswith('diagnose'):
                continue
            status, _, _ = runs.run(f'{name!r}', argv, outputs)
            statuses[status] = statuses.get(status, 0) + 1
    print(f'{len(records)} records ({alike} read as the good one: not diagnosed again), '
          f'{runs.count} runs, exit status: {statuses}')
    assert not runs.problems, f'{len(runs.problems)} of {runs.count} runs:\n' + '\n'.join(
        runs.problems)
    # The fuzzer exercised both outcomes (a generator that only made unreadable files, or
    # only good ones, would test little).
    assert statuses.get(0, 0) > 50 and statuses.get(1, 0) > 200, statuses


def test_fuzz_data_options_in_process(tmp_path, good_record, unrendered):
    """Odd option values on good and odd records: the same contract."""
    good, params, (t, x, y) = good_record
    runs = Runs(tmp_path)
    write_csv_columns(tmp_path / 'ms.csv', {'t_ms': 1e3 * t, 'current': x, 'displacement': y})
    write_bag_signals(tmp_path / 'bag', t, x, y)
    out = [str(tmp_path / 'p.yaml'), str(tmp_path / 'fit.json')]
    identify = ['identify', *ORDER, '-o', out[0], '--json', out[1]]
    report = [str(tmp_path / 'report.json'), str(tmp_path / 'report')]
    diagnose = [*ORDER, '--json', report[0], '--report', report[1]]
    for source, extra in [
            (good, ['--time-scale', '0']), (good, ['--time-scale', '-1e-3']),
            (good, ['--time-scale', 'nan']), (good, ['--time-scale', '1e-300']),
            (good, ['--time-scale', '1e300']), (good, ['--input-scale', '1e300']),
            (good, ['--output-scale', '1e-300']), (good, ['--output-scale', 'inf']),
            (good, ['--input-column', 'displacement']),
            (good, ['--input-column', 'time', '--output-column', 'current']),
            (good, ['--time-column', '']), (good, ['--time-column', 'current']),
            (good, ['--order', '1', '0']), (good, ['--order', '0', '0']),
            (good, ['--order', '60', '30']), (good, ['--order', 'auto']),
            (good, ['--order', '-4', '2']), (good, ['--order', '4.5', '2']),
            (good, ['--drop-nonfinite']), (good, ['--anchor', 'origin']),
            (good, ['--periodic']),
            (tmp_path / 'ms.csv', ['--time-column', 't_ms']),
            (tmp_path / 'ms.csv', ['--time-column', 't_ms', '--time-scale', '1e-3']),
            (tmp_path / 'bag', ['--time-scale', '1e-3']),
            (tmp_path / 'bag', ['--time-scale', '1e3', '--sample-period', '1e-3']),
            (tmp_path / 'bag', ['--output-scale', '1e-300']),
            (tmp_path / 'bag', ['--input-topic', '/displacement']),
    ]:
        runs.run(f'{source.name} {extra}', [*identify[:1], str(source), *identify[1:],
                                            *extra], out)
        runs.run(f'{source.name} {extra}', ['diagnose', str(source), *diagnose, *extra],
                 report)
    for extra in (['--window', '0', '0.5'], ['--window', '1', '0.5'], ['--window', 'nan', '1'],
                  ['--window', '-1e300', '1e300'], ['--split', '0.1'], ['--split', '0.9'],
                  ['--split', 'nan'], ['--split', '0.95']):
        runs.run(f'{extra}', ['diagnose', str(good), *diagnose, *extra], report)
    print(f'{runs.count} runs with odd options')
    assert not runs.problems, f'{len(runs.problems)} of {runs.count} runs:\n' + '\n'.join(
        runs.problems)


def _validation_with_a_late_rate(directory, seed=5):
    """
    Write a validation record: a full sweep in 60 samples over 4 s, then 399 at 1 kHz.

    Its determined part starts within the sweep (about sample 45); from 1 kHz on, the
    residual's lag window is 0.2 s = 200 samples: a prefix of L samples is scored on
    L - 45 of them, fewer than the window for L up to about 245.
    """
    k = np.arange(60)
    fast = 4.0 + np.arange(1, 400) * 1e-3
    t = np.r_[k * (4.0 / 60.0), fast]
    x = np.r_[np.interp(k, [0, 15, 45, 60], [1.0, 1.8, 0.2, 1.0]),
              1.0 + 0.6 * np.sin(2.0 * np.pi * (fast - 4.0) / 0.15)]
    y = MagnetostrictiveActuator(ActuatorConfig(noise_std_m=1e-9), seed=seed).simulate(t, x)
    return _rows(t, x, y)


def test_validation_records_of_every_length(tmp_path, good_record, unrendered):
    """
    ``diagnose --validate`` on the first L samples of a validation record, L = 0, 1, ...

    Every L up to past the diagnosis' minimum (100 scored samples after the burn-in), then
    every 10th and every L near the end of the residual's lag window (200 samples at
    1 kHz).  Before the fix, L from the minimum to the window's end crashed np.corrcoef.
    """
    good = good_record[0]
    rows = _validation_with_a_late_rate(tmp_path)
    runs = Runs(tmp_path)
    report = [tmp_path / 'report.json', tmp_path / 'report']
    validation = tmp_path / 'validation.csv'

    def run(length):
        validation.write_text(_text(HEADER, rows[:length]))
        status, _, err = runs.run(f'validation of {length} samples', [
            'diagnose', str(good), '--validate', str(validation), *ORDER,
            '--json', str(report[0]), '--report', str(report[1])], report)
        return status, (json.loads(report[0].read_text()) if status == 0 else err)

    status, full = run(len(rows))
    assert status == 0, full
    burn_in = full['data']['validation_burn_in']
    minimum, window = burn_in + 100, burn_in + 200
    outcomes = {length: run(length) for length in range(0, minimum + 3)}
    for length in [*range(minimum + 3, window - 3, 10), *range(window - 3, window + 4)]:
        outcomes[length] = run(length)
    print(f'{runs.count} validation lengths: 0..{minimum + 2} each, then up to {window + 3}; '
          f'exit 0 from {minimum}')
    assert not runs.problems, f'{len(runs.problems)} of {runs.count} runs:\n' + '\n'.join(
        runs.problems)
    assert outcomes[minimum - 1][0] == 1 and 'too little to score' in outcomes[minimum - 1][1]
    for length in range(minimum, window + 4):
        if length in outcomes:
            status, result = outcomes[length]
            assert status == 0, (length, result)
            scored = length - result['data']['validation_burn_in']
            # The lag window shrank to half the scored samples where those are fewer.
            assert abs(result['residual']['lag_of_best_correlation']) <= (
                min(200, scored // 2) * 1e-3 + 1e-9)


@pytest.mark.parametrize('case', ['diagnose, short validation', 'identify, empty file',
                                  'simulate, semicolons'])
def test_fuzz_cases_as_processes(tmp_path, good_record, case):
    """The console script's process: exit status, stderr, rendered report plots."""
    good, params, (t, x, y) = good_record
    if case.startswith('diagnose'):
        rows = _validation_with_a_late_rate(tmp_path)
        (tmp_path / 'v.csv').write_text(_text(HEADER, rows[:200]))     # 155 scored
        argv = ['diagnose', str(good), '--validate', str(tmp_path / 'v.csv'), *ORDER,
                '--json', str(tmp_path / 'r.json'), '--report', str(tmp_path / 'report')]
    elif case.startswith('identify'):
        (tmp_path / 'empty.csv').write_bytes(b'')
        argv = ['identify', str(tmp_path / 'empty.csv'), '-o', str(tmp_path / 'p.yaml')]
    else:
        (tmp_path / 'semi.csv').write_text(_text(HEADER, _rows(t, x, y), sep=';'))
        argv = ['simulate', str(params), '--input', str(tmp_path / 'semi.csv'), '--output',
                str(tmp_path / 'out.csv')]
    done = subprocess.run([sys.executable, '-m', 'mpi_ros.app.cli', *argv], capture_output=True,
                          text=True, timeout=300)
    assert contract_breach(done.returncode, done.stderr) is None, done.stderr
    if case.startswith('diagnose'):
        assert done.returncode == 0, done.stderr
        plots = sorted((tmp_path / 'report').glob('*.png'))
        # The loops, the residual and one signature plot per registered effect that draws one.
        drawn = sum(effect.plot is not None for effect in EFFECTS.values())
        assert len(plots) == 2 + drawn == 7 and all(p.stat().st_size > 1000 for p in plots)
        assert done.stdout.strip() == json.loads((tmp_path / 'r.json').read_text())['cause']
    else:
        assert done.returncode == 1
        assert done.stderr.count('\n') == 1 and done.stderr.startswith('error: CSV file ')
        assert not list(tmp_path.glob('*.yaml')) and not (tmp_path / 'out.csv').exists()


#: Bytes that mean something to a CSV or number parser, and some arbitrary ones.
_BYTES = st.one_of(st.sampled_from(list(b',;."\n\r\t -+eE#0129naif_\x00')),
                   st.integers(0, 255))


@settings(max_examples=25, deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(data=st.data())
def test_mutated_records_through_identify_and_simulate(tmp_path, good_record, data):
    """Random edits of the good file (seeded by hypothesis' derandomize): the same contract."""
    good, params, _ = good_record
    raw = bytearray(good.read_bytes())
    for _ in range(data.draw(st.integers(1, 6), label='edits')):
        kind = data.draw(st.sampled_from(['replace', 'insert', 'delete', 'truncate',
                                          'swap lines']))
        at = data.draw(st.integers(0, len(raw) - 1)) if raw else 0
        if kind == 'replace' and raw:
            raw[at] = data.draw(_BYTES)
        elif kind == 'insert':
            raw[at:at] = bytes(data.draw(st.lists(_BYTES, min_size=1, max_size=6)))
        elif kind == 'delete':
            del raw[at:at + data.draw(st.integers(1, 40))]
        elif kind == 'truncate':
            del raw[at:]
        else:
            lines = bytes(raw).split(b'\n')
            i, j = (data.draw(st.integers(0, max(len(lines) - 1, 0))) for _ in range(2))
            lines[i], lines[j] = lines[j], lines[i]
            raw = bytearray(b'\n'.join(lines))
    path = tmp_path / 'mutated.csv'
    path.write_bytes(bytes(raw))
    runs = Runs(tmp_path)
    commands = _commands(tmp_path, path, good, params)
    for command in ('identify', 'simulate'):
        runs.run('mutated', *commands[command])
    assert not runs.problems, '\n'.join(runs.problems)
