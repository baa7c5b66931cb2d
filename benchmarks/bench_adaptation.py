#!/usr/bin/env python3
# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Online adaptation in the closed loop: the static against the adaptive compensator.

For every scenario and seed, the model is identified on the actuator without drift ("in
the morning": a plant simulator process plays and records its identification excitation,
60 s at 500 Hz; offline, the built-in actuator), then a fresh plant with the scenario's
drift tracks a smooth trajectory inside 15-85 % of the recorded range for ``--duration``
seconds, once with the static compensator and once with ``adaptation.enabled`` (default
adaptation parameters), each in lock step at ``--rate`` Hz in real time over DDS
(:meth:`mpi_ros.harness.driver.LoopDriver.exchange_paced`; the compensator takes the plant
simulator's ``displacement`` readings itself).

Scenarios: ``thermal`` (thermal drift, 3 um/A^2, tau 30 s), ``none`` (no drift: adaptation
must not make it worse), ``poor`` (thermal drift, starting from a model of order (4, 2)),
and offline only ``gain`` (the reading's gain grows 8 % and its zero 2 um over 120 s),
``thermal_model`` (a thermal-drift model identified on a record drifting 3 um/A^2 tracks an
actuator drifting 6 um/A^2: its weight w_T is adapted with Gamma) and ``thermal_gamma``
(the same, with Gamma alone identified on that record), ``thermal_same`` (the thermal
model on an actuator drifting as identified: adapting w_T must not make it worse).

Reports the RMS tracking error per 10 s window (% of the recorded range), the ratio
adaptive / static in the last window and over the last three, the updates accepted, and
draws the windows as ``adaptation_windows.png``.

Run: ``python benchmarks/bench_adaptation.py [--seeds 1 2] [--scenarios thermal none poor]
[--rate 200] [--duration 240] [--offline] [--output DIR]``.  DDS stays on this machine
(``ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST``), on ``--domain-id`` or a free benchmark domain;
every process is stopped by its PID.
"""

import argparse
import contextlib
import json
import math
import os
from pathlib import Path
import sys
import time

from bench_closed_loop_effects import claimed_domain, DDSLoop
import numpy as np

NOISE = 2e-8
RECORD_RATE = 500.0
RECORD_DURATION = 60.0
DRIFTS = {
    'thermal': {'thermal_gain_m_per_a2': 3e-6, 'thermal_time_constant_s': 30.0},
    'none': {},
    'poor': {'thermal_gain_m_per_a2': 3e-6, 'thermal_time_constant_s': 30.0},
    'gain': {},
    'thermal_model': {'thermal_gain_m_per_a2': 6e-6, 'thermal_time_constant_s': 30.0},
    'thermal_gamma': {'thermal_gain_m_per_a2': 6e-6, 'thermal_time_constant_s': 30.0},
    'thermal_same': {'thermal_gain_m_per_a2': 3e-6, 'thermal_time_constant_s': 30.0},
}
#: The drift of the identification record ("in the morning"); none by default.
IDENTIFY_DRIFT = {
    'thermal_model': {'thermal_gain_m_per_a2': 3e-6, 'thermal_time_constant_s': 30.0},
    'thermal_gamma': {'thermal_gain_m_per_a2': 3e-6, 'thermal_time_constant_s': 30.0},
    'thermal_same': {'thermal_gain_m_per_a2': 3e-6, 'thermal_time_constant_s': 30.0},
}
DESCRIPTIONS = {
    'thermal': 'thermal drift 3 um/A^2, tau 30 s; model (14, 7)',
    'none': 'no drift; model (14, 7)',
    'poor': 'thermal drift; model (4, 2)',
    'gain': 'reading gain +8 %, zero +2 um over 120 s; model (14, 7)',
    'thermal_model': 'drift 3 -> 6 um/A^2; thermal model (14, 7), w_T adapted',
    'thermal_gamma': 'drift 3 -> 6 um/A^2; Gamma (14, 7) alone, same record',
    'thermal_same': 'drift 3 um/A^2 as identified; thermal model (14, 7), w_T adapted',
}
ORDERS = {'thermal': (14, 7), 'none': (14, 7), 'poor': (4, 2), 'gain': (14, 7),
          'thermal_model': (14, 7), 'thermal_gamma': (14, 7), 'thermal_same': (14, 7)}
_MODELS = {}
WINDOW = 10.0


def _progress(text):
    print(text, file=sys.stderr, flush=True)


def windows(measured, desired, span, rate):
    """Return the RMS error per 10 s window [% of the range]."""
    error = (np.asarray(measured) - np.asarray(desired)) / span
    n = int(WINDOW * rate)
    return [100 * math.sqrt(float(np.mean(error[a:a + n] ** 2)))
            for a in range(0, error.size - n + 1, n)]


def trajectory(lo, hi, duration, rate):
    """Return times and the desired displacement inside 15-85 % of ``[lo, hi]``."""
    from mpi_ros.plant.excitation import tracking_trajectory
    span = hi - lo
    return tracking_trajectory(duration, sample_rate=rate, low=lo + 0.15 * span,
                               high=hi - 0.15 * span, final_envelope=1.0)


def offline_model(scenario, seed):
    """Identify the scenario's model on its record (once per scenario and seed)."""
    from mpi_ros import identify
    from mpi_ros.extensions.thermal_drift import fit_thermal_drift
    from mpi_ros.plant.actuator import ActuatorConfig, MagnetostrictiveActuator
    from mpi_ros.plant.excitation import identification_excitation
    if (scenario, seed) not in _MODELS:
        t, x = identification_excitation(RECORD_DURATION, sample_rate=RECORD_RATE, seed=seed)
        y = MagnetostrictiveActuator(ActuatorConfig(
            noise_std_m=NOISE, **IDENTIFY_DRIFT.get(scenario, {})), seed=seed).simulate(t, x)
        n, l = ORDERS[scenario]  # noqa: E741
        model = (fit_thermal_drift(t, x, y, order=(n, l))
                 if scenario in ('thermal_model', 'thermal_same')
                 else identify(x, y, n=n, l=l).model)
        _MODELS[scenario, seed] = model, float(np.min(y)), float(np.max(y))
    return _MODELS[scenario, seed]


def offline_run(scenario, seed, rate, duration, adaptive):
    """Run one loop without DDS (core objects); return windows and updates."""
    from mpi_ros.compensation import Compensator
    from mpi_ros.compensation.adaptation import Adaptation, AdaptationSettings
    from mpi_ros.plant.actuator import ActuatorConfig, MagnetostrictiveActuator
    model, lo, hi = offline_model(scenario, seed)
    times, desired = trajectory(lo, hi, duration, rate)
    plant = MagnetostrictiveActuator(ActuatorConfig(noise_std_m=NOISE, **DRIFTS[scenario]),
                                     seed=seed + 2)
    compensator = Compensator(model, output_min=0.0, output_max=2.0, sample_period=1 / rate)
    adaptation = Adaptation(model, AdaptationSettings(sample_period=1 / rate))
    measured = np.empty(times.size)
    for k in range(times.size):
        current = compensator.command(float(desired[k]))
        ramp = min(times[k] / 120.0, 1.0) if scenario == 'gain' else 0.0
        measured[k] = (plant.step(float(times[k]), current) * (1 + 0.08 * ramp)
                       + 2e-6 * ramp)
        if adaptive:
            adaptation.record_command(current)
            adaptation.record_measurement(measured[k])
            if k and k % int(rate) == 0:
                adaptation.step()
                candidate = adaptation.take_candidate()
                if candidate is not None:
                    compensator.install(candidate.model)
                    adaptation.applied(candidate, True)
    updates = adaptation.status()['adaptation_updates_accepted'] if adaptive else 0
    return windows(measured, desired, hi - lo, rate), updates


class AdaptationLoop(DDSLoop):
    """The node processes of one benchmark run (the effects benchmark's), stopped by PID."""

    def __init__(self, out, rate):
        super().__init__(out)
        self.rate = rate

    def identify(self, scenario, seed):
        """Record the undrifted plant's excitation, identify; return params file and range."""
        from mpi_ros import identify
        from mpi_ros.params import write_params_yaml
        from mpi_ros.recordings import read_bag_signals
        bag = self.out / f'record_{seed}'
        if not bag.exists():
            args = ['-p', f'noise_std:={NOISE!r}', '-p', f'seed:={seed}',
                    '-p', 'excitation.enabled:=true',
                    '-p', f'excitation.duration:={RECORD_DURATION!r}',
                    '-p', f'excitation.sample_rate:={RECORD_RATE!r}', '-p', f'record.path:={bag}']
            proc = self.start('plant-simulator', args, f'record_{seed}.log')
            deadline = time.monotonic() + RECORD_DURATION + 180.0
            while proc.running() and time.monotonic() < deadline:
                time.sleep(0.5)
            self.stop(proc)
        record = read_bag_signals(bag)
        n, l = ORDERS[scenario]  # noqa: E741
        model = identify(record.current, record.displacement, n=n, l=l).model
        params = self.out / f'model_{scenario}_{seed}.yaml'
        write_params_yaml(params, model.to_params())
        return params, float(np.min(record.displacement)), float(np.max(record.displacement))

    def track(self, scenario, seed, params, times, desired, adaptive):
        """Track ``desired``; return the measured displacement and the compensator's log."""
        driver = self.driver
        plant_args = ['-p', f'noise_std:={NOISE!r}', '-p', f'seed:={seed + 2}']
        for key, value in DRIFTS[scenario].items():
            plant_args += ['-p', f'actuator.{key}:={value!r}']
        plant = self.start('plant-simulator', plant_args, 'plant.log')
        driver.wait_for(lambda: driver.current_pub.get_subscription_count() > 0,
                        'the plant simulator to start', 60.0)
        log = f'compensator_{scenario}_{seed}_{"adaptive" if adaptive else "static"}.log'
        comp = self.start('compensator', [
            '--params-file', str(params), '-p', 'output.min:=0.0', '-p', 'output.max:=2.0',
            '-p', f'sample_period:={1.0 / self.rate!r}',
            '-p', f'adaptation.enabled:={"true" if adaptive else "false"}'], log)
        try:
            driver.wait_for(lambda: driver.desired_pub.get_subscription_count() > 0,
                            'the compensator to subscribe', 60.0)
            driver.handshake(driver.desired_pub, desired[0])
            _, measured = driver.exchange_paced(driver.desired_pub, desired, times,
                                                timeout=5.0)
        finally:
            self.stop(comp, plant)
        text = (self.out / log).read_text()
        return measured, text.count('adaptation: update ')


@contextlib.contextmanager
def _domain(given):
    os.environ['ROS_AUTOMATIC_DISCOVERY_RANGE'] = 'LOCALHOST'
    with claimed_domain(given) as domain:
        os.environ['ROS_DOMAIN_ID'] = str(domain)
        yield domain


def plot(rows, path):
    """Draw the windows: one panel per scenario, static dashed grey, adaptive per seed."""
    import matplotlib
    matplotlib.use('Agg')
    import matplotlib.pyplot as plt
    scenarios = list(dict.fromkeys(row['scenario'] for row in rows))
    columns = min(2, len(scenarios))
    lines = math.ceil(len(scenarios) / columns)
    fig, axes = plt.subplots(lines, columns, figsize=(6 * columns, 3.6 * lines),
                             squeeze=False, sharex=True)
    for ax, scenario in zip(axes.ravel(), scenarios):
        for i, row in enumerate(r for r in rows if r['scenario'] == scenario):
            centre = (np.arange(len(row['static'])) + 0.5) * WINDOW
            ax.plot(centre, row['static'], '--', color='0.55', linewidth=1,
                    label='static' if i == 0 else None)
            ax.plot(centre, row['adaptive'], '-', color=f'C{i}', marker='o', markersize=2.5,
                    label=f'adaptive, seed {row["seed"]} ({row["updates"]} updates, last '
                          f'window {row["ratio_last"]:.2f}x)')
        ax.set_yscale('log')
        ax.set_title(f'{scenario}: {DESCRIPTIONS[scenario]}', fontsize=9)
        ax.set_ylabel('RMS error per 10 s [% of range]', fontsize=8)
        ax.grid(True, which='both', alpha=0.3)
        ax.legend(fontsize=6.5, loc='best')
    for ax in axes[-1]:
        ax.set_xlabel('time since the start of tracking [s]', fontsize=8)
    for ax in axes.ravel()[len(scenarios):]:
        ax.set_visible(False)
    fig.suptitle(f'Static vs adaptive compensator ({rows[0]["mode"]}, default adaptation '
                 'parameters)', fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def main():
    """Run the scenarios, print the table, write JSON and the plot."""
    p = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    p.add_argument('--seeds', type=int, nargs='+', default=[1])
    p.add_argument('--scenarios', nargs='+', default=['thermal', 'none', 'poor'],
                   choices=sorted(DRIFTS))
    p.add_argument('--rate', type=float, default=200.0)
    p.add_argument('--duration', type=float, default=240.0)
    p.add_argument('--offline', action='store_true')
    p.add_argument('--domain-id', type=int, default=None)
    p.add_argument('--output', default='bench_adaptation')
    args = p.parse_args()
    out = Path(args.output)
    out.mkdir(parents=True, exist_ok=True)
    rows = []
    loop = None
    with contextlib.ExitStack() as stack:
        if not args.offline:
            stack.enter_context(_domain(args.domain_id))
            import rclpy
            rclpy.init(args=['bench_adaptation'])
            loop = AdaptationLoop(out, args.rate)
            stack.callback(rclpy.try_shutdown)
            stack.callback(loop.close)
        for scenario in args.scenarios:
            for seed in args.seeds:
                if loop is None:
                    static, _ = offline_run(scenario, seed, args.rate, args.duration, False)
                    adaptive, updates = offline_run(scenario, seed, args.rate, args.duration,
                                                    True)
                else:
                    if scenario in ('gain', 'thermal_model', 'thermal_gamma', 'thermal_same'):
                        continue
                    params, lo, hi = loop.identify(scenario, seed)
                    times, desired = trajectory(lo, hi, args.duration, args.rate)
                    runs = {}
                    for adaptive_run in (False, True):
                        _progress(f'[bench] {scenario} seed {seed}: '
                                  f'{"adaptive" if adaptive_run else "static"}')
                        measured, count = loop.track(scenario, seed, params, times, desired,
                                                     adaptive_run)
                        runs[adaptive_run] = (windows(measured, desired, hi - lo, args.rate),
                                              count)
                    static, adaptive, updates = runs[False][0], runs[True][0], runs[True][1]
                row = {'scenario': scenario, 'seed': seed, 'static': static,
                       'adaptive': adaptive, 'updates': updates,
                       'ratio_last': adaptive[-1] / static[-1],
                       'ratio_last3': sum(adaptive[-3:]) / sum(static[-3:]),
                       'mode': 'offline' if loop is None else f'DDS, {args.rate:g} Hz'}
                rows.append(row)
                print(f'{scenario:8s} seed {seed}: last window static {static[-1]:.3f} %, '
                      f'adaptive {adaptive[-1]:.3f} % (ratio {row["ratio_last"]:.2f}; last 3 '
                      f'{row["ratio_last3"]:.2f}), {updates} updates', flush=True)
    load = ' '.join(f'{v:.2f}' for v in os.getloadavg())
    print(f'load average at the end: {load}; {time.strftime("%Y-%m-%d %H:%M")}')
    (out / 'results.json').write_text(json.dumps(rows, indent=1))
    if rows:
        plot(rows, out / 'adaptation_windows.png')
        print(f'wrote {out / "results.json"} and {out / "adaptation_windows.png"}')


if __name__ == '__main__':
    main()
