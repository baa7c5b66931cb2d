# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""Tests of mpi_ros.recordings: bags and CSV files in, Recording out, atomic writes."""

from pathlib import Path
import shutil
import subprocess
import sys

from hypothesis import given, HealthCheck, settings, strategies as st
from mpi_ros.errors import DataError
from mpi_ros.recordings import (
    atomic_write, BagRecorder, read_bag_signals, read_csv_signals, read_csv_table,
    read_signals, Recording, write_bag_signals, write_csv_columns)
from mpi_ros.recordings.bag_reader import _sort_dedupe
from mpi_ros.recordings.recording import check_magnitudes
import numpy as np
import pytest
from rosbags.rosbag2 import StoragePlugin, Writer
from rosbags.typesys import get_typestore, Stores

SHARED = Path(__file__).resolve().parents[1].parent / 'shared'
MEASURED_CSV = SHARED / 'data/measured/pnzt-aixacct-tue/csv/SLOW_table03_TEST_800V.csv'
STORAGES = ['sqlite3', 'mcap']
EXACT = 0.0  # values go through float64 unchanged
TIME_TOL = 1e-9  # [s] times are stored as rounded integer nanoseconds


def _signals(n=50, seed=0):
    rng = np.random.default_rng(seed)
    time = np.cumsum(rng.uniform(1e-3, 2e-3, n))
    current = rng.uniform(-1.0, 1.0, n)
    displacement = rng.normal(0.0, 1e-6, n)
    return time, current, displacement


def _leftovers(directory):
    """Names of temporary files or directories left beside a target."""
    return sorted(p.name for p in Path(directory).iterdir() if p.name.startswith('.'))


def _write_raw_bag(path, topics):
    """Write a bag with rosbags directly: topics maps name -> (msgtype, list of (ns, msg))."""
    store = get_typestore(Stores.ROS2_JAZZY)
    with Writer(path, version=9, storage_plugin=StoragePlugin.SQLITE3) as writer:
        for topic, (msgtype, messages) in topics.items():
            conn = writer.add_connection(topic, msgtype, typestore=store)
            for stamp, msg in messages:
                writer.write(conn, stamp, store.serialize_cdr(msg, msgtype))


def _float64(value):
    store = get_typestore(Stores.ROS2_JAZZY)
    return store.types['std_msgs/msg/Float64'](data=float(value))


def _write_csv(path, text):
    path.write_text(text, encoding='utf-8')
    return path


def _csv_text(n=20, *, header='time,current,displacement', seed=0):
    time, current, displacement = _signals(n, seed)
    rows = [f'{t!r},{x!r},{s!r}'
            for t, x, s in zip(time.tolist(), current.tolist(), displacement.tolist())]
    return '\n'.join(['# a comment', header, *rows]) + '\n', (time, current, displacement)


# ------------------------------------------------------------------ Recording


def test_recording_freezes_copies():
    data = np.arange(3.0)
    rec = Recording(data, data, data, source='x', notes=['n'])
    data[0] = 99.0
    assert rec.time[0] == 0.0
    assert rec.notes == ('n',)
    assert len(rec) == 3
    with pytest.raises(ValueError, match='read-only'):
        rec.current[0] = 1.0


def test_recording_rejects_bad_arrays():
    with pytest.raises(DataError, match='equal lengths'):
        Recording([0.0, 1.0], [0.0], [0.0, 1.0])
    with pytest.raises(DataError, match='one-dimensional'):
        Recording(np.zeros((2, 2)), np.zeros(2), np.zeros(2))
    with pytest.raises(DataError, match='array of numbers'):
        Recording(['a', 'b'], [0.0, 1.0], [0.0, 1.0])


# ------------------------------------------------------------------ bags: round trips


@pytest.mark.parametrize('storage', STORAGES)
def test_bag_round_trip(tmp_path, storage):
    time, current, displacement = _signals()
    time = time - time[0]
    bag = tmp_path / 'run'
    write_bag_signals(bag, time, current, displacement, storage=storage)
    assert _leftovers(tmp_path) == []
    suffix = {'sqlite3': '.db3', 'mcap': '.mcap'}[storage]
    for source in (bag, bag / 'metadata.yaml', bag / f'run{suffix}'):
        rec = read_bag_signals(source)
        np.testing.assert_allclose(rec.time, time, rtol=0, atol=TIME_TOL)
        np.testing.assert_allclose(rec.current, current, rtol=0, atol=EXACT)
        np.testing.assert_allclose(rec.displacement, displacement, rtol=0, atol=EXACT)
        assert rec.notes == ()
        assert rec.source == str(source)
    assert len(read_signals(bag)) == time.size


