# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""Fixtures shared by the process tests (test/integration, test/faults)."""

import pytest

from .ros_domain import ros_domain_environment


@pytest.fixture(scope='module')
def ros_env():
    """Give the module a ROS_DOMAIN_ID of its own, local-only discovery; yield the id."""
    with ros_domain_environment() as domain_id:
        yield domain_id
