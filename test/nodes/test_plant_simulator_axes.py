# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
The plant simulator with several axes, over DDS in-process: one plant per axis.

With ``truth:=mpi`` every axis is the same MPI model, streamed on its own: each column of
the displacement blocks must equal that model driven by the column's currents alone (no
time dependence, no noise), for one-sample messages and chunks alike.
"""

import time

from mpi_ros.nodes.plant_simulator import PlantSimulatorNode
from mpi_ros.nodes.spinning import events_executor
import numpy as np
import pytest
import rclpy
from rclpy.parameter import Parameter
from std_msgs.msg import Float64MultiArray

from ..core_models import random_model

AXES = 3
TIMEOUT = 30.0


def test_each_axis_is_its_own_plant(ros_context):
    model = random_model(np.random.default_rng(2), n=4, l=2, initial_history=False)
    overrides = [Parameter('axes', value=AXES), Parameter('truth', value='mpi')]
    for key, value in model.to_params().items():
        if isinstance(value, (list, tuple, np.ndarray)):
            value = [float(v) for v in value]
        elif key.endswith('output_sign'):
            value = int(value)
        else:
            value = float(value)
        overrides.append(Parameter(key, value=value))
    node = PlantSimulatorNode(context=ros_context, parameter_overrides=overrides)
    source = rclpy.create_node('command_source', context=ros_context)
    received = []
    publisher = source.create_publisher(Float64MultiArray, 'current_commands', 1000)
    source.create_subscription(Float64MultiArray, 'displacements',
                               lambda msg: received.append(np.array(msg.data)), 1000)
    executor = events_executor(ros_context)
    executor.add_node(node)
    executor.add_node(source)
    try:
        deadline = time.monotonic() + TIMEOUT
        while (publisher.get_subscription_count() < 1
               or node.count_subscribers('displacements') < 1) and time.monotonic() < deadline:
            executor.spin_once(timeout_sec=0.05)
        rng = np.random.default_rng(5)
        currents = np.clip(np.cumsum(rng.normal(0.0, 0.2, (40, AXES)), axis=0), -2.0, 2.0)
        chunks = [currents[k:k + 1] for k in range(20)] + [currents[20:30], currents[30:40]]
        for chunk in chunks:
            publisher.publish(Float64MultiArray(data=chunk.reshape(-1).tolist()))
        deadline = time.monotonic() + TIMEOUT
        while len(received) < len(chunks) and time.monotonic() < deadline:
            executor.spin_once(timeout_sec=0.02)
    finally:
        executor.shutdown()
        source.destroy_node()
        node.destroy_node()
    assert len(received) == len(chunks)
    displacements = np.concatenate(received).reshape(-1, AXES)
    for axis in range(AXES):
        stream = model.stream()
        expected = [stream.step(float(i)) for i in currents[:, axis]]
        assert displacements[:, axis] == pytest.approx(expected, rel=1e-12, abs=1e-18)
