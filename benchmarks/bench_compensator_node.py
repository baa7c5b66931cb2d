#!/usr/bin/env python3
# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Compensator node throughput, latency and soak benchmark over DDS (run on demand).

Three processes: this one publishes ``desired_displacement`` at ``--rate`` Hz, the
compensator node computes ``current_command``, and a receiver process records the arrival
time and the value of every command.  Times come from CLOCK_MONOTONIC, which all processes
share; reliable in-order delivery pairs the k-th command with the k-th desired value.

Reports: messages sent/received (drops), achieved rate, latency percentiles (desired in ->
command out, measured in another process), latency percentiles per 10 s window (drift),
non-finite or out-of-range commands, and the compensator's resident memory over time
(growth).

Targets: 10,000 messages/s for 10 s, zero drops, p99 <= 1 ms (ROS package issue);
10 minutes at 10,000/s without drops, memory growth or latency drift (reliability issue:
``--duration 600``).

Usage: ``python benchmarks/bench_compensator_node.py [--rate 10000] [--duration 10]
[--reliability reliable|best_effort] [--qos-depth 10000] [--pin] [--axes N [--chunk K]]
[--node compensator|relay:events|relay:waitset|relay:poll|relay:naive]
[--receiver ordinary|naive|raw|delivered] [--adaptation [--worker process|thread]
[--priority idle|low] [--rounds N]]``

