# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""Message readers: JointState and Float64MultiArray bags, the registry, DataOptions."""

from mpi_ros.errors import DataError
from mpi_ros.recordings import (
    DATA_OPTIONS, DataOptions, MESSAGE_READERS, MessageReader, read_bag_signals,
    read_recording, read_signals, write_bag_signals, write_csv_columns)
from mpi_ros.recordings.messages import supported_types
import numpy as np
import pytest

from .message_bags import (
    ARRAY, FLOAT64, float64, float64_array, JOINT_STATE, joint_state, STORE, write_array_signals,
    write_bag, write_joint_state_signals)

JOINTS = {'input_topic': '/joint_states', 'output_topic': '/joint_states',
          'input_joint': 'actuator', 'input_field': 'effort', 'output_joint': 'actuator',
          'output_field': 'position'}
ARRAYS = {'input_topic': '/command', 'output_topic': '/measurement', 'input_index': 1,
          'output_index': 0}


def _signals(n=40, seed=0):
    rng = np.random.default_rng(seed)
    time = np.cumsum(rng.uniform(1e-3, 2e-3, n))
    return time, rng.uniform(-1.0, 1.0, n), rng.normal(0.0, 1e-6, n)


def _joint_bag(tmp_path, n=20, **fields):
    """One /joint_states topic of `n` messages with the given fields for joints a and b."""
    messages = [(k, joint_state(['a', 'b'], stamp_ns=k, **fields)) for k in range(n)]
    return write_bag(tmp_path / 'joints', {'/joint_states': (JOINT_STATE, messages)})


# ------------------------------------------------------------------ JointState


@pytest.mark.parametrize('storage', ['sqlite3', 'mcap'])
def test_joint_state_round_trip(tmp_path, storage):
    time, current, displacement = _signals()
    bag = write_joint_state_signals(tmp_path / 'js', time, current, displacement, storage)
    rec = read_bag_signals(bag, **JOINTS)
    np.testing.assert_array_equal(rec.current, current)
    np.testing.assert_array_equal(rec.displacement, displacement)
    np.testing.assert_allclose(rec.time, time - time[0], atol=1e-9, rtol=0)
    assert rec.notes == ()


def test_joint_state_unknown_joint_lists_the_names(tmp_path):
    bag = write_joint_state_signals(tmp_path / 'js', *_signals())
    with pytest.raises(DataError, match=r'message 0 of topic /joint_states \(sensor_msgs/msg/'
                                        r"JointState\) in bag .*: it has no joint 'elbow' "
                                        r"\(input_joint\); joints found: 'wrist', 'actuator'; "
                                        r'set input_joint to one of them'):
        read_bag_signals(bag, **dict(JOINTS, input_joint='elbow'))


def test_joint_state_without_joint_takes_the_only_one_or_asks(tmp_path):
    messages = [(k, joint_state(['solo'], position=[0.1 * k], effort=[0.2 * k]))
                for k in range(20)]
    bag = write_bag(tmp_path / 'solo', {'/joint_states': (JOINT_STATE, messages)})
    rec = read_bag_signals(bag, input_topic='/joint_states', output_topic='/joint_states',
                           input_field='effort')
    np.testing.assert_allclose(rec.current, 0.2 * np.arange(20), rtol=0, atol=0)
    np.testing.assert_allclose(rec.displacement, 0.1 * np.arange(20), rtol=0, atol=0)
    two = write_joint_state_signals(tmp_path / 'js', *_signals())
    with pytest.raises(DataError, match=r"it holds 2 joints \('wrist', 'actuator'\) and "
                                        r'output_joint is not set; set output_joint to one'):
        read_bag_signals(two, **dict(JOINTS, output_joint=None))


def test_joint_state_missing_field(tmp_path):
    bag = _joint_bag(tmp_path, position=[1.0, 2.0])          # no velocity, no effort
    with pytest.raises(DataError, match=r"it has no effort for joint 'b': effort holds 0 "
                                        r'value\(s\) for 2 joint\(s\) .*set input_field to a '
                                        r'filled field \(position\)'):
        read_bag_signals(bag, **dict(JOINTS, input_joint='b', output_joint='a'))


def test_same_topic_same_selection_is_refused(tmp_path):
    bag = write_joint_state_signals(tmp_path / 'js', *_signals())
    with pytest.raises(DataError, match=r'input_topic and output_topic are both '
                                        r"'/joint_states' with the same joint, field and"):
        read_bag_signals(bag, **dict(JOINTS, input_field='position'))


# ------------------------------------------------------------------ Float64MultiArray


