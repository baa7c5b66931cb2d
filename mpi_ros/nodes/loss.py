# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Turn a node's DDS events into loss counts: no silent loss.

The counting (sequence gaps, DDS sample-lost events, incompatible peers, the backlog and
the throttled warning) is :class:`mpi_ros.compensation.loss.LossCounter`, on plain
numbers; a :class:`LossMonitor` is that counter with the event callbacks of one input
subscription and one output publisher, and the node's logger for its warnings.
"""

from typing import Any

from rclpy.event_handler import PublisherEventCallbacks, SubscriptionEventCallbacks

from ..compensation.loss import LossCounter

__all__ = ['LossMonitor']


class LossMonitor(LossCounter):
    """
    Loss counters of one input topic and one output topic of a node, fed by DDS events.

    Parameters
    ----------
    node : rclpy.node.Node
        The node (its logger reports incompatible peers and losses).
    input_topic, output_topic : str
        Topic names, for the log lines.
    reliability : str
        The node's ``qos_reliability``, for the log lines.

    """

    def __init__(self, node: Any, input_topic: str, output_topic: str,
                 reliability: str) -> None:
        super().__init__(input_topic, output_topic, reliability)
        self._node = node

    def subscription_callbacks(self) -> SubscriptionEventCallbacks:
        """Return the event callbacks for the input subscription."""
        return SubscriptionEventCallbacks(
            message_lost=self._on_message_lost,
            incompatible_qos=lambda info: self._on_incompatible(self.topics[0], info))

    def publisher_callbacks(self) -> PublisherEventCallbacks:
        """Return the event callbacks for the output publisher."""
        return PublisherEventCallbacks(
            incompatible_qos=lambda info: self._on_incompatible(self.topics[1], info))

    def _on_message_lost(self, info: Any) -> None:
        self.message_lost(int(info.total_count_change))

    def _on_incompatible(self, topic: str, info: Any) -> None:
        # total_count: rmw_fastrtps reports total_count_change 0 for this event.
        policy = getattr(info.last_policy_kind, 'name', str(info.last_policy_kind))
        self._node.get_logger().warning(self.incompatible(topic, int(info.total_count), policy))

    def log(self, now: float, what: str) -> bool:
        """
        Log one warning about the messages lost since the last one, at most every 5 s.

        Parameters
        ----------
        now, what
            As for :meth:`mpi_ros.compensation.loss.LossCounter.report`.

        Returns
        -------
        bool
            True when a line was logged.

        """
        line = self.report(now, what)
        if line is not None:
            self._node.get_logger().warning(line)
        return line is not None