``--adaptation --rounds N`` measures adaptation off (``--echo``: the receiver answers as
the actuator all the same), off with a process that takes the readings as the adaptation's
child does (``--sink``: the second 10 kHz stream's cost without the adaptation), on, and
on beside that process (``on+sink``: adaptation added to a loop whose readings someone reads
already, as a tracking controller or a logger does), alternately, N runs each, on the same
machine load, and prints one line per run and the medians: the comparison of
docs/adaptation.md (issue 29).

``--axes N`` (N > 1) runs the multi-axis compensator on the Float64MultiArray topics, each
message carrying ``--chunk`` samples of every axis (``--rate`` is messages per second).
``--node relay:MODE`` puts one of the relays of ``relay.py`` (no arithmetic) in place of the
compensator: the floor (with ``--axes N``, the relay of the array topics).
``--receiver`` picks how commands are received: ``ordinary`` (a deserialising callback on
the EventsExecutor, default), ``naive`` (``rclpy.spin``'s SingleThreadedExecutor) or
``raw`` (serialized, the queue drained per callback).  Every run prints the load average,
the CPU per process and per compensator thread, the CPU per message, and the largest
difference of a command from the single-axis core (from a relay: from the desired value
it relays, 0).

``--reliability`` sets the QoS of all three endpoints (a reliable Fast DDS writer wakes its
event thread on every sample to restart its heartbeat timer: about 10,000 extra wake-ups
per second in the sender and in the compensator).  ``--pin`` gives the compensator (all
its threads) the last CPU and this process and the receiver the others, so that the load
generator does not preempt the node under test.  The figures are in docs/reliability.md.

The core is importable (``run_benchmark`` returns the numbers as a dict); the test suite
runs a short soak through it (``test/faults/test_soak.py``).
"""

import argparse
import os
from pathlib import Path
import random
import signal
import struct
import subprocess
import sys
import tempfile
import time
from typing import Any, Optional

import numpy as np

__all__ = ['BENCH_MODEL', 'run_benchmark', 'format_results', 'main']

#: A Float64 serialized as the actuator publishes it: the CDR little-endian encapsulation
#: header (0x0001 read little-endian, two bytes of options), then the double.
_PACK_READING = struct.Struct('<H2xd').pack


def _reading(value: float) -> bytes:
    """Return a displacement reading serialized as a little-endian CDR Float64."""
    return _PACK_READING(0x0100, value)


#: The model the benchmark's compensator runs (n=14, l=7, as in the paper).
BENCH_MODEL = {
    'model.hysteresis.thresholds': list(np.arange(15) / 15 * 1.8),
    'model.hysteresis.weights': [1.0] + [0.05] * 14,
    'model.hysteresis.initial_states': [0.0] * 15,
    'model.superposition.thresholds': [0.0] + list(np.arange(1, 8) / 8 * 1.5),
    'model.superposition.weights': [2e-5] + [-1e-6, 1e-6] * 3 + [-1e-6],
}


def run_benchmark(rate: float, duration: float, *, output_min: float = 0.0,
                  output_max: float = 2.0, window: float = 10.0,
                  workdir: Optional[Path] = None, qos_depth: int = 10000,
                  reliability: str = 'reliable', pin: bool = False,
                  node_kind: str = 'compensator',
                  receiver_kind: str = 'ordinary', axes: int = 1,
                  chunk: int = 1, adaptation: bool = False,
                  echo: bool = False, worker: str = 'process',
                  sink: bool = False, priority: str = 'idle') -> dict[str, Any]:
    """
    Drive a compensator process at ``rate`` messages/s for ``duration`` s and measure it.

    The caller's environment (``ROS_DOMAIN_ID``, ``ROS_AUTOMATIC_DISCOVERY_RANGE``) is
    used by this process and by the two it starts; both are stopped before returning.

    Parameters
    ----------
    rate : float
        Desired displacements published per second [1/s].
    duration : float
        Length of the load [s].
    output_min, output_max : float
        The compensator's output limits [A].
    window : float
        Length [s] of the windows of the latency drift statistics.
    workdir : Path, optional
        Directory for logs, the receiver's data and ``latency_us.npy`` (every message's
        latency, in order; default: a new temporary directory).
    qos_depth : int
        Keep-last depth of the three endpoints.
    reliability : str
        ``reliable`` or ``best_effort``, for the three endpoints.
    pin : bool
        Run the compensator on the last CPU only and the sender and receiver on the
        others (needs at least 2 CPUs).
    node_kind : str
        ``compensator``, or ``relay:MODE`` for one of the relays of ``relay.py`` in its
        place (the floor: no arithmetic).
    receiver_kind : str
        ``ordinary``: a ``Float64`` callback (deserialised), one message per call, spun
        by the EventsExecutor as the package's nodes spin; ``naive``: the same callback
        spun by ``rclpy.spin`` (SingleThreadedExecutor); ``raw``: serialized messages,
        every queued one taken in one callback (the lightest receiver); ``delivered``: a
        wait set takes them, each stamped when DDS delivered it (its
        ``received_timestamp``), so that the receiver's own work, answering as the
        actuator, is not counted as the node's latency (the take times are reported too).
    axes : int
        1: the single-axis node on Float64 topics; N > 1: the multi-axis node (every axis
        with the benchmark model) on the Float64MultiArray topics.
    chunk : int
        Samples per array message (``axes`` > 1): ``rate`` messages/s carry ``rate *
        chunk`` samples of every axis per second.
    adaptation : bool
        Single axis: run the compensator with ``adaptation.enabled`` and let the receiver
        act as the actuator: it answers every command with the benchmark model's
        displacement on ``displacement`` (lock step; with ``worker`` ``process`` the
        adaptation's child process subscribes to it, the node's own process does not),
        so the adaptation pairs, fits and,
        from 10 s on (5 s held out, 5 s in the Gram matrix), solves a candidate every
        second while the command path is measured (``adaptation.min_excitation`` 0.1:
        the trajectory spans 27 % of the input range).
    echo : bool
        The receiver answers as the actuator even without ``adaptation`` (the same work
        in the receiver for a fair comparison of adaptation on and off).
    worker : str
        Where the adaptation fits: ``process`` (``adaptation.process`` true, the node's
        default) or ``thread``.
    priority : str
        ``adaptation.priority`` of the child process: ``idle`` (the node's default) or
        ``low``.
    sink : bool
        With ``echo`` or ``adaptation``: a process of its own takes the readings on
        ``displacement`` as the adaptation's child process does (the same subscriber,
        :class:`mpi_ros.nodes.adaptation_readings.ReadingSubscriber`). Without
        ``adaptation``: the second 10 kHz stream costs the machine what it costs with
        adaptation on, and only the adaptation differs; with it: the loop's readings
        have a reader besides the adaptation's (a tracking controller, a logger).

    Returns
    -------
    dict
        ``sent``, ``received``, ``drops``, ``elapsed`` [s], ``achieved_rate`` [1/s],
        ``latency_us`` (``p50``, ``p99``, ``p999``, ``max``), ``windows`` (list of
        ``(start_s, p50, p99, p999)`` in us), ``nonfinite`` and ``outside_limits``
        (command counts), ``command_range`` [A], ``rss_kib`` (list of ``(t_s, KiB)``),
        ``rss_growth_mib`` (from t=1 s to the end), ``compensator_exit``, ``cores``,
        ``domain_id``, ``workdir``, ``processes_left`` (PIDs of started processes still
        running at the end; empty), ``cpu_percent`` (``compensator``, ``sender``,
        ``receiver``: CPU time over the load, % of one core), ``qos_depth``,
        ``reliability``, ``pinned``, ``max_error_vs_core`` (largest difference of a
        command from the single-axis core, when every command arrived from the
        compensator) or ``max_error_vs_desired`` (from a relay: of a command from the
        desired value it relays; 0).

    """
    import rclpy
    from std_msgs.msg import Float64

    from mpi_ros import MPIModel
    from std_msgs.msg import Float64MultiArray, MultiArrayDimension

    from mpi_ros.harness.processes import NodeProcess
    from mpi_ros.nodes.qos import loop_qos
    from mpi_ros.nodes.multi_axis import axis_key
    from mpi_ros.params import write_params_yaml

    model = MPIModel.from_params(BENCH_MODEL)
    count = int(rate * duration)
    tmp = Path(tempfile.mkdtemp(prefix='mpi_ros_bench_')) if workdir is None else Path(workdir)
    params = tmp / 'params.yaml'
    arrays = axes > 1
    chunk = chunk if arrays else 1
    model_params = model.to_params()
    if arrays:
        model_params = {axis_key(k, key): value for k in range(axes)
                        for key, value in model_params.items()}
        model_params['axes'] = axes
    write_params_yaml(params, dict(model_params, **{
        'qos_depth': qos_depth, 'qos_reliability': reliability,
        'output.min': output_min, 'output.max': output_max}))
    cores = sorted(_CPUS)
    if pin and len(cores) < 2:
        msg = f'--pin needs at least 2 CPUs; this process may use {cores}'
        raise RuntimeError(msg)
    node_cpus, load_cpus = set(cores[-1:]), set(cores[:-1])
    if node_kind == 'compensator':
        # The desired trajectory spans 27 % of the model's input range: below the default
        # adaptation.min_excitation (30 %) the adaptation would pause and never solve.
        extra = (['-p', 'adaptation.enabled:=true', '-p', f'sample_period:={1.0 / rate!r}',
                  '-p', f'adaptation.process:={str(worker == "process").lower()}',
                  '-p', f'adaptation.priority:={priority}',
                  '-p', 'adaptation.min_excitation:=0.1']
                 if adaptation else [])
        comp = NodeProcess('compensator', ['--params-file', str(params), '-p',
                                           'diagnostics_period:=5.0', *extra],
                           tmp / 'compensator.log')
    else:
        comp = _ScriptProcess(
            [str(Path(__file__).with_name('relay.py')), '--mode', node_kind.split(':')[1],
             '--qos-depth', str(qos_depth), '--reliability', reliability,
             '--axes', str(axes)],
            tmp / 'compensator.log')
    out = str(tmp / 'received.npy')
    receiver = subprocess.Popen(
        [sys.executable, __file__, '--role', 'receiver', '--out', out, '--count', str(count),
         '--duration', str(duration + 60.0), '--qos-depth', str(qos_depth),
         '--reliability', reliability, '--receiver', receiver_kind, '--axes', str(axes),
         '--chunk', str(chunk), *(['--echo'] if adaptation or echo else [])],
        env=dict(os.environ))
    sink_proc = None
    if sink and (echo or adaptation):
        sink_proc = subprocess.Popen(
            [sys.executable, __file__, '--role', 'sink', '--out', out, '--qos-depth',
             str(qos_depth), '--reliability', reliability, '--rate', str(rate)],
            env=dict(os.environ), stdin=subprocess.PIPE)
    if pin:
        # Right after the start, before rclpy creates any thread: every later thread
        # (DDS receive and event threads) inherits the affinity.
        _pin(comp.pid, node_cpus)
        _pin(receiver.pid, load_cpus)
        _pin(os.getpid(), load_cpus)
    context = rclpy.Context()
    rclpy.init(context=context)
    node = rclpy.create_node('bench_sender', context=context)
    if arrays:
        pub = node.create_publisher(Float64MultiArray, 'desired_displacements',
                                    loop_qos(qos_depth, reliability))
    else:
        pub = node.create_publisher(Float64, 'desired_displacement',
                                    loop_qos(qos_depth, reliability))
    output_topic = 'current_commands' if arrays else 'current_command'

    try:
        deadline = time.monotonic() + 60.0
        while (pub.get_subscription_count() < 1 or not Path(out + '.ready').exists()
               or node.count_subscribers(output_topic) < 1
               or (sink_proc is not None and not Path(out + '.sink').exists())):
            if time.monotonic() > deadline:
                msg = 'compensator or receiver did not start in 60 s'
                raise RuntimeError(msg)
            time.sleep(0.05)
        time.sleep(2.0)                                      # let DDS finish matching
        lo, hi = 5e-6, 3e-5
        t = (np.arange(count * chunk) / (rate * chunk))[:, None] + np.arange(axes) * 0.1
        desired = lo + (hi - lo) * (0.5 + 0.4 * np.sin(2 * np.pi * 1.0 * t)
                                    + 0.1 * np.sin(2 * np.pi * 13.0 * t))
        if arrays:
            msg = Float64MultiArray()
            msg.layout.dim = [
                MultiArrayDimension(label='samples', size=chunk, stride=chunk * axes),
                MultiArrayDimension(label='axes', size=axes, stride=axes)]
            blocks = [desired[k * chunk:(k + 1) * chunk].reshape(-1).tolist()
                      for k in range(count)]
        else:
            msg = Float64()
            samples = desired[:, 0].tolist()
        sent = np.zeros(count, dtype=np.int64)
        rss = []
        period_ns = int(1e9 / rate)
        pids = {'compensator': comp.pid, 'sender': os.getpid(), 'receiver': receiver.pid}
        for child in _children(comp.pid):          # the adaptation's process, if any
            pids[f'compensator child {child}'] = child
        if sink_proc is not None:
            pids['sink'] = sink_proc.pid
        cpu_start = {name: _cpu_seconds(pid) for name, pid in pids.items()}
        threads_start = _thread_cpu_seconds(comp.pid)
        children = [pid for name, pid in pids.items() if name.startswith('compensator child')]
        child_start = {pid: _thread_cpu_seconds(pid) for pid in children}
        start = time.monotonic_ns()
        next_rss = start
        k = 0
        while k < count:
            # Publish every sample that is due, then sleep ~0.2 ms: no busy wait, so the
            # sender does not take a core from the compensator on a 2-core machine.
            now = time.monotonic_ns()
            due = min(count, (now - start) // period_ns + 1)
            while k < due:
                if arrays:
                    msg.data = blocks[k]
                else:
                    msg.data = samples[k]
                sent[k] = time.monotonic_ns()
                pub.publish(msg)
                k += 1
            if now >= next_rss:
                rss.append(((now - start) / 1e9, _rss_kib(comp.pid)))
                next_rss += 1_000_000_000
            time.sleep(0.0002)
        elapsed = (time.monotonic_ns() - start) / 1e9
        cpu_percent = {name: 100.0 * (_cpu_seconds(pid) - cpu_start[name]) / elapsed
                       for name, pid in pids.items()}
        threads_end = _thread_cpu_seconds(comp.pid)
        thread_percent: dict[str, float] = {}
        for tid, (name, seconds) in threads_end.items():
            used = seconds - threads_start.get(tid, (name, 0.0))[1]
            thread_percent[name] = thread_percent.get(name, 0.0) + 100.0 * used / elapsed
        child_percent: dict[str, float] = {}
        for pid in children:
            for tid, (name, seconds) in _thread_cpu_seconds(pid).items():
                used = seconds - child_start[pid].get(tid, (name, 0.0))[1]
                child_percent[name] = child_percent.get(name, 0.0) + 100.0 * used / elapsed
        receiver.wait(timeout=duration + 120.0)
        rss.append((elapsed, _rss_kib(comp.pid)))
    finally:
        node.destroy_node()
        rclpy.try_shutdown(context=context)
        status = comp.stop()
        if receiver.poll() is None:
            receiver.kill()
            receiver.wait()
        if sink_proc is not None:
            sink_proc.communicate(timeout=30.0)          # stdin closed: the sink ends
    left = [p.pid for p in (comp.proc, receiver, *([sink_proc] if sink_proc else []))
            if p.poll() is None]
    stamps = np.load(out)
    values = np.load(out.replace('.npy', '_values.npy'))
    n = stamps.size
    latency_us = (stamps - sent[:n]) / 1e3
    np.save(tmp / 'latency_us.npy', latency_us)
    taken_file = Path(out.replace('.npy', '_taken.npy'))
    taken_us = (np.load(taken_file) - sent[:n]) / 1e3 if taken_file.exists() else None
    max_error = relay_error = None
    if n == count and node_kind != 'compensator':
        # A relay sends back the desired values themselves: check that instead.
        relay_error = float(np.max(np.abs(values.reshape(count * chunk, axes) - desired)))
    elif n == count:
        # Every command against the single-axis core, axis by axis (command_batch gives
        # what per-sample commands give).
        from mpi_ros.compensation import Compensator
        commands = values.reshape(count * chunk, axes)
        max_error = max(
            float(np.max(np.abs(commands[:, k] - Compensator(
                model, output_min=output_min, output_max=output_max).command_batch(
                    desired[:, k])))) for k in range(axes))
    adaptation_log = ([line.strip() for line in
                       (tmp / 'compensator.log').read_text().splitlines()
                       if 'adaptation' in line] if adaptation else [])
    results: dict[str, Any] = {
        'cores': os.cpu_count(), 'domain_id': os.environ.get('ROS_DOMAIN_ID'),
        'rate': rate, 'duration': duration, 'sent': count, 'received': n,
        'drops': count - n, 'elapsed': elapsed, 'achieved_rate': count / elapsed,
        'nonfinite': int(np.count_nonzero(~np.isfinite(values))),
        'outside_limits': int(np.count_nonzero((values < output_min) | (values > output_max))),
        'command_range': (float(values.min()), float(values.max())) if n else None,
        'latency_us': {}, 'windows': [], 'rss_kib': rss,
        'rss_growth_mib': (rss[-1][1] - rss[1][1]) / 1024 if len(rss) > 2 else None,
        'compensator_exit': status, 'workdir': str(tmp), 'processes_left': left,
        'adaptation_log': adaptation_log[-3:],
        'adaptation_updates': sum('adaptation: update' in line for line in adaptation_log),
        'adaptation_restarts': sum('fell behind' in line for line in adaptation_log),
        'cpu_percent': cpu_percent, 'compensator_threads': thread_percent,
        'child_threads': child_percent,
        'qos_depth': qos_depth, 'reliability': reliability,
        'pinned': pin, 'node': node_kind, 'receiver': receiver_kind,
        'load_average': os.getloadavg(), 'axes': axes, 'chunk': chunk,
        'max_error_vs_core': max_error, 'max_error_vs_desired': relay_error,
    }
    if n:
        results['latency_us'] = _percentiles(latency_us)
        if taken_us is not None and taken_us.size:
            # --receiver delivered: the same commands stamped when this receiver took them.
            results['latency_taken_us'] = _percentiles(taken_us)
        size = int(window * rate)
        results['windows'] = [
            (i / rate, *np.percentile(latency_us[i:i + size], [50, 99, 99.9]))
            for i in range(0, n - size + 1, size)]
    return results


def _percentiles(latency_us: np.ndarray) -> dict[str, float]:
    """Return p50, p99, p99.9 and the largest of latencies [us], by those names."""
    p50, p99, p999 = np.percentile(latency_us, [50, 99, 99.9])
    return {'p50': p50, 'p99': p99, 'p999': p999, 'max': float(latency_us.max())}


def format_results(results: dict[str, Any]) -> str:
    """
    Format the results of :func:`run_benchmark` as the report the script prints.

    Parameters
    ----------
    results : dict
        As returned by :func:`run_benchmark`.

    Returns
    -------
    str
        Several lines of text.

    """
    r = results
    pinning = ('compensator pinned to its own CPU' if r['pinned']
               else 'no CPU pinning')
    load = ' '.join(f'{v:.2f}' for v in r['load_average'])
    lines = [f'machine: {r["cores"]} cores, load average {load} (at the end); ROS_DOMAIN_ID '
             f'{r["domain_id"]}; QoS {r["reliability"]}, depth {r["qos_depth"]}; {pinning}',
             f'node: {r["node"]}; receiver: {r["receiver"]}; {r["axes"]} axes, '
             f'{r["chunk"]} samples per message '
             f'({r["rate"] * r["chunk"] * r["axes"]:,.0f} samples/s in all)',
             f'sent {r["sent"]} desired values in {r["elapsed"]:.2f} s '
             f'({r["achieved_rate"]:,.0f}/s), received {r["received"]} commands, '
             f'drops {r["drops"]}',
             f'commands: {r["nonfinite"]} non-finite, {r["outside_limits"]} outside the limits,'
             f' range {r["command_range"]}']
    lat = r['latency_us']
    if lat:
        lines.append(f'latency desired->command [us]: p50 {lat["p50"]:.0f}, p99 {lat["p99"]:.0f}'
                     f', p99.9 {lat["p999"]:.0f}, max {lat["max"]:.0f} (target p99 <= 1000)')
    taken = r.get('latency_taken_us')
    if taken:
        lines.append(f'  the same, stamped when the receiver took them: p50 {taken["p50"]:.0f}'
                     f', p99 {taken["p99"]:.0f}, p99.9 {taken["p999"]:.0f}, max '
                     f'{taken["max"]:.0f}')
    if len(r['windows']) > 1:
        lines.append('latency per window [us] (start s: p50/p99/p99.9):')
        lines.extend(f'  {t:5.0f}: {p50:6.0f} {p99:7.0f} {p999:7.0f}'
                     for t, p50, p99, p999 in r['windows'])
    rss = r['rss_kib']
    lines.append('compensator RSS [MiB] over time: ' + ' '.join(
        f'{t_:.0f}s:{kib / 1024:.1f}' for t_, kib in rss[::max(1, len(rss) // 12)] + rss[-1:]))
    if r['rss_growth_mib'] is not None:
        lines.append(f'compensator RSS growth: {r["rss_growth_mib"]:+.1f} MiB '
                     f'(from t={rss[1][0]:.0f} s to the end)')
    lines.append('CPU over the load [% of one core]: ' + ', '.join(
        f'{name} {value:.0f}' for name, value in r['cpu_percent'].items()))
    busy = {k: v for k, v in r['compensator_threads'].items() if v >= 0.5}
    lines.append('compensator CPU per thread [% of one core]: ' + ', '.join(
        f'{name} {value:.0f}' for name, value in sorted(busy.items(), key=lambda i: -i[1])))
    busy = {k: v for k, v in r.get('child_threads', {}).items() if v >= 0.5}
    if busy:
        lines.append("the compensator's child process, CPU per thread [% of one core]: "
                     + ', '.join(f'{name} {value:.0f}' for name, value
                                 in sorted(busy.items(), key=lambda i: -i[1])))
    per_message = r['cpu_percent']['compensator'] * 1e4 / r['rate']
    lines.append(f'compensator CPU per message: {per_message:.1f} us (per sample of one axis'
                 f' {per_message / (r["chunk"] * r["axes"]):.2f} us)')
    if r['max_error_vs_core'] is not None:
        lines.append(f'largest |command - single-axis core|: {r["max_error_vs_core"]:.1e} A')
    if r.get('max_error_vs_desired') is not None:
        lines.append('relay: largest |command - desired| (the values relayed): '
                     f'{r["max_error_vs_desired"]:.1e}')
    lines.append(f'compensator exit status: {r["compensator_exit"]}')
    lines.extend(f'  {line}' for line in r.get('adaptation_log', []))
    return '\n'.join(lines)


def main() -> None:
    """Run the benchmark from the command line and print the report."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument('--rate', type=float, default=10000.0, help='messages per second')
    parser.add_argument('--duration', type=float, default=10.0, help='seconds of load')
    parser.add_argument('--reliability', choices=('reliable', 'best_effort'),
                        default='reliable', help='QoS reliability of all endpoints')
    parser.add_argument('--qos-depth', type=int, default=10000,
                        help='keep-last depth of all endpoints')
    parser.add_argument('--pin', action='store_true',
                        help='compensator on the last CPU, sender and receiver on the others')
    parser.add_argument('--node', default='compensator',
                        help='compensator, or relay:naive|events|waitset|poll (relay.py)')
    parser.add_argument('--receiver', choices=('ordinary', 'naive', 'raw', 'delivered'),
                        default='ordinary', help='how the receiver subscribes')
    parser.add_argument('--axes', type=int, default=1,
                        help='1: Float64 topics; N > 1: the multi-axis node, array topics')
    parser.add_argument('--chunk', type=int, default=1, help='samples per array message')
    parser.add_argument('--adaptation', action='store_true',
                        help='online adaptation on, the receiver answering as the actuator '
                             '(single axis; use with --receiver raw)')
    parser.add_argument('--worker', choices=('process', 'thread'), default='process',
                        help='with --adaptation: fit in a child process (default) or a thread')
    from mpi_ros.compensation.adaptation import PRIORITIES
    parser.add_argument('--priority', choices=PRIORITIES, default=PRIORITIES[0],
                        help='with --adaptation: adaptation.priority of the child process')
    parser.add_argument('--echo', action='store_true',
                        help='the receiver answers as the actuator on displacement (implied by '
                             '--adaptation; alone: the same receiver load without adaptation)')
    parser.add_argument('--sink', action='store_true',
                        help='with --echo: a process of its own takes the readings')
    parser.add_argument('--rounds', type=int, default=0,
                        help='with --adaptation: N runs without and N with it, alternately, '
                             'and their medians')
    parser.add_argument('--role', default='sender', help=argparse.SUPPRESS)
    parser.add_argument('--out', default='', help=argparse.SUPPRESS)
    parser.add_argument('--count', type=int, default=0, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.receiver == 'delivered' and args.axes > 1:
        parser.error('--receiver delivered takes the single-axis Float64 commands; use it '
                     'without --axes, or another receiver with --axes N')
    if args.role == 'sink':
        _sink(args.out, args.qos_depth, args.reliability, 1.0 / args.rate)
        return
    if args.role == 'receiver':
        _receiver(args.out, args.count, args.duration, args.qos_depth, args.reliability,
                  args.receiver, args.axes, args.chunk, echo=args.echo)
        return
    os.environ['ROS_AUTOMATIC_DISCOVERY_RANGE'] = 'LOCALHOST'
    os.environ.setdefault('ROS_DOMAIN_ID', str(random.randint(101, 199)))
    if args.rounds and args.adaptation:
        _compare_adaptation(args)
        return
    print(format_results(run_benchmark(args.rate, args.duration, qos_depth=args.qos_depth,
                                       reliability=args.reliability, pin=args.pin,
                                       node_kind=args.node, receiver_kind=args.receiver,
                                       axes=args.axes, chunk=args.chunk,
                                       adaptation=args.adaptation, echo=args.echo,
                                       worker=args.worker, sink=args.sink,
                                       priority=args.priority)),
          flush=True)


def _compare_adaptation(args: argparse.Namespace) -> None:
    """Run adaptation off and on alternately ``args.rounds`` times; print runs and medians."""
    modes = ('off', 'off+sink', 'on', 'on+sink')
    runs: dict[str, list[dict[str, Any]]] = {mode: [] for mode in modes}
    print(f'adaptation off (--echo: the receiver answers on displacement, no one reads it),'
          f' off+sink (a process takes the readings as the adaptation child does), on'
          f' (--worker {args.worker} --priority {args.priority}) and on+sink (on, the'
          f' readings taken by that process too), alternately,'
          f' {args.rounds} runs each of'
          f' {args.duration:g} s at {args.rate:g}/s; latency desired -> command [ms]',
          flush=True)
    for _ in range(args.rounds):
        for mode in modes:
            before = os.getloadavg()[0]
            r = run_benchmark(args.rate, args.duration, qos_depth=args.qos_depth,
                              reliability=args.reliability, pin=args.pin,
                              receiver_kind=args.receiver, adaptation=mode.startswith('on'),
                              echo=True, worker=args.worker, sink=mode.endswith('+sink'),
                              priority=args.priority)
            r['load_before'] = before
            runs[mode].append(r)
            print(_run_line(r, mode), flush=True)
    medians = {}
    for mode, results in runs.items():
        whole = [r['latency_us']['p99'] / 1e3 for r in results if r['drops'] == 0]
        late = [r['windows'][1][2] / 1e3 for r in results
                if r['drops'] == 0 and len(r['windows']) > 1]
        medians[mode] = (float(np.median(whole)) if whole else float('nan'),
                         float(np.median(late)) if late else float('nan'))
        taken = [r['latency_taken_us']['p99'] / 1e3 for r in results
                 if r['drops'] == 0 and 'latency_taken_us' in r]
        print(f'median p99 {mode} (runs without loss): {medians[mode][0]:.2f} ms whole, '
              f'{medians[mode][1]:.2f} ms 10-20 s'
              + (f' (taken: {float(np.median(taken)):.2f} ms whole)' if taken else ''),
              flush=True)
    for on, base in (('on', 'off'), ('on', 'off+sink'), ('on+sink', 'off+sink')):
        print(f'{on} / {base}: {medians[on][0] / medians[base][0]:.2f}x whole, '
              f'{medians[on][1] / medians[base][1]:.2f}x 10-20 s (goal: loss 0, <= 1.2x)',
              flush=True)


def _run_line(r: dict[str, Any], mode: str) -> str:
    """One line of a comparison run: load, loss, p50/p99 [ms], CPU [% of a core]."""
    lat = r['latency_us']
    late = f'{r["windows"][1][2] / 1e3:.2f}' if len(r['windows']) > 1 else 'n/a'
    cpu = ', '.join(f'{name} {value:.0f}' for name, value in r['cpu_percent'].items())
    return (f'{time.strftime("%H:%M:%S")} {mode}: load '
            f'{r["load_before"]:.1f}-{r["load_average"][0]:.1f}, lost {r["drops"]} of '
            f'{r["sent"]}, p50 {lat.get("p50", float("nan")) / 1e3:.2f}, p99 '
            f'{lat.get("p99", float("nan")) / 1e3:.2f} whole / {late} 10-20 s'
            + (f' (taken: p99 {r["latency_taken_us"]["p99"] / 1e3:.2f})'
               if 'latency_taken_us' in r else '')
            + f'; CPU {cpu}'
            + (f'; adaptation updates {r["adaptation_updates"]}, restarts at low'
               f' {r["adaptation_restarts"]}' if mode.startswith('on') else ''))


def _sink(out: str, qos_depth: int, reliability: str, sample_period: float) -> None:
    """Take the readings on displacement as the adaptation's child does, until stdin ends."""
    from mpi_ros.compensation.adaptation import ReadingSource
    from mpi_ros.nodes.adaptation_readings import ReadingSubscriber
    taken = [0]

    def record(values: np.ndarray) -> None:
        taken[0] += values.size

    reader = ReadingSubscriber(ReadingSource('/displacement', qos_depth, reliability,
                                             sample_period, 'bench_sink'), record)
    Path(out + '.sink').touch()
    sys.stdin.read()
    reader.close()
    print(f'sink: {taken[0]} readings taken, {reader.lost} lost', flush=True)


def _receiver(out: str, count: int, timeout: float, qos_depth: int,
              reliability: str, kind: str, axes: int, chunk: int,
              echo: bool = False) -> None:
    import rclpy
    from std_msgs.msg import Float64

    from mpi_ros.array_layout import float64_of
    from mpi_ros.nodes.qos import loop_qos
    from mpi_ros.nodes.spinning import events_executor
    rclpy.init()
    node = rclpy.create_node('bench_receiver')
    from std_msgs.msg import Float64MultiArray
    stamps = np.zeros(count, dtype=np.int64)
    values = np.zeros(count) if axes == 1 else np.zeros((count, chunk * axes))
    received = [0]

    if echo:
        # The actuator: the benchmark model's displacement for every command, published
        # raw (4-byte CDR header, the double) on displacement for the adaptation.
        from mpi_ros import MPIModel
        actuator = MPIModel.from_params(BENCH_MODEL).stream()
        # Compile the stream's step now, on a throwaway stream, before the receiver says
        # it is ready: compiled on the first command, it held that command's answer (and
        # every later one queued behind it) for 0.5-1 s, a p99 that said nothing of the node.
        MPIModel.from_params(BENCH_MODEL).stream().step(0.0)
        readings = node.create_publisher(Float64, 'displacement', loop_qos(qos_depth, reliability))
        publish_raw = readings.handle.publish_raw

    def on_command(data: bytes) -> None:
        # Serialized messages (CDR: 4-byte encapsulation header, then the double; byte 1
        # says little-endian), no Float64 objects, and every queued message taken in this
        # one callback: the measuring process stays far lighter than the node it measures.
        # Every queued command is stamped as it is taken, before the actuator answers any
        # of them: publishing a reading to a subscriber costs the receiver tens of us, which
        # would otherwise delay the stamps of the commands queued behind it (a latency of
        # the receiver's, not of the node's).
        take = subscription.handle.take_message
        first = received[0]
        while True:
            k = received[0]
            if k < count:
                stamps[k] = time.monotonic_ns()
                values[k] = float64_of(data)
            received[0] = k + 1
            taken = take(Float64, True)
            if taken is None:
                break
            data = taken[0]
        if echo:
            for k in range(first, min(received[0], count)):
                publish_raw(_reading(actuator.step(values[k])))

    def on_message(msg: Float64) -> None:
        # An ordinary subscriber: rclpy deserialises every command into a Float64.
        k = received[0]
        if k < count:
            stamps[k] = time.monotonic_ns()
            values[k] = msg.data
        received[0] = k + 1

    def on_array(msg: Float64MultiArray) -> None:
        # An ordinary subscriber of the array topic: a deserialised Float64MultiArray.
        k = received[0]
        if k < count:
            stamps[k] = time.monotonic_ns()
            values[k] = msg.data
        received[0] = k + 1

    qos = loop_qos(qos_depth, reliability)
    if kind == 'delivered':
        _deliveries(node, out, count, timeout, qos, stamps, values,
                    publish_raw if echo else None, actuator if echo else None)
        return
    if axes > 1:
        subscription = node.create_subscription(Float64MultiArray, 'current_commands',
                                                on_array, qos)
    elif kind == 'raw':
        subscription = node.create_subscription(Float64, 'current_command', on_command, qos,
                                                raw=True)
    else:
        subscription = node.create_subscription(Float64, 'current_command', on_message, qos)
    executor = (rclpy.executors.SingleThreadedExecutor() if kind == 'naive'
                else events_executor())
    executor.add_node(node)
    # Ready only once this reader has matched the compensator's writer: commands published
    # before the match are lost (volatile), which under load cost the first 0.3-0.6 s of
    # commands (the later ones then look 0.3-0.6 s late, being paired with earlier sends).
    deadline = time.monotonic() + 60.0
    while subscription.get_publisher_count() < 1 and time.monotonic() < deadline:
        executor.spin_once(timeout_sec=0.05)
    Path(out + '.ready').touch()
    deadline = time.monotonic() + timeout
    while received[0] < count and time.monotonic() < deadline:
        executor.spin_once(timeout_sec=0.01)
    n = min(received[0], count)
    np.save(out.replace('.npy', '_values.npy'), values[:n])
    np.save(out, stamps[:n])
    node.destroy_node()
    rclpy.try_shutdown()


def _deliveries(node: Any, out: str, count: int, timeout: float, qos: Any,
                stamps: np.ndarray, values: np.ndarray, publish_raw: Any,
                actuator: Any) -> None:
    """
    Receive the commands with a wait set, each stamped when DDS delivered it.

    The stamp is the reader's ``received_timestamp`` (set by Fast DDS as the sample enters
    the reader's history, in its receive thread), not the time this thread takes it: what
    this thread does in between (answering as the actuator) is not counted as the node's
    latency.  Fast DDS stamps with the realtime clock; it is mapped to CLOCK_MONOTONIC by
    the offset measured at the start and at the end (linearly between them, so a slewing
    clock shifts no stamp by more than the offset's change, which is printed).  The take
    times are saved too (``*_taken.npy``).
    """
    from rclpy.impl.implementation_singleton import rclpy_implementation as _rclpy
    from std_msgs.msg import Float64

    from mpi_ros.array_layout import float64_of
    taken_at = np.zeros(count, dtype=np.int64)
    received_ns = np.zeros(count, dtype=np.int64)
    subscription = node.create_subscription(Float64, 'current_command', lambda _: None, qos,
                                            raw=True)
    deadline = time.monotonic() + 60.0
    while subscription.get_publisher_count() < 1 and time.monotonic() < deadline:
        time.sleep(0.05)
    offset_start = time.time_ns() - time.monotonic_ns()
    Path(out + '.ready').touch()
    take = subscription.handle.take_message
    wait_set = _rclpy.WaitSet(1, 0, 0, 0, 0, 0, node.context.handle)
    k = 0
    deadline = time.monotonic() + timeout
    with subscription.handle, node.context.handle:
        while k < count and time.monotonic() < deadline:
            wait_set.clear_entities()
            wait_set.add_subscription(subscription.handle)
            wait_set.wait(100_000_000)
            first = k
            while k < count and (taken := take(Float64, True)) is not None:
                data, info = taken
                taken_at[k] = time.monotonic_ns()
                received_ns[k] = info['received_timestamp']
                values[k] = float64_of(data)
                k += 1
            if publish_raw is not None:
                for j in range(first, k):
                    publish_raw(_reading(actuator.step(values[j])))
    offset_end = time.time_ns() - time.monotonic_ns()
    if k:
        share = (received_ns[:k] - received_ns[0]) / max(1, received_ns[k - 1] - received_ns[0])
        offset = offset_start + share * (offset_end - offset_start)
        stamps[:k] = received_ns[:k] - np.round(offset).astype(np.int64)
    print(f'receiver: realtime - monotonic offset changed by '
          f'{(offset_end - offset_start) / 1e3:.1f} us over the run', flush=True)
    np.save(out.replace('.npy', '_values.npy'), values[:k])
    np.save(out.replace('.npy', '_taken.npy'), taken_at[:k])
    np.save(out, stamps[:k])
    node.destroy_node()
    import rclpy
    rclpy.try_shutdown()


class _ScriptProcess:
    """A benchmark script in its own process, with NodeProcess's pid/proc/stop."""

    def __init__(self, argv: list[str], log: Path) -> None:
        self._log = open(log, 'w')  # noqa: SIM115 - closed in stop()
        self.proc = subprocess.Popen([sys.executable, *argv], stdout=self._log,
                                     stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL)
        self.pid = self.proc.pid

    def stop(self) -> Optional[int]:
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGINT)
            try:
                self.proc.wait(timeout=5.0)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
        self._log.close()
        return self.proc.returncode


#: The CPUs this process may use when it starts (``--pin`` then narrows its own to the
#: load's: a second run of ``--rounds`` must split the same set again).
_CPUS = frozenset(os.sched_getaffinity(0))


def _pin(pid: int, cpus: set) -> None:
    """Restrict every thread of process ``pid`` (and the threads it starts) to ``cpus``."""
    for task in Path(f'/proc/{pid}/task').iterdir():
        try:
            os.sched_setaffinity(int(task.name), cpus)
        except OSError:                                  # the thread has just ended
            pass


def _cpu_seconds(pid: int) -> float:
    """User + system CPU time [s] of process ``pid`` so far (0 when it is gone)."""
    try:
        fields = Path(f'/proc/{pid}/stat').read_text().rsplit(')', 1)[1].split()
    except OSError:
        return 0.0
    return (int(fields[11]) + int(fields[12])) / os.sysconf('SC_CLK_TCK')


def _thread_cpu_seconds(pid: int) -> dict[int, tuple[str, float]]:
    """User + system CPU time [s] of every thread of process ``pid``, with its name."""
    threads = {}
    tick = os.sysconf('SC_CLK_TCK')
    try:
        tasks = list(Path(f'/proc/{pid}/task').iterdir())
    except OSError:
        return threads
    for task in tasks:
        try:
            head, tail = (task / 'stat').read_text().rsplit(')', 1)
        except OSError:
            continue
        fields = tail.split()
        threads[int(task.name)] = (head.split('(', 1)[1],
                                   (int(fields[11]) + int(fields[12])) / tick)
    return threads


def _children(pid: int) -> list[int]:
    """Return the PIDs of the child processes of ``pid`` (none when it is gone)."""
    try:
        text = Path(f'/proc/{pid}/task/{pid}/children').read_text()
    except OSError:
        return []
    return [int(word) for word in text.split()]


def _rss_kib(pid: int) -> int:
    try:
        text = Path(f'/proc/{pid}/status').read_text()
    except OSError:
        return 0
    for line in text.splitlines():
        if line.startswith('VmRSS:'):
            return int(line.split()[1])
    return 0


if __name__ == '__main__':
    main()
