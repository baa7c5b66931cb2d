# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Chunked Float64MultiArray bags (layout.dim = samples x axes): K samples of one axis per message.

The reference is the same data recorded one sample per message (no ``dim``), each sample
logged at its own time; a chunk is logged at the time of its last sample. With evenly
spaced samples the reader must rebuild exactly the per-sample recording, whatever the
chunk sizes of the input and output topics.
"""

from mpi_ros.app.cli import main
from mpi_ros.errors import DataError
from mpi_ros.params import read_params_yaml
from mpi_ros.plant.actuator import MagnetostrictiveActuator
from mpi_ros.plant.excitation import identification_excitation
from mpi_ros.recordings import DataOptions, read_bag_signals, read_recording, read_signals
from mpi_ros.recordings.messages import Float64MultiArrayReader, Selection, SelectionError
import numpy as np
import pytest

from .message_bags import ARRAY, chunked, float64_array, float64_block, write_bag

AXES = 3
#: Sample period [ns] of the synthetic recordings (1 kHz).
PERIOD = 1_000_000
TOPICS = {'input_topic': '/current_commands', 'output_topic': '/displacements'}


def _data(n=300, seed=0):
    """Return stamps [ns] and (n x AXES) currents and displacements."""
    rng = np.random.default_rng(seed)
    stamps = 5_000_000_000 + PERIOD * np.arange(n, dtype=np.int64)
    currents = rng.uniform(-1.0, 1.0, (n, AXES))
    displacements = rng.normal(0.0, 1e-6, (n, AXES))
    return stamps, currents, displacements


def _per_sample_bag(path, stamps, currents, displacements):
    """One sample of every axis per message; the output logged 1 ns after the input."""
    return write_bag(path, {
        '/current_commands': (ARRAY, [(int(s), float64_array(row))
                                      for s, row in zip(stamps, currents)]),
        '/displacements': (ARRAY, [(int(s) + 1, float64_array(row))
                                   for s, row in zip(stamps, displacements)])})


def _chunked_bag(path, stamps, currents, displacements, input_sizes, output_sizes,
                 storage='sqlite3'):
    return write_bag(path, {
        '/current_commands': (ARRAY, chunked(stamps, currents, input_sizes)),
        '/displacements': (ARRAY, chunked(stamps + 1, displacements, output_sizes))},
        storage)


def _assert_same(rec, ref):
    np.testing.assert_array_equal(rec.time, ref.time)
    np.testing.assert_array_equal(rec.current, ref.current)
    np.testing.assert_array_equal(rec.displacement, ref.displacement)


@pytest.mark.parametrize('storage', ['sqlite3', 'mcap'])
@pytest.mark.parametrize('input_sizes, output_sizes', [
    (10, 4),            # 10 kHz-style chunks of 10, the output in chunks of 4
    (7, 1),             # a short last chunk (300 = 42 * 7 + 6); output as chunks of 1
    ((1, 5, 12, 3), (9, 2)),        # sizes change from message to message
])
def test_chunks_give_the_per_sample_recording(tmp_path, storage, input_sizes, output_sizes):
    stamps, currents, displacements = _data()
    reference = _per_sample_bag(tmp_path / 'samples', stamps, currents, displacements)
    bag = _chunked_bag(tmp_path / 'chunks', stamps, currents, displacements, input_sizes,
                       output_sizes, storage)
    for axis in range(AXES):
        options = DataOptions(**TOPICS, input_index=axis, output_index=axis)
        rec, ref = read_recording(bag, options), read_recording(reference, options)
        _assert_same(rec, ref)
        np.testing.assert_array_equal(rec.current, currents[:, axis])
        assert ref.notes == ()
        assert any('chunked message(s)' in note and 'the last of each at its log time' in note
                   for note in rec.notes)


def test_one_sample_chunks_read_as_plain_arrays(tmp_path):
    stamps, currents, displacements = _data(50)
    reference = _per_sample_bag(tmp_path / 'samples', stamps, currents, displacements)
    bag = _chunked_bag(tmp_path / 'ones', stamps, currents, displacements, 1, 1)
    rec = read_bag_signals(bag, **TOPICS, input_index=2, output_index=2)
    _assert_same(rec, read_bag_signals(reference, **TOPICS, input_index=2, output_index=2))
    assert rec.notes == ()                      # K = 1: nothing to time, nothing to note


def test_jittery_log_times_tile_the_gaps(tmp_path):
    """Each chunk's samples spread evenly over the time since the previous message."""
    stamps, currents, displacements = _data(200, seed=1)
    rng = np.random.default_rng(3)
    logged = stamps + rng.integers(0, 400_000, stamps.size)      # receive jitter < period
    logged = np.maximum.accumulate(logged)
    bag = write_bag(tmp_path / 'jitter', {
        '/current_commands': (ARRAY, chunked(logged, currents, 10)),
        '/displacements': (ARRAY, chunked(logged + 1, displacements, 10))})
    rec = read_bag_signals(bag, **TOPICS, input_index=0, output_index=0)
    assert len(rec) == 200
    assert np.all(np.diff(rec.time) > 0)
    ends = logged[9::10]
    np.testing.assert_allclose(rec.time[9::10], (ends - ends[0]) * 1e-9 + rec.time[9],
                               rtol=0, atol=1e-15)
    gaps = np.diff(ends) / 10                                      # chunk m: (T_m - T_m-1)/K
    np.testing.assert_allclose(np.diff(rec.time[10:20]), gaps[0] * 1e-9, rtol=0, atol=2e-9)
    first = np.median(gaps) * 1e-9                                 # first chunk: the median
    np.testing.assert_allclose(np.diff(rec.time[:10]), first, rtol=0, atol=2e-9)
    np.testing.assert_array_equal(rec.current, currents[:, 0])
    np.testing.assert_array_equal(rec.displacement, displacements[:, 0])


