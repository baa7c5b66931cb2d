#!/usr/bin/env python3
# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Out of sample (issue 24): non-MPI plants identified at (14, 7), compensated on a new trajectory.

Each plant seed draws a Preisach core (the built-in actuator's relay plane, no effect) with its
own density and static map, records its excitation (cut after a drawn 0-4 s of the run, so
some records start at rest and some mid-history), is identified at (14, 7) with ``identify``,
and is then compensated offline (``compensation.Compensator``) on a smooth trajectory: one
sweep over the range, then two sines inside 15-85 % of the range.  The errors are taken
after the sweep: RMS over the output's range and (38).

Fits compared:

- ``identify``: the code under test;
- ``burn-in``: the weights fitted only after the plays are determined (the first part of the
  record only wipes out the memory; no start state is estimated).

Usage: ``python benchmarks/eval_out_of_sample.py [--seeds 0-11]``; run it from an old checkout
(``PYTHONPATH``) to compare with earlier code (its ``identify`` column).
"""

import argparse
import time

from mpi_ros import identify
from mpi_ros.compensation import Compensator
from mpi_ros.plant.actuator import ActuatorConfig, MagnetostrictiveActuator
from mpi_ros.plant.excitation import identification_excitation
import numpy as np

NOISE = 0.002
RANGE_M = 3.4e-5
RATE = 200.0
ORDER = (14, 7)
LOW, HIGH = 0.2, 1.8


def plant(seed):
    """Return the actuator config of a seed and the samples cut off the record's start."""
    rng = np.random.default_rng(seed)
    config = ActuatorConfig(
        noise_std_m=NOISE * RANGE_M, sensor_zero_current_a=LOW, sensor_zero_peak_current_a=HIGH,
        coercive_current_a=float(rng.uniform(0.15, 0.45)),
        coercive_spread_a=float(rng.uniform(0.05, 0.2)),
        interaction_center_a=float(rng.uniform(0.8, 1.2)),
        interaction_spread_a=float(rng.uniform(0.3, 0.6)),
        reversible_fraction=float(rng.uniform(0.05, 0.2)),
        map_linear_fraction=float(rng.uniform(0.1, 0.4)),
        map_knee=float(rng.uniform(0.35, 0.7)))
    cut = int(rng.uniform(0.0, 4.0) * RATE)
    return config, cut


def record(seed):
    """Return the plant's excitation record: time, current, displacement, its config."""
    config, cut = plant(seed)
    t, x = identification_excitation(30.0, sample_rate=RATE, seed=seed, holds=False,
                                     bursts=False)
    y = MagnetostrictiveActuator(config, seed=seed).simulate(t, x)
    return t[cut:] - t[cut], x[cut:], y[cut:], config


def trajectory(lo, hi):
    """Return the desired displacement: one sweep (2-98 %), then two sines in 15-85 %."""
    span = hi - lo
    ramp = np.linspace(0.0, 1.0, int(2 * RATE))
    sweep = lo + span * (0.02 + 0.96 * np.concatenate([ramp, ramp[::-1]]))
    t = np.arange(int(20 * RATE)) / RATE
    shape = 0.5 - 0.21 * np.cos(2 * np.pi * 0.31 * t) - 0.14 * np.cos(2 * np.pi * 0.83 * t)
    sines = lo + span * shape
    desired = np.concatenate([sweep, sines])
    return desired, sweep.size


def loop_errors(model, config, seed, lo, hi):
    """Return (RMS over the range, (38)) of the compensated plant after the sweep."""
    desired, after = trajectory(lo, hi)
    compensator = Compensator(model, output_min=LOW, output_max=HIGH)
    command = compensator.command_batch(desired)
    t = np.arange(desired.size) / RATE
    measured = MagnetostrictiveActuator(config, seed=seed + 500).simulate(t, command)
    error = (measured - desired)[after:]
    rms = float(np.sqrt(np.mean(error ** 2)) / (hi - lo))
    control = float(np.max(np.abs(error)) / np.max(np.abs(desired[after:])))
    return rms, control


def burn_in_model(x, y):
    """Return the (14, 7) model fitted only after the plays are determined."""
    from mpi_ros.identification.fitter import fit_record
    from mpi_ros.identification.qp import scaled_design
    from mpi_ros.identification.record import prepare_record
    from mpi_ros.identification.start_states import determined_from
    rec = prepare_record(x, y)
    design = scaled_design(x, y, *ORDER, sign=rec.sign)
    split = determined_from(design.scaled_input(x), float(design.hysteresis_thresholds[-1]))
    return fit_record(rec, *ORDER, burn_in=split, choose=False).model


def main():
    """Print the table."""
    parser = argparse.ArgumentParser()
    parser.add_argument('--seeds', default='0-11')
    parser.add_argument('--skip-burn-in', action='store_true')
    args = parser.parse_args()
    a, b = (int(v) for v in args.seeds.split('-'))
    print('seed  identify RMS/(38) %     burn-in RMS/(38) %   ratio   (identify s)')
    for seed in range(a, b + 1):
        t, x, y, config = record(seed)
        lo, hi = float(np.min(y)), float(np.max(y))
        started = time.perf_counter()
        result = identify(x, y, n=ORDER[0], l=ORDER[1])
        took = time.perf_counter() - started
        rms, control = loop_errors(result.model, config, seed, lo, hi)
        line = f'{seed:4d}  {100 * rms:6.3f} / {100 * control:6.3f}'
        if not args.skip_burn_in:
            brms, bcontrol = loop_errors(burn_in_model(x, y), config, seed, lo, hi)
            line += f'     {100 * brms:6.3f} / {100 * bcontrol:6.3f}   {rms / brms:5.2f}'
        print(f'{line}   ({took:.2f} s, {result.start_state.get("kind")},'
              f' burn-in {result.burn_in}, w_H[-1] {result.model.hysteresis.weights[-1]:.3g})',
              flush=True)


if __name__ == '__main__':
    main()
