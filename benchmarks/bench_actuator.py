#!/usr/bin/env python3
# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Actuator (plant simulation) speed benchmark (run on demand, not in the test suite).

Measures :class:`mpi_ros.plant.actuator.MagnetostrictiveActuator` on the machine this runs on:
batch ``simulate`` (samples per second, best of repeats) and the streaming ``step`` the
plant simulator node calls once per command (median and p99 per sample), without effects
and with every plant effect on, and ``advance`` with one sample (the general path, with the
array checks of the boundary).  Issue 19 moved the effects from the compiled kernel into
the effect registry; this is how that change is checked not to slow the plant down.

Usage: ``python benchmarks/bench_actuator.py [--samples N] [--steps N] [--repeats N]``
"""

import argparse
import os
import platform
import time

from mpi_ros.plant.actuator import ActuatorConfig, MagnetostrictiveActuator
import numpy as np

#: Every effect of the built-in plant on (the strengths of the tests and the demo).
ALL_EFFECTS = {'creep_gain': 0.05, 'eddy_time_constant_s': 0.005,
               'thermal_gain_m_per_a2': 2e-6, 'dead_time_s': 0.0035, 'noise_std_m': 1e-8}


def main() -> None:
    """Print the batch and streaming speed, plain and with every effect."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument('--samples', type=int, default=200_000)
    parser.add_argument('--steps', type=int, default=20_000)
    parser.add_argument('--repeats', type=int, default=7)
    args = parser.parse_args()
    print(f'machine: {platform.processor() or platform.machine()}, {os.cpu_count()} cores, '
          f'python {platform.python_version()}')
    t = np.arange(args.samples) / 1000.0
    x = 1.0 + 0.8 * np.sin(2 * np.pi * 1.0 * t) * np.cos(2 * np.pi * 0.13 * t)
    for name, config in (('no effects', ActuatorConfig()),
                         ('all effects', ActuatorConfig(**ALL_EFFECTS))):
        act = MagnetostrictiveActuator(config, seed=1)
        act.simulate(t[:100], x[:100])                    # compile / load the kernels
        times = []
        for _ in range(args.repeats):
            t0 = time.perf_counter()
            act.simulate(t, x)
            times.append(time.perf_counter() - t0)
        laps = np.empty(args.steps)
        clock = time.perf_counter_ns
        for k, (tk, xk) in enumerate(zip(t[:args.steps].tolist(), x[:args.steps].tolist())):
            t0 = clock()
            act.step(tk, xk)
            laps[k] = clock() - t0
        chunk = np.empty(args.steps)                      # one-sample advance() calls
        act.reset()
        for k, (tk, xk) in enumerate(zip(t[:args.steps].tolist(), x[:args.steps].tolist())):
            t0 = clock()
            act.advance([tk], [xk])
            chunk[k] = clock() - t0
        print(f'{name}: simulate {args.samples / min(times) / 1e6:.2f} million samples/s'
              f' (best of {args.repeats}); step median {np.median(laps) / 1e3:.2f} us,'
              f' p99 {np.percentile(laps, 99) / 1e3:.2f} us; one-sample advance median'
              f' {np.median(chunk) / 1e3:.2f} us')


if __name__ == '__main__':
    main()
