# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""Fixtures of the node tests: a private rclpy context on this run's local-only domain."""

import pytest
import rclpy

from .ros_env import run_domain_id


@pytest.fixture
def ros_context(monkeypatch):
    """Yield an initialised private rclpy.Context on this run's local-only domain."""
    monkeypatch.setenv('ROS_AUTOMATIC_DISCOVERY_RANGE', 'LOCALHOST')
    monkeypatch.setenv('ROS_DOMAIN_ID', str(run_domain_id()))
    monkeypatch.delenv('ROS_LOCALHOST_ONLY', raising=False)
    context = rclpy.Context()
    rclpy.init(context=context)
    try:
        yield context
    finally:
        rclpy.try_shutdown(context=context)