def test_sample_period_option(tmp_path):
    stamps, currents, displacements = _data(40)
    bag = _chunked_bag(tmp_path / 'c', stamps, currents, displacements, 10, 10)
    rec = read_bag_signals(bag, **TOPICS, input_index=1, output_index=1, sample_period=2e-4)
    within = np.diff(rec.time.reshape(4, 10), axis=1)
    np.testing.assert_allclose(within, 2e-4, rtol=0, atol=1e-12)   # as given, not 1 ms
    assert any('sample_period 0.0002 s apart' in note for note in rec.notes)
    # A period longer than the log times allow: samples moved after the previous chunk.
    rec = read_bag_signals(bag, **TOPICS, input_index=1, output_index=1, sample_period=2e-3)
    assert np.all(np.diff(rec.time) > 0)
    assert any('longer than the log times allow; check sample_period); moved to 1 ns after it'
               in note for note in rec.notes)
    # 0 means "infer", as the node parameter's default.
    assert DataOptions(sample_period=0.0).sample_period is None


def test_time_scale_of_a_bag(tmp_path):
    """A bag logged at a tenth of the speed: time_scale 0.1 gives the actuator's time."""
    stamps, currents, displacements = _data(40)
    slow = stamps[0] + 10 * (stamps - stamps[0])                  # 10 ms between samples
    bag = _chunked_bag(tmp_path / 'slow', slow, currents, displacements, 10, 10)
    reference = _chunked_bag(tmp_path / 'live', stamps, currents, displacements, 10, 10)
    options = {**TOPICS, 'input_index': 1, 'output_index': 1}
    rec = read_bag_signals(bag, **options, time_scale=0.1)
    ref = read_bag_signals(reference, **options)
    np.testing.assert_allclose(rec.time, ref.time, rtol=0, atol=1e-12)
    np.testing.assert_allclose(np.diff(rec.time), 1e-3, rtol=0, atol=1e-12)
    assert any('(first message: 0.001 s, the median)' in note for note in rec.notes)
    # --sample-period is in s of the actuator (after the scale), as its unit says.
    rec = read_bag_signals(bag, **options, time_scale=0.1, sample_period=2e-4)
    within = np.diff(rec.time.reshape(4, 10), axis=1)
    np.testing.assert_allclose(within, 2e-4, rtol=0, atol=1e-12)
    rec = read_recording(bag, DataOptions(**options, time_scale=0.1))
    np.testing.assert_allclose(rec.time, ref.time, rtol=0, atol=1e-12)
    with pytest.raises(DataError, match=r'--time-scale must be > 0 \(the factor from the '
                                        r'recorded time to s, e.g. 1e-3 for ms\); found -0.1'):
        DataOptions(time_scale=-0.1, spelling='cli')


