# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Identification on measured records from ``../shared/data/measured`` (skipped when absent).

PNZT piezoceramic (aixACCT + interferometer; voltage [V] -> displacement [nm], each table
with its own zero, the 1 Hz tables falling with the voltage), an SMA morphing-wing rig
(quasi-static reversal curves, no time base) and a 10 kHz piezo rig (TUM; a step before the
record, 740 Hz ringing, creep, lag; rising-amplitude sines at 20, 40 and 100 Hz).  The data
are not redistributable: they are read where they lie, never copied.  See each SOURCE.md.

Issue 17's acceptance: every record that is not a butterfly is identified whole (order
auto), and the model simulated from the record's first sample is within 1.1x (or 0.5 points)
of a plain (14, 7) QP with one constant term fitted on the same record; butterfly records
are refused, naming the butterfly.
"""

from pathlib import Path

from mpi_ros import IdentificationError, identify
from mpi_ros.identification import fit_plain
from mpi_ros.recordings import read_csv_signals
import numpy as np
import pytest

MEASURED = Path(__file__).resolve().parents[1].parent / 'shared' / 'data' / 'measured'
PNZT = MEASURED / 'pnzt-aixacct-tue' / 'csv'
SMA = MEASURED / 'sma-morphing-wing-basaeri'
TUM = MEASURED / 'tum_piezo'

pytestmark = pytest.mark.skipif(not MEASURED.is_dir(),
                                reason=f'measured data not found at {MEASURED}')


def _table(name):
    rec = read_csv_signals(PNZT / f'{name}.csv', time_column='Time_s',
                           input_column='Vplus_V', output_column='D1_nm', output_scale=1e-9)
    return rec.time, rec.current, rec.displacement


def _columns(name, amplitude):
    # MeasurementData/Serie1: side-by-side voltage [V] and displacement [nm] columns.
    lines = [line for line in (PNZT / name).read_text().splitlines()
             if not line.startswith('#')]
    header = lines[0].split(',')
    data = np.loadtxt(lines[1:], delimiter=',')
    volts = next(i for i, h in enumerate(header) if h.startswith('V') and amplitude in h)
    return None, data[:, volts], data[:, volts + 1] * 1e-9


def _sma(name):
    rec = read_csv_signals(SMA / f'{name}_assembled_sequence.csv', time_column=None,
                           input_column='v', output_column='y')
    return None, rec.current, rec.displacement


def _tum(name):
    rec = read_csv_signals(TUM / f'{name}.csv', time_column='time', input_column='input',
                           output_column='output')
    return rec.time, rec.current, rec.displacement


def plain_qp(x, y):
    """Return the plain (14, 7) QP's simulation of the record from its first sample."""
    return fit_plain(x, y, 14, 7).simulate(x)


def _rms(sim, y):
    return float(np.sqrt(np.mean((sim - y) ** 2)) / np.ptp(y))


GOOD = {
    'SMA DataT': lambda: _sma('DataT'),
    'SMA DataE': lambda: _sma('DataE'),
    'SMA input_data': lambda: _sma('input_data'),
    'PNZT 800 V (table 3)': lambda: _table('SLOW_table03_TEST_800V'),
    'PNZT 1000 V (table 4)': lambda: _table('SLOW_table04_TEST_1000V'),
    'PNZT 1200 V (table 5)': lambda: _table('SLOW_table05_TEST_1200V'),
    'PNZT 800 V after switching (table 7)': lambda: _table('SLOW_table07_TEST_800V'),
    'PNZT 800 V after switching (table 9)': lambda: _table('SLOW_table09_TEST_800V'),
    'PNZT loop 0.8 kV': lambda: _columns('MeasurementData_single_loops.csv', '08kv'),
    'PNZT loop 1.0 kV': lambda: _columns('MeasurementData_single_loops.csv', '1kv'),
    'PNZT loop 1.1 kV': lambda: _columns('MeasurementData_single_loops.csv', '11kv'),
    'PNZT loop 1.5 kV': lambda: _columns('MeasurementData_single_loops.csv', '15kv'),
    'PNZT loop 1.9 kV': lambda: _columns('MeasurementData_single_loops.csv', '19kv'),
    **{f'TUM {name}': (lambda name=name: _tum(name)) for name in (
        'id_20hz_nolp_20140609', 'rs_20hz_nolp_20140608', 'rs_40hz_nolp_20140608',
        'rs_100hz_nolp_20140608', 'rs_100hz_nolp_20140612', 'rs_100hz_lp_20140608')},
}

