# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Issue 27: one units rule for every command (``mpi_ros.units``), values stored in SI.

A voltage-driven actuator recorded with ``Vplus_V`` and ``D1_nm`` columns: ``identify``
reads V and nm, stores V and m, names the voltage in its messages and the YAML header and
records ``model.input_quantity: voltage``, with no warning.  The same nm column without a
unit in its name is read as m and warned about, naming ``--output-unit``; stating the unit
gives the same model.  ``compensate`` of such a model under limits that cut its range says
how much is unreachable, in V.
"""

from mpi_ros.app.cli import main
from mpi_ros.params import read_params_yaml
from mpi_ros.plant.actuator import MagnetostrictiveActuator
from mpi_ros.plant.excitation import identification_excitation
from mpi_ros.recordings import DataOptions, read_recording, write_csv_columns
from mpi_ros.units import named_unit, resolve_units
import numpy as np
import pytest

VOLTS_PER_AMPERE = 112.5           # 0.2..1.8 A of the built-in actuator -> -90..90 V


@pytest.fixture(scope='module')
def piezo_csv(tmp_path_factory):
    """Write the record with unit suffixes (ms, V, nm) and without (nm values in 'D1')."""
    t, current = identification_excitation(8.0, sample_rate=500.0, seed=3)
    displacement = MagnetostrictiveActuator().simulate(t, current)
    volts = VOLTS_PER_AMPERE * (current - 1.0)
    tmp = tmp_path_factory.mktemp('units')
    write_csv_columns(tmp / 'named.csv', {'time_ms': 1e3 * t, 'Vplus_V': volts,
                                          'D1_nm': 1e9 * displacement})
    write_csv_columns(tmp / 'bare.csv', {'time': t, 'Vplus_V': volts, 'D1': 1e9 * displacement})
    return tmp, t, volts, displacement


@pytest.mark.parametrize('name, role, unit', [
    ('Vplus_V', 'input', 'V'), ('I_mA', 'input', 'mA'), ('coil current', 'input', 'A'),
    ('D1_nm', 'output', 'nm'), ('x_um', 'output', 'µm'), ('pos_mm', 'output', 'mm'),
    ('time_ms', 'time', 'ms'), ('t_us', 'time', 'us'), ('time', 'time', None),
    ('/current_command', 'input', 'A'), ('/displacement', 'output', None),
    ('D1_nm', 'input', None),
])
def test_named_units(name, role, unit):
    assert named_unit(name, role) == unit


def test_a_scale_that_converts_the_named_unit_is_not_applied_twice():
    # The old spelling --output-scale 1e-9 on a D1_nm column still gives m.
    assert resolve_units(output_name='D1_nm', output_scale=1e-9).output_factor == 1.0
    assert resolve_units(output_name='D1_nm').output_factor == 1e-9
    assert resolve_units(output_name='D1_nm', output_unit='um').output_factor == 1e-6
    units = resolve_units(input_name='volts', input_scale=0.1)          # converts V to A
    assert (units.input, units.input_quantity) == ('A', 'current')
    with pytest.raises(ValueError, match="unknown input unit 'parsec'"):
        resolve_units(input_unit='parsec')


def test_the_options_refuse_unknown_units():
    from mpi_ros.errors import DataError
    with pytest.raises(DataError, match=r'--output-unit must be one of m, mm, um, µm, nm, pm '
                                        r"or unset; found 'inch'"):
        DataOptions(output_unit='inch', spelling='cli')


def test_identify_reads_v_and_nm_and_writes_si_without_warning(piezo_csv, capsys):
    tmp, t, volts, displacement = piezo_csv
    recording = read_recording(tmp / 'named.csv', DataOptions(time_column='time_ms'))
    np.testing.assert_allclose(recording.time, t, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(recording.current, volts, rtol=1e-12)
    np.testing.assert_allclose(recording.displacement, displacement, rtol=1e-12)
    assert recording.units.input_quantity == 'voltage' and recording.warnings == ()

    capsys.readouterr()
    assert main(['identify', str(tmp / 'named.csv'), '--time-column', 'time_ms', '--order',
                 '6,3', '--dynamics', 'off', '-o', str(tmp / 'named.yaml')]) == 0
    err = capsys.readouterr().err
    assert 'warning' not in err
    lo, hi = float(recording.current.min()), float(recording.current.max())
    d_lo, d_hi = float(recording.displacement.min()), float(recording.displacement.max())
    line = (f'identified on voltage {lo!r} to {hi!r} V, displacement {d_lo!r} to {d_hi!r} m')
    assert line in err
    assert 'current' not in err.split('identified on')[1].splitlines()[0]
    text = (tmp / 'named.yaml').read_text()
    assert f'# {line}' in text
    written = read_params_yaml(tmp / 'named.yaml')
    assert written['model.input_quantity'] == 'voltage'
    assert (written['output.min'], written['output.max']) == (lo, hi)
    assert abs(written['model.output_offset']) < 1e-3                 # m, not nm


def test_an_unscaled_nm_column_read_as_m_is_warned_about(piezo_csv, capsys):
    tmp, _, _, _ = piezo_csv
    capsys.readouterr()
    assert main(['identify', str(tmp / 'bare.csv'), '--order', '6,3', '--dynamics', 'off',
                 '-o', str(tmp / 'bare.yaml')]) == 0
    warnings = [line for line in capsys.readouterr().err.splitlines()
                if line.startswith('warning: ')]
    assert len(warnings) == 1
    assert 'the displacement spans' in warnings[0] and '--output-unit nm' in warnings[0]
    # Stating the unit: no warning, and the model of the named columns.
    assert main(['identify', str(tmp / 'bare.csv'), '--order', '6,3', '--dynamics', 'off',
                 '--output-unit', 'nm', '-o', str(tmp / 'stated.yaml')]) == 0
    assert 'warning' not in capsys.readouterr().err
    stated = read_params_yaml(tmp / 'stated.yaml')
    bare = read_params_yaml(tmp / 'bare.yaml')
    assert stated['model.output_offset'] == pytest.approx(1e-9 * bare['model.output_offset'],
                                                          rel=1e-6)


def test_compensate_names_volts_and_the_unreachable_share(piezo_csv, capsys):
    tmp, _, _, displacement = piezo_csv
    if not (tmp / 'named.yaml').exists():
        assert main(['identify', str(tmp / 'named.csv'), '--time-column', 'time_ms',
                     '--order', '6,3', '--dynamics', 'off', '-o', str(tmp / 'named.yaml')]) == 0
    desired = displacement.min() + np.array([0.1, 0.5, 0.9]) * np.ptp(displacement)
    write_csv_columns(tmp / 'desired.csv', {'desired_um': 1e6 * desired})
    capsys.readouterr()
    assert main(['compensate', str(tmp / 'named.yaml'), '--input', str(tmp / 'desired.csv'),
                 '--output', str(tmp / 'v.csv')]) == 0
    err = capsys.readouterr().err
    assert 'warning' not in err and "'desired_um': µm" in err
    # The start's words carry the model's unit (they said A for every model).
    rest = read_params_yaml(tmp / 'named.yaml')['output.min']
    assert 'note: start: rest_low: at rest after a sweep up to the highest identified input,' \
        in err and f'V, and down to the lowest, {rest:.6g} V' in err
    header_limits = read_params_yaml(tmp / 'named.yaml')
    assert main(['compensate', str(tmp / 'named.yaml'), '--input', str(tmp / 'desired.csv'),
                 '--output-min', '0', '--output-max', '2', '--output', str(tmp / 'c.csv')]) == 0
    err = capsys.readouterr().err
    assert 'of its displacement range' in err and 'is unreachable' in err
    assert 'clamped to 0 to 2 V' in err
    assert header_limits['output.min'] < 0.0


def test_a_voltage_read_as_a_current_is_warned_about(piezo_csv, tmp_path):
    _, t, volts, displacement = piezo_csv
    write_csv_columns(tmp_path / 'input.csv', {'time': t, 'input': volts,
                                               'output': displacement})
    [warning] = read_recording(tmp_path / 'input.csv', DataOptions(spelling='cli')).warnings
    assert warning.startswith('the input reaches 112 A') and '--input-unit V' in warning
    stated = read_recording(tmp_path / 'input.csv',
                            DataOptions(spelling='cli', input_unit='V'))
    assert stated.warnings == () and stated.units.input_quantity == 'voltage'
    # A named current is the user's statement: no warning, whatever its size.
    write_csv_columns(tmp_path / 'amps.csv', {'time': t, 'I_A': volts, 'y': displacement})
    assert read_recording(tmp_path / 'amps.csv').warnings == ()


def test_simulate_refuses_volts_for_a_current_model(tmp_path, capsys):
    t, current = identification_excitation(8.0, sample_rate=500.0, seed=1)
    displacement = MagnetostrictiveActuator().simulate(t, current)
    write_csv_columns(tmp_path / 'rec.csv', {'time': t, 'current_A': current,
                                             'displacement': displacement})
    assert main(['identify', str(tmp_path / 'rec.csv'), '--order', '4,2', '--dynamics', 'off',
                 '-o', str(tmp_path / 'p.yaml')]) == 0
    write_csv_columns(tmp_path / 'v.csv', {'u_V': current})
    capsys.readouterr()
    assert main(['simulate', str(tmp_path / 'p.yaml'), '--input', str(tmp_path / 'v.csv'),
                 '--output', str(tmp_path / 's.csv')]) == 1
    assert ("column 'u_V' is in V, but" in capsys.readouterr().err)
    write_csv_columns(tmp_path / 'ma.csv', {'i_mA': 1e3 * current})
    assert main(['simulate', str(tmp_path / 'p.yaml'), '--input', str(tmp_path / 'ma.csv'),
                 '--output', str(tmp_path / 'm.csv')]) == 0
    write_csv_columns(tmp_path / 'a.csv', {'current': current})
    assert main(['simulate', str(tmp_path / 'p.yaml'), '--input', str(tmp_path / 'a.csv'),
                 '--output', str(tmp_path / 'a_out.csv')]) == 0
    from mpi_ros.recordings import read_csv_table
    milli = read_csv_table(tmp_path / 'm.csv')[1][:, 1]
    plain = read_csv_table(tmp_path / 'a_out.csv')[1][:, 1]
    np.testing.assert_allclose(milli, plain, rtol=1e-12)        # mA converted to A