@pytest.mark.parametrize('storage', STORAGES)
def test_bag_custom_topics_round_trip(tmp_path, storage):
    time, current, displacement = _signals(12)
    bag = tmp_path / 'custom'
    write_bag_signals(bag, time, current, displacement, input_topic='/u', output_topic='/y',
                      storage=storage)
    rec = read_signals(bag, input_topic='/u', output_topic='/y')
    np.testing.assert_allclose(rec.displacement, displacement, rtol=0, atol=EXACT)
    with pytest.raises(DataError, match=r'no topic /current_command; topics in the bag: /u'):
        read_bag_signals(bag)


def test_bag_pairing_holds_latest_input(tmp_path):
    bag = tmp_path / 'pairing'
    with BagRecorder(bag) as rec:
        rec.write_output(0.0005, -1.0)  # before any command: dropped
        rec.write_output(0.0008, -2.0)  # before any command: dropped
        for k in range(5):
            rec.write_input(0.001 + 0.01 * k, float(k))
        for k in range(40):  # outputs four times faster than the commands
            rec.write_output(0.001 + 0.0025 * k, 1e-6 * k)
    assert rec.counts == {'/current_command': 5, '/displacement': 42}
    out = read_bag_signals(bag)
    t_out = 0.001 + 0.0025 * np.arange(40)
    expected_current = np.minimum(np.floor((t_out - 0.001) / 0.01 + 1e-9), 4.0)  # inclusive
    np.testing.assert_array_equal(out.current, expected_current)
    np.testing.assert_allclose(out.displacement, 1e-6 * np.arange(40), rtol=0, atol=EXACT)
    np.testing.assert_allclose(out.time, t_out - t_out[0], rtol=0, atol=TIME_TOL)
    assert any('dropped 2 /displacement' in note for note in out.notes)


def test_bag_duplicates_keep_last_and_are_noted(tmp_path):
    bag = tmp_path / 'dup'
    with BagRecorder(bag) as rec:
        rec.write_input(0.0, 1.0)
        rec.write_input(0.0001, 2.0)
        for k in range(12):
            rec.write_output(0.001 * (k + 1), float(k))
        rec.write_output(0.012, 100.0)  # same time as the last one: this value wins
        rec.write_output(0.005, 50.0)
    out = read_bag_signals(bag)
    assert out.displacement.size == 12
    assert out.displacement[-1] == 100.0
    assert out.displacement[4] == 50.0
    assert any('2 duplicate time stamp(s)' in note for note in out.notes)


def test_sort_dedupe_is_stable_and_keeps_last():
    stamps = np.array([30, 10, 20, 10, 40, 30], dtype=np.int64)
    values = np.array([0.0, 1.0, 2.0, 3.0, 4.0, 5.0])
    t, v, n_unsorted, n_duplicate = _sort_dedupe(stamps, values)
    np.testing.assert_array_equal(t, [10, 20, 30, 40])
    np.testing.assert_array_equal(v, [3.0, 2.0, 5.0, 4.0])
    assert (n_unsorted, n_duplicate) == (3, 2)  # descents 30>10, 20>10, 40>30


# ------------------------------------------------------------------ bags: errors


def test_bag_missing_path(tmp_path):
    with pytest.raises(DataError, match=r'bag .*nope does not exist; check the path'):
        read_bag_signals(tmp_path / 'nope')
    with pytest.raises(DataError, match=r'nope does not exist'):
        read_signals(tmp_path / 'nope')


def test_not_a_bag(tmp_path):
    empty = tmp_path / 'empty'
    empty.mkdir()
    with pytest.raises(DataError, match=r'is not a rosbag2 bag: it holds no metadata.yaml'):
        read_bag_signals(empty)
    text = _write_csv(tmp_path / 'notes.txt', 'hello')
    with pytest.raises(DataError, match=r'notes.txt is not a rosbag2 bag'):
        read_bag_signals(text)
    with pytest.raises(DataError, match=r"unknown file type '.txt'"):
        read_signals(text)
    fake = _write_csv(tmp_path / 'fake.db3', 'not sqlite at all, just text' * 10)
    with pytest.raises(DataError, match=r'cannot read bag .*fake.db3.*truncated or corrupt'):
        read_bag_signals(fake)


