# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
The range a model was identified on; ``simulate`` and ``compensate`` outside it (issue 20).

``compensate`` counts the desired displacements the model cannot reach with currents in
its range and clamps as the compensator node does (``--no-clamp``: it does not);
``simulate`` counts the currents outside the identified input range.  Both warn on stderr
with the count and how far the samples go.  The range is the one ``identify`` wrote in the
YAML's header, else the one the model's thresholds tell.
"""

from dataclasses import replace
import re

from mpi_ros import identify, MPIModel
from mpi_ros.app.cli import main
from mpi_ros.app.ranges import identified_range, outside, recorded_range
from mpi_ros.compensation import Compensator, operating_range
from mpi_ros.compensation.limits import limits_shortfall
from mpi_ros.params import read_params_yaml, write_params_yaml
from mpi_ros.plant.synthetic import synthetic_record
from mpi_ros.recordings import read_csv_table, write_csv_columns
import numpy as np
import pytest

from .core_models import hand_model

# A hand-written Gamma (not identified: its S thresholds are not spaced as (29)-(31)).
HAND = hand_model()

#: The identified current range against the recorded one, as a fraction of its span:
#: measured 2026-11 at most 1.03 % over the synthetic kinds below at (8, 4) and (14, 7).
CURRENT_RANGE_TOLERANCE = 0.02


@pytest.fixture(scope='module')
def identified(tmp_path_factory):
    """Identify a synthetic record (0..1.8 A) with the CLI; return the folder and record."""
    tmp = tmp_path_factory.mktemp('ranges')
    rec = synthetic_record('virgin', 0)
    write_csv_columns(tmp / 'rec.csv', {'time': rec.time, 'current': rec.current,
                                        'displacement': rec.displacement})
    assert main(['identify', str(tmp / 'rec.csv'), '--order', '8,4', '--dynamics', 'off',
                 '-o', str(tmp / 'p.yaml')]) == 0
    return tmp, rec


def _warnings(err):
    return [line for line in err.splitlines() if line.startswith('warning: ')]


def _file_limits(path):
    return f'output.min of {path} and output.max of {path}'


def _count(line):
    return int(re.match(r'warning: (\d+) of (\d+) ', line).group(1))


# ------------------------------------------------------------------ the identified range


@pytest.mark.parametrize('kind', ['virgin', 'mid-history', '300-sample loop',
                                  'lag 1.5 ms at 1 kHz'])
@pytest.mark.parametrize('order', [(8, 4), (14, 7)])
def test_identified_range_is_the_records(kind, order):
    rec = synthetic_record(kind, 1)
    model = identify(rec.current, rec.displacement, order=order, time=rec.time,
                     dynamics='off').model
    # identify keeps the record's input range; the displacement range is what the major
    # loop over it reaches, the record's output range up to the model's error there.
    found = identified_range(model)
    assert found.current == (rec.current.min(), rec.current.max())
    np.testing.assert_allclose(found.displacement,
                               [rec.displacement.min(), rec.displacement.max()],
                               rtol=0, atol=0.02 * np.ptp(rec.displacement))
    # A model without it (an older file): the thresholds tell both.  The displacement
    # range follows exactly from the thresholds (29)-(31) place.
    found = identified_range(replace(model, identified_input_range=None))
    np.testing.assert_allclose(found.displacement,
                               [rec.displacement.min(), rec.displacement.max()],
                               rtol=0, atol=1e-9 * np.ptp(rec.displacement))
    span = np.ptp(rec.current)
    np.testing.assert_allclose(found.current, [rec.current.min(), rec.current.max()],
                               rtol=0, atol=CURRENT_RANGE_TOLERANCE * span)


def test_a_hand_written_model_does_not_tell_its_range():
    found = identified_range(MPIModel.from_params(HAND))
    assert found.current is None and found.displacement is None


@pytest.mark.parametrize('kept', [True, False])
def test_clamping_to_the_identified_range_never_clips_inside_its_displacement_range(kept):
    # Any history of desired values inside the identified displacement range is reached
    # with currents inside the identified current range: nothing is clamped (the range
    # identify keeps, and the thresholds' of an older file).
    rec = synthetic_record('mid-history', 2)
    model = identify(rec.current, rec.displacement, order=(8, 4), dynamics='off').model
    if not kept:
        model = replace(model, identified_input_range=None)
    found = identified_range(model)
    rng = np.random.default_rng(3)
    lo, hi = found.displacement
    walk = np.cumsum(rng.normal(0.0, 0.05, 5000)) % 2.0         # reflected into [0, 1]
    desired = lo + (hi - lo) * np.where(walk > 1.0, 2.0 - walk, walk)
    assert desired.min() < lo + 0.01 * (hi - lo) and desired.max() > hi - 0.01 * (hi - lo)
    comp = Compensator(model, output_min=found.current[0], output_max=found.current[1])
    commands = comp.command_batch(desired)
    assert comp.counters['clamped'] == 0
    assert found.current[0] <= commands.min() and commands.max() <= found.current[1]


def test_outside_counts_and_measures():
    out = outside([0.0, 1.0, 2.5, -0.5, 3.0, np.nan], 0.0, 2.0)
    assert (out.count, out.total, out.below, out.above) == (3, 6, 0.5, 1.0)
    assert out.describe('currents', ', the range', 'A') == (
        '3 of 6 currents (50 %) lie outside 0 to 2 A, the range: below it by up to 0.5 A, '
        'above it by up to 1 A')
    assert outside([0.5, 1.5], 0.0, 2.0).count == 0


def test_identify_records_the_range_in_the_header(identified, tmp_path):
    tmp, rec = identified
    found = recorded_range(tmp / 'p.yaml')
    assert found.current == (rec.current.min(), rec.current.max())              # exact
    assert found.displacement == (rec.displacement.min(), rec.displacement.max())
    write_params_yaml(tmp_path / 'bare.yaml', read_params_yaml(tmp / 'p.yaml'),
                      header='written by hand')
    assert recorded_range(tmp_path / 'bare.yaml') is None
    write_params_yaml(tmp_path / 'odd.yaml', read_params_yaml(tmp / 'p.yaml'),
                      header='identified on current 2 to 1 A, displacement 0 to 1 m')
    assert recorded_range(tmp_path / 'odd.yaml') is None
    assert recorded_range(tmp_path / 'missing.yaml') is None


# ------------------------------------------------------------------ compensate


def _desired_file(tmp, rec, factor):
    # A sine around the middle of the record's displacement, `factor` times its half range.
    t = np.arange(3000) / 500.0
    mid, half = rec.displacement.mean(), 0.5 * np.ptp(rec.displacement)
    desired = mid + factor * half * np.sin(2 * np.pi * 0.7 * t)
    write_csv_columns(tmp / f'desired_{factor}.csv', {'time': t, 'desired': desired})
    return tmp / f'desired_{factor}.csv', desired


def test_compensate_inside_the_range_is_quiet_and_exact(identified, capsys):
    tmp, rec = identified
    path, desired = _desired_file(tmp, rec, 0.7)
    capsys.readouterr()
    assert main(['compensate', str(tmp / 'p.yaml'), '--input', str(path),
                 '--output', str(tmp / 'in.csv')]) == 0
    assert _warnings(capsys.readouterr().err) == []
    model = MPIModel.from_params(read_params_yaml(tmp / 'p.yaml'))
    _, table = read_csv_table(tmp / 'in.csv')
    np.testing.assert_allclose(table[:, 2], model.inverse().simulate(desired), rtol=0,
                               atol=1e-9)


def test_compensate_warns_and_clamps_as_the_node(identified, capsys):
    tmp, rec = identified
    path, desired = _desired_file(tmp, rec, 1.4)
    model = MPIModel.from_params(read_params_yaml(tmp / 'p.yaml'))
    lo, hi = recorded_range(tmp / 'p.yaml').current          # the record's, in the header
    capsys.readouterr()
    assert main(['compensate', str(tmp / 'p.yaml'), '--input', str(path),
                 '--output', str(tmp / 'c.csv')]) == 0
    reach = operating_range(model, lo, hi)
    expected = outside(desired, *reach)
    assert expected.count > 100
    first, second = _warnings(capsys.readouterr().err)
    # identify wrote the record's range as output.min / output.max (issue 27).
    params = read_params_yaml(tmp / 'p.yaml')
    assert (params['output.min'], params['output.max']) == (lo, hi)
    assert first == 'warning: ' + expected.describe(
        'desired displacements', f', the range the model reaches with currents from {lo:.4g}'
        f' to {hi:.4g} A (from {_file_limits(tmp / "p.yaml")})', 'm')
    _, table = read_csv_table(tmp / 'c.csv')
    commands = table[:, 2]
    assert lo <= commands.min() and commands.max() <= hi
    # The node's compensator, fed the same values, gives the same commands and counts.
    node = Compensator(model, output_min=lo, output_max=hi)
    np.testing.assert_array_equal(commands, node.command_batch(desired))
    assert _count(second) == node.counters['clamped'] > 0
    assert 'clamped to' in second and '--no-clamp' in second


def test_no_clamp_writes_the_inverse_and_says_how_far(identified, capsys):
    tmp, rec = identified
    path, desired = _desired_file(tmp, rec, 1.4)
    model = MPIModel.from_params(read_params_yaml(tmp / 'p.yaml'))
    lo, hi = recorded_range(tmp / 'p.yaml').current
    capsys.readouterr()
    assert main(['compensate', str(tmp / 'p.yaml'), '--input', str(path), '--no-clamp',
                 '--output', str(tmp / 'n.csv')]) == 0
    warnings = _warnings(capsys.readouterr().err)
    _, table = read_csv_table(tmp / 'n.csv')
    commands = table[:, 2]
    np.testing.assert_allclose(commands, model.inverse().simulate(desired), rtol=0, atol=1e-9)
    beyond = outside(commands, lo, hi)
    assert beyond.count > 0 and beyond.above > 0.0 and beyond.below > 0.0
    assert warnings[1] == 'warning: ' + beyond.describe(
        'commands', f' (from {_file_limits(tmp / "p.yaml")})', 'A') + (
        '; not clamped (--no-clamp)')


def test_options_and_parameter_file_limits_win(identified, capsys):
    tmp, rec = identified
    path, desired = _desired_file(tmp, rec, 1.4)
    params = read_params_yaml(tmp / 'p.yaml')
    assert main(['compensate', str(tmp / 'p.yaml'), '--input', str(path), '--output-min',
                 '0.5', '--output-max', '1.2', '--output', str(tmp / 'o.csv')]) == 0
    commands = read_csv_table(tmp / 'o.csv')[1][:, 2]
    assert commands.min() == 0.5 and commands.max() == 1.2
    assert 'clamped to 0.5 to 1.2 A (from --output-min and --output-max)' in (
        capsys.readouterr().err)
    # A compensator parameter file with output.min / output.max: the node's limits.
    write_params_yaml(tmp / 'node.yaml', dict(params, **{'output.min': 0.4, 'output.max': 1.5}))
    assert main(['compensate', str(tmp / 'node.yaml'), '--input', str(path),
                 '--output', str(tmp / 'f.csv')]) == 0
    commands = read_csv_table(tmp / 'f.csv')[1][:, 2]
    assert commands.min() == 0.4 and commands.max() == 1.5
    assert f'(from output.min of {tmp / "node.yaml"} and output.max of' in (
        capsys.readouterr().err)
    assert main(['compensate', str(tmp / 'p.yaml'), '--input', str(path), '--output-min',
                 '1.5', '--output-max', '1.0', '--output', str(tmp / 'x.csv')]) == 1
    assert capsys.readouterr().err.strip().splitlines()[-1] == (
        'error: the current range must be finite with its minimum below its maximum; found '
        '1.5 (--output-min) and 1 (--output-max); pass --output-min and --output-max with '
        "the actuator's safe range")
    assert not (tmp / 'x.csv').exists()


def test_an_extended_model_is_clamped_too(tmp_path, capsys):
    # A record with an input lag: identify models it (model.rate_dependence.*); the
    # compensator's streaming inverse with the identified limits.
    rec = synthetic_record('lag 3 ms at 1 kHz', 0)
    write_csv_columns(tmp_path / 'lag.csv', {'time': rec.time, 'current': rec.current,
                                             'displacement': rec.displacement})
    assert main(['identify', str(tmp_path / 'lag.csv'), '--order', '8,4',
                 '-o', str(tmp_path / 'lag.yaml')]) == 0
    assert 'model.rate_dependence.time_constant' in read_params_yaml(tmp_path / 'lag.yaml')
    path, desired = _desired_file(tmp_path, rec, 1.4)
    capsys.readouterr()
    assert main(['compensate', str(tmp_path / 'lag.yaml'), '--input', str(path),
                 '--output', str(tmp_path / 'c.csv')]) == 0
    warnings = _warnings(capsys.readouterr().err)
    assert len(warnings) == 2 and 'clamped to' in warnings[1]
    lo, hi = recorded_range(tmp_path / 'lag.yaml').current
    commands = read_csv_table(tmp_path / 'c.csv')[1][:, 2]
    assert lo <= commands.min() and commands.max() <= hi
    assert main(['compensate', str(tmp_path / 'lag.yaml'), '--input', str(path), '--no-clamp',
                 '--output', str(tmp_path / 'n.csv')]) == 0
    unclamped = read_csv_table(tmp_path / 'n.csv')[1][:, 2]
    assert unclamped.min() < lo and unclamped.max() > hi
    assert 'not clamped (--no-clamp)' in capsys.readouterr().err


def test_a_hand_written_model_is_not_clamped(tmp_path, capsys):
    write_params_yaml(tmp_path / 'hand.yaml', HAND)
    desired = MPIModel.from_params(HAND).simulate(np.linspace(0.0, 3.0, 50))
    write_csv_columns(tmp_path / 'd.csv', {'desired': desired})
    assert main(['compensate', str(tmp_path / 'hand.yaml'), '--input', str(tmp_path / 'd.csv'),
                 '--output', str(tmp_path / 'c.csv')]) == 0
    err = capsys.readouterr().err
    assert _warnings(err) == []
    assert 'does not tell the range it was identified on' in err and 'no clamping' in err
    np.testing.assert_allclose(read_csv_table(tmp_path / 'c.csv')[1][:, 1],
                               np.linspace(0.0, 3.0, 50), atol=1e-9)


# ------------------------------------------------------------------ simulate


def test_simulate_warns_about_currents_outside_the_identified_range(identified, capsys):
    tmp, rec = identified
    model = MPIModel.from_params(read_params_yaml(tmp / 'p.yaml'))
    lo, hi = recorded_range(tmp / 'p.yaml').current
    current = 0.9 + 1.2 * np.sin(np.linspace(0.0, 6 * np.pi, 900))
    write_csv_columns(tmp / 'cur.csv', {'current': current})
    capsys.readouterr()
    assert main(['simulate', str(tmp / 'p.yaml'), '--input', str(tmp / 'cur.csv'),
                 '--output', str(tmp / 's.csv')]) == 0
    expected = outside(current, lo, hi)
    assert expected.count > 0
    assert _warnings(capsys.readouterr().err) == [
        'warning: ' + expected.describe(
            'currents', ', the input range the model was identified on', 'A')
        + '; the model extrapolates there']
    np.testing.assert_allclose(read_csv_table(tmp / 's.csv')[1][:, 1],
                               model.simulate(current), rtol=0, atol=1e-15)
    write_csv_columns(tmp / 'in.csv', {'current': rec.current[::7]})
    assert main(['simulate', str(tmp / 'p.yaml'), '--input', str(tmp / 'in.csv'),
                 '--output', str(tmp / 's2.csv')]) == 0
    assert _warnings(capsys.readouterr().err) == []


def test_without_the_header_the_thresholds_range_is_used(identified, tmp_path, capsys):
    tmp, rec = identified
    # A file of an older identify: no header, no output.min / output.max.
    write_params_yaml(tmp_path / 'bare.yaml', {
        key: value for key, value in read_params_yaml(tmp / 'p.yaml').items()
        if not key.startswith('output.')})
    model = MPIModel.from_params(read_params_yaml(tmp_path / 'bare.yaml'))
    lo, hi = identified_range(model).current
    path, _ = _desired_file(tmp_path, rec, 1.4)
    capsys.readouterr()
    assert main(['compensate', str(tmp_path / 'bare.yaml'), '--input', str(path),
                 '--output', str(tmp_path / 'c.csv')]) == 0
    assert f'clamped to {lo:.4g} to {hi:.4g} A' in capsys.readouterr().err
    commands = read_csv_table(tmp_path / 'c.csv')[1][:, 2]
    assert commands.min() == lo and commands.max() == hi


def test_ringing_widens_the_thresholds_range_the_header_does_not(tmp_path, capsys):
    # Ringing after steps overshoots the output: the thresholds span the overshoot, and the
    # current that reaches it on the major loop lies far above the recorded current.
    rec = synthetic_record('ringing 740 Hz', 0)
    write_csv_columns(tmp_path / 'ring.csv', {'time': rec.time, 'current': rec.current,
                                              'displacement': rec.displacement})
    assert main(['identify', str(tmp_path / 'ring.csv'), '--order', '8,4', '--dynamics',
                 'off', '-o', str(tmp_path / 'ring.yaml')]) == 0
    params = read_params_yaml(tmp_path / 'ring.yaml')
    lo, hi = recorded_range(tmp_path / 'ring.yaml').current
    assert (lo, hi) == (rec.current.min(), rec.current.max())
    # The model keeps the recorded range (model.identified_input_range): a node, which
    # reads no header, judges its limits by it.
    assert params['model.identified_input_range'] == [lo, hi]
    assert identified_range(MPIModel.from_params(params)).current == (lo, hi)
    assert limits_shortfall(MPIModel.from_params(params), lo, hi) is None
    # A file without it (written before): the thresholds' range.
    del params['model.identified_input_range']
    model = MPIModel.from_params(params)
    assert identified_range(model).current[1] > hi + 0.5 * (hi - lo)
    path, _ = _desired_file(tmp_path, rec, 1.4)
    capsys.readouterr()
    assert main(['compensate', str(tmp_path / 'ring.yaml'), '--input', str(path),
                 '--output', str(tmp_path / 'c.csv')]) == 0
    commands = read_csv_table(tmp_path / 'c.csv')[1][:, 2]
    assert lo <= commands.min() and commands.max() == hi
    # The header's limits are the recorded range: no share of it is called unreachable (the
    # thresholds' wider range made every such model warn, the README's TUM example too);
    # limits that cut the recorded range still are.
    err = capsys.readouterr().err
    assert 'is unreachable' not in err
    assert limits_shortfall(model, lo, hi) is not None
    assert limits_shortfall(model, lo, hi, (lo, hi)) is None
    cut = limits_shortfall(model, lo, 0.5 * (lo + hi), (lo, hi))
    assert cut is not None and cut.identified == (lo, hi) and 0.2 < cut.unreachable < 0.8
