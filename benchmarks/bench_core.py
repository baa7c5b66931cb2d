#!/usr/bin/env python3
# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Core speed benchmark (run on demand, not in the test suite).

Targets of the core issue, measured on the machine this runs on:

- identification from 1,000,000 samples at n=14, l=7 in <= 1 s wall, with the start state
  estimated, and with the lag and dead time estimated too (issue 17);
- batch Gamma and Gamma^-1 >= 10 million samples/s;
- streaming single-sample Gamma^-1 step <= 5 us median;
- the compensator's compiled block loop (chunks of one axis, samples x axes blocks of
  several): cost per axis-sample, and per one-sample block of 8 and 64 axes (issue 12).

Usage: ``python benchmarks/bench_core.py [--samples N]``
"""

import argparse
import os
import platform
import time

from mpi_ros import identify
from mpi_ros.compensation import Compensator, MultiAxisCompensator
from mpi_ros.operators.filters import first_order_lag
import numpy as np


def _signal(samples: int, rng: np.random.Generator) -> np.ndarray:
    t = np.linspace(0.0, samples / 10000.0, samples)       # 10 kHz, the paper's DSP rate
    return 1.0 + 0.8 * (np.sin(2 * np.pi * 1.0 * t) * (0.6 + 0.4 * np.cos(2 * np.pi * 0.05 * t))
                        + 0.2 * rng.standard_normal(samples).cumsum() / np.sqrt(samples))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument('--samples', type=int, default=1_000_000)
    parser.add_argument('--repeats', type=int, default=5)
    args = parser.parse_args()
    rng = np.random.default_rng(0)
    x = np.clip(_signal(args.samples, rng), 0.2, 1.8)
    truth_y = 2e-5 * (x - 0.2) ** 1.4 + 3e-6 * np.sin(3 * x)
    y = truth_y + rng.normal(0.0, 2e-8, x.size)
    print(f'machine: {platform.processor() or platform.machine()}, {os.cpu_count()} cores, '
          f'python {platform.python_version()}')
    identify(x, y, n=14, l=7)          # compile the kernels first (a short cut is refused)
    times = []
    for _ in range(args.repeats):
        t0 = time.perf_counter()
        result = identify(x, y, n=14, l=7)
        times.append(time.perf_counter() - t0)
    print(f'identify {x.size:,} samples, n=14 l=7 (start state estimated): median'
          f' {np.median(times):.3f} s, best {min(times):.3f} s (target <= 1 s)')
    # With the time base: lag and dead time estimated too (a 3 ms lag of the input here).
    t = np.arange(x.size) / 10000.0
    lagged = first_order_lag(t, x, 3e-3)
    y_lag = 2e-5 * (lagged - 0.2) ** 1.4 + 3e-6 * np.sin(3 * lagged) + rng.normal(
        0.0, 2e-8, x.size)
    identify(x[:50000], y_lag[:50000], n=14, l=7, time=t[:50000])
    times = []
    for _ in range(args.repeats):
        t0 = time.perf_counter()
        timed = identify(x, y_lag, n=14, l=7, time=t)
        times.append(time.perf_counter() - t0)
    print(f'identify {x.size:,} samples at 10 kHz, n=14 l=7, start state and dynamics'
          f' estimated (lag found {1e3 * timed.dynamics.lag_time_constant:.3f} ms, true'
          f' 3.000 ms): median {np.median(times):.3f} s, best {min(times):.3f} s'
          ' (target <= 1 s)')
    model = result.model
    inverse = model.inverse()
    for name, op, data in (('batch Gamma', model, x), ('batch Gamma^-1', inverse, y)):
        op.simulate(data[:1000])
        times = []
        for _ in range(args.repeats):
            t0 = time.perf_counter()
            op.simulate(data)
            times.append(time.perf_counter() - t0)
        print(f'{name}: {data.size / np.median(times) / 1e6:.1f} million samples/s '
              '(target >= 10)')
    stream = inverse.stream()
    desired = y[:200000]
    stream.step(float(desired[0]))
    laps = np.empty(desired.size)
    clock = time.perf_counter_ns
    for k, v in enumerate(desired.tolist()):
        t0 = clock()
        stream.step(v)
        laps[k] = clock() - t0
    print(f'streaming Gamma^-1 step: median {np.median(laps) / 1e3:.2f} us, '
          f'p99 {np.percentile(laps, 99) / 1e3:.2f} us (target median <= 5 us)')
    comp = Compensator(model, output_min=0.2, output_max=1.8)
    for k, v in enumerate(desired.tolist()):
        t0 = clock()
        comp.command(v)
        laps[k] = clock() - t0
    print(f'compensator command (clamp, counters, turning-point memory): median '
          f'{np.median(laps) / 1e3:.2f} us, p99 {np.percentile(laps, 99) / 1e3:.2f} us')
    _blocks(model, desired, args.repeats)


def _blocks(model, desired: np.ndarray, repeats: int) -> None:
    """Print the block loop's cost: chunks, samples x axes blocks, one-sample blocks."""
    comp = Compensator(model, output_min=0.2, output_max=1.8)
    comp.command_batch(desired[:10])
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        comp.command_batch(desired)
        times.append(time.perf_counter() - t0)
    print(f'compensator chunk of {desired.size:,} samples: {min(times) / desired.size * 1e9:.0f}'
          ' ns per sample (best of repeats)')
    for axes in (8, 64):
        multi = MultiAxisCompensator([model] * axes, output_min=0.2, output_max=1.8)
        block = np.repeat(desired[:20000, None], axes, axis=1)
        multi.command(block[:2])
        t0 = time.perf_counter()
        multi.command(block)
        per = (time.perf_counter() - t0) / block.size * 1e9
        rows = list(block[:5000])
        laps = np.empty(len(rows))
        clock = time.perf_counter_ns
        for k, row in enumerate(rows):
            t0 = clock()
            multi.command(row)
            laps[k] = clock() - t0
        print(f'{axes} axes: block of 20,000 samples {per:.0f} ns per axis-sample; one-sample'
              f' block median {np.median(laps) / 1e3:.2f} us, p99'
              f' {np.percentile(laps, 99) / 1e3:.2f} us')


if __name__ == '__main__':
    main()