BUTTERFLY = {
    'PNZT 1400 V 0.1 Hz (table 1)': lambda: _table('SLOW_table01_TEST_0_1Hz'),
    'PNZT 1400 V 0.01 Hz (table 2)': lambda: _table('SLOW_table02_TEST_0_01Hz'),
    'PNZT 1400 V 1 Hz (table 6)': lambda: _table('SLOW_table06_TEST_1400V'),
    'PNZT butterfly 1300 V': lambda: _columns('Serie1_butterfly_0p5Hz.csv', '1300V'),
    'PNZT butterfly 1600 V': lambda: _columns('Serie1_butterfly_0p5Hz.csv', '1600V'),
    'PNZT creep 1400 V (table 1)': lambda: _table('CREEP_table01_CREEP_1400V_1000V_60S'),
    'PNZT creep 1400 V (table 3)': lambda: _table('CREEP_table03_CREEP_1400V_1000V_105S'),
}


@pytest.mark.parametrize('name', sorted(GOOD))
def test_records_are_identified_whole_as_well_as_a_plain_qp(name):
    time, current, displacement = GOOD[name]()
    result = identify(current, displacement, order='auto', time=time)
    # The parameter form simulated from the first sample reproduces the reported error.
    model = result.full_model
    sim = model.response(time, current)       # time ignored by a static model
    whole = _rms(sim, displacement)
    assert whole == pytest.approx(result.whole_record_rms_error, rel=1e-6)
    reference = _rms(plain_qp(current, displacement), displacement)
    assert whole <= max(1.1 * reference, reference + 0.005)
    assert result.rms_error < result.linear_rms_error


def test_a_record_worse_than_a_line_on_its_held_out_blocks_is_refused():
    # PNZT 800 V after switching (table 10), one loop of 401 samples: 4.35 % in sample, but on
    # its own held-out blocks (5 contiguous folds) clearly worse than a straight line on most
    # folds, inside the input range each fold was fitted on (issue 26: no exit 0 there).
    time, current, displacement = _table('SLOW_table10_TEST_800V')
    with pytest.raises(IdentificationError, match='no better than a straight line on the'
                                                  ' record.s held-out blocks'):
        identify(current, displacement, order='auto', time=time)


@pytest.mark.parametrize('name', sorted(BUTTERFLY))
def test_butterfly_records_are_refused_naming_the_butterfly(name):
    time, current, displacement = BUTTERFLY[name]()
    for order in [(14, 7), 'auto']:
        with pytest.raises(IdentificationError, match='not monotone in the input.*butterfly'):
            identify(current, displacement, order=order, time=time)


def test_a_record_unrelated_to_its_input_is_refused():
    # Table 8: the 800 V repeat after the switching run drifts with the input's timing but
    # not with its value (correlation -0.17): refused as not a hysteresis of this input.
    time, current, displacement = _table('SLOW_table08_TEST_800V')
    with pytest.raises(IdentificationError, match='correlation is -0.17'):
        identify(current, displacement, order='auto', time=time)


def test_tum_record_start_ringing_and_lag_are_found():
    # The record starts with a step from (probably) 0 V down to -90 V just before its
    # first sample, rings at about 740 Hz for some 60 ms, and lags by about a sample.
    time, current, displacement = _tum('rs_20hz_nolp_20140608')
    result = identify(current, displacement, order='auto', time=time)
    assert 'rings at about 7' in result.findings            # 7xx Hz
    assert 300 < result.excluded < 1500                     # 30-150 ms of ringing left out
    assert result.burn_in == 0                               # the start state is estimated
    estimate = result.dynamics_estimate
    assert 0.0 < min(estimate.dead_time, estimate.lag_time_constant) < 1e-3
    # The whole record from its first sample, ringing included, against the plain QP.
    assert result.whole_record_rms_error < _rms(plain_qp(current, displacement),
                                                displacement)
    # The ringing is a lightly damped output mode (SOURCE.md: 742 Hz, 13-15 ms; its frequency
    # rises from 727 to 750 Hz as it decays, a linear mode fits about 723 Hz), modelled: the
    # mode starts deflected by the step (from +0.6 um to about -17 um) and cuts the
    # whole-record error by a third, the start's ringing by more than half.
    mode = result.resonance
    assert mode.modelled and result.full_model.cause == 'resonance'
    assert 700.0 < mode.frequency < 760.0 and 0.008 < mode.decay < 0.016
    assert 14e-6 < mode.deflection < 19e-6
    assert mode.error < 0.7 * mode.static_error
    assert mode.outside_error <= mode.static_outside_error + 1e-3
    start = slice(0, 1000)                                   # the first 100 ms
    static = result.full_model.model.simulate(current)       # Gamma without the mode
    assert _rms(result.full_model.response(time, current)[start], displacement[start]) < \
        0.5 * _rms(static[start], displacement[start])


