# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""`mpi-ros <node> --ros-args ...` as a separate process: starts, fails clearly, stops."""

import pytest

from .processes import NodeProcess


@pytest.mark.slow
def test_mpi_ros_compensator_runs_and_stops_on_sigint():
    args = ['compensator', '--ros-args', '-r', '__node:=process_smoke',
            '-p', 'output.min:=0.2', '-p', 'output.max:=1.8']
    with NodeProcess(args) as node:
        assert node.wait_for_output('no model given yet', timeout=60.0), node.output
        status = node.stop()
    assert status == 0, node.output


@pytest.mark.slow
def test_mpi_ros_compensator_refuses_a_bad_model():
    args = ['compensator', '--ros-args', '-r', '__node:=process_bad',
            '-p', 'model.hysteresis.thresholds:=[0.0, 0.5]',
            '-p', 'model.hysteresis.weights:=[1.0, -1.0]',
            '-p', 'model.hysteresis.initial_states:=[0.0, 0.0]',
            '-p', 'model.superposition.thresholds:=[0.0]',
            '-p', 'model.superposition.weights:=[1.0e-5]']
    with NodeProcess(args) as node:
        status = node.process.wait(timeout=60.0)
    assert status == 1, node.output
    assert 'error: compensator: model.hysteresis.weights' in node.output
