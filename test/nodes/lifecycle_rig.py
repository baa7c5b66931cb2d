# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
A compensator node and a client node on one executor: lifecycle and parameter services.

The client drives the node only through its services over DDS, as a lifecycle manager or
``ros2 lifecycle`` does: ``<node>/change_state`` and ``<node>/get_state``
(``lifecycle_msgs``), ``<node>/set_parameters_atomically`` and ``<node>/set_parameters``
(``rcl_interfaces``).  Every wait is bounded; nothing here asserts a time.
"""

import time

from lifecycle_msgs.msg import Transition
from lifecycle_msgs.srv import ChangeState, GetState
from mpi_ros.nodes.spinning import events_executor
from rcl_interfaces.srv import SetParameters, SetParametersAtomically
import rclpy
from rclpy.parameter import Parameter

#: Longest wait for anything [s].
TIMEOUT = 30.0


class LifecycleRig:
    """
    A node under test, a client node and their executor.

    Parameters
    ----------
    context : rclpy.context.Context
        The private context of the test.
    node : rclpy.node.Node
        The compensator node (already built).
    name : str
        Fully qualified name of the node, e.g. ``/compensator``.

    """

    def __init__(self, context, node, name='/compensator'):
        self.node = node
        self.name = name
        self.client = rclpy.create_node('lifecycle_client', context=context)
        self.executor = events_executor(context)
        self.executor.add_node(node)
        self.executor.add_node(self.client)
        self._change = self.client.create_client(ChangeState, f'{name}/change_state')
        self._get = self.client.create_client(GetState, f'{name}/get_state')
        self._atomic = self.client.create_client(
            SetParametersAtomically, f'{name}/set_parameters_atomically')
        self._set = self.client.create_client(SetParameters, f'{name}/set_parameters')

    def close(self):
        """Stop the executor and destroy the client (the test destroys the node)."""
        self.executor.shutdown()
        self.client.destroy_node()

    # -- spinning -------------------------------------------------------------------------
    def spin_until(self, condition, timeout=TIMEOUT):
        """Spin until ``condition()`` holds or ``timeout`` passed; return its last value."""
        deadline = time.monotonic() + timeout
        while not condition() and time.monotonic() < deadline:
            self.executor.spin_once(timeout_sec=0.02)
        return condition()

    def spin_for(self, seconds):
        """Spin for a while (lets late messages arrive; nothing is asserted on time)."""
        deadline = time.monotonic() + seconds
        while time.monotonic() < deadline:
            self.executor.spin_once(timeout_sec=0.02)

    def loop_matched(self, publisher):
        """
        Wait until ``publisher`` (the client's input) reaches the node and back.

        Both writers must be *matched* with a reader: ``count_subscribers`` of the graph
        can see a subscription before its writer is matched, and a volatile writer drops
        what it publishes before that.
        """
        def matched():
            output = getattr(self.node, '_publisher', None)    # created by configure
            return (publisher.get_subscription_count() > 0 and output is not None
                    and output.get_subscription_count() > 0)

        return self.spin_until(matched)

    def call(self, client, request):
        """Call a service of the node and return its response (bounded waits)."""
        assert self.spin_until(client.service_is_ready), f'{client.srv_name} not ready'
        future = client.call_async(request)
        assert self.spin_until(future.done), f'{client.srv_name} did not answer'
        return future.result()

    # -- lifecycle_msgs -------------------------------------------------------------------
    def change_state(self, label):
        """Request a transition by label (``configure``, ``activate``...); return success."""
        request = ChangeState.Request(transition=Transition(label=label))
        return self.call(self._change, request).success

    def transition(self, transition_id):
        """Request a transition by id (``lifecycle_msgs.msg.Transition``); return success."""
        request = ChangeState.Request(transition=Transition(id=transition_id))
        return self.call(self._change, request).success

    def state(self):
        """Return the label of the node's state from its get_state service."""
        return self.call(self._get, GetState.Request()).current_state.label

    # -- rcl_interfaces -------------------------------------------------------------------
    def push(self, values):
        """Send ``{name: value}`` in one set_parameters_atomically request; return result."""
        request = SetParametersAtomically.Request(
            parameters=[Parameter(name, value=value).to_parameter_msg()
                        for name, value in values.items()])
        return self.call(self._atomic, request).result

    def set_each(self, values):
        """Send ``{name: value}`` in one set_parameters request (ros2 param load's path)."""
        request = SetParameters.Request(
            parameters=[Parameter(name, value=value).to_parameter_msg()
                        for name, value in values.items()])
        return self.call(self._set, request).results
