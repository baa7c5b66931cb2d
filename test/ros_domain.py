# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
A ROS_DOMAIN_ID of its own for each test module that starts node processes.

Each module claims a domain in :data:`DOMAIN_RANGE` with an exclusive ``flock`` on a file
in the temporary directory, starting at an offset derived from the process id.  A
second test run on the same machine (or another module of this run, while the first
still holds its domain) takes the next free one, so runs never see each other's nodes.
The lock is released when the module ends; child processes do not inherit it.
Every process a test starts also gets ``ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST``.
"""

import contextlib
import fcntl
import os
from pathlib import Path
import tempfile

__all__ = ['DOMAIN_RANGE', 'claim_domain', 'ros_domain_environment']

#: Domains of the process tests (test/nodes uses 40-59; 231-232 are left to benchmarks).
DOMAIN_RANGE = (200, 230)

_LOCK_DIR = Path(tempfile.gettempdir()) / 'mpi_ros_test_domains'


@contextlib.contextmanager
def claim_domain():
    """
    Hold a free ROS_DOMAIN_ID of :data:`DOMAIN_RANGE` for the duration of a ``with``.

    Yields
    ------
    int
        The domain id.

    Raises
    ------
    RuntimeError
        When every domain of the range is held by other test runs.

    """
    low, high = DOMAIN_RANGE
    size = high - low + 1
    _LOCK_DIR.mkdir(exist_ok=True)
    for step in range(size):
        domain_id = low + (os.getpid() + step) % size
        handle = open(_LOCK_DIR / f'{domain_id}.lock', 'w')  # noqa: SIM115 - closed below
        try:
            fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            handle.close()
            continue
        try:
            yield domain_id
        finally:
            handle.close()
        return
    msg = f'every ROS_DOMAIN_ID in {low}-{high} is held by other test runs'
    raise RuntimeError(msg)


@contextlib.contextmanager
def ros_domain_environment():
    """
    Set this process's DDS environment to a claimed domain, local-only, for a ``with``.

    Yields
    ------
    int
        The domain id; ``os.environ`` holds it (children inherit it) until the end.

    """
    keys = ('ROS_DOMAIN_ID', 'ROS_AUTOMATIC_DISCOVERY_RANGE', 'ROS_LOCALHOST_ONLY')
    saved = {key: os.environ.get(key) for key in keys}
    with claim_domain() as domain_id:
        os.environ['ROS_DOMAIN_ID'] = str(domain_id)
        os.environ['ROS_AUTOMATIC_DISCOVERY_RANGE'] = 'LOCALHOST'
        os.environ.pop('ROS_LOCALHOST_ONLY', None)
        try:
            yield domain_id
        finally:
            for key, value in saved.items():
                if value is None:
                    os.environ.pop(key, None)
                else:
                    os.environ[key] = value
