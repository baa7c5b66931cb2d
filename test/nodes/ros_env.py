# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
The DDS environment of every test: local-only discovery on a run-specific domain.

Every test (and every process a test starts) uses ``ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST``
so that DDS never sends multicast off this machine, and a ``ROS_DOMAIN_ID`` in 40-59 picked
per test run (``MPI_ROS_TEST_DOMAIN_ID`` overrides it), so parallel runs do not see each
other. Integration tests that start nodes as separate processes pass
:func:`ros_environment` as their ``env``.
"""

import os

DOMAIN_RANGE = (40, 59)


def run_domain_id():
    """Return this run's ROS_DOMAIN_ID (from MPI_ROS_TEST_DOMAIN_ID or the process id)."""
    override = os.environ.get('MPI_ROS_TEST_DOMAIN_ID')
    if override:
        return int(override)
    low, high = DOMAIN_RANGE
    return low + os.getpid() % (high - low + 1)


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