@pytest.mark.parametrize('storage', ['sqlite3', 'mcap'])
def test_array_round_trip(tmp_path, storage):
    time, current, displacement = _signals()
    bag = write_array_signals(tmp_path / 'arr', time, current, displacement, storage)
    rec = read_bag_signals(bag, **ARRAYS)
    np.testing.assert_array_equal(rec.current, current)
    np.testing.assert_array_equal(rec.displacement, displacement)


def test_array_index_out_of_range_and_missing(tmp_path):
    bag = write_array_signals(tmp_path / 'arr', *_signals())
    with pytest.raises(DataError, match=r'message 0 of topic /command .*: input_index 2 is out '
                                        r'of range: the array holds 2 element\(s\); set '
                                        r'input_index to one of 0 to 1'):
        read_bag_signals(bag, **dict(ARRAYS, input_index=2))
    with pytest.raises(DataError, match=r'it holds 2 elements and output_index is not set; set '
                                        r'output_index to one of 0 to 1'):
        read_bag_signals(bag, **dict(ARRAYS, output_index=None))


def test_array_data_offset_is_honoured(tmp_path):
    messages = [(k, float64_array([99.0, 0.5 * k, 1e-6 * k], data_offset=1)) for k in range(20)]
    bag = write_bag(tmp_path / 'offset', {'/a': (ARRAY, messages)})
    rec = read_bag_signals(bag, input_topic='/a', output_topic='/a', input_index=0,
                           output_index=1)
    np.testing.assert_array_equal(rec.current, 0.5 * np.arange(20))
    np.testing.assert_array_equal(rec.displacement, 1e-6 * np.arange(20))
    with pytest.raises(DataError, match=r'holds 2 element\(s\) after layout.data_offset 1'):
        read_bag_signals(bag, input_topic='/a', output_topic='/a', input_index=0,
                         output_index=2)


# ------------------------------------------------------------------ types and selectors


def test_unsupported_type_lists_the_supported_ones(tmp_path):
    point = STORE.types['geometry_msgs/msg/Point']
    bag = write_bag(tmp_path / 'point', {
        '/current_command': (FLOAT64, [(k, float64(k)) for k in range(20)]),
        '/displacement': ('geometry_msgs/msg/Point',
                          [(k, point(x=1.0, y=0.0, z=0.0)) for k in range(20)])})
    with pytest.raises(DataError, match=r'has type geometry_msgs/msg/Point; expected '
                                        r'std_msgs/msg/Float64, sensor_msgs/msg/JointState or '
                                        r'std_msgs/msg/Float64MultiArray; republish'):
        read_bag_signals(bag)
    assert supported_types() == ('std_msgs/msg/Float64, sensor_msgs/msg/JointState or '
                                 'std_msgs/msg/Float64MultiArray')


def test_selector_for_a_type_without_it_is_refused(tmp_path):
    bag = tmp_path / 'plain'
    write_bag_signals(bag, *_signals())
    with pytest.raises(DataError, match=r'input_joint does not apply to topic /current_command '
                                        r'.*std_msgs/msg/Float64 has no joints or elements '
                                        r'.*applies to sensor_msgs/msg/JointState\); remove'):
        read_bag_signals(bag, input_joint='a')
    with pytest.raises(DataError, match=r'output_field does not apply to topic /displacement'):
        read_bag_signals(bag, output_field='effort')
    with pytest.raises(DataError, match=r'output_index does not apply .*applies to '
                                        r'std_msgs/msg/Float64MultiArray'):
        read_bag_signals(bag, output_index=0)


def test_a_new_type_is_one_class_and_one_registry_line(tmp_path, monkeypatch):
    class PointXReader(MessageReader):
        msgtype = 'geometry_msgs/msg/Point'

        def value(self, msg, selection):
            return float(msg.x)

    monkeypatch.setitem(MESSAGE_READERS, PointXReader.msgtype, PointXReader())
    point = STORE.types['geometry_msgs/msg/Point']
    bag = write_bag(tmp_path / 'point', {
        '/current_command': (FLOAT64, [(k, float64(k)) for k in range(20)]),
        '/displacement': ('geometry_msgs/msg/Point',
                          [(k, point(x=2.0 * k, y=0.0, z=0.0)) for k in range(20)])})
    rec = read_bag_signals(bag)
    np.testing.assert_array_equal(rec.displacement, 2.0 * np.arange(20))


# ------------------------------------------------------------------ DataOptions, read_recording


