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
(b) Every record in ``../shared/data/measured`` (PNZT tables and loops, SMA reversal
    curves): order auto and (14, 7), training and validation RMS, the straight line's,
    the operating point, or the refusal.

Usage: ``python benchmarks/evaluate_identification.py [--measured DIR] [--plot PNG]``
"""

import argparse
from pathlib import Path
import time

from mpi_ros import IdentificationError, identify
from mpi_ros.actuator import ActuatorConfig, MagnetostrictiveActuator
from mpi_ros.excitation import identification_excitation
from mpi_ros.identification import burn_in, identify_weights
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
            table = {(r['n'], r['l']): r['nonlinearity_error'] for r in result.order_table}
            valid = validation_error(result.model, xv + bias, offset + sign * yv)
            above = table[result.order] / min(table.values()) - 1
            autos.append(f'{result.order} {_pct(valid).strip()} (held-out +{100 * above:.0f} %)')
        print(f'  {variant:26s} ' + '; '.join(row))
        print(f'  {"":26s} auto: ' + '; '.join(autos))


def _pnzt_table(directory, name):
    rec = read_csv_signals(directory / 'pnzt-aixacct-tue' / 'csv' / f'{name}.csv',
                           time_column='Time_s', input_column='Vplus_V',
                           output_column='D1_nm', output_scale=1e-9)
    return rec.current, rec.displacement


def _pnzt_columns(directory, name):
    path = directory / 'pnzt-aixacct-tue' / 'csv' / name
    lines = [line for line in path.read_text().splitlines() if not line.startswith('#')]
    header = lines[0].split(',')
    data = np.loadtxt(lines[1:], delimiter=',')
    return {header[k]: (data[:, k], data[:, k + 1] * 1e-9) for k in range(1, len(header), 2)}


def _sma(directory, name):
    rec = read_csv_signals(directory / 'sma-morphing-wing-basaeri'
                           / f'{name}_assembled_sequence.csv',
                           time_column=None, input_column='v', output_column='y')
    return rec.current, rec.displacement


def measured_records(directory):
    """Return ``{name: (current, displacement, validation name or None)}``."""
    records = {}
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


#: Validation partner: another table of the same amplitude and state (each has its own
#: zero: only the offset is re-estimated), or, for the SMA, the other data set of the rig.
PARTNERS = {
    'SLOW_table09_TEST_800V': 'SLOW_table10_TEST_800V',
    'SLOW_table10_TEST_800V': 'SLOW_table09_TEST_800V',
    'SMA DataT': 'SMA DataE',
    'SMA DataE': 'SMA DataT',
}


def evaluate_measured(directory):
    """Print the table of part (b); return the records."""
    print(f'\n(b) measured records in {directory}: RMS % of the output range'
          ' (training after the burn-in; validation on the partner record, its zero'
          ' re-estimated)')
    records = measured_records(directory)
    print(f'{"record":34s} {"N":>5s} {"burn":>5s} {"line":>6s}  {"auto":>8s} {"train":>6s}'
          f' {"valid":>6s}  {"(14,7)":>6s} {"valid":>6s}  operating point / refusal')
    for name, (x, y) in records.items():
        head = f'{name:34s} {x.size:5d}'
        partner = records.get(PARTNERS.get(name, ''))
        try:
            auto = identify(x, y, order='auto')
            fixed = identify(x, y, n=14, l=7)
        except IdentificationError as err:
            print(f'{head} REFUSED: {str(err)[:150]}')
            continue
        valid = [validation_error(r.model, *partner, reestimate_offset=True)
                 if partner is not None else float('nan') for r in (auto, fixed)]
        m = fixed.model
        print(f'{head} {fixed.burn_in:5d} {_pct(fixed.linear_rms_error)}  {str(auto.order):>8s}'
              f' {_pct(auto.rms_error)} {_pct(valid[0])}  {_pct(fixed.rms_error)}'
              f' {_pct(valid[1])}  x0 {m.input_offset:.4g}, y0 {m.output_offset:.4g},'
              f' sign {m.output_sign:+d}')
    return records


def plot(records, path):
    """Plot SMA reversal curves with the (14, 7) model, and why a PNZT single cycle is refused."""
    import matplotlib
    matplotlib.use('Agg')
    import matplotlib.pyplot as plt
    from mpi_ros.identification import fit_model
    fig, axes = plt.subplots(1, 3, figsize=(15, 4.6))
    for ax, name in zip(axes[:2], ('SMA DataT', 'SMA DataE')):
        x, y = records[name]
        result = identify(x, y, n=14, l=7)
        sim = result.model.simulate(x)
        k = result.burn_in
        ax.plot(x, y, color='0.6', lw=1, label='measured')
        ax.plot(x[k:], sim[k:], 'r-', lw=1,
                label=f'MPI (14, 7), RMS {100 * result.rms_error:.1f} %')
        ax.set_title(f'{name}: reversal curves (line {100 * result.linear_rms_error:.1f} %)',
                     fontsize=9)
        ax.set_xlabel('input (units not stated)')
        ax.set_ylabel('output (units not stated)')
        ax.legend(fontsize=7)
    ax = axes[2]
    x, y = records['loop Vplus_08kv_V']
    model, design, _ = fit_model(x, y, 14, 7)        # no checks: what identify refuses
    sim = model.simulate(x)
    k = design.burn_in
    ax.plot(x * 1e-3, y * 1e9, color='0.6', lw=1, label='measured (one cycle)')
    ax.plot(x[k:] * 1e-3, sim[k:] * 1e9, 'r-', lw=1.5, label='fit on the part after the burn-in')
    ax.plot(x[:k] * 1e-3, np.clip(sim[:k] * 1e9, -400, 800), 'r:', lw=1,
            label='the same model before it (clipped)')
    ax.set_title('PNZT 0.8 kV single loop: refused (loops not determined)', fontsize=9)
    ax.set_xlabel('kV')
    ax.set_ylabel('nm')
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    print(f'\nplot: {path}')


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    default = Path(__file__).resolve().parents[1].parent / 'shared' / 'data' / 'measured'
    parser.add_argument('--measured', type=Path, default=default)
    parser.add_argument('--plot', type=Path, default=None)
    args = parser.parse_args()
    started = time.perf_counter()
    evaluate_actuator()
    if args.measured.is_dir():
        records = evaluate_measured(args.measured)
        if args.plot is not None:
            plot(records, args.plot)
    else:
        print(f'\n(b) skipped: no measured data at {args.measured}')
    print(f'\n{time.perf_counter() - started:.0f} s')


if __name__ == '__main__':
    main()
