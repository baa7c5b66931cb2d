#!/usr/bin/env python3
# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Evaluate the identification on a rig's operating point and on measured records (issue 9).

(a) The built-in magnetostrictive-like actuator (not an MPI model), its sensor zeroed at the
    lowest current of the paper's range (0.2 A after a 1.8 A peak), 0.2 % sensor noise,
    three plants: identified on one excitation, validated on a different one (RMS over the
    output range after the validation record's burn-in).  Designs: the centred one
    (``identify``'s default), the paper's as printed (``anchor='origin'``) and the paper's
    with one constant term in the generalised error.  Variants: as recorded, sensor zero
    -20 um, +0.5 A bias, both, falling sensor.
(b) Every record in ``../shared/data/measured`` (TUM piezo captures, PNZT tables and loops,
    SMA reversal curves), identified whole with order auto and its time base: the model
    simulated from sample 0 against the plain (14, 7) QP with one constant term (issue 17),
    the start state, the dynamics, or the refusal and its cause.
(c) Cross-rate: a TUM model identified on one rate, simulated on the others.
(d) Issue 17's synthetic plants (lag, dead time, ringing, starts, rising sines, a 300-sample
    loop), three seeds: refusals, the dynamics estimated against the truth, the errors.
(e) The rest of each measured record: identified (order auto, its time base) on its first
    70 %, simulated over the whole record from its start (the state carried on), scored on
    the last 30 %, which the fit never saw, against a straight line fitted on the same 70 %.

Usage: ``python benchmarks/evaluate_identification.py [--measured DIR] [--parts abcde]``
"""

import argparse
from pathlib import Path
import time
import warnings

from mpi_ros import IdentificationError, identify, MPIWarning
from mpi_ros.identification import burn_in, fit_plain, identify_weights
from mpi_ros.plant.actuator import ActuatorConfig, MagnetostrictiveActuator
from mpi_ros.plant.excitation import identification_excitation
from mpi_ros.plant.synthetic import SYNTHETIC_KINDS, synthetic_record
from mpi_ros.recordings import read_csv_signals
import numpy as np

NOISE = 0.002                     # sensor noise, fraction of the output range
RANGE_M = 3.4e-5
ZEROED = {'sensor_zero_current_a': 0.2, 'sensor_zero_peak_current_a': 1.8}
PLANTS = (
    {},
    {'coercive_current_a': 0.22, 'interaction_center_a': 1.05, 'map_knee': 0.45},
    {'coercive_current_a': 0.38, 'coercive_spread_a': 0.14, 'map_linear_fraction': 0.3},
)
ORDERS = tuple((2 * k, k) for k in range(11))
VARIANTS = {
    'as recorded': (0.0, 0.0, 1),
    'zero -20 um': (0.0, -2e-5, 1),
    'bias +0.5 A': (0.5, 0.0, 1),
    'zero -20 um, bias +0.5 A': (0.5, -2e-5, 1),
    'falling sensor': (0.0, 0.0, -1),
}


def validation_error(model, x, y, *, reestimate_offset=False):
    """RMS over the output range after the burn-in; optionally re-estimate the zero only."""
    start = burn_in(x, 0.99 * np.ptp(x), to_turning_point=True)
    error = model.simulate(x)[start:] - y[start:]
    if reestimate_offset:            # a separate record with its own sensor zero
        error = error - np.mean(error)
    return float(np.sqrt(np.mean(error * error)) / np.ptp(y))


def origin_with_constant(x, y, n, l):  # noqa: E741
    """Fit the paper's design (anchor='origin') with one constant term in the error."""
    design, w_h, w_s_inv, w_c, _, _ = identify_weights(
        x, y, n, l, anchor='origin', extra_columns=lambda _: np.ones((x.size, 1)),
        extra_lower=np.array([-np.inf]))
    return design.model(w_h, w_s_inv, float(w_c[0]))


def _actuator_records(plant):
    config = ActuatorConfig(noise_std_m=NOISE * RANGE_M, **ZEROED, **PLANTS[plant])
    seed = 10 + plant
    t, x = identification_excitation(60.0, sample_rate=200.0, seed=seed, holds=False,
                                     bursts=False)
    y = MagnetostrictiveActuator(config, seed=seed).simulate(t, x)
    tv, xv = identification_excitation(60.0, sample_rate=200.0, seed=1000 + seed,
                                       main_frequency=0.5, holds=True, bursts=True)
    yv = MagnetostrictiveActuator(config, seed=seed).simulate(tv, xv)
    return (x, y), (xv, yv)


def _fit_or_nan(fit, x, y, xv, yv):
    try:
        return validation_error(fit(x, y), xv, yv)
    except IdentificationError:
        return float('nan')


def _pct(value):
    return '   —  ' if not np.isfinite(value) else f'{100 * value:6.2f}'


def evaluate_actuator():
    """Print the tables of part (a)."""
    print('(a) built-in actuator zeroed at 0.2 A, 0.2 % noise; validation RMS % of range on'
          ' a different excitation')
    designs = {
        'centred (identify)': lambda n, m: lambda x, y: identify(x, y, n=n, l=m).model,
        'paper (origin)': lambda n, m: lambda x, y: identify(
            x, y, n=n, l=m, anchor='origin').model,
        'origin + constant': lambda n, m: lambda x, y: origin_with_constant(x, y, n, m),
    }
    records = [_actuator_records(p) for p in range(len(PLANTS))]
    print('\nerror by order, variant "as recorded" (plants 0 / 1 / 2):')
    print(f'{"design":22s} ' + ' '.join(f'{f"({n},{l})":>20s}' for n, l in ORDERS))
    for name, design in designs.items():
        cells = []
        for n, l in ORDERS:  # noqa: E741
            values = [_fit_or_nan(design(n, l), x, y, xv, yv) for (x, y), (xv, yv) in records]
            cells.append('/'.join(_pct(v).strip() for v in values))
        print(f'{name:22s} ' + ' '.join(f'{c:>20s}' for c in cells))
    print('\n(14, 7) by variant (plants 0 / 1 / 2) and order auto (centred):')
    for variant, (bias, offset, sign) in VARIANTS.items():
        row = []
        for name, design in designs.items():
            values = [_fit_or_nan(design(14, 7), x + bias, offset + sign * y, xv + bias,
                                  offset + sign * yv) for (x, y), (xv, yv) in records]
            row.append(f'{name}: ' + '/'.join(_pct(v).strip() for v in values))
        autos = []
        for (x, y), (xv, yv) in records:
            result = identify(x + bias, offset + sign * y, order='auto')
            table = {(r['n'], r['l']): r['rms_error'] for r in result.order_table}
            valid = validation_error(result.model, xv + bias, offset + sign * yv)
            above = table[result.order] / min(table.values()) - 1
            autos.append(f'{result.order} {_pct(valid).strip()}'
                         f' (held-out RMS +{100 * above:.0f} %)')
        print(f'  {variant:26s} ' + '; '.join(row))
        print(f'  {"":26s} auto: ' + '; '.join(autos))


def _pnzt_table(directory, name):
    rec = read_csv_signals(directory / 'pnzt-aixacct-tue' / 'csv' / f'{name}.csv',
                           time_column='Time_s', input_column='Vplus_V',
                           output_column='D1_nm', output_scale=1e-9)
    return rec.time, rec.current, rec.displacement


def _pnzt_columns(directory, name):
    path = directory / 'pnzt-aixacct-tue' / 'csv' / name
    lines = [line for line in path.read_text().splitlines() if not line.startswith('#')]
    header = lines[0].split(',')
    data = np.loadtxt(lines[1:], delimiter=',')
    return {header[k]: (None, data[:, k], data[:, k + 1] * 1e-9)
            for k in range(1, len(header), 2)}


def _sma(directory, name):
    rec = read_csv_signals(directory / 'sma-morphing-wing-basaeri'
                           / f'{name}_assembled_sequence.csv',
                           time_column=None, input_column='v', output_column='y')
    return None, rec.current, rec.displacement


def _tum(directory, name):
    rec = read_csv_signals(directory / 'tum_piezo' / f'{name}.csv', time_column='time',
                           input_column='input', output_column='output')
    return rec.time, rec.current, rec.displacement


TUM = ('id_20hz_nolp_20140609', 'rs_20hz_nolp_20140608', 'rs_40hz_nolp_20140608',
       'rs_100hz_nolp_20140608', 'rs_100hz_nolp_20140612', 'rs_100hz_lp_20140608')


def measured_records(directory):
    """Return ``{name: (time or None, current, displacement)}``."""
    records = {}
    for name in TUM:
        records[f'TUM {name}'] = _tum(directory, name)
    slow = sorted((directory / 'pnzt-aixacct-tue' / 'csv').glob('SLOW_*.csv'))
    creep = sorted((directory / 'pnzt-aixacct-tue' / 'csv').glob('CREEP_*.csv'))
    for path in slow + creep:
        records[path.stem] = _pnzt_table(directory, path.stem)
    for file, tag in (('MeasurementData_single_loops.csv', 'loop'),
                      ('Serie1_butterfly_0p5Hz.csv', 'Serie1')):
        for column, signals in _pnzt_columns(directory, file).items():
            records[f'{tag} {column}'] = signals
    for name in ('DataT', 'DataE', 'input_data'):
        records[f'SMA {name}'] = _sma(directory, name)
    return records


def _rms(sim, y):
    return float(np.sqrt(np.mean((sim - y) ** 2)) / np.ptp(y))


def evaluate_measured(directory):
    """Print the table of part (b): every record whole, against the plain (14, 7) QP."""
    print(f'\n(b) measured records in {directory}, identify order auto on the whole record'
          ' (with its time base): RMS % of the output range, the model simulated from sample'
          ' 0 (mpi-ros simulate), against the plain (14, 7) QP with one constant term and the'
          ' straight line')
    records = measured_records(directory)
    print(f'{"record":38s} {"N":>6s} {"order":>8s} {"model":>7s} {"QP":>9s} {"line":>6s}'
          '  start / dynamics / refusal')
    for name, (t, x, y) in records.items():
        started = time.perf_counter()
        reference = _rms(fit_plain(x, y).simulate(x), y)
        line = _rms(np.polyval(np.polyfit(x, y, 1), x), y)
        head = f'{name:38s} {x.size:6d}'
        try:
            result = identify(x, y, order='auto', time=t)
        except IdentificationError as err:
            print(f'{head} {"refused":>8s} {"":>7s} {_pct(reference):>9s} {_pct(line)}  '
                  f'{str(err)[:110]}')
            continue
        dyn = result.dynamics.describe()
        print(f'{head} {str(result.order):>8s} {_pct(result.whole_record_rms_error)}'
              f' {_pct(reference):>9s} {_pct(line)}  {result.start_state["kind"]}; {dyn};'
              f' ringing {result.excluded} samples{_mode(result)}'
              f' ({time.perf_counter() - started:.1f} s)')
    return records


def _mode(result):
    # The output mode fitted on the ringing: frequency, decay, the static model's error.
    mode = result.resonance
    if mode.frequency <= 0.0:
        return ''
    kept = 'modelled' if mode.modelled else 'not modelled'
    return (f', mode {mode.frequency:.4g} Hz {1e3 * mode.decay:.3g} ms {kept}'
            f' (static {_pct(mode.static_error).strip()})')


def evaluate_cross_rate(directory):
    """Print part (c): a TUM model of one rate simulated on the other rates."""
    print('\n(c) cross-rate (TUM, 2014-06-08, same sensor zero): identified on the rate of'
          ' the row (order auto), simulated on the record of each column from its first'
          ' sample; RMS % of the output range after 0.1 s (the ringing of the start left'
          ' out); the straight line of the row in brackets')
    names = {'20 Hz': 'rs_20hz_nolp_20140608', '40 Hz': 'rs_40hz_nolp_20140608',
             '100 Hz': 'rs_100hz_nolp_20140608'}
    data = {rate: _tum(directory, name) for rate, name in names.items()}
    print(f'{"identified on":14s} ' + ' '.join(f'{rate:>16s}' for rate in names))
    for rate, (t, x, y) in data.items():
        result = identify(x, y, order='auto', time=t)
        line = np.polyfit(x, y, 1)
        cells = []
        for tv, xv, yv in data.values():
            model = result.full_model
            sim = model.response(tv, xv)
            keep = tv >= 0.1
            cells.append(f'{_pct(_rms(sim[keep], yv[keep])).strip()}'
                         f' ({_pct(_rms(np.polyval(line, xv[keep]), yv[keep])).strip()})')
        print(f'{rate + " " + str(result.order):14s} ' + ' '.join(f'{c:>16s}' for c in cells))


def evaluate_rest(directory, share=0.7):
    """Print part (e): each measured record fitted on its first part, scored on the rest."""
    print(f'\n(e) the rest of each measured record: identified on its first {100 * share:.0f} %'
          ' (order auto, its time base), simulated on from its start over the whole record;'
          ' RMS % of the whole output range on the last'
          f' {100 * (1 - share):.0f} % (never fitted),'
          ' then on the part fitted; the straight line fitted on the same part, on the rest; the'
          " share of the rest's input outside the range fitted (%)")
    print(f'{"record":38s} {"N":>6s} {"order":>8s} {"rest":>7s} {"line":>7s} {"fitted":>7s}'
          f' {"outside":>8s}  weights from / refusal')
    for name, (t, x, y) in measured_records(directory).items():
        cut = int(share * x.size)
        head = f'{name:38s} {x.size:6d}'
        try:
            with warnings.catch_warnings():
                warnings.simplefilter('ignore', MPIWarning)
                result = identify(x[:cut], y[:cut], order='auto',
                                  time=None if t is None else t[:cut])
        except IdentificationError as err:
            print(f'{head} {"refused":>8s}  {str(err)[:110]}')
            continue
        sim = result.full_model.response(t, x)
        line = np.polyval(np.polyfit(x[:cut], y[:cut], 1), x[cut:])
        span = float(np.ptp(y))

        def error(a, b):
            return float(np.sqrt(np.mean((a - b) ** 2)) / span)

        seen = (float(np.min(x[:cut])), float(np.max(x[:cut])))
        outside = float(np.mean((x[cut:] < seen[0]) | (x[cut:] > seen[1])))
        print(f'{head} {str(result.order):>8s} {_pct(error(sim[cut:], y[cut:]))}'
              f' {_pct(error(line, y[cut:]))} {_pct(error(sim[:cut], y[:cut]))}'
              f' {100 * outside:8.0f}  {result.weights_from}')


def evaluate_synthetic(seeds=(1, 2, 3)):
    """Print part (d): issue 17's synthetic plants, identified whole."""
    print('\n(d) synthetic plants (mpi_ros.plant.synthetic; built-in actuator, 0.2 % noise,'
          ' own zero'
          ' and sign), order auto with the time base: refusals, dynamics estimated (dead time'
          ' / lag, ms; the modelled one starred), the model from sample 0 (RMS %), the fitted'
          ' samples (ringing left out), the plain (14, 7) QP; the output mode found')
    print(f'{"plant":32s} {"seed":>4s} {"order":>8s} {"dead time":>10s} {"lag":>10s}'
          f' {"truth":>12s} {"model":>6s} {"fitted":>6s} {"QP":>6s}')
    for kind in SYNTHETIC_KINDS:
        for seed in seeds:
            record = synthetic_record(kind, seed)
            t, x, y, truth = record.time, record.current, record.displacement, record.truth
            reference = _rms(fit_plain(x, y).simulate(x), y)
            try:
                result = identify(x, y, order='auto', time=t)
            except IdentificationError as err:
                print(f'{kind:32s} {seed:4d} REFUSED {str(err)[:100]}')
                continue
            e = result.dynamics_estimate
            star_d = '*' if result.dynamics.dead_time else ' '
            star_l = '*' if result.dynamics.lag_time_constant else ' '
            true = (f'L {1e3 * truth["dead_time"]:.3g}' if truth['dead_time'] else
                    f'tau {1e3 * truth["lag_time_constant"]:.3g}'
                    if truth['lag_time_constant'] else '-')
            print(f'{kind:32s} {seed:4d} {str(result.order):>8s} {1e3 * e.dead_time:9.3g}'
                  f'{star_d} {1e3 * e.lag_time_constant:9.3g}{star_l} {true:>12s}'
                  f' {_pct(result.whole_record_rms_error)} {_pct(result.rms_error)}'
                  f' {_pct(reference)}{_mode(result)}')


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    default = Path(__file__).resolve().parents[1].parent / 'shared' / 'data' / 'measured'
    parser.add_argument('--measured', type=Path, default=default)
    parser.add_argument('--parts', default='abcde', help='which parts to run (default abcde)')
    args = parser.parse_args()
    started = time.perf_counter()
    if 'a' in args.parts:
        evaluate_actuator()
    if args.measured.is_dir():
        if 'b' in args.parts:
            evaluate_measured(args.measured)
        if 'c' in args.parts:
            evaluate_cross_rate(args.measured)
        if 'e' in args.parts:
            evaluate_rest(args.measured)
    else:
        print(f'\n(b), (c) skipped: no measured data at {args.measured}')
    if 'd' in args.parts:
        evaluate_synthetic()
    print(f'\n{time.perf_counter() - started:.0f} s')


if __name__ == '__main__':
    main()