@pytest.mark.parametrize('storage', STORAGES)
@pytest.mark.parametrize('fraction', [0.02, 0.5, 0.9])
def test_bag_truncated(tmp_path, storage, fraction):
    bag = tmp_path / 'cut'
    write_bag_signals(bag, *_signals(200), storage=storage)
    storage_file = next(p for p in bag.iterdir() if p.name != 'metadata.yaml')
    data = storage_file.read_bytes()
    storage_file.write_bytes(data[:int(len(data) * fraction)])
    with pytest.raises(DataError, match=r'cannot read bag .*cut.*truncated or corrupt'):
        read_bag_signals(bag)


def test_bag_missing_storage_file(tmp_path):
    bag = tmp_path / 'gone'
    write_bag_signals(bag, *_signals(20))
    (bag / 'gone.db3').unlink()
    with pytest.raises(DataError, match=r'is not a rosbag2 bag|cannot read bag'):
        read_bag_signals(bag)


def test_bag_without_metadata_reads_storage_file(tmp_path):
    bag = tmp_path / 'interrupted'
    write_bag_signals(bag, *_signals(20))
    (bag / 'metadata.yaml').unlink()
    rec = read_bag_signals(bag)
    assert len(rec) == 20
    assert any('no metadata.yaml' in note for note in rec.notes)
    shutil.copy(bag / 'interrupted.db3', bag / 'second.db3')
    with pytest.raises(DataError, match=r'no metadata.yaml and 2 storage files; run `ros2 bag'):
        read_bag_signals(bag)


def test_bag_wrong_message_type(tmp_path):
    store = get_typestore(Stores.ROS2_JAZZY)
    text = store.types['std_msgs/msg/String']
    bag = tmp_path / 'typed'
    _write_raw_bag(bag, {
        '/current_command': ('std_msgs/msg/Float64', [(k, _float64(k)) for k in range(20)]),
        '/displacement': ('std_msgs/msg/String', [(k, text(data='x')) for k in range(20)]),
    })
    with pytest.raises(DataError, match=r'topic /displacement in bag .* has type '
                                        r'std_msgs/msg/String; expected std_msgs/msg/Float64'):
        read_bag_signals(bag)


def test_bag_missing_topic_lists_present_ones(tmp_path):
    bag = tmp_path / 'one_topic'
    _write_raw_bag(bag, {
        '/current_command': ('std_msgs/msg/Float64', [(k, _float64(k)) for k in range(20)]),
        '/other': ('std_msgs/msg/Float64', [(k, _float64(k)) for k in range(20)]),
    })
    with pytest.raises(DataError, match=r'has no topic /displacement; topics in the bag: '
                                        r'/current_command \(std_msgs/msg/Float64\), /other'
                                        r'.*pass output_topic='):
        read_bag_signals(bag)


def test_bag_empty_and_single_topics(tmp_path):
    empty = tmp_path / 'empty_topic'
    _write_raw_bag(empty, {
        '/current_command': ('std_msgs/msg/Float64', [(k, _float64(k)) for k in range(20)]),
        '/displacement': ('std_msgs/msg/Float64', []),
    })
    with pytest.raises(DataError, match=r'topic /displacement in bag .* has no messages; '
                                        r'check that its publisher ran'):
        read_bag_signals(empty)
    single = tmp_path / 'single'
    _write_raw_bag(single, {
        '/current_command': ('std_msgs/msg/Float64', [(0, _float64(1.0))]),
        '/displacement': ('std_msgs/msg/Float64', [(k, _float64(k)) for k in range(20)]),
    })
    with pytest.raises(DataError, match=r'topic /current_command in bag .* has a single '
                                        r'message'):
        read_bag_signals(single)


def test_bag_too_few_pairs(tmp_path):
    bag = tmp_path / 'few'
    with BagRecorder(bag) as rec:
        for k in range(20):
            rec.write_output(0.001 * k, float(k))
        rec.write_input(0.0105, 1.0)
        rec.write_input(0.0106, 2.0)
    with pytest.raises(DataError, match=r'only 9 /displacement message\(s\) at or after the '
                                        r'first /current_command message \(need at least 10\)'):
        read_bag_signals(bag)


def test_bag_nonfinite_rejected_or_dropped(tmp_path):
    time, current, displacement = _signals(30)
    displacement[[7, 12, 20]] = [np.nan, np.inf, -np.inf]
    bag = tmp_path / 'nan'
    write_bag_signals(bag, time, current, displacement)
    with pytest.raises(DataError, match=r'topic /displacement in bag .* has 3 non-finite '
                                        r'value\(s\) \(NaN/Inf\), the first at message 7 .*'
                                        r'drop_nonfinite=True'):
        read_bag_signals(bag)
    rec = read_bag_signals(bag, drop_nonfinite=True)
    assert len(rec) == 27
    assert np.all(np.isfinite(rec.displacement))
    assert any('dropped 3 non-finite' in note for note in rec.notes)


