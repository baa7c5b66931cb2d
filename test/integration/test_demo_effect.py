# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
``mpi-ros demo --effect``: the extended compensator against the plain one, over DDS.

The demo runs as its own process on this module's ``ROS_DOMAIN_ID`` (the ``ros_env``
fixture) and starts and stops its node processes itself.  Short durations keep the run
under about 80 s; the plant's effect depends on time, so the samples go out in real time.
"""

import json
import os
import subprocess
import sys
import time

import yaml


def test_extended_compensator_beats_plain_on_plant_with_rate_dependence(ros_env, tmp_path):
    out = tmp_path / 'demo'
    cmd = [sys.executable, '-m', 'mpi_ros.app.cli', 'demo', '--effect', 'rate_dependence',
           '--eddy-time-constant', '0.005', '--duration', '30', '--track-duration', '12',
           '--domain-id', str(ros_env), '--output', str(out)]
    wall_before = time.time()
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=170,
                          env=dict(os.environ), stdin=subprocess.DEVNULL)
    wall_after = time.time()
    assert (out / 'results.json').is_file(), _failure(proc, out)
    results = json.loads((out / 'results.json').read_text())
    plain, extended = (r['control_error'] for r in results['tracking'])
    assert results['effect'] == 'rate_dependence'
    assert results['plant'] == {'actuator.eddy_time_constant_s': 0.005}
    # How late the samples went out depends on the machine's load: reported, not asserted
    # (``mpi-ros demo`` writes the same figures to results.json and report.md).
    print('send lateness [s] per run (sample period '
          f'{1.0 / results["sample_rate"]:g} s):', json.dumps(results['lateness_s']))
    # The fitted lag is near the plant's eddy-current time constant.
    tau = results['extension']['model.rate_dependence.time_constant']
    assert 0.0025 < tau < 0.01, tau
    assert extended < plain, (plain, extended, _failure(proc, out))
    assert proc.returncode == 0, _failure(proc, out)
    assert (out / 'report.md').is_file() and (out / 'tracking_error.png').is_file()
    # stderr is not a terminal here: the messages, and no progress line.
    assert '[demo] identified' in proc.stderr
    assert '\r' not in proc.stderr and '\x1b' not in proc.stderr
    # The bag has real time stamps (wall clock), not times from 1970.
    metadata = yaml.safe_load((out / 'identification_bag' / 'metadata.yaml').read_text())
    info = metadata['rosbag2_bagfile_information']
    start = info['starting_time']['nanoseconds_since_epoch'] * 1e-9
    end = start + info['duration']['nanoseconds'] * 1e-9
    assert wall_before <= start <= end <= wall_after, (wall_before, start, end, wall_after)


def _failure(proc: subprocess.CompletedProcess, out) -> str:
    # What a failed run leaves to read: its exit status, stderr and the node logs' ends.
    logs = ''.join(f'\n--- {log.name} (end) ---\n{log.read_text(errors="replace")[-1500:]}'
                   for log in sorted(out.glob('*.log')))
    return f'exit {proc.returncode}; stderr (end):\n{proc.stderr[-3000:]}{logs}'
