# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
A short soak through the compensator process: the benchmark harness, 5 s at 2,000 msg/s.

The full soak (10 minutes at 10,000 messages/s) is ``benchmarks/bench_compensator_node.py
--rate 10000 --duration 600``; its numbers are in ``docs/reliability.md``. Here the same
harness checks what does not depend on the machine's speed: every desired value gets its
command (no drops), every command is finite and inside the output limits, the resident
memory stays put, and both processes the harness starts are gone at the end.
"""

import importlib.util
from pathlib import Path

BENCH = Path(__file__).resolve().parents[2] / 'benchmarks' / 'bench_compensator_node.py'
RATE = 2000.0          # [1/s]
DURATION = 5.0         # [s]
RSS_GROWTH_MIB = 16.0  # allowed growth of the resident memory from t = 1 s to the end


def _bench():
    spec = importlib.util.spec_from_file_location('bench_compensator_node', BENCH)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_short_soak_loses_nothing_and_stays_safe(ros_env, tmp_path):
    bench = _bench()
    results = bench.run_benchmark(RATE, DURATION, output_min=0.2, output_max=1.8,
                                  window=1.0, workdir=tmp_path)
    report = bench.format_results(results)
    print(report)
    assert results['sent'] == int(RATE * DURATION)
    assert results['drops'] == 0, report
    assert results['nonfinite'] == 0, report
    assert results['outside_limits'] == 0, report
    assert results['rss_growth_mib'] < RSS_GROWTH_MIB, report
    assert results['compensator_exit'] == 0, report
    assert results['processes_left'] == [], report
    assert len(results['windows']) == DURATION