def test_bag_unknown_time_source(tmp_path):
    bag = tmp_path / 'ok'
    write_bag_signals(bag, *_signals(12))
    with pytest.raises(DataError, match=r"time_source must be one of \('receive',\); found "
                                        r"'header'"):
        read_bag_signals(bag, time_source='header')


def test_bag_same_topics_rejected(tmp_path):
    with pytest.raises(DataError, match=r'input_topic and output_topic are both'):
        read_bag_signals(tmp_path, input_topic='/a', output_topic='/a')
    with pytest.raises(DataError, match=r'output_topic must be a non-empty topic name'):
        BagRecorder(tmp_path / 'x', output_topic='')


def test_read_signals_rejects_options_of_other_reader(tmp_path):
    bag = tmp_path / 'opts'
    write_bag_signals(bag, *_signals(12))
    with pytest.raises(DataError, match=r'option\(s\) input_column do not apply to rosbag2 '
                                        r'bag'):
        read_signals(bag, input_column='current')
    csv_file = _write_csv(tmp_path / 'a.csv', _csv_text()[0])
    with pytest.raises(DataError, match=r'option\(s\) input_topic do not apply to CSV file'):
        read_signals(csv_file, input_topic='/x')


# ------------------------------------------------------------------ bag writing


def test_write_bag_is_atomic_on_error(tmp_path):
    bag = tmp_path / 'atomic'
    with pytest.raises(RuntimeError, match='boom'):
        with BagRecorder(bag, storage='mcap') as rec:
            rec.write_input(0.0, 1.0)
            raise RuntimeError('boom')
    assert not bag.exists()
    assert _leftovers(tmp_path) == []
    time, current, displacement = _signals(12)
    time[5] = time[4]
    with pytest.raises(DataError, match=r'time must increase by at least 2 ns per sample; '
                                        r'sample 5'):
        write_bag_signals(bag, time, current, displacement)
    with pytest.raises(DataError, match=r'time must be finite and between 0'):
        write_bag_signals(bag, -time, current, displacement)
    with pytest.raises(DataError, match=r'equal lengths'):
        write_bag_signals(bag, time[:3], current, displacement)
    assert list(tmp_path.iterdir()) == []


def test_bag_recorder_state_errors(tmp_path):
    rec = BagRecorder(tmp_path / 'state')
    with pytest.raises(DataError, match=r'is not open; call open\(\) first'):
        rec.write_input(0.0, 1.0)
    rec.open()
    with pytest.raises(DataError, match=r'write_output time t must be a finite time >= 0 s'):
        rec.write_output(float('nan'), 1.0)
    with pytest.raises(DataError, match=r'value for topic /current_command must be a number'):
        rec.write_input(0.0, 'high')
    rec.close()
    rec.close()  # idempotent
    with pytest.raises(DataError, match=r'was already opened; create a new BagRecorder'):
        rec.open()
    with pytest.raises(DataError, match=r"storage must be one of \['mcap', 'sqlite3'\]"):
        BagRecorder(tmp_path / 'x', storage='rosbag1')


def test_bag_exists_and_overwrite(tmp_path):
    bag = tmp_path / 'again'
    write_bag_signals(bag, *_signals(12, seed=1))
    with pytest.raises(DataError, match=r'it exists already; choose another path or pass '
                                        r'overwrite=True'):
        write_bag_signals(bag, *_signals(12, seed=2))
    with pytest.raises(DataError, match=r'directory .*missing does not exist; create it first'):
        write_bag_signals(tmp_path / 'missing' / 'bag', *_signals(12))
    time, current, displacement = _signals(15, seed=2)
    write_bag_signals(bag, time, current, displacement, overwrite=True, storage='mcap')
    np.testing.assert_allclose(read_bag_signals(bag).current, current, rtol=0, atol=EXACT)
    assert sorted(p.name for p in bag.iterdir()) == ['again.mcap', 'metadata.yaml']
    assert _leftovers(tmp_path) == []


# ------------------------------------------------------------------ CSV signals


def test_csv_defaults_and_round_trip(tmp_path):
    time, current, displacement = _signals(25)
    path = tmp_path / 'sig.csv'
    write_csv_columns(path, {'time': time, 'current': current, 'displacement': displacement},
                      comment='made by a test\nsecond line')
    rec = read_signals(path)
    np.testing.assert_array_equal(rec.time, time)
    np.testing.assert_array_equal(rec.current, current)
    np.testing.assert_array_equal(rec.displacement, displacement)
    assert rec.notes == ()
    assert path.read_text().startswith('# made by a test\n# second line\ntime,')


