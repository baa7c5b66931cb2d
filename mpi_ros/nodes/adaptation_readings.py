# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
The adaptation's child process, taking the displacement readings itself.

The compensator node with ``adaptation.process`` true starts its adaptation's child with
this module as the entry (:class:`mpi_ros.compensation.adaptation.AdaptationProcess`,
``entry`` and ``readings``): the child runs the core's
:func:`mpi_ros.compensation.adaptation.serve_socket` with :func:`subscribe`, so the readings
on ``displacement`` reach an rclpy context of the child's own and the node's process, whose
single-threaded executor is the command path, never handles one.  The node sends the child
its commands in batches over the socket pair; the child pairs them with the readings in
order, as before (lock step or ``adaptation.delay``).

The subscription has the node's QoS (``qos_depth``, ``qos_reliability``) on the node's
resolved topic, from a node ``<compensator>_adaptation`` in the compensator's namespace (no
parameter services, no rosout).  No executor serves it: a thread of the child takes every
queued reading as CDR bytes (``take_message``) every :data:`POLL_PERIOD_S` (or a quarter of
the time ``qos_depth`` readings take, if shorter, but at least every millisecond) and
decodes the batch with one numpy call; the readings wait in the subscription's history
meanwhile (``qos_depth`` 10000 holds 1 s of a 10 kHz stream), so the child wakes 100 times
a second, not once per reading.  A message that is not a CDR Float64 is not decoded but
counted (the node shows ``adaptation_malformed_readings`` and adds them to its
``malformed``); a gap in the publisher's sequence numbers (readings the history dropped) is
counted as ``adaptation_lost_readings``.  Either keeps its place as a NaN reading
(:func:`~mpi_ros.compensation.adaptation.with_gaps`): the k-th reading still answers the
k-th command, and the adaptation freezes over the gap as over any garbage reading.
"""

import math
import threading
import time
from typing import Any, Callable, List

import numpy as np
import numpy.typing as npt
import rclpy
from rclpy.context import Context
from rclpy.signals import SignalHandlerOptions
from std_msgs.msg import Float64

from .qos import loop_qos
from ..array_layout import FLOAT64_SIZE, malformed_float64
from ..compensation.adaptation import ReadingSource, with_gaps
from ..compensation.adaptation import serve_socket as serve_adaptation

__all__ = ['MATCH_TIMEOUT_S', 'POLL_PERIOD_S', 'ReadingSubscriber', 'serve_socket',
           'subscribe']

#: Interval [s] between two takes of the queued readings.
POLL_PERIOD_S = 0.01
#: Longest wait [s] for a publisher of the readings to match before the child says it is
#: ready: the child's participant is new, and a plant that already runs answers the first
#: commands only into the readers it has matched (1 s was too short under load: one closed
#: loop over DDS lost the first readings, and its pairs shifted).
MATCH_TIMEOUT_S = 5.0
#: Longest wait [s] for the taking thread at close.
CLOSE_TIMEOUT_S = 2.0


def serve_socket(descriptor: int) -> None:
    """
    Serve the node's adaptation on an inherited socket, taking the readings here.

    Parameters
    ----------
    descriptor : int
        The child's end of the socket pair (see
        :func:`mpi_ros.compensation.adaptation.serve_socket`).

    """
    serve_adaptation(descriptor, subscribe=subscribe)


def subscribe(source: ReadingSource,
              record: Callable[[npt.NDArray[np.float64]], None]) -> 'ReadingSubscriber':
    """
    Open the readings' subscription of ``source`` in this process.

    Parameters
    ----------
    source : ReadingSource
        Topic, QoS and the child node's name.
    record : callable
        Called with each batch of readings [m], shape (N,), in the order they arrived.

    Returns
    -------
    ReadingSubscriber
        The open subscription (close it with :meth:`ReadingSubscriber.close`).

    """
    return ReadingSubscriber(source, record)


class ReadingSubscriber:
    """
    A raw subscription of Float64 readings in a context of its own, taken by a thread.

    Waits (at most :data:`MATCH_TIMEOUT_S`) for a publisher to match before it returns.

    Parameters
    ----------
    source : ReadingSource
        Topic, QoS and the child node's name.
    record : callable
        Called with each batch of readings [m], shape (N,), in order.

    """

    def __init__(self, source: ReadingSource,
                 record: Callable[[npt.NDArray[np.float64]], None]) -> None:
        self._record = record
        self.malformed = 0
        self.last_malformed = ''
        self.lost = 0
        self._sequence = -1
        self._period = min(POLL_PERIOD_S, max(1e-3, source.depth * source.sample_period / 4))
        self._context = Context()
        rclpy.init(args=[], context=self._context,
                   signal_handler_options=SignalHandlerOptions.NO)
        try:
            self._node = rclpy.create_node(
                source.node_name, namespace=source.namespace, context=self._context,
                start_parameter_services=False, enable_rosout=False)
            self._subscription = self._node.create_subscription(
                Float64, source.topic, _unused, loop_qos(source.depth, source.reliability),
                raw=True)
        except BaseException:
            rclpy.try_shutdown(context=self._context)
            raise
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name='readings', daemon=True)
        self._thread.start()
        deadline = time.monotonic() + MATCH_TIMEOUT_S
        while (self._subscription.get_publisher_count() < 1
               and time.monotonic() < deadline):
            time.sleep(0.01)

    def faults(self) -> dict[str, Any]:
        """Return ``malformed``, ``last_malformed``, ``lost`` and ``publishers`` (matched)."""
        return {'malformed': self.malformed, 'last_malformed': self.last_malformed,
                'lost': self.lost, 'publishers': self._subscription.get_publisher_count()}

    def close(self) -> None:
        """Stop the taking thread (at most :data:`CLOSE_TIMEOUT_S`), release the context."""
        self._stop.set()
        self._thread.join(CLOSE_TIMEOUT_S)
        if not self._thread.is_alive():
            self._node.destroy_node()
        rclpy.try_shutdown(context=self._context)

    def _run(self) -> None:
        while not self._stop.wait(self._period):
            self._take()

    def _take(self) -> None:
        # Every queued reading, as CDR bytes; a batch of 12-byte little-endian CDR messages
        # (what a ROS 2 node publishes on x86 and ARM) is decoded in one numpy call,
        # anything else one by one.
        take = self._subscription.handle.take_message
        batch: List[bytes] = []
        sequences: List[int] = []
        while True:
            taken = take(Float64, True)
            if taken is None:
                break
            data, info = taken
            batch.append(data)
            sequences.append(int(info['publication_sequence_number']))
        if not batch:
            return
        joined = b''.join(batch)
        values = None
        if len(joined) == FLOAT64_SIZE * len(batch):
            rows = np.frombuffer(joined, dtype=np.uint8).reshape(len(batch), FLOAT64_SIZE)
            if np.all(rows[:, 0] == 0) and np.all(rows[:, 1] == 1):
                values = rows[:, 4:].copy().view('<f8').reshape(-1)
        if values is None:
            values = np.array([self._decode(data) for data in batch], dtype=np.float64)
        values, lost, self._sequence = with_gaps(values, np.array(sequences), self._sequence)
        self.lost += lost
        self._record(values)

    def _decode(self, data: bytes) -> float:
        # A malformed message keeps its place as a NaN reading.
        if len(data) < FLOAT64_SIZE or data[0] != 0 or data[1] > 1:
            self.malformed += 1
            self.last_malformed = malformed_float64(data)
            return math.nan
        return float(np.frombuffer(data, dtype='<f8' if data[1] == 1 else '>f8',
                                   count=1, offset=4)[0])


def _unused(data: bytes) -> None:
    # The subscription's callback: no executor serves it (the thread takes the readings).
    return None