def test_a_single_chunk_needs_the_sample_period(tmp_path):
    stamps, currents, displacements = _data(30)
    bag = write_bag(tmp_path / 'one', {
        '/current_commands': (ARRAY, [(int(stamps[-1]), float64_block(currents))]),
        '/displacements': (ARRAY, [(int(stamps[-1]) + 1, float64_block(displacements))])})
    with pytest.raises(DataError, match=r'topic /current_commands \[0\] in bag .* has a single '
                                        r'message \(a chunk of 30 samples\): the interval '
                                        r'between its samples cannot be inferred from one log '
                                        r'time; pass --sample-period <seconds> or record '
                                        r'longer'):
        read_recording(bag, DataOptions(**TOPICS, input_index=0, output_index=0,
                                        spelling='cli'))
    rec = read_bag_signals(bag, **TOPICS, input_index=0, output_index=0, sample_period=1e-3)
    np.testing.assert_array_equal(rec.current, currents[:, 0])
    np.testing.assert_allclose(rec.time, 1e-3 * np.arange(30), rtol=0, atol=1e-12)


def test_row_stride_and_data_offset_are_honoured(tmp_path):
    stamps, currents, displacements = _data(40)
    messages = {
        '/current_commands': [(int(stamps[k + 9]), float64_block(currents[k:k + 10],
                                                                 data_offset=2, row_stride=5))
                              for k in range(0, 40, 10)],
        '/displacements': [(int(stamps[k + 4]) + 1,
                            float64_block(displacements[k:k + 5], row_stride=4))
                           for k in range(0, 40, 5)]}
    bag = write_bag(tmp_path / 'strided', {topic: (ARRAY, m) for topic, m in messages.items()})
    rec = read_bag_signals(bag, **TOPICS, input_index=2, output_index=1)
    np.testing.assert_array_equal(rec.current, currents[:, 2])
    np.testing.assert_array_equal(rec.displacement, displacements[:, 1])


def _bad_bag(tmp_path, message):
    stamps, currents, displacements = _data(20)
    return write_bag(tmp_path / 'bad', {
        '/current_commands': (ARRAY, [(int(stamps[9]), message),
                                      (int(stamps[19]), message)]),
        '/displacements': (ARRAY, chunked(stamps + 1, displacements, 5))})


@pytest.mark.parametrize('message, index, match', [
    (float64_block(np.zeros((10, AXES))), 3,
     r'message 0 of topic /current_commands \(std_msgs/msg/Float64MultiArray\) in bag .*: '
     r'--input-index 3 is out of range: the message holds 10 sample\(s\) x 3 axes '
     r'\(layout.dim = samples x axes\); set --input-index to an axis, one of 0 to 2'),
    (float64_block(np.zeros((10, AXES))), None,
     r'it holds chunks of 10 sample\(s\) x 3 axes \(layout.dim = samples x axes\) and '
     r'--input-index is not set; set --input-index to the axis, one of 0 to 2'),
    (float64_block(np.zeros((10, AXES)), sizes=(12, AXES)), 0,
     r'its layout announces 12 sample\(s\) x 3 axes \(layout.dim = samples x axes\), which '
     r'needs 36 values, but data holds 30; fix layout.dim in the publisher \(dim\[0\] = '
     r'samples, dim\[1\] = axes\) to match the data'),
    (float64_block(np.zeros((10, AXES)), data_offset=1, row_stride=4, sizes=(11, AXES)), 0,
     r'announces 11 sample\(s\) x 3 axes \(layout.dim = samples x axes, row stride 4, '
     r'layout.data_offset 1\), which needs 44 values, but data holds 41'),
    (float64_block(np.zeros((0, AXES))), 0,
     r'its layout announces 0 sample\(s\) x 3 axes .*: a chunk needs at least one sample and '
     r'one axis; fix layout.dim in the publisher'),
])
def test_bad_layouts_and_indices_are_refused(tmp_path, message, index, match):
    bag = _bad_bag(tmp_path, message)
    options = DataOptions(**TOPICS, input_index=index, output_index=0, spelling='cli')
    with pytest.raises(DataError, match=match) as info:
        read_recording(bag, options)
    assert 'np.' not in str(info.value)