def test_csv_named_columns_scales_quotes_and_crlf(tmp_path):
    rows = [f'{k},"x{k}",{0.1 * k!r},{k * 1000.0!r},{k * 2.0!r}' for k in range(12)]
    text = '\r\n'.join(['"ms","label","volt","nm","other"', *rows]) + '\r\n'
    path = _write_csv(tmp_path / 'q.csv', text)
    rec = read_csv_signals(path, time_column='ms', input_column='volt', output_column='nm',
                           output_scale=1e-9, time_scale=1e-3, input_scale=2.0)
    np.testing.assert_allclose(rec.time, np.arange(12) * 1e-3, rtol=1e-15)
    np.testing.assert_allclose(rec.current, 0.2 * np.arange(12), rtol=1e-15)
    np.testing.assert_allclose(rec.displacement, np.arange(12) * 1e-6, rtol=1e-15)
    # Issue 27: without scales the column names give the units (ms, nm) and the values are
    # converted to SI; 'volt' names a voltage, kept in V.
    default = read_csv_signals(path, time_column='ms', input_column='volt')
    np.testing.assert_allclose(default.displacement, np.arange(12) * 1000.0 * 1e-9,
                               rtol=1e-15)
    np.testing.assert_allclose(default.time, np.arange(12) * 1e-3, rtol=1e-15)
    assert default.units.input_quantity == 'voltage'
    assert (default.units.time, default.units.output) == ('ms', 'nm')


def test_csv_without_time_column(tmp_path):
    path = _write_csv(tmp_path / 'nt.csv', 'v,y\n' + ''.join(f'{k},{2 * k}\n' for k in range(10)))
    rec = read_csv_signals(path, time_column=None)
    np.testing.assert_array_equal(rec.time, np.arange(10.0))
    np.testing.assert_array_equal(rec.displacement, 2.0 * np.arange(10))
    assert rec.notes == ('no time column: time is the sample index 0, 1, 2, ...',)


def test_csv_time_not_increasing_is_noted(tmp_path):
    text, _ = _csv_text(12)
    lines = text.splitlines()
    lines[5] = '0.0,' + lines[5].split(',', 1)[1]
    rec = read_csv_signals(_write_csv(tmp_path / 't.csv', '\n'.join(lines)))
    assert rec.notes == ("time column 'time' is not strictly increasing (first at line 6); "
                         'samples are kept in file order',)


@pytest.mark.parametrize(('text', 'match'), [
    ('', r'is empty; expected a header row'),
    ('\n  \n', r'is empty; expected a header row'),
    ('# only\n# comments\n', r'has only comments; expected a header row'),
    ('0,1,2\n' * 12, r'has no header row: line 1 holds numbers'),
    ('time,,displacement\n', r'has an empty name for column 2'),
    ('time,a,a\n', r"repeats column name\(s\) 'a'"),
    ('time,a,b\n' + '0,1,2\n' * 5 + '0,1\n',
     r'line 7 has 2 field\(s\) but the header \(line 1\) has 3'),
    ('time,a,b\n' + '0,1,2\n' * 9, r'has only 9 data row\(s\); a recording needs at least 10'),
    ('time,a,b\n' + '0,1,2\n' * 9 + '0,1,x2\n',
     r"line 11, column 'b' \(column 3\): expected a number, found 'x2'"),
    ('time,a,b\n' + '0,1,2\n' * 9 + '0,,2\n',
     r'1 row\(s\) with non-finite values \(NaN, Inf or empty fields\), the first at line 11, '
     r"column 'a' \(an empty field\); fix the data or pass drop_nonfinite=True"),
    ('time,a,b\n' + '0,1,2\n' * 9 + '0,1_0,2\n', r"found '1_0'"),
    ('time,a,b\n' + '0,1,"2\n' * 10, r'line 3 is not valid CSV'),
])
def test_csv_errors(tmp_path, text, match):
    path = _write_csv(tmp_path / 'bad.csv', text)
    with pytest.raises(DataError, match=match):
        read_csv_signals(path)