def test_cross_rate_tum_model_validates_on_the_other_rates():
    # Identified on the 20 Hz capture, simulated on the 40 and 100 Hz captures of the same
    # day (same sensor zero): better than the straight line of the 20 Hz record there.
    time, current, displacement = _tum('rs_20hz_nolp_20140608')
    result = identify(current, displacement, order='auto', time=time)
    line = np.polyfit(current, displacement, 1)
    for name in ('rs_40hz_nolp_20140608', 'rs_100hz_nolp_20140608'):
        tv, xv, yv = _tum(name)
        model = result.full_model
        sim = model.response(tv, xv)
        keep = tv >= 0.1                                     # after the start's ringing
        assert _rms(sim[keep], yv[keep]) < 0.5 * _rms(np.polyval(line, xv[keep]), yv[keep])


def test_tum_loops_widen_with_rate_and_the_diagnosis_names_rate_dependence(tmp_path):
    # Issue 18: the rig's 20 and 40 Hz records (joined, each with its own start state) train
    # the plain model and the extensions; the 100 Hz record, a rate not used to fit them,
    # validates.  The loop widens with the rate (the lag's phase grows: SOURCE.md), so the
    # rate-dependent extension must win there, named through the CLI a user runs.
    import json
    from mpi_ros.app.diagnose_cli import diagnose_main
    report = tmp_path / 'report.json'
    status = diagnose_main([
        str(TUM / 'rs_20hz_nolp_20140608.csv'), str(TUM / 'rs_40hz_nolp_20140608.csv'),
        '--validate', str(TUM / 'rs_100hz_nolp_20140608.csv'), '--time-column', 'time',
        '--input-column', 'input', '--output-column', 'output', '--quiet',
        '--json', str(report), '--report', str(tmp_path / 'report'),
        '--params-out', str(tmp_path / 'rate.yaml')])
    assert status == 0
    result = json.loads(report.read_text())
    assert result['cause'] == 'rate_dependence'
    assert result['gain'] >= 0.2
    rate = next(c for c in result['candidates'] if c['cause'] == 'rate_dependence')
    # A lag of a fraction of a millisecond (the SOURCE.md's fit: about 0.1 ms).
    assert 0.0 < rate['parameters']['model.rate_dependence.time_constant'] < 1e-3
    # The parameter file a compensator loads carries the lag.
    from mpi_ros.params import read_params_yaml
    loaded = read_params_yaml(tmp_path / 'rate.yaml')
    assert loaded['model.rate_dependence.time_constant'] == pytest.approx(
        rate['parameters']['model.rate_dependence.time_constant'])


def test_a_record_whose_start_nothing_explains_is_refused_when_that_is_most_of_it():
    # The first 70 % of PNZT table 5: the plays are determined only at its sample 261 of 280
    # (its widest excursion comes last) and no candidate history explains the samples before.
    # Before the check, identify kept the last 19 samples for an order (8, 4), exited well,
    # and the model reproduced its own record from sample 0 at 112 % of the output range
    # (a straight line: 17 %).  Whole, the same table is identified (GOOD above).
    t, x, y = _table('SLOW_table05_TEST_1200V')
    cut = int(0.7 * x.size)
    with pytest.raises(IdentificationError, match=r'no start state explains the first \d+ of'
                       r' \d+ samples.*would rest on its last \d+ samples.*start the record'
                       r' with a sweep'):
        identify(x[:cut], y[:cut], order='auto', time=t[:cut])
    # Cut at half, the start left out is 81 of 200 samples: still identified.
    result = identify(x[:200], y[:200], order='auto', time=t[:200])
    assert 0 < result.burn_in <= 100