def test_reader_value_and_values():
    reader = Float64MultiArrayReader()
    block = np.arange(12.0).reshape(4, AXES)
    np.testing.assert_array_equal(reader.values(float64_block(block), Selection('/a', index=1)),
                                  block[:, 1])
    assert reader.value(float64_block(block[2:3]), Selection('/a', index=2)) == 8.0
    np.testing.assert_array_equal(reader.values(float64_array([1.0, 2.0]),
                                                Selection('/a', index=1)), [2.0])
    with pytest.raises(SelectionError, match=r'it holds a chunk of 4 samples \(samples x '
                                             r'axes\), not one number; read it with '
                                             r'values\(\)'):
        reader.value(float64_block(block), Selection('/a', index=0))


def test_nonfinite_sample_in_a_chunk(tmp_path):
    stamps, currents, displacements = _data(40)
    displacements[23, 1] = np.nan
    bag = _chunked_bag(tmp_path / 'nan', stamps, currents, displacements, 10, 10)
    with pytest.raises(DataError, match=r'topic /displacements \[1\] in bag .* has 1 non-finite '
                                        r'value\(s\) \(NaN/Inf\), the first at sample 3 of '
                                        r'message 2 \(0.023 s after the first sample\); fix the '
                                        r'publisher or pass drop_nonfinite=True'):
        read_bag_signals(bag, **TOPICS, input_index=1, output_index=1)
    rec = read_bag_signals(bag, **TOPICS, input_index=1, output_index=1, drop_nonfinite=True)
    assert len(rec) == 39
    rec = read_bag_signals(bag, **TOPICS, input_index=0, output_index=0)   # axis 0 is clean
    assert len(rec) == 40


def test_sample_period_is_validated_and_routed():
    with pytest.raises(DataError, match=r'--sample-period must be a finite number >= 0 \[s\] '
                                        r'\(the interval between the samples of a chunked '
                                        r'message; 0 or unset infers it from the log times\); '
                                        r'found -0.001$'):
        DataOptions(sample_period=np.float64(-1e-3), spelling='cli')
    with pytest.raises(DataError, match=r'found nan'):
        DataOptions(sample_period=float('nan'))
    assert DataOptions.from_mapping({'sample_period': 0.0}, spelling='parameter') == \
        DataOptions(spelling='parameter')


def test_cli_identify_fits_a_chunked_bag_like_the_per_sample_one(tmp_path):
    t, base = identification_excitation(10.0, sample_rate=250.0, seed=4)
    currents = np.column_stack([base, 0.8 * base + 0.3, 1.1 * base - 0.2])
    displacements = np.column_stack([MagnetostrictiveActuator().simulate(t, currents[:, k])
                                     for k in range(AXES)])
    stamps = np.round(t * 1e9).astype(np.int64)
    reference = _per_sample_bag(tmp_path / 'samples', stamps, currents, displacements)
    bag = _chunked_bag(tmp_path / 'chunks', stamps, currents, displacements, 10, 6)
    fitted = {}
    for name, path in (('samples', reference), ('chunks', bag)):
        out = tmp_path / f'{name}.yaml'
        assert main(['identify', str(path), '--order', '5,3', '-o', str(out),
                     '--input-topic', '/current_commands', '--input-index', '1',
                     '--output-topic', '/displacements', '--output-index', '1']) == 0
        fitted[name] = read_params_yaml(out)
    assert fitted['chunks'] == fitted['samples']


def test_read_signals_accepts_sample_period(tmp_path):
    stamps, currents, displacements = _data(30)
    bag = _chunked_bag(tmp_path / 'c', stamps, currents, displacements, 10, 10)
    rec = read_signals(bag, **TOPICS, input_index=0, output_index=0, sample_period=1e-3)
    np.testing.assert_allclose(rec.time, 1e-3 * np.arange(30), rtol=0, atol=1e-12)


def _flat(messages):
    """Return the same chunks as K x N values without layout.dim."""
    flat = [(stamp, float64_array(message.data)) for stamp, message in messages]
    for _, message in flat:
        message.layout.dim = []
    return flat