def test_csv_missing_file_and_columns(tmp_path):
    with pytest.raises(DataError, match=r'CSV file .*absent.csv does not exist'):
        read_csv_signals(tmp_path / 'absent.csv')
    with pytest.raises(DataError, match=r'is a directory, not a CSV file'):
        read_csv_signals(tmp_path)
    path = _write_csv(tmp_path / 'c.csv', _csv_text()[0])
    with pytest.raises(DataError, match=r"has no column 'volts' \(input_column\); available "
                                        r"columns: 'time', 'current', 'displacement'"):
        read_csv_signals(path, input_column='volts')
    with pytest.raises(DataError, match=r"has no column 'Time_s' \(time_column\); available "
                                        r'.*time_column=None'):
        read_csv_signals(path, time_column='Time_s')
    with pytest.raises(DataError, match=r"no column after the input column 'displacement'"):
        read_csv_signals(path, input_column='displacement')
    with pytest.raises(DataError, match=r"input_column and output_column are both 'current'"):
        read_csv_signals(path, input_column='current', output_column='current')
    with pytest.raises(DataError, match=r'output_scale must be a finite non-zero number'):
        read_csv_signals(path, output_scale=0.0)
    only_time = _write_csv(tmp_path / 'ot.csv', 'time\n' + '0\n' * 12)
    with pytest.raises(DataError, match=r"no column besides the time column 'time'"):
        read_csv_signals(only_time)


def test_csv_not_utf8(tmp_path):
    path = tmp_path / 'latin.csv'
    path.write_bytes(b'time,current,displacement\n' + b'0,1,2\n' * 3 + b'0,\xb5,2\n')
    with pytest.raises(DataError, match=r'line 5 is not UTF-8 text .*save the file as UTF-8'):
        read_csv_signals(path)


def test_csv_nonfinite_rejected_or_dropped(tmp_path):
    text, (time, current, _) = _csv_text(15)
    lines = text.splitlines()
    lines[5] = lines[5].rsplit(',', 1)[0] + ',nan'
    lines[9] = lines[9].split(',', 1)[0] + ',inf,' + lines[9].rsplit(',', 1)[1]
    path = _write_csv(tmp_path / 'nan.csv', '\n'.join(lines))
    with pytest.raises(DataError, match=r'has 2 row\(s\) with non-finite values \(NaN, Inf or '
                                        r'empty fields\), the first at line 6, column '
                                        r"'displacement' \('nan'\)"):
        read_csv_signals(path)
    rec = read_csv_signals(path, drop_nonfinite=True)
    assert len(rec) == 13
    np.testing.assert_array_equal(rec.time, np.delete(time, [3, 7]))
    assert rec.notes == ('dropped 2 row(s) with non-finite values (NaN, Inf or empty fields)',)
    short = _write_csv(tmp_path / 'short.csv', '\n'.join(lines[:13]))
    with pytest.raises(DataError, match=r'only 9 data row\(s\) after dropping non-finite rows'):
        read_csv_signals(short, drop_nonfinite=True)


def test_csv_empty_fields_are_missing_values(tmp_path):
    """Empty fields (pandas' NaN) are dropped by drop_nonfinite like NaN/Inf, else refused."""
    text, (time, current, displacement) = _csv_text(15)
    lines = text.splitlines()                  # lines[k] is file line k + 1: sample k - 2
    lines[4] = lines[4].split(',', 1)[0] + ',,' + lines[4].rsplit(',', 1)[1]   # current
    lines[8] = lines[8].rsplit(',', 1)[0] + ','                                 # displacement
    lines[11] = ',' + lines[11].split(',', 1)[1]                                 # time
    path = _write_csv(tmp_path / 'pandas.csv', '\n'.join(lines))
    with pytest.raises(DataError, match=r'has 3 row\(s\) with non-finite values \(NaN, Inf or '
                                        r"empty fields\), the first at line 5, column 'current' "
                                        r'\(an empty field\); fix the data or pass '
                                        r'drop_nonfinite=True'):
        read_csv_signals(path)
    rec = read_csv_signals(path, drop_nonfinite=True)
    assert len(rec) == 12
    np.testing.assert_array_equal(rec.time, np.delete(time, [2, 6, 9]))
    np.testing.assert_array_equal(rec.current, np.delete(current, [2, 6, 9]))
    assert rec.notes == ('dropped 3 row(s) with non-finite values (NaN, Inf or empty fields)',)
    header, table = read_csv_table(path, drop_nonfinite=True)
    assert table.shape == (12, 3)
    with pytest.raises(DataError, match=r'the first at line 5, column .current. \(an empty'):
        read_csv_table(path)


