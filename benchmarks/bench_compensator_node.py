#!/usr/bin/env python3
# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Compensator node throughput, latency and soak benchmark over DDS (run on demand).

Three processes: this one publishes ``desired_displacement`` at ``--rate`` Hz, the
compensator node computes ``current_command``, and a receiver process records the arrival
time of every command.  Times come from CLOCK_MONOTONIC, which all processes share;
reliable in-order delivery pairs the k-th command with the k-th desired value.

Reports: messages sent/received (drops), achieved rate, latency percentiles (desired in ->
command out, measured in another process), latency per 10 s window (drift) and the
compensator's resident memory over time (growth).

Targets: 10,000 messages/s for 10 s, zero drops, p99 <= 1 ms (ROS package issue);
10 minutes at 10,000/s without drops, memory growth or latency drift (reliability issue:
``--duration 600``).

Usage: ``python benchmarks/bench_compensator_node.py [--rate 10000] [--duration 10]``
"""

import argparse
import os
import random
import sys
import tempfile
import time
from pathlib import Path

import numpy as np


def _receiver(out: str, count: int, timeout: float) -> None:
    import rclpy
    from rclpy.executors import SingleThreadedExecutor
    from std_msgs.msg import Float64

    from mpi_ros.nodes.loop import loop_qos
    rclpy.init()
    node = rclpy.create_node('bench_receiver')
    stamps = np.zeros(count, dtype=np.int64)
    received = [0]

    def on_command(msg: Float64) -> None:
        # Take every queued message in this one callback: rclpy's per-spin cost would
        # otherwise make the receiver, not the compensator, the bottleneck.
        while True:
            k = received[0]
            if k < count:
                stamps[k] = time.monotonic_ns()
            received[0] = k + 1
            if subscription.handle.take_message(Float64, False) is None:
                break

    subscription = node.create_subscription(Float64, 'current_command', on_command,
                                            loop_qos(10000))
    executor = SingleThreadedExecutor()
    executor.add_node(node)
    Path(out + '.ready').touch()
    deadline = time.monotonic() + timeout
    while received[0] < count and time.monotonic() < deadline:
        executor.spin_once(timeout_sec=0.01)
    np.save(out, stamps[:min(received[0], count)])
    node.destroy_node()
    rclpy.try_shutdown()


def _rss_kib(pid: int) -> int:
    for line in Path(f'/proc/{pid}/status').read_text().splitlines():
        if line.startswith('VmRSS:'):
            return int(line.split()[1])
    return 0


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument('--rate', type=float, default=10000.0, help='messages per second')
    parser.add_argument('--duration', type=float, default=10.0, help='seconds of load')
    parser.add_argument('--role', default='sender', help=argparse.SUPPRESS)
    parser.add_argument('--out', default='', help=argparse.SUPPRESS)
    parser.add_argument('--count', type=int, default=0, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.role == 'receiver':
        _receiver(args.out, args.count, args.duration)
        return

    os.environ['ROS_AUTOMATIC_DISCOVERY_RANGE'] = 'LOCALHOST'
    os.environ.setdefault('ROS_DOMAIN_ID', str(random.randint(101, 199)))
    import subprocess

    import rclpy
    from std_msgs.msg import Float64

    from mpi_ros import MPIModel
    from mpi_ros.nodes.loop import loop_qos, NodeProcess
    from mpi_ros.params import write_params_yaml

    model = MPIModel.from_params({
        'model.hysteresis.thresholds': list(np.arange(15) / 15 * 1.8),
        'model.hysteresis.weights': [1.0] + [0.05] * 14,
        'model.hysteresis.initial_states': [0.0] * 15,
        'model.superposition.thresholds': [0.0] + list(np.arange(1, 8) / 8 * 1.5),
        'model.superposition.weights': [2e-5] + [-1e-6, 1e-6] * 3 + [-1e-6]})
    count = int(args.rate * args.duration)
    tmp = Path(tempfile.mkdtemp(prefix='mpi_ros_bench_'))
    params = tmp / 'params.yaml'
    write_params_yaml(params, dict(model.to_params(), **{'qos_depth': 10000}))
    comp = NodeProcess('compensator', ['--params-file', str(params), '-p',
                                       'diagnostics_period:=5.0'], tmp / 'compensator.log')
    out = str(tmp / 'received.npy')
    receiver = subprocess.Popen(
        [sys.executable, __file__, '--role', 'receiver', '--out', out, '--count', str(count),
         '--duration', str(args.duration + 60.0)], env=dict(os.environ))
    rclpy.init()
    node = rclpy.create_node('bench_sender')
    pub = node.create_publisher(Float64, 'desired_displacement', loop_qos(10000))
    try:
        deadline = time.monotonic() + 60.0
        while (pub.get_subscription_count() < 1 or not Path(out + '.ready').exists()
               or node.count_subscribers('current_command') < 1):
            if time.monotonic() > deadline:
                raise SystemExit('error: compensator or receiver did not start in 60 s')
            time.sleep(0.05)
        time.sleep(2.0)                                      # let DDS finish matching
        lo, hi = 5e-6, 3e-5
        t = np.arange(count) / args.rate
        desired = lo + (hi - lo) * (0.5 + 0.4 * np.sin(2 * np.pi * 1.0 * t)
                                    + 0.1 * np.sin(2 * np.pi * 13.0 * t))
        sent = np.zeros(count, dtype=np.int64)
        rss = []
        period_ns = int(1e9 / args.rate)
        msg = Float64()
        start = time.monotonic_ns()
        next_rss = start
        k = 0
        while k < count:
            # Publish every sample that is due, then sleep ~0.2 ms: no busy wait, so the
            # sender does not take a core from the compensator on a 2-core machine.
            now = time.monotonic_ns()
            due = min(count, (now - start) // period_ns + 1)
            while k < due:
                msg.data = float(desired[k])
                sent[k] = time.monotonic_ns()
                pub.publish(msg)
                k += 1
            if now >= next_rss:
                rss.append(((now - start) / 1e9, _rss_kib(comp.pid)))
                next_rss += 1_000_000_000
            time.sleep(0.0002)
        elapsed = (time.monotonic_ns() - start) / 1e9
        receiver.wait(timeout=args.duration + 120.0)
        rss.append((elapsed, _rss_kib(comp.pid)))
    finally:
        node.destroy_node()
        rclpy.try_shutdown()
        comp.stop()
        if receiver.poll() is None:
            receiver.kill()
    stamps = np.load(out)
    n = stamps.size
    latency_us = (stamps - sent[:n]) / 1e3
    print(f'machine: {os.cpu_count()} cores; ROS_DOMAIN_ID {os.environ["ROS_DOMAIN_ID"]}')
    print(f'sent {count} desired values in {elapsed:.2f} s ({count / elapsed:,.0f}/s), '
          f'received {n} commands, drops {count - n}')
    if n:
        p50, p99, p999 = np.percentile(latency_us, [50, 99, 99.9])
        print(f'latency desired->command [us]: p50 {p50:.0f}, p99 {p99:.0f}, '
              f'p99.9 {p999:.0f}, max {latency_us.max():.0f} (target p99 <= 1000)')
        window = int(10 * args.rate)
        if n >= 2 * window:
            p99s = [np.percentile(latency_us[i:i + window], 99)
                    for i in range(0, n - window + 1, window)]
            print('p99 per 10 s window [us]: ' + ' '.join(f'{v:.0f}' for v in p99s))
    print('compensator RSS [MiB] over time: ' + ' '.join(
        f'{t_:.0f}s:{kib / 1024:.1f}' for t_, kib in rss[::max(1, len(rss) // 12)]))
    print(f'compensator RSS growth: {(rss[-1][1] - rss[1][1]) / 1024:+.1f} MiB '
          f'(from t={rss[1][0]:.0f} s to the end)' if len(rss) > 2 else '')


if __name__ == '__main__':
    main()
