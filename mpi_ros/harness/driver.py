# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Drive the compensator/plant loop from outside in lock step: :class:`LoopDriver`.

The driver of ``mpi-ros demo``, the integration tests and the benchmarks; production nodes
never import it.  The nodes run in their own processes (:mod:`mpi_ros.harness.processes`).
The driver publishes a command or a desired displacement and waits for the measured
displacement it causes, so results do not depend on DDS timing.
"""

import time
from typing import Any, Callable, Optional

import numpy as np
import numpy.typing as npt
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node
from std_msgs.msg import Float64

from ..errors import MPIError
from ..nodes.qos import loop_qos

__all__ = ['LoopDriver']


class LoopDriver(Node):
    """
    Publishes ``current_command`` or ``desired_displacement``, waits for ``displacement``.

    Parameters
    ----------
    node_name : str
        Name of the driver node.
    **kwargs
        Passed on to :class:`rclpy.node.Node`.

    """

    def __init__(self, node_name: str = 'mpi_ros_loop_driver', **kwargs: Any) -> None:
        super().__init__(node_name, **kwargs)
        qos = loop_qos()
        self.current_pub = self.create_publisher(Float64, 'current_command', qos)
        self.desired_pub = self.create_publisher(Float64, 'desired_displacement', qos)
        self.create_subscription(Float64, 'displacement', self._on_displacement, qos)
        self.create_subscription(Float64, 'current_command', self._on_command, qos)
        self.displacement: Optional[float] = None
        self.command: Optional[float] = None
        self.commands: list[float] = []
        self.executor_ = SingleThreadedExecutor(context=self.context)
        self.executor_.add_node(self)

    def _on_displacement(self, msg: Float64) -> None:
        self.displacement = msg.data

    def _on_command(self, msg: Float64) -> None:
        self.command = msg.data
        self.commands.append(msg.data)

    def spin_for(self, seconds: float) -> None:
        """Process callbacks for ``seconds``."""
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            self.executor_.spin_once(timeout_sec=0.005)

    def wait_for(self, condition: Callable[[], bool], what: str, timeout: float) -> None:
        """Spin until ``condition()`` holds; raise MPIError naming ``what`` on timeout."""
        deadline = time.monotonic() + timeout
        while not condition():
            if time.monotonic() > deadline:
                msg = f'timed out after {timeout:g} s waiting for {what}'
                raise MPIError(msg)
            self.executor_.spin_once(timeout_sec=0.005)

    def detached(self) -> '_Detached':
        """Context in which the node may be spun by another executor (service calls)."""
        return _Detached(self)

    def handshake(self, publisher: Any, value: float, timeout: float = 60.0) -> float:
        """
        Repeat the first sample until the loop answers (DDS matching takes time).

        Repeating one value is harmless for a rate-independent plant.  Answers to
        earlier tries are drained before returning, so lock step is kept.
        """
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            self.displacement = None
            publisher.publish(Float64(data=float(value)))
            end = time.monotonic() + 0.5
            while self.displacement is None and time.monotonic() < end:
                self.executor_.spin_once(timeout_sec=0.005)
            if self.displacement is not None:
                self.spin_for(0.3)
                answered: Any = self.displacement
                return float(answered)
        msg = f'no answer from the loop within {timeout:g} s; see the node logs'
        raise MPIError(msg)

    def exchange(self, publisher: Any, value: float, timeout: float = 5.0) -> float:
        """
        Publish one value and return the displacement it causes.

        For a desired displacement, also wait until the compensator's command has
        arrived: the two topics are delivered independently.
        """
        self.displacement = None
        self.command = None
        publisher.publish(Float64(data=float(value)))
        if publisher is self.desired_pub:
            self.wait_for(lambda: self.displacement is not None and self.command is not None,
                          'the compensator and the plant simulator to answer', timeout)
        else:
            self.wait_for(lambda: self.displacement is not None,
                          'the plant simulator to answer', timeout)
        answer: Any = self.displacement
        return float(answer)

    def exchange_paced(self, publisher: Any, values: npt.ArrayLike, times: npt.ArrayLike, *,
                       timeout: float = 5.0) -> tuple[np.ndarray, np.ndarray]:
        """
        Publish ``values[k]`` at ``times[k]`` in real time, each in lock step.

        The plant simulator times a command by its steady clock at its arrival (the
        compensator by its ``message_time``: by default ``sample_period`` apart), so the
        plant's creep or eddy-current lag see the rate the compensator assumes only if
        the samples are sent on schedule: sample ``k`` is published when ``times[k] -
        times[0]`` seconds have passed since the first one (or at once, if the previous
        answer came later), then its answer is awaited as in :meth:`exchange`.

        Parameters
        ----------
        publisher : rclpy.publisher.Publisher
            ``current_pub`` or ``desired_pub``.
        values : array_like of float, shape (N,)
            Currents [A] or desired displacements [m].
        times : array_like of float, shape (N,)
            Schedule [s], non-decreasing.
        timeout : float
            Longest wait for each answer [s].

        Returns
        -------
        sent : ndarray of float, shape (N,)
            Time of each publication [s] on the schedule's time base (``sent - times`` is
            how late each sample went out).
        displacement : ndarray of float, shape (N,)
            Measured displacement each sample caused [m].

        """
        value_array = np.asarray(values, dtype=np.float64)
        schedule = np.asarray(times, dtype=np.float64)
        sent = np.empty(value_array.size)
        displacement = np.empty(value_array.size)
        start = time.monotonic() - float(schedule[0]) if schedule.size else 0.0
        for k in range(value_array.size):
            wait = start + float(schedule[k]) - time.monotonic()
            if wait > 0.0:
                time.sleep(wait)
            sent[k] = time.monotonic() - start
            displacement[k] = self.exchange(publisher, float(value_array[k]), timeout)
        return sent, displacement

    def destroy_node(self) -> None:
        """Shut the private executor down, then destroy the node."""
        self.executor_.remove_node(self)
        self.executor_.shutdown()
        super().destroy_node()


class _Detached:

    def __init__(self, driver: LoopDriver) -> None:
        self.driver = driver

    def __enter__(self) -> LoopDriver:
        self.driver.executor_.remove_node(self.driver)
        return self.driver

    def __exit__(self, *exc: Any) -> None:
        self.driver.executor_.add_node(self.driver)