@pytest.mark.parametrize(('edits', 'drop', 'match'), [
    # A text field after an empty one: the empty one (line 4) is named, not the later text.
    ([(4, 'current', ''), (12, 'time', 'abc')], False,
     r"the first at line 4, column 'current' \(an empty field\)"),
    # The columns are read time, current, displacement; the first bad line still wins.
    ([(9, 'time', 'x'), (3, 'displacement', 'y')], False,
     r"line 3, column 'displacement' \(column 3\): expected a number, found 'y'"),
    ([(9, 'time', ''), (3, 'displacement', 'nan'), (6, 'current', 'inf')], False,
     r"3 row\(s\) .* the first at line 3, column 'displacement' \('nan'\)"),
    # Dropping cannot mend text: with drop_nonfinite the text field is named.
    ([(4, 'current', ''), (12, 'time', 'abc')], True,
     r"line 12, column 'time' \(column 1\): expected a number, found 'abc'"),
    # Within one line the leftmost bad field is named.
    ([(7, 'displacement', ''), (7, 'time', 'nan')], False,
     r"the first at line 7, column 'time' \('nan'\)"),
])
def test_csv_error_names_the_first_bad_line(tmp_path, edits, drop, match):
    text, _ = _csv_text(15)
    lines = text.splitlines()                  # lines[k] is file line k + 1
    names = lines[1].split(',')
    for line, column, value in edits:
        fields = lines[line - 1].split(',')
        fields[names.index(column)] = value
        lines[line - 1] = ','.join(fields)
    path = _write_csv(tmp_path / 'bad.csv', '\n'.join(lines))
    with pytest.raises(DataError, match=match):
        read_csv_signals(path, drop_nonfinite=drop)


@pytest.mark.parametrize(('scales', 'match'), [
    ({'output_scale': 1e-300},
     r'the displacement spans only [0-9.e-]+ m, too small to compute with .* rescale it to m '
     r'with output_scale=<factor> \(now 1e-300\)'),
    ({'input_scale': 1e120}, r'the current reaches [0-9.e+]+ A, too large to compute with'),
    ({'time_scale': 1e-200}, r'the time spans only [0-9.e-]+ s, too small'),
])
def test_csv_magnitudes_outside_the_arithmetic_are_refused(tmp_path, scales, match):
    path = _write_csv(tmp_path / 'm.csv', _csv_text(15)[0])
    with pytest.raises(DataError, match=match):
        read_csv_signals(path, **scales)
    rec = read_csv_signals(path, output_scale=1e-12, input_scale=1e12, time_scale=1e-12)
    assert len(rec) == 15                      # 1e-12 .. 1e12 is far inside
    with pytest.raises(DataError, match=r'x: the displacement reaches inf m, too large'):
        check_magnitudes(Recording([0.0, 1.0], [0.0, 1.0], [0.0, np.inf], source='x'))


def test_measured_csv_reads():
    if not MEASURED_CSV.is_file():
        pytest.skip(f'measured data not found at {MEASURED_CSV}')
    rec = read_signals(MEASURED_CSV, time_column='Time_s', input_column='Vplus_V',
                       output_column='D1_nm', output_scale=1e-9)
    assert len(rec) == 401
    assert rec.notes == ()
    np.testing.assert_allclose(rec.time[:3], [0.0, 0.0025, 0.005], rtol=0, atol=1e-15)
    np.testing.assert_allclose(rec.current[:2], [75.84723, 84.08724], rtol=1e-15)
    np.testing.assert_allclose(rec.displacement[:2], [0.0, -3.233214e-9], rtol=1e-15)
    assert np.all(np.diff(rec.time) > 0)
    header, table = read_csv_table(MEASURED_CSV)
    assert header[:3] == ['Time_s', 'Vplus_V', 'Vminus_V']
    assert table.shape == (401, 13)


# ------------------------------------------------------------------ tables, atomic writes


def test_csv_table_round_trip(tmp_path):
    rng = np.random.default_rng(3)
    columns = {'time': np.arange(7) * 0.1, 'current': rng.normal(size=7) * 10.0 ** rng.integers(
        -300, 300, 7), 'extra': rng.normal(size=7)}
    path = tmp_path / 'table.csv'
    write_csv_columns(path, columns)
    header, table = read_csv_table(path)
    assert header == ['time', 'current', 'extra']
    np.testing.assert_array_equal(table, np.column_stack(list(columns.values())))