def test_chunks_without_layout_dim_need_array_axes(tmp_path):
    stamps, currents, displacements = _data(60)
    reference = _per_sample_bag(tmp_path / 'samples', stamps, currents, displacements)
    bag = write_bag(tmp_path / 'flat', {
        '/current_commands': (ARRAY, _flat(chunked(stamps, currents, 10))),
        '/displacements': (ARRAY, chunked(stamps + 1, displacements, 6))})
    options = DataOptions(**TOPICS, input_index=1, output_index=1, array_axes=AXES)
    _assert_same(read_recording(bag, options), read_recording(reference, options))
    # Without array_axes a dim-less message would be one sample: refused, with the fix.
    with pytest.raises(DataError, match=r'bag .*: topic /current_commands holds 30 values per '
                                        r'message without layout.dim while /displacements '
                                        r'holds chunks of 3 axes \(layout.dim = samples x '
                                        r'axes\); its messages look like chunks of 10 samples '
                                        r'x 3 axes, which would be read as one sample each; '
                                        r'pass --array-axes 3 to read them as the multi-axis '
                                        r'nodes do, or republish them with a layout.dim'):
        read_recording(bag, DataOptions(**TOPICS, input_index=1, output_index=1,
                                        spelling='cli'))


@pytest.mark.parametrize('messages, axes, match', [
    ([float64_array(np.zeros(7))], 3,
     r'message 0 of topic /current_commands .*: it holds 7 value\(s\) and no layout.dim, not '
     r'whole samples of --array-axes 3 axes \(samples x axes, row-major\); publish K x N '
     r'values or set layout.dim, or set --array-axes to the number of axes'),
    ([float64_block(np.zeros((4, 3)))], 2,
     r'it holds chunks of \d+ sample\(s\) x 3 axes \(layout.dim = samples x axes\), but '
     r'--array-axes is 2; set --array-axes to 3 \(one column per axis\)'),
    ([float64_array(np.zeros(6))], 3,
     r'--input-index 4 is out of range: the message holds 2 sample\(s\) x 3 axes '
     r'\(--array-axes 3, no layout.dim\); set --input-index to an axis, one of 0 to 2'),
])
def test_array_axes_errors(tmp_path, messages, axes, match):
    stamps, _, displacements = _data(20)
    bag = write_bag(tmp_path / 'bad', {
        '/current_commands': (ARRAY, [(int(stamps[k]), messages[0]) for k in (9, 19)]),
        '/displacements': (ARRAY, chunked(stamps + 1, displacements, 5))})
    index = 4 if 'out of range' in match else 0
    with pytest.raises(DataError, match=match):
        read_recording(bag, DataOptions(**TOPICS, input_index=index, output_index=0,
                                        array_axes=axes, spelling='cli'))


def test_array_axes_keeps_one_sample_messages(tmp_path):
    """Read N values per message (one sample of every axis) the same with array_axes = N."""
    stamps, currents, displacements = _data(30)
    bag = _per_sample_bag(tmp_path / 'samples', stamps, currents, displacements)
    plain = read_bag_signals(bag, **TOPICS, input_index=2, output_index=2)
    _assert_same(read_bag_signals(bag, **TOPICS, input_index=2, output_index=2,
                                  array_axes=AXES), plain)
    with pytest.raises(DataError, match=r'array_axes must be a whole number >= 1 \(the axes '
                                        r'of an array message without layout.dim\) or unset; '
                                        r'found 0$'):
        DataOptions(array_axes=0)


def test_chunks_logged_closer_than_their_size_in_ns_stay_in_order(tmp_path):
    """Two chunks of 10 logged 5 ns apart: their samples cannot be 1 ns apart; kept in order."""
    stamps, currents, displacements = _data(40)
    logged = stamps.copy()
    logged[19] = logged[9] + 5
    bag = write_bag(tmp_path / 'close', {
        '/current_commands': (ARRAY, chunked(logged, currents, 10)),
        '/displacements': (ARRAY, chunked(stamps + 1, displacements, 10))})
    rec = read_bag_signals(bag, **TOPICS, input_index=0, output_index=0)
    assert len(rec) == 40
    assert any('(messages logged fewer ns apart than they hold samples); moved to 1 ns after '
               'it' in note for note in rec.notes)
