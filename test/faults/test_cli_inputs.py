# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
``mpi-ros identify`` on bad inputs: exit status 1, ``error: ...`` naming it, no output file.

``test/test_recordings.py`` covers the readers (each bag and CSV fault raises
``DataError`` with its message); here the same faults go through the command line, which
must turn them into exit status 1 and one ``error:`` line, and must leave neither the
parameter YAML nor the ``--json`` statistics (nor a temporary file) behind. Both files
are written to a temporary file and renamed, and only once everything has succeeded.
"""

from pathlib import Path
import subprocess
import sys

from mpi_ros.app.cli import main
from mpi_ros.plant.actuator import MagnetostrictiveActuator
from mpi_ros.plant.excitation import identification_excitation
from mpi_ros.recordings import write_bag_signals
import numpy as np
import pytest
from rosbags.rosbag2 import StoragePlugin, Writer
from rosbags.typesys import get_typestore, Stores


def _raw_bag(path, topics):
    """Write a bag directly: topics maps name -> list of (stamp ns, value)."""
    store = get_typestore(Stores.ROS2_JAZZY)
    msgtype = 'std_msgs/msg/Float64'
    with Writer(path, version=9, storage_plugin=StoragePlugin.SQLITE3) as writer:
        for topic, messages in topics.items():
            conn = writer.add_connection(topic, msgtype, typestore=store)
            for stamp, value in messages:
                writer.write(conn, stamp, store.serialize_cdr(
                    store.types[msgtype](data=float(value)), msgtype))
    return path


def _signals(seconds=6.0, rate=200.0):
    t, current = identification_excitation(seconds, sample_rate=rate, seed=2, holds=False,
                                           bursts=False)
    return t, current, MagnetostrictiveActuator().simulate(t, current)


def _csv(path, header, rows):
    path.write_text(header + '\n' + ''.join(','.join(str(v) for v in row) + '\n'
                                            for row in rows))
    return path


def _good_bag(directory, storage='sqlite3'):
    path = directory / f'good_{storage}'
    write_bag_signals(path, *_signals(), storage=storage)
    return path


def _truncated(directory, storage):
    path = _good_bag(directory, storage)
    storage_file = next(p for p in path.iterdir() if p.name != 'metadata.yaml')
    data = storage_file.read_bytes()
    storage_file.write_bytes(data[:len(data) // 2])
    return path


def _overwritten(directory):
    path = _good_bag(directory)
    storage_file = next(p for p in path.iterdir() if p.suffix == '.db3')
    data = bytearray(storage_file.read_bytes())
    data[0:4096] = bytes(np.random.default_rng(0).integers(0, 256, 4096, dtype=np.uint8))
    storage_file.write_bytes(bytes(data))
    return path


def _csv_rows(size=1200):
    t, current, displacement = _signals()
    return [(f'{a:.6f}', f'{b:.9g}', f'{c:.9g}') for a, b, c in
            zip(t[:size], current[:size], displacement[:size])]


# (name, make(directory) -> (data path, extra arguments), text the error must contain)
CASES = [
    ('bag missing topic', lambda d: (_good_bag(d), ['--output-topic', '/nope']),
     'has no topic /nope'),
    ('bag with empty topics', lambda d: (_raw_bag(d / 'empty', {
        '/current_command': [], '/displacement': []}), []), 'has no messages'),
    ('bag without topics', lambda d: (_raw_bag(d / 'none', {}), []), 'has no topic'),
    ('bag single message', lambda d: (_raw_bag(d / 'single', {
        '/current_command': [(0, 1.0)],
        '/displacement': [(k, 1e-6 * k) for k in range(50)]}), []), 'a single message'),
    ('bag truncated sqlite3', lambda d: (_truncated(d, 'sqlite3'), []), 'truncated or corrupt'),
    ('bag truncated mcap', lambda d: (_truncated(d, 'mcap'), []), 'truncated or corrupt'),
    ('bag overwritten header', lambda d: (_overwritten(d), []), 'truncated or corrupt'),
    ('not a bag', lambda d: ((d / 'nothing').mkdir() or d / 'nothing', []),
     'is not a rosbag2 bag'),
    ('bag path missing', lambda d: (d / 'gone', []), 'does not exist'),
    ('csv missing column', lambda d: (_csv(d / 'a.csv', 'time,current', [
        r[:2] for r in _csv_rows()]), []), 'column'),
    ('csv named column missing', lambda d: (_csv(d / 'b.csv', 'time,current,displacement',
                                                 _csv_rows()),
                                            ['--output-column', 'position']), 'position'),
    ('csv text in numeric field', lambda d: (_csv(d / 'c.csv', 'time,current,displacement',
                                                  _csv_rows()[:500] + [('2.5', 'abc', '0.0')]
                                                  + _csv_rows()[501:]), []), 'abc'),
    ('csv NaN', lambda d: (_csv(d / 'n.csv', 'time,current,displacement',
                                _csv_rows()[:300] + [('1.505', '0.5', 'nan')]
                                + _csv_rows()[302:]), []), 'non-finite'),
    ('csv empty', lambda d: (_csv(d / 'e.csv', 'time,current,displacement', []), []), 'e.csv'),
    ('too few samples for the order', lambda d: (_csv(d / 'f.csv', 'time,current,displacement',
                                                      _csv_rows(40)), ['--order', '14', '7']),
     'too few samples to identify order n=14, l=7'),
    ('constant current', lambda d: (_csv(d / 'k.csv', 'time,current,displacement', [
        (f'{0.005 * k:.3f}', '1.0', f'{1e-6 * (k % 7):.3g}') for k in range(400)]), []),
     'the current is constant'),
    ('bad order', lambda d: (_good_bag(d), ['--order', '14']), '--order'),
]


def _outputs(directory):
    return sorted(p.name for p in Path(directory).iterdir()
                  if p.name.startswith('.') or p.suffix in ('.yaml', '.json'))


@pytest.mark.parametrize('name, make, needle', CASES, ids=[c[0] for c in CASES])
def test_identify_bad_input_fails_cleanly(tmp_path, capsys, name, make, needle):
    data_dir = tmp_path / 'data'
    data_dir.mkdir()
    out_dir = tmp_path / 'out'
    out_dir.mkdir()
    data, extra = make(data_dir)
    status = main(['identify', str(data), '-o', str(out_dir / 'params.yaml'),
                   '--json', str(out_dir / 'fit.json'), *extra])
    err = capsys.readouterr().err
    assert status == 1, err
    last = err.strip().splitlines()[-1]
    assert last.startswith('error: '), err
    assert needle in last, err
    assert 'Traceback' not in err
    assert _outputs(out_dir) == []
    assert [p.name for p in data_dir.iterdir() if p.name.startswith('.')] == []


def test_identify_refuses_data_without_a_reversal(tmp_path, capsys):
    t = np.arange(2000) / 200.0
    current = 0.2 + 1.6 * t / t[-1]                       # one ramp up: no loop at all
    displacement = MagnetostrictiveActuator().simulate(t, current)
    data = _csv(tmp_path / 'ramp.csv', 'time,current,displacement',
                [(f'{a:.4f}', f'{b:.9g}', f'{c:.9g}') for a, b, c in
                 zip(t, current, displacement)])
    status = main(['identify', str(data), '--order', '14', '7', '-o', str(tmp_path / 'p.yaml')])
    err = capsys.readouterr().err
    assert status == 1, err
    assert 'excitation' in err.strip().splitlines()[-1]
    assert not (tmp_path / 'p.yaml').exists()


@pytest.mark.parametrize('where', ['output', 'json'])
def test_identify_unwritable_target_writes_nothing(tmp_path, capsys, where):
    bag = _good_bag(tmp_path)
    targets = {'output': tmp_path / 'params.yaml', 'json': tmp_path / 'fit.json'}
    targets[where] = tmp_path / 'missing' / targets[where].name
    status = main(['identify', str(bag), '--order', '4', '2', '-o', str(targets['output']),
                   '--json', str(targets['json'])])
    err = capsys.readouterr().err
    assert status == 1, err
    assert err.strip().splitlines()[-1].startswith('error: ')
    assert 'missing' in err.strip().splitlines()[-1]
    assert _outputs(tmp_path) == []


def test_identify_good_input_writes_both_files(tmp_path, capsys):
    """The control: the same command on good data succeeds and writes both files."""
    bag = _good_bag(tmp_path)
    status = main(['identify', str(bag), '--order', '4', '2', '-o', str(tmp_path / 'p.yaml'),
                   '--json', str(tmp_path / 'fit.json')])
    assert status == 0, capsys.readouterr().err
    assert _outputs(tmp_path) == ['fit.json', 'p.yaml']


def test_identify_exit_status_of_the_process(tmp_path):
    """The installed command's process exits with status 1 (not a traceback's)."""
    data = _raw_bag(tmp_path / 'single', {'/current_command': [(0, 1.0)],
                                          '/displacement': [(k, 1.0) for k in range(20)]})
    done = subprocess.run([sys.executable, '-m', 'mpi_ros.app.cli', 'identify', str(data),
                           '-o', str(tmp_path / 'p.yaml')], capture_output=True, text=True,
                          timeout=120)
    assert done.returncode == 1
    assert done.stderr.startswith('error: ')
    assert not (tmp_path / 'p.yaml').exists()