def test_csv_table_errors(tmp_path):
    with pytest.raises(DataError, match=r'has no column besides the time column'):
        read_csv_table(_write_csv(tmp_path / 'a.csv', 'time\n0\n'))
    with pytest.raises(DataError, match=r'has a header but no data rows'):
        read_csv_table(_write_csv(tmp_path / 'b.csv', 'time,current\n'))
    with pytest.raises(DataError, match=r"line 3, column 'current' \(column 2\): expected a "
                                        r"number, found 'abc'"):
        read_csv_table(_write_csv(tmp_path / 'c.csv', 'time,current\n0,1\n1,abc\n'))
    with pytest.raises(DataError, match=r'the first at line 2, column .current.'):
        read_csv_table(_write_csv(tmp_path / 'd.csv', 'time,current\n0,nan\n1,2\n'))
    header, table = read_csv_table(tmp_path / 'd.csv', drop_nonfinite=True)
    np.testing.assert_array_equal(table, [[1.0, 2.0]])
    with pytest.raises(DataError, match=r'every row holds NaN/Inf or an empty field'):
        read_csv_table(_write_csv(tmp_path / 'e.csv', 'current\nnan\n'), drop_nonfinite=True)


def test_write_csv_columns_errors(tmp_path):
    with pytest.raises(DataError, match=r'no columns given'):
        write_csv_columns(tmp_path / 'x.csv', {})
    with pytest.raises(DataError, match=r"invalid column name 'a,b'"):
        write_csv_columns(tmp_path / 'x.csv', {'a,b': [1.0]})
    with pytest.raises(DataError, match=r'the arrays must have equal lengths'):
        write_csv_columns(tmp_path / 'x.csv', {'a': [1.0], 'b': [1.0, 2.0]})
    with pytest.raises(DataError, match=r'directory .*nodir does not exist'):
        write_csv_columns(tmp_path / 'nodir' / 'x.csv', {'a': [1.0]})
    assert list(tmp_path.iterdir()) == []


def test_atomic_write_leaves_nothing_on_failure(tmp_path):
    target = tmp_path / 'out.txt'
    with pytest.raises(RuntimeError, match='disk on fire'):
        with atomic_write(target) as handle:
            handle.write('partial')
            raise RuntimeError('disk on fire')
    assert list(tmp_path.iterdir()) == []
    with atomic_write(target) as handle:
        handle.write('old')
    with pytest.raises(KeyboardInterrupt):
        with atomic_write(target) as handle:
            handle.write('new but interrupted')
            raise KeyboardInterrupt
    assert target.read_text() == 'old'
    assert _leftovers(tmp_path) == []
    with atomic_write(target, binary=True) as handle:
        handle.write(b'\x00new')
    assert target.read_bytes() == b'\x00new'
    with pytest.raises(DataError, match=r'cannot write file .* it is a directory'):
        with atomic_write(tmp_path):
            pass


# ------------------------------------------------------------------ robustness


@settings(max_examples=300, deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(data=st.data())
def test_corrupted_csv_reads_or_raises_data_error(tmp_path, data):
    text, _ = _csv_text(14, seed=5)
    raw = bytearray(text.encode())
    # Mostly bytes that mean something to a CSV or number parser, some arbitrary ones.
    byte = st.one_of(st.sampled_from(list(b',."\n\r\t -+eE#0129naif_\x00')),
                     st.integers(0, 255))
    for _ in range(data.draw(st.integers(1, 4), label='n_edits')):
        kind = data.draw(st.sampled_from(['replace', 'truncate', 'insert', 'delete']))
        pos = data.draw(st.integers(0, max(len(raw) - 1, 0)))
        if kind == 'replace' and raw:
            raw[pos] = data.draw(byte)
        elif kind == 'truncate':
            del raw[pos:]
        elif kind == 'insert':
            raw[pos:pos] = bytes(data.draw(st.lists(byte, min_size=1, max_size=4)))
        elif raw:
            del raw[pos]
    path = tmp_path / 'fuzz.csv'
    path.write_bytes(bytes(raw))
    try:
        rec = read_csv_signals(path, drop_nonfinite=data.draw(st.booleans()))
    except DataError:
        pass
    else:
        assert len(rec) >= 10
        assert np.all(np.isfinite(rec.current)) and np.all(np.isfinite(rec.displacement))
    try:
        header, table = read_csv_table(path)
    except DataError:
        pass
    else:
        assert table.shape == (table.shape[0], len(header))


def test_module_does_not_import_rclpy():
    code = 'import sys, mpi_ros.recordings; sys.exit("rclpy" in sys.modules)'
    result = subprocess.run([sys.executable, '-c', code], capture_output=True, text=True,
                            cwd=Path(__file__).resolve().parents[1], check=False)
    assert result.returncode == 0, result.stderr