def test_read_recording_names_options_as_the_user_wrote_them(tmp_path):
    bag = write_joint_state_signals(tmp_path / 'js', *_signals())
    cli = DataOptions(**dict(JOINTS, input_joint='elbow'), spelling='cli')
    with pytest.raises(DataError, match=r"no joint 'elbow' \(--input-joint\); joints found: "
                                        r"'wrist', 'actuator'; set --input-joint to one"):
        read_recording(bag, cli)
    node = DataOptions(**dict(JOINTS, input_joint='elbow'), spelling='parameter')
    with pytest.raises(DataError, match=r'\(input_joint\)'):
        read_recording(bag, node)
    with pytest.raises(DataError, match=r'bag .* has no topic /nope; .*pass --output-topic '
                                        r'<topic> with one of them'):
        read_recording(bag, DataOptions(**dict(JOINTS, output_topic='/nope'), spelling='cli'))


def test_read_recording_scales_bags_and_csv(tmp_path):
    time, current, displacement = _signals()
    bag = write_array_signals(tmp_path / 'arr', time, current, 1e9 * displacement)
    options = DataOptions(**ARRAYS, output_scale=1e-9, input_scale=2.0)
    rec = read_recording(bag, options)
    np.testing.assert_allclose(rec.displacement, displacement, rtol=1e-15, atol=0)
    np.testing.assert_array_equal(rec.current, 2.0 * current)
    write_csv_columns(tmp_path / 'a.csv', {'t': time, 'x': current, 'y': 1e9 * displacement})
    rec = read_recording(tmp_path / 'a.csv', DataOptions(time_column='t', output_scale=1e-9))
    np.testing.assert_allclose(rec.displacement, displacement, rtol=1e-15, atol=0)


def test_read_recording_drop_hint_follows_the_spelling(tmp_path):
    time, current, displacement = _signals()
    displacement[5] = np.nan
    write_csv_columns(tmp_path / 'n.csv', {'time': time, 'x': current, 'y': displacement})
    with pytest.raises(DataError, match=r'fix the data or pass --drop-nonfinite to drop'):
        read_recording(tmp_path / 'n.csv', DataOptions(spelling='cli'))
    with pytest.raises(DataError, match=r'pass -p drop_nonfinite:=true'):
        read_recording(tmp_path / 'n.csv', DataOptions(spelling='parameter'))
    rec = read_recording(tmp_path / 'n.csv', DataOptions(drop_nonfinite=True))
    assert len(rec) == time.size - 1
    with pytest.raises(DataError, match=r"no column 'T' \(--time-column\); .*pass "
                                        r"--time-column <name>, or --time-column '' if"):
        read_recording(tmp_path / 'n.csv', DataOptions(time_column='T', spelling='cli'))


@pytest.mark.parametrize('options, match', [
    ({'input_field': 'torque'},
     r"--input-field must be one of position, velocity, effort; found 'torque'"),
    ({'output_index': -1}, r'--output-index must be a whole number >= 0 .*found -1'),
    ({'output_index': 1.5}, r'--output-index must be a whole number >= 0 .*found 1.5'),
    ({'input_scale': np.float64(np.nan)},
     r'--input-scale must be a finite non-zero number; found nan$'),
    ({'output_scale': np.float64(0.0)}, r'found 0.0$'),
    ({'input_topic': ''}, r'--input-topic must be a non-empty topic name'),
])
def test_data_options_are_validated(options, match):
    with pytest.raises(DataError, match=match) as info:
        DataOptions(**options, spelling='cli')
    assert 'np.' not in str(info.value)


def test_data_options_from_parameters_and_argparse_values():
    values = {option.name: option.parameter_default for option in DATA_OPTIONS}
    assert DataOptions.from_mapping(values, spelling='parameter') == \
        DataOptions(spelling='parameter')
    values.update(input_index=3, time_column='', input_joint='j')
    options = DataOptions.from_mapping(values, spelling='parameter')
    assert (options.input_index, options.time_column, options.input_joint) == (3, None, 'j')
    cli = DataOptions.from_mapping({'input_index': None, 'output_scale': 1e-9,
                                    'unrelated': 1}, spelling='cli')
    assert cli == DataOptions(output_scale=1e-9, spelling='cli')
    with pytest.raises(DataError, match=r'--input-index must be a whole number >= 0'):
        DataOptions.from_mapping({'input_index': -1}, spelling='cli')


def test_read_signals_routes_listed_keywords(tmp_path):
    bag = write_joint_state_signals(tmp_path / 'js', *_signals())
    rec = read_signals(bag, **JOINTS)
    assert len(rec) == 40
    write_csv_columns(tmp_path / 'a.csv', dict(zip(('time', 'x', 'y'), _signals())))
    with pytest.raises(DataError, match=r'option\(s\) input_joint do not apply to CSV file'):
        read_signals(tmp_path / 'a.csv', input_joint='a')
