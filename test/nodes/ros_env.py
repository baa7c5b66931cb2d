# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
The DDS environment of every test: local-only discovery on a run-specific domain.

Every test (and every process a test starts) uses ``ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST``
so that DDS never sends multicast off this machine, and a ``ROS_DOMAIN_ID`` in 40-59 claimed
per test run with a file lock (``MPI_ROS_TEST_DOMAIN_ID`` overrides it), so parallel runs do
not see each other. Integration tests that start nodes as separate processes pass
:func:`ros_environment` as their ``env``.
"""

import fcntl
import os
from pathlib import Path
import tempfile

DOMAIN_RANGE = (40, 59)
_LOCK_DIR = Path(tempfile.gettempdir()) / 'mpi_ros_test_domains'
_CLAIMED = []


def run_domain_id():
    """
    Return this run's ROS_DOMAIN_ID (from MPI_ROS_TEST_DOMAIN_ID, else a claimed one).

    The first call claims a domain of :data:`DOMAIN_RANGE` with an exclusive ``flock``
    (starting at an offset from the process id, taking the next free one), held until
    this test process ends: two test runs on one machine never share a domain (with the
    process id alone they did whenever their ids were equal modulo 20).
    """
    override = os.environ.get('MPI_ROS_TEST_DOMAIN_ID')
    if override:
        return int(override)
    if not _CLAIMED:
        low, high = DOMAIN_RANGE
        size = high - low + 1
        _LOCK_DIR.mkdir(exist_ok=True)
        for step in range(size):
            domain_id = low + (os.getpid() + step) % size
            handle = open(_LOCK_DIR / f'{domain_id}.lock', 'w')  # noqa: SIM115 - held
            try:
                fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except OSError:
                handle.close()
                continue
            _CLAIMED.append((domain_id, handle))     # kept open: the claim lasts the run
            break
        else:
            msg = f'every ROS_DOMAIN_ID in {low}-{high} is held by other test runs'
            raise RuntimeError(msg)
    return _CLAIMED[0][0]


def ros_environment(domain_id=None):
    """
    Return an environment for child processes that keeps DDS on this machine.

    Parameters
    ----------
    domain_id : int, optional
        ROS_DOMAIN_ID; this run's by default.

    Returns
    -------
    dict
        ``os.environ`` plus ``ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST`` and the domain.

    """
    env = dict(os.environ)
    env['ROS_AUTOMATIC_DISCOVERY_RANGE'] = 'LOCALHOST'
    env['ROS_DOMAIN_ID'] = str(run_domain_id() if domain_id is None else domain_id)
    env.pop('ROS_LOCALHOST_ONLY', None)
    return env
