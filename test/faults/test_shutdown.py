# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Stopping busy nodes with several signals: exit status 0, no traceback, no abort.

Each node runs as ``ros2 run`` starts it (its console script), configured and busy: the
test floods its input topic from a thread while it sends two signals 50 ms apart (Ctrl-C
twice, or Ctrl-C and then ``kill``). With rclpy's own signal handlers this ended in
``RuntimeError: Unable to convert call argument``, ``publisher's context is invalid``,
exit status -2 or, under ``ros2 launch``, an abort (-6); see ``mpi_ros/nodes/spinning.py``.
Every wait is bounded; every process is stopped by PID.
"""

import contextlib
import signal
import threading
import time

import pytest
from std_msgs.msg import Float64

from .helpers import desired_values, first_command, LIMITS
from ..process_signals import bad_output, node_command

#: Seconds between the two signals.
GAP = 0.05


@contextlib.contextmanager
def flooding(publisher, values):
    """Publish ``values`` over and over from a thread (about 10 per ms) during a ``with``."""
    stop = threading.Event()

    def run():
        k = 0
        while not stop.is_set():
            publisher.publish(Float64(data=float(values[k % len(values)])))
            k += 1
            if k % 10 == 0:
                time.sleep(0.001)

    thread = threading.Thread(target=run, daemon=True)
    thread.start()
    try:
        yield
    finally:
        stop.set()
        thread.join(timeout=10.0)


def send(group, label, names):
    for name in names:
        group.signal(label, getattr(signal, name))
        time.sleep(GAP)


@pytest.mark.slow
@pytest.mark.parametrize('signals', [('SIGINT', 'SIGINT'), ('SIGINT', 'SIGTERM')])
def test_busy_compensator_exits_cleanly_on_two_signals(group, driver, bags, signals):
    _, params, params_file = bags['a']
    group.start('compensator', node_command('compensator') + [
        '--ros-args', '--params-file', str(params_file),
        '-p', f'output.min:={LIMITS[0]}', '-p', f'output.max:={LIMITS[1]}'])
    assert group.wait_for_output('compensator', 'model version 1 applied'), \
        group.output('compensator')
    values = desired_values(params, 500, seed=2)
    first_command(driver, values[0])
    with flooding(driver.desired_pub, values):
        driver.wait_for(lambda: len(driver.commands) > 500, 'commands under load', 60.0)
        send(group, 'compensator', signals)
        statuses = group.wait_all(timeout=30.0)
    output = group.output('compensator')
    assert statuses == {'compensator': 0}, output
    assert bad_output(output) == [], output


@pytest.mark.slow
@pytest.mark.parametrize('record', [False, True])
def test_busy_plant_simulator_exits_cleanly_on_two_signals(group, driver, tmp_path, record):
    bag = tmp_path / 'recorded'
    extra = ['--ros-args', '-p', f'record.path:={bag}'] if record else []
    group.start('plant', node_command('plant_simulator') + extra)
    assert group.wait_for_output('plant', 'simulating'), group.output('plant')
    driver.handshake(driver.current_pub, 1.0)
    currents = [LIMITS[0] + (LIMITS[1] - LIMITS[0]) * (k % 100) / 99.0 for k in range(100)]
    with flooding(driver.current_pub, currents):
        for _ in range(3):                      # answers keep coming under load
            driver.displacement = None
            driver.wait_for(lambda: driver.displacement is not None, 'displacements', 30.0)
        send(group, 'plant', ('SIGINT', 'SIGINT'))
        statuses = group.wait_all(timeout=30.0)
    output = group.output('plant')
    assert statuses == {'plant': 0}, output
    assert bad_output(output) == [], output
    assert output.count('simulating') == 1
    if record:                  # the recording is finished (and logged) before shutdown
        assert f'into {bag}' in output
        assert (bag / 'metadata.yaml').is_file()


@pytest.mark.slow
@pytest.mark.parametrize('phase, order, marker', [
    ('fit', 'auto', 'identifying from'),                    # signals during the fit
    ('push', '6,3', 'fitted order'),                        # while waiting for the target
])
def test_identifier_stops_cleanly_on_two_signals(group, bags, phase, order, marker):
    bag, _, _ = bags['a']
    group.start('identifier', node_command('identifier') + [
        '--ros-args', '-p', f'bag:={bag}', '-p', f'order:={order}',
        '-p', 'target_node:=/nobody_here', '-p', 'service_timeout:=120.0'])
    assert group.wait_for_output('identifier', marker), group.output('identifier')
    send(group, 'identifier', ('SIGINT', 'SIGTERM'))
    statuses = group.wait_all(timeout=30.0)
    output = group.output('identifier')
    assert statuses == {'identifier': 0}, output
    assert bad_output(output) == [], output
    assert 'identifier: stopped by SIGINT' in output
    assert 'accepted the model' not in output
