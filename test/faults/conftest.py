# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Fixtures of the fault, load and security tests (helpers in ``helpers.py``).

Every test that starts processes asserts at the end that none of them is left running.
"""

from mpi_ros.harness.driver import LoopDriver
from mpi_ros.nodes.identifier import fit_bag
from mpi_ros.params import write_params_yaml
from mpi_ros.plant.actuator import MagnetostrictiveActuator
from mpi_ros.plant.excitation import identification_excitation
from mpi_ros.recordings import write_bag_signals
import pytest
import rclpy

from .helpers import B_SCALE, Nodes, ORDER
from ..process_signals import ProcessGroup


@pytest.fixture
def nodes(ros_env, tmp_path):
    """Yield a :class:`Nodes`; afterwards every process it started has ended."""
    started = Nodes(tmp_path)
    try:
        yield started
    finally:
        started.stop_all()
        alive = [p.pid for p in started.started if p.proc.poll() is None]
        assert not alive, f'processes left running: {alive}'


@pytest.fixture
def group(ros_env, tmp_path):
    """Yield a ProcessGroup; afterwards none of its processes runs."""
    processes = ProcessGroup(tmp_path)
    try:
        yield processes
    finally:
        processes.close()


@pytest.fixture
def driver(ros_env):
    """Yield a LoopDriver on a private rclpy context of the module's domain."""
    context = rclpy.Context()
    rclpy.init(context=context)
    node = LoopDriver('mpi_ros_fault_driver', context=context)
    try:
        yield node
    finally:
        node.destroy_node()
        rclpy.try_shutdown(context=context)


@pytest.fixture(scope='module')
def bags(tmp_path_factory):
    """Return bags of the actuator (a) and of its output times 1.3 (b) with their fits."""
    t, current = identification_excitation(12.0, sample_rate=250.0, seed=1)
    displacement = MagnetostrictiveActuator().simulate(t, current)
    root = tmp_path_factory.mktemp('bags')
    out = {}
    for name, scale in (('a', 1.0), ('b', B_SCALE)):
        path = root / name
        write_bag_signals(path, t, current, scale * displacement)
        fit = fit_bag(str(path), input_topic='/current_command',
                      output_topic='/displacement', order=ORDER)
        params_file = root / f'{name}.yaml'
        write_params_yaml(params_file, fit.parameters)
        out[name] = (path, fit.parameters, params_file)
    assert out['a'][1] != out['b'][1]
    return out
