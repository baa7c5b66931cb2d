# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Helpers of the fault, load and security tests: node processes, lock-step driving, services.

Every node runs in its own process (``python -m mpi_ros.app.cli <node> --ros-args ...``) on
the module's own ``ROS_DOMAIN_ID`` with local-only discovery (``ros_env`` of
``test/conftest.py``) and is stopped by PID (SIGINT, then SIGKILL).
"""

import time

from mpi_ros.compensation import Compensator, operating_range
from mpi_ros.harness.processes import NodeProcess
from mpi_ros.operators.model import MPIModel
import numpy as np
import pytest
from rcl_interfaces.msg import ParameterType
from rcl_interfaces.srv import GetParameters
from std_msgs.msg import Float64

__all__ = ['B_SCALE', 'LIMITS', 'ORDER', 'Nodes', 'call_service', 'commands_for',
           'desired_values', 'first_command', 'get_parameters', 'log_text', 'mirror',
           'wait_exit', 'wait_for_log']

LIMITS = (0.2, 1.8)            # [A] output.min, output.max of every compensator here
ORDER = (6, 3)                 # small model: quick fits
B_SCALE = 1.3                  # bag B: the same actuator with 1.3 times the displacement


class Nodes:
    """Start node processes; stop them all at the end and check that none survives."""

    def __init__(self, directory):
        self.directory = directory
        self.started = []

    def start(self, node, *ros_args):
        """Start ``mpi-ros <node> --ros-args <ros_args>``; return the NodeProcess."""
        log = self.directory / f'{node}-{len(self.started)}.log'
        proc = NodeProcess(node, list(ros_args), log)
        self.started.append(proc)
        return proc

    def compensator(self, *ros_args):
        """Start a compensator with this module's output limits."""
        return self.start('compensator', '-p', f'output.min:={LIMITS[0]}',
                          '-p', f'output.max:={LIMITS[1]}', *ros_args)

    def stop_all(self):
        """Stop every started process (SIGINT, then SIGKILL)."""
        for proc in self.started:
            proc.stop()


def log_text(proc):
    """Return what the process has logged so far."""
    return proc.log_path.read_text(errors='replace')


def wait_for_log(proc, marker, timeout=60.0):
    """Poll the process's log until it contains ``marker``; fail on timeout or exit."""
    deadline = time.monotonic() + timeout
    while marker not in log_text(proc):
        if time.monotonic() > deadline or not proc.running():
            if marker in log_text(proc):
                return
            pytest.fail(f'{marker!r} not in the log of {proc.log_path.name}:\n'
                        f'{log_text(proc)}')
        time.sleep(0.005)


def wait_exit(proc, timeout):
    """Wait for the process to end by itself; return its exit status."""
    status = proc.proc.wait(timeout=timeout)
    proc.stop()                       # closes the log
    return status


def first_command(driver, value, timeout=60.0):
    """
    Repeat the first desired value until the compensator answers (DDS matching).

    Repeating a value does not change the state of the rate-independent inverse. The
    answers are drained and ``driver.commands`` is cleared before returning.
    """
    driver.wait_for(lambda: driver.desired_pub.get_subscription_count() > 0,
                    'the compensator to subscribe', timeout)
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        driver.command = None
        driver.desired_pub.publish(Float64(data=float(value)))
        end = time.monotonic() + 0.5
        while driver.command is None and time.monotonic() < end:
            driver.executor_.spin_once(timeout_sec=0.005)
        if driver.command is not None:
            driver.spin_for(0.3)
            command = driver.command
            driver.commands.clear()
            return command
    pytest.fail(f'no command from the compensator within {timeout:g} s')


def commands_for(driver, values, timeout=5.0):
    """Publish the desired values one by one (lock step); return the commands."""
    out = []
    for value in values:
        driver.command = None
        driver.desired_pub.publish(Float64(data=float(value)))
        driver.wait_for(lambda: driver.command is not None, 'a command', timeout)
        out.append(driver.command)
    return np.array(out)


def call_service(driver, srv_type, service, request, timeout=10.0):
    """Call a service of another process through the driver; return the response."""
    client = driver.create_client(srv_type, service)
    try:
        assert client.wait_for_service(timeout_sec=timeout), f'no service {service}'
        future = client.call_async(request)
        driver.executor_.spin_until_future_complete(future, timeout_sec=timeout)
        assert future.done(), f'{service} did not answer within {timeout:g} s'
        return future.result()
    finally:
        driver.destroy_client(client)


def get_parameters(driver, names, node='/compensator'):
    """Return the target's values of ``names`` (lists for arrays) via get_parameters."""
    response = call_service(driver, GetParameters, f'{node}/get_parameters',
                            GetParameters.Request(names=list(names)))
    values = {}
    for name, value in zip(names, response.values):
        if value.type == ParameterType.PARAMETER_DOUBLE_ARRAY:
            values[name] = list(value.double_array_value)
        elif value.type == ParameterType.PARAMETER_DOUBLE:
            values[name] = value.double_value
        elif value.type == ParameterType.PARAMETER_INTEGER:
            values[name] = value.integer_value
        else:
            values[name] = value
    return values


def mirror(params, limits=LIMITS):
    """Return the core compensator the node builds from the same model and limits."""
    model = params if isinstance(params, MPIModel) else MPIModel.from_params(params)
    return Compensator(model, output_min=limits[0], output_max=limits[1])


def desired_values(params, size, seed):
    """Return random desired displacements inside the operating range [m]."""
    lo, hi = operating_range(MPIModel.from_params(params), *LIMITS)
    rng = np.random.default_rng(seed)
    phase = np.cumsum(rng.uniform(0.02, 0.2, size))
    return lo + (hi - lo) * (0.5 + 0.45 * np.sin(phase))
