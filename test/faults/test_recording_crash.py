# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
The plant simulator killed with ``kill -9`` while recording: its bag keeps what it committed.

The recorder (``BagRecorder``, ``flush_period`` 1 s) commits at the first write after each
second. The test exchanges samples in lock step, waits longer than that period, exchanges
a few more (the first write commits all before it; the node publishes before it records,
so the later answers show that write was done), kills the node with SIGKILL and reads the
temporary bag it left: every exchanged sample is there. (Before: a sqlite3 schema without
rows, an mcap of 0 bytes.) The wait is a condition of the test, not a timing assertion.
"""

import signal

from mpi_ros.recordings import read_bag_signals
import numpy as np
import pytest

from .helpers import LIMITS
from ..process_signals import node_command

#: Samples exchanged before the pause.
SAMPLES = 200


@pytest.mark.slow
@pytest.mark.parametrize('storage', ['sqlite3', 'mcap'])
def test_plant_simulator_killed_while_recording_keeps_its_samples(group, driver, tmp_path,
                                                                  storage):
    bag = tmp_path / 'recorded'
    group.start('plant', node_command('plant_simulator') + [
        '--ros-args', '-p', f'record.path:={bag}', '-p', f'record.storage:={storage}'])
    assert group.wait_for_output('plant', 'simulating'), group.output('plant')
    driver.handshake(driver.current_pub, 1.0)
    currents = LIMITS[0] + (LIMITS[1] - LIMITS[0]) * (
        0.5 + 0.5 * np.sin(np.linspace(0.0, 6.0 * np.pi, SAMPLES)))
    answers = [driver.exchange(driver.current_pub, value) for value in currents]
    driver.spin_for(1.5)                         # longer than the recorder's flush_period
    for _ in range(5):                           # the first write commits everything before
        driver.exchange(driver.current_pub, 1.0)  # it; the next answers show it was done
    group.signal('plant', signal.SIGKILL)
    assert group.wait('plant') == -signal.SIGKILL
    assert not bag.exists()                      # a bag appears at its path only when closed
    left = [p for p in tmp_path.iterdir() if p.name.startswith('.recorded.')]
    assert len(left) == 1, sorted(p.name for p in tmp_path.iterdir())
    recording = read_bag_signals(left[0] / 'recorded')
    assert any('no metadata.yaml' in note for note in recording.notes)
    # Every exchanged pair is in the bag, in order (the handshake's before them).
    found = np.flatnonzero(np.isin(recording.current, currents))
    assert found.size >= SAMPLES
    np.testing.assert_array_equal(recording.displacement[found[-SAMPLES:]], answers)
