# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Files a user can trust (issue 25): hostile inputs, own inputs as outputs, crashes mid-write.

* Parameter YAML nested 1,000 deep, an alias bomb, broken YAML, a typo key: exit status 1,
  one ``error:`` line, the inputs untouched, no output. Each command runs as a process with
  its address space capped (``RLIMIT_AS``) and a timeout as safety bounds (no timing is
  asserted).
* No command writes over one of its inputs (also through a symbolic link or a bag folder);
  a symbolic link as output is written through, a file's mode is kept.
* Bags: a sqlite3 storage cut by one byte, rows deleted, an mcap byte flipped: one error
  line. A recorder killed with ``kill -9`` leaves a readable partial bag.
* ``kill -9`` mid-write: the process kills itself at each rename of
  :func:`mpi_ros.recordings.atomic_writes` in turn; every output then holds the old file or
  the new one, never a part, and identify's JSON tells whether it belongs to the YAML.
"""

import hashlib
import json
import os
from pathlib import Path
import resource
import signal
import sqlite3
import subprocess
import sys
import textwrap

from mpi_ros.app.cli import main
from mpi_ros.errors import DataError
from mpi_ros.plant.actuator import MagnetostrictiveActuator
from mpi_ros.plant.excitation import identification_excitation
from mpi_ros.recordings import atomic_writes, BagRecorder, read_bag_signals, \
    write_bag_signals, write_csv_columns
import numpy as np
import pytest

ORDER = ['--order', '4', '2']
#: Safety bounds of every process here (not assertions on speed or memory).
TIMEOUT = 120.0
ADDRESS_SPACE = 3 * 2**30


def _signals(seconds=4.0, rate=300.0):
    t, current = identification_excitation(seconds, sample_rate=rate, seed=3, holds=False,
                                           bursts=False)
    return t, current, MagnetostrictiveActuator().simulate(t, current)


@pytest.fixture(scope='module')
def files(tmp_path_factory):
    """Return a folder with a record (CSV, both bags), its columns and a parameter file."""
    root = tmp_path_factory.mktemp('files')
    t, x, y = _signals()
    write_csv_columns(root / 'd.csv', {'time': t, 'current': x, 'displacement': y})
    write_csv_columns(root / 'x.csv', {'time': t, 'current': x})
    write_csv_columns(root / 'y.csv', {'time': t, 'desired': y})
    for storage in ('sqlite3', 'mcap'):
        write_bag_signals(root / f'bag_{storage}', t, x, y, storage=storage)
    assert main(['identify', str(root / 'd.csv'), *ORDER, '-o', str(root / 'p.yaml')]) == 0
    return root


def _limit():
    resource.setrlimit(resource.RLIMIT_AS, (ADDRESS_SPACE, ADDRESS_SPACE))


def _run(*argv, cwd=None):
    return subprocess.run([sys.executable, '-m', 'mpi_ros.app.cli', *map(str, argv)],
                          capture_output=True, text=True, timeout=TIMEOUT, cwd=cwd,
                          preexec_fn=_limit)


def _digests(directory):
    return {p.name: hashlib.sha256(p.read_bytes()).hexdigest()
            for p in sorted(Path(directory).rglob('*')) if p.is_file()}


def _one_error(done, needle):
    # Exactly one error line, the last (diagnose prints its progress lines before it).
    lines = done.stderr.strip().splitlines()
    assert done.returncode == 1, done.stderr[-2000:]
    errors = [line for line in lines if 'error' in line.lower()]
    assert errors == lines[-1:] and lines[-1].startswith('error: '), done.stderr[-2000:]
    assert needle in lines[-1], lines[-1]
    return lines[-1]


def _alias_bomb():
    lines = ['compensator:', '  ros__parameters:', '    a: &a [1.0,1.0,1.0,1.0,1.0,1.0,1.0,'
             '1.0,1.0]']
    previous = 'a'
    for name in 'bcdefghi':
        lines.append(f'    {name}: &{name} [' + ','.join([f'*{previous}'] * 9) + ']')
        previous = name
    lines += ['    model:', '      hysteresis:', '        thresholds: *i',
              '        weights: *i', '        initial_states: *i', '      superposition:',
              '        thresholds: *i', '        weights: *i']
    return '\n'.join(lines) + '\n'


BAD_YAML = {
    'nested 1000 deep (lists)': ('compensator:\n  ros__parameters:\n    model: '
                                 + '[' * 1000 + ']' * 1000 + '\n', 'nested more than'),
    'nested 1000 deep (maps)': ('compensator:\n  ros__parameters:\n    model: '
                                + '{a: ' * 1000 + '1' + '}' * 1000 + '\n', 'nested more than'),
    'alias bomb': (_alias_bomb(), 'aliases are not allowed'),
    'broken flow list': ('compensator:\n  ros__parameters:\n    model: {a: [1, 2\n  x: : :\n',
                         'not valid YAML'),
    'tab indentation': ('compensator:\n\tros__parameters: {}\n', 'not valid YAML'),
    'not UTF-8': (b'compensator: \xff\xfe\n', 'not UTF-8'),
}


@pytest.mark.parametrize('command, name', [('simulate', name) for name in BAD_YAML] + [
    ('compensate', 'alias bomb'), ('compensate', 'nested 1000 deep (maps)')])
def test_hostile_parameter_files_give_one_error_line(files, tmp_path, command, name):
    text, needle = BAD_YAML[name]
    params = tmp_path / 'bad.yaml'
    params.write_bytes(text if isinstance(text, bytes) else text.encode())
    before = _digests(tmp_path) | _digests(files)
    column = files / ('x.csv' if command == 'simulate' else 'y.csv')
    done = _run(command, params, '--input', column, '--output', tmp_path / 'out.csv')
    _one_error(done, needle)
    assert 'Traceback' not in done.stderr
    assert _digests(tmp_path) | _digests(files) == before
    assert not (tmp_path / 'out.csv').exists()


def test_a_parameter_file_beyond_the_size_limit_is_refused(tmp_path, monkeypatch):
    from mpi_ros import params
    from mpi_ros.params import read_params_yaml
    monkeypatch.setattr(params, 'MAX_FILE_BYTES', 1000)
    big = tmp_path / 'big.yaml'
    big.write_text('compensator:\n  ros__parameters:\n    a: [' + '1.0, ' * 400 + '1.0]\n')
    with pytest.raises(DataError, match='is larger than'):
        read_params_yaml(big)


def test_a_typo_key_is_an_error_naming_the_closest_key(files, tmp_path):
    params = tmp_path / 'typo.yaml'
    params.write_text((files / 'p.yaml').read_text().replace('output_offset', 'output_ofset'))
    done = _run('compensate', params, '--input', files / 'y.csv', '--output', tmp_path / 'o.csv')
    line = _one_error(done, 'model.output_ofset (did you mean model.output_offset?)')
    assert 'compensator does not know' in line
    assert not (tmp_path / 'o.csv').exists()
    # The node's own keys (limits, switches) and rclpy's are known: no error.
    extra = tmp_path / 'node.yaml'
    extra.write_text((files / 'p.yaml').read_text().replace(
        '    model:', '    use_sim_time: false\n    output:\n      min: 0.1\n      max: 1.7\n'
        '    model:'))
    done = _run('compensate', extra, '--input', files / 'y.csv', '--output', tmp_path / 'o.csv')
    assert done.returncode == 0, done.stderr


def _own_input_cases(files, tmp):
    (tmp / 'link.csv').symlink_to(files / 'd.csv')
    return {
        'identify -o DATA': ['identify', files / 'd.csv', *ORDER, '-o', files / 'd.csv'],
        'identify --json DATA': ['identify', files / 'd.csv', *ORDER, '-o', tmp / 'q.yaml',
                                 '--json', files / 'd.csv'],
        'identify -o link to DATA': ['identify', files / 'd.csv', *ORDER, '-o',
                                     tmp / 'link.csv'],
        'identify -o inside the bag': ['identify', files / 'bag_sqlite3', *ORDER, '-o',
                                       files / 'bag_sqlite3' / 'metadata.yaml'],
        'identify -o same as --json': ['identify', files / 'd.csv', *ORDER, '-o',
                                       tmp / 'q.yaml', '--json', tmp / 'q.yaml'],
        'compensate --output --input': ['compensate', files / 'p.yaml', '--input',
                                        files / 'y.csv', '--output', files / 'y.csv'],
        'simulate --output PARAMS': ['simulate', files / 'p.yaml', '--input', files / 'x.csv',
                                     '--output', files / 'p.yaml'],
        'diagnose --json DATA': ['diagnose', files / 'd.csv', *ORDER, '--json',
                                 files / 'd.csv', '--report', tmp / 'r'],
        'diagnose --params-out --validate': ['diagnose', files / 'd.csv', '--validate',
                                             files / 'x.csv', *ORDER, '--json',
                                             tmp / 'r.json', '--report', tmp / 'r',
                                             '--params-out', files / 'x.csv'],
    }


def test_no_command_writes_over_its_own_input(files, tmp_path):
    before = _digests(files)
    cases = _own_input_cases(files, tmp_path)
    for name, argv in cases.items():
        done = _run(*argv)
        line = _one_error(done, 'nothing was written')
        assert any(text in line for text in ('destroy the input', 'change the input',
                                             'same file')), (name, line)
        assert _digests(files) == before, name
    assert sorted(p.name for p in tmp_path.iterdir()) == ['link.csv']


def test_a_symbolic_link_is_written_through_and_a_mode_is_kept(files, tmp_path):
    target = tmp_path / 'real.yaml'
    target.write_text('old\n')
    target.chmod(0o600)
    link = tmp_path / 'link.yaml'
    link.symlink_to(target.name)
    assert main(['identify', str(files / 'd.csv'), *ORDER, '-o', str(link)]) == 0
    assert link.is_symlink() and os.readlink(link) == target.name
    assert 'ros__parameters' in target.read_text()
    assert target.stat().st_mode & 0o777 == 0o600
    out = tmp_path / 'sim.csv'
    out.write_text('old\n')
    out.chmod(0o640)
    assert main(['simulate', str(files / 'p.yaml'), '--input', str(files / 'x.csv'),
                 '--output', str(out)]) == 0
    assert out.stat().st_mode & 0o777 == 0o640
    assert sorted(p.name for p in tmp_path.iterdir()) == ['link.yaml', 'real.yaml', 'sim.csv']


def _copy_bag(files, tmp_path, storage):
    source = files / f'bag_{storage}'
    copy = tmp_path / f'bag_{storage}'
    copy.mkdir()
    for p in source.iterdir():
        (copy / p.name).write_bytes(p.read_bytes())
    return copy, next(p for p in copy.iterdir() if p.suffix in ('.db3', '.mcap'))


def _cut_one_byte(path):
    path.write_bytes(path.read_bytes()[:-1])


def _delete_rows(path):
    with sqlite3.connect(path) as db:
        db.execute('DELETE FROM messages WHERE id IN (SELECT id FROM messages ORDER BY id '
                   'DESC LIMIT 3)')


def _flip_a_message_byte(path):
    data = bytearray(path.read_bytes())
    data[len(data) // 3] ^= 0xFF            # inside the first chunk's messages
    path.write_bytes(bytes(data))


@pytest.mark.parametrize('storage, damage, needle', [
    ('sqlite3', _cut_one_byte, 'not the whole 4096-byte pages'),
    ('sqlite3', _delete_rows, 'its metadata.yaml records'),
    ('mcap', _cut_one_byte, 'truncated or corrupt'),
    ('mcap', _flip_a_message_byte, 'truncated or corrupt'),
], ids=['sqlite3 cut by one byte', 'sqlite3 rows deleted', 'mcap cut by one byte',
        'mcap byte flipped'])
def test_a_damaged_bag_gives_one_error_line(files, tmp_path, storage, damage, needle):
    bag, storage_file = _copy_bag(files, tmp_path, storage)
    damage(storage_file)
    damaged = _digests(bag)
    done = _run('identify', bag, *ORDER, '-o', tmp_path / 'p.yaml')
    line = _one_error(done, needle)
    assert str(bag) in line and 're-record' in line
    assert _digests(bag) == damaged
    assert not (tmp_path / 'p.yaml').exists()


RECORDER = textwrap.dedent("""
    import sys, time
    from mpi_ros.recordings import BagRecorder
    recorder = BagRecorder(sys.argv[1], storage=sys.argv[2], flush_period=0.2)
    recorder.open()
    for k in range(1500):
        recorder.write_input(1e-3 * k, 0.5 + 0.4 * ((k // 150) % 2))
        recorder.write_output(1e-3 * k + 1e-6, 1e-6 * ((k // 150) % 2) + 1e-9 * k)
    time.sleep(0.3)                      # longer than flush_period: the next write commits
    recorder.write_input(1.5, 0.5)
    print('written', flush=True)
    time.sleep(600)
""")


@pytest.mark.parametrize('storage', ['sqlite3', 'mcap'])
def test_a_recorder_killed_with_sigkill_leaves_a_readable_partial_bag(tmp_path, storage):
    target = tmp_path / 'run'
    proc = subprocess.Popen([sys.executable, '-c', RECORDER, str(target), storage],
                            stdout=subprocess.PIPE, text=True, preexec_fn=_limit)
    try:
        assert proc.stdout.readline().strip() == 'written'
    finally:
        proc.send_signal(signal.SIGKILL)
        proc.wait(timeout=TIMEOUT)
        proc.stdout.close()
    assert not target.exists()               # the bag appears at its path only when closed
    partial = [p for p in tmp_path.iterdir() if p.name.startswith('.run.')]
    assert len(partial) == 1, list(tmp_path.iterdir())
    recording = read_bag_signals(partial[0] / 'run')
    assert len(recording.time) >= 1499               # all but the unpaired last
    assert any('metadata.yaml' in note for note in recording.notes)
    if storage == 'mcap':
        assert any('was not finished' in note for note in recording.notes)


def test_an_unfinished_mcap_is_read_up_to_its_last_whole_chunk(tmp_path):
    t, x, y = _signals(seconds=2.0)
    with BagRecorder(tmp_path / 'run', storage='mcap', flush_period=0.0) as recorder:
        for k in range(t.size):
            recorder.write_input(t[k], x[k])
            recorder.write_output(t[k] + 1e-6, y[k])
    storage_file = tmp_path / 'run' / 'run.mcap'
    (tmp_path / 'run' / 'metadata.yaml').unlink()         # as a killed recorder leaves it
    data = storage_file.read_bytes()
    storage_file.write_bytes(data[:len(data) // 2])       # cut inside a chunk
    recording = read_bag_signals(tmp_path / 'run')
    assert 0.1 * t.size < len(recording.time) < t.size
    np.testing.assert_array_equal(recording.current, x[:len(recording.time)])
    np.testing.assert_array_equal(recording.displacement, y[:len(recording.time)])
    assert any('was not finished' in note for note in recording.notes)


KILLER = textwrap.dedent("""
    import os, signal, sys
    from mpi_ros.recordings import files
    from mpi_ros.app.cli import main
    calls = {'n': 0}
    real = os.replace
    def replace(source, target):
        calls['n'] += 1
        if calls['n'] == int(sys.argv[1]):
            os.kill(os.getpid(), signal.SIGKILL)     # kill -9 just before this rename
        return real(source, target)
    files.os.replace = replace
    sys.exit(main(sys.argv[2:]))
""")


def _killed_at(rename, argv, cwd):
    return subprocess.run([sys.executable, '-c', KILLER, str(rename), *map(str, argv)],
                          capture_output=True, text=True, timeout=TIMEOUT, cwd=cwd,
                          preexec_fn=_limit)


def _sha(path):
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


def test_identify_killed_at_each_rename_keeps_a_usable_pair(files, tmp_path):
    yaml_path, json_path = tmp_path / 'p.yaml', tmp_path / 'p.json'
    argv = ['identify', files / 'bag_sqlite3', *ORDER, '-o', yaml_path, '--json', json_path]
    assert main([str(a) for a in argv]) == 0
    old = {'yaml': yaml_path.read_bytes(), 'json': json_path.read_bytes()}
    assert json.loads(old['json'])['params_file']['sha256'] == _sha(yaml_path)
    # Another fit (the CSV record) writes other bytes; killed before each rename.
    argv[1] = files / 'd.csv'
    done = _killed_at(1, argv, tmp_path)
    assert done.returncode == -signal.SIGKILL
    assert yaml_path.read_bytes() == old['yaml'] and json_path.read_bytes() == old['json']
    done = _killed_at(2, argv, tmp_path)            # between the two renames
    assert done.returncode == -signal.SIGKILL
    assert yaml_path.read_bytes() != old['yaml'] and json_path.read_bytes() == old['json']
    assert json.loads(json_path.read_text())['params_file']['sha256'] != _sha(yaml_path)
    debris = sorted(p.name for p in tmp_path.iterdir() if p.name.startswith('.'))
    assert len(debris) == 1 and debris[0].startswith('.p.json.'), debris
    # The next run removes the dead writer's temporary file and writes a matching pair.
    assert main([str(a) for a in argv]) == 0
    assert json.loads(json_path.read_text())['params_file']['sha256'] == _sha(yaml_path)
    assert sorted(p.name for p in tmp_path.iterdir()) == ['p.json', 'p.yaml']


def test_diagnose_killed_at_a_rename_keeps_old_or_new_files(files, tmp_path):
    def command(folder, split):
        return ['diagnose', files / 'bag_sqlite3', *ORDER, '--split', split, '--json',
                folder / 'r.json', '--report', folder / 'r']

    work, fresh = tmp_path / 'work', tmp_path / 'fresh'
    work.mkdir()
    fresh.mkdir()
    assert main([str(a) for a in command(work, 0.6)]) == 0
    assert main([str(a) for a in command(fresh, 0.5)]) == 0   # what the killed runs write
    old, new = _digests(work), _digests(fresh)
    assert old.keys() == new.keys() and old['r.json'] != new['r.json']
    renames = len(old)                      # one per file: the plots, summary.md, the JSON
    for rename in (1, renames // 2 + 1, renames):
        done = _killed_at(rename, command(work, 0.5), tmp_path)
        assert done.returncode == -signal.SIGKILL, done.stderr[-2000:]
        now = _digests(work)
        kept = {name: digest for name, digest in now.items() if not name.startswith('.')}
        assert kept.keys() == old.keys()
        assert all(digest in (old[name], new[name]) for name, digest in kept.items())
        assert kept['r.json'] == old['r.json']          # the JSON is renamed last
        assert all(p.stat().st_size > 0 for p in work.rglob('*') if p.is_file())
    assert main([str(a) for a in command(work, 0.5)]) == 0
    assert _digests(work) == new                       # no debris left, all files new


def test_atomic_writes_leave_nothing_after_an_error(tmp_path):
    first, second = tmp_path / 'a.txt', tmp_path / 'b.txt'
    first.write_text('old a')
    stale = tmp_path / '.b.txt.999999999.abcdefgh.tmp'       # a dead writer's (no such pid)
    stale.write_text('partial')
    with pytest.raises(ValueError, match='midway'):
        with atomic_writes([first, second]) as (a, b):
            a.write('new a')
            b.write('new b')
            raise ValueError('midway')
    assert first.read_text() == 'old a' and not second.exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == ['a.txt']
    with pytest.raises(DataError, match='are the same file'):
        with atomic_writes([first, tmp_path / '.' / 'a.txt']):
            pass


def test_a_device_is_written_in_place_not_replaced(files, tmp_path):
    before = os.stat(os.devnull)
    assert main(['simulate', str(files / 'p.yaml'), '--input', str(files / 'x.csv'),
                 '--output', os.devnull]) == 0
    after = os.stat(os.devnull)
    assert (after.st_ino, after.st_mode, after.st_rdev) == (
        before.st_ino, before.st_mode, before.st_rdev)
    assert not list(Path(os.devnull).parent.glob('.null.*'))


def test_diagnose_on_a_constant_output_says_constant(files, tmp_path):
    t, x, _ = _signals()
    write_csv_columns(tmp_path / 'c.csv', {'time': t, 'current': x,
                                           'displacement': np.full(t.size, 2.5e-5)})
    argv = ['--json', tmp_path / 'r.json', '--report', tmp_path / 'r', *ORDER]
    for data in (['diagnose', tmp_path / 'c.csv'],
                 ['diagnose', files / 'd.csv', '--validate', tmp_path / 'c.csv']):
        done = _run(*data, *argv)
        line = _one_error(done, 'the displacement is constant')
        assert 'butterfly' not in line
    assert not (tmp_path / 'r.json').exists()


@pytest.mark.parametrize('argv, needle', [
    (['simulate', '{p}', '--input', '/dev/zero', '--output', '{t}/o.csv'], 'is a device'),
    (['simulate', '/dev/zero', '--input', '{x}', '--output', '{t}/o.csv'], 'larger than'),
    (['simulate', '{p}', '--input', '{t}', '--output', '{t}/o.csv'], 'is a directory'),
    (['diagnose', '{d}', *ORDER, '--json', '{t}/r.json', '--report', '{x}'], 'is a file'),
], ids=['device as CSV', 'device as YAML', 'folder as CSV', 'file as report folder'])
def test_odd_paths_give_one_error_line_before_any_work(files, tmp_path, capsys, argv, needle):
    names = {'p': files / 'p.yaml', 'x': files / 'x.csv', 'd': files / 'd.csv', 't': tmp_path}
    before = _digests(files)
    status = main([arg.format(**names) for arg in argv])
    err = capsys.readouterr().err.strip().splitlines()
    assert status == 1 and err[-1].startswith('error: ') and needle in err[-1], err
    assert [line for line in err if 'error' in line.lower()] == err[-1:]
    assert _digests(files) == before and list(tmp_path.iterdir()) == []
