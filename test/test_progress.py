# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
The progress line (issue 20): drawn on a terminal, quiet with ``--quiet`` or without one.

A terminal is faked by a text stream whose ``isatty()`` is True.  No timing is asserted.
"""

import io
import json
import sys

from mpi_ros.app.cli import main
from mpi_ros.app.progress import Progress
import mpi_ros.identification.order_selection as selection
from mpi_ros.model_fit import identify
from mpi_ros.plant.synthetic import synthetic_record
from mpi_ros.recordings import write_csv_columns
import numpy as np
import pytest

#: What only a status line writes: a carriage return and the erase-line sequence.
STATUS = '\r\x1b[K'


class Terminal(io.StringIO):
    """A stream that says it is a terminal."""

    def isatty(self):
        return True


@pytest.fixture(scope='module')
def record_csv(tmp_path_factory):
    rec = synthetic_record('lag 1.5 ms at 1 kHz', 0)
    path = tmp_path_factory.mktemp('progress') / 'rec.csv'
    write_csv_columns(path, {'time': rec.time, 'current': rec.current,
                             'displacement': rec.displacement})
    return path


# ------------------------------------------------------------------ the helper


def test_status_line_on_a_terminal_and_permanent_lines_everywhere():
    term = Terminal()
    with Progress(stream=term, tick=0.0) as progress:
        progress('phase one')
        progress.say('a result')
        progress('phase two')
    text = term.getvalue()
    assert text.count(STATUS) >= 3 and 'phase one' in text and 'phase two' in text
    # The permanent line replaces the status line, which is drawn again below it.
    assert f'{STATUS}a result\n' in text and text.endswith(STATUS)
    for quiet, stream in ((True, Terminal()), (False, io.StringIO())):
        with Progress(stream=stream, quiet=quiet, tick=0.0) as progress:
            assert not progress.active
            progress('phase one')
            progress.update('a loop step')
            progress.say('a result')
        assert stream.getvalue() == 'a result\n'


def test_updates_in_a_loop_are_thinned_but_the_last_text_is_kept():
    term = Terminal()
    progress = Progress(stream=term, interval=3600.0, tick=0.0)
    progress('start')
    for k in range(1000):
        progress.update(f'sample {k}')
    assert term.getvalue().count(STATUS) == 1        # the interval has not passed
    progress('done')                                 # forced
    assert term.getvalue().endswith('done')
    progress.close()


def test_identify_reports_phases_orders_and_dynamics_trials():
    rec = synthetic_record('lag 1.5 ms at 1 kHz', 0)
    lines = []
    result = identify(rec.current, rec.displacement, order='auto', time=rec.time,
                      progress=lines.append)
    assert lines[0] == f'analysing the record ({rec.current.size} samples)'
    tried = [line for line in lines if line.startswith('order selection: n=')]
    assert len(tried) == len(result.order_table)
    assert tried[0] == 'order selection: n=0, l=0 (1 of at most 11)'
    assert any(line.startswith('dynamics: trial fit ') for line in lines)
    assert lines[-2:] == [f'fitting n={result.order[0]}, l={result.order[1]} on the whole '
                          'record', 'judging the fit against the straight line']


# ------------------------------------------------------------------ the commands


@pytest.mark.parametrize('terminal, quiet, drawn', [
    (False, False, False), (True, True, False), (True, False, True)])
def test_identify_command(record_csv, tmp_path, monkeypatch, capsys, terminal, quiet, drawn):
    if terminal:
        monkeypatch.setattr(sys, 'stderr', Terminal())
    argv = ['identify', str(record_csv), '--order', 'auto', '-o', str(tmp_path / 'p.yaml')]
    assert main(argv + (['--quiet'] if quiet else [])) == 0
    err = sys.stderr.getvalue() if terminal else capsys.readouterr().err
    assert (STATUS in err) == drawn and ('order selection: n=' in err) == drawn
    assert ('\r' in err) == drawn
    assert 'identifying from' in err and f'wrote {tmp_path / "p.yaml"}' in err


@pytest.mark.parametrize('terminal, quiet, drawn', [
    (False, False, False), (True, True, False), (True, False, True)])
def test_diagnose_command(tmp_path, monkeypatch, capsys, terminal, quiet, drawn):
    if terminal:
        monkeypatch.setattr(sys, 'stderr', Terminal())
    argv = ['diagnose', '--excitation', str(tmp_path / 'x.csv')]
    assert main(argv + (['--quiet'] if quiet else [])) == 0
    err = sys.stderr.getvalue() if terminal else capsys.readouterr().err
    assert (STATUS in err) == drawn and ('\r' in err) == drawn
    assert f'wrote {tmp_path / "x.csv"}\n' in err


def test_demo_takes_quiet(capsys):
    # The option parses (the run itself, not on a terminal, is test/integration).
    assert main(['demo', '--quiet', '--domain-id', '999']) == 1
    assert capsys.readouterr().err.strip().endswith(
        "error: --domain-id must be an integer from 0 to 232; found '999'; pass --domain-id "
        'N or unset ROS_DOMAIN_ID')


# ------------------------------------------------------------------ the order table


def test_unstable_orders_are_marked_in_the_table_and_the_json(record_csv, tmp_path,
                                                              monkeypatch, capsys):
    # Make two orders' held-out errors absurd: one huge, one not a number (as an order
    # that blows up on a short record gives).
    errors = selection.range_errors
    absurd = {3: (883.282, 88.3), 4: (float('nan'), float('nan'))}
    calls = []

    def errors_with_absurd_orders(sim, y, held):
        calls.append(1)
        return absurd.get(len(calls), errors(sim, y, held))

    monkeypatch.setattr(selection, 'range_errors', errors_with_absurd_orders)
    assert main(['identify', str(record_csv), '--order', 'auto', '-o', str(tmp_path / 'p.yaml'),
                 '--json', str(tmp_path / 'fit.json')]) == 0
    err = capsys.readouterr().err
    assert '  n= 4 l= 2  held-out error unstable (not considered)' in err
    assert '  n= 6 l= 3  held-out error unstable (not considered)' in err
    assert '88328' not in err and '8830' not in err and 'nan' not in err.lower()
    text = (tmp_path / 'fit.json').read_text()
    assert 'NaN' not in text and 'Infinity' not in text        # strict JSON
    table = json.loads(text)['order_table']
    marked = {(row['n'], row['l']): row for row in table if row['unstable']}
    assert sorted(marked) == [(4, 2), (6, 3)]
    assert marked[(6, 3)]['rms_error'] is None
    assert all(np.isfinite(row['rms_error']) and row['rms_error'] < 1.0
               for row in table if not row['unstable'])
    chosen = json.loads(text)['order']
    assert tuple(chosen) not in marked
