# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Count the messages a node never got, from what DDS tells: no silent loss.

A keep-last queue that overflows drops its oldest messages without any DDS event; a
reliable writer whose own keep-last history overflows before a reader acknowledged sends
a GAP, which Fast DDS reports to the reader as *sample lost*; a peer with incompatible QoS
(a best-effort publisher on a reliable subscription) exchanges nothing at all.  A
:class:`LossMonitor` counts all three for one input topic:

- ``lost_sequence_gaps``: jumps of the publisher's sequence number
  (``publication_sequence_number`` of each message the node takes itself while serving
  its queue; the message the executor hands over comes without it and is accounted as
  one in between).  A jump counts only while exactly one publisher feeds the topic
  (asked when a jump is seen: several publishers interleave their numbers), and a
  number that goes back (a restarted publisher) starts the count again.
- ``lost_dds_events``: the DDS *sample lost* event of the subscription.
- ``incompatible_qos``: requested / offered incompatible QoS events of the subscription
  and publisher.

``messages_lost`` is the larger of the first two (a GAP shows in both).  The largest number
of messages served in one callback in a diagnostics period (``max_backlog``) tells how
close the queue came to ``qos_depth``.
"""

import math
from typing import Any, Callable, Dict, List, Optional

from rclpy.event_handler import PublisherEventCallbacks, SubscriptionEventCallbacks

from ..compensation.status import LOSS_ADVICE, loss_problems

__all__ = ['LOG_PERIOD_S', 'LOSS_ADVICE', 'LossMonitor']

#: At most one log line about lost messages per this period [s].
LOG_PERIOD_S = 5.0


class LossMonitor:
    """
    Loss counters of one input topic and one output topic of a node.

    Parameters
    ----------
    node : rclpy.node.Node
        The node (its logger reports incompatible peers).
    input_topic, output_topic : str
        Topic names, for the log lines.
    reliability : str
        The node's ``qos_reliability``, for the log lines.

    """

    def __init__(self, node: Any, input_topic: str, output_topic: str,
                 reliability: str) -> None:
        self._node = node
        self._topics = (input_topic, output_topic)
        self._reliability = reliability
        self.lost_sequence_gaps = 0
        self.lost_dds_events = 0
        self.publishers = 0
        #: Returns the number of publishers of the input (set once the subscription exists).
        self.publisher_count: Callable[[], int] = lambda: 1
        self.max_backlog = 0
        self._incompatible: Dict[str, int] = {}
        self._last_number: Optional[int] = None
        self._unsequenced = 0
        self._logged = (-math.inf, 0)

    # -- event callbacks ----------------------------------------------------------------
    def subscription_callbacks(self) -> SubscriptionEventCallbacks:
        """Return the event callbacks for the input subscription."""
        return SubscriptionEventCallbacks(
            message_lost=self._on_message_lost,
            incompatible_qos=lambda info: self._on_incompatible(self._topics[0], info))

    def publisher_callbacks(self) -> PublisherEventCallbacks:
        """Return the event callbacks for the output publisher."""
        return PublisherEventCallbacks(
            incompatible_qos=lambda info: self._on_incompatible(self._topics[1], info))

    def _on_message_lost(self, info: Any) -> None:
        self.lost_dds_events += int(info.total_count_change)

    def _on_incompatible(self, topic: str, info: Any) -> None:
        # total_count: rmw_fastrtps reports total_count_change 0 for this event.
        self._incompatible[topic] = max(self._incompatible.get(topic, 0),
                                        int(info.total_count))
        policy = getattr(info.last_policy_kind, 'name', str(info.last_policy_kind))
        self._node.get_logger().warning(
            f'{topic}: a peer with incompatible QoS ({policy.replace("RMW_QOS_POLICY_", "")})'
            f'; it exchanges nothing with this node. This node uses qos_reliability='
            f'{self._reliability}: a best_effort publisher does not reach a reliable '
            'subscription')

    def restart(self) -> None:
        """Forget the last sequence number: a new subscription (lifecycle configure)."""
        self._last_number = None
        self._unsequenced = 0

    # -- message path -------------------------------------------------------------------
    def delivered(self) -> None:
        """Account for a message the executor handed over (its number is unknown)."""
        self._unsequenced += 1

    def taken(self, number: Optional[int]) -> None:
        """Check the sequence number of a message the node took itself (None: unknown)."""
        last, unsequenced = self._last_number, self._unsequenced
        self._last_number, self._unsequenced = number, 0
        if number is None or last is None:
            return
        gap = number - last - 1 - unsequenced
        if gap > 0:
            self.publishers = self.publisher_count()
            if self.publishers == 1:
                self.lost_sequence_gaps += gap

    def served(self, count: int) -> None:
        """Note the number of messages one callback served: how full the queue was."""
        if count > self.max_backlog:
            self.max_backlog = count

    # -- reports ------------------------------------------------------------------------
    @property
    def lost(self) -> int:
        """Return the messages lost so far: the larger of sequence gaps and DDS events."""
        return max(self.lost_sequence_gaps, self.lost_dds_events)

    @property
    def incompatible_qos(self) -> int:
        """Peers with incompatible QoS seen so far (both topics)."""
        return sum(self._incompatible.values())

    def counters(self) -> Dict[str, int]:
        """Return the loss counters by name, as /diagnostics reports them."""
        return {'messages_lost': self.lost, 'lost_sequence_gaps': self.lost_sequence_gaps,
                'lost_dds_events': self.lost_dds_events,
                'incompatible_qos': self.incompatible_qos}

    def period(self, counters: Dict[str, int], before: Dict[str, int], depth: int,
               what: str) -> List[str]:
        """
        Describe the losses of a diagnostics period; restart ``max_backlog``.

        The sentences are :func:`mpi_ros.compensation.status.loss_problems` of the
        period's counters (``counters``, ``before``), ``depth`` (``qos_depth``), the
        largest backlog and ``what`` the messages carry.

        """
        backlog, self.max_backlog = self.max_backlog, 0
        self.last_backlog = backlog
        return loss_problems(counters, before, depth, backlog, what)

    last_backlog = 0

    def log(self, now: float, what: str) -> bool:
        """
        Log one warning about the messages lost since the last one, at most every 5 s.

        Parameters
        ----------
        now : float
            Steady time [s].
        what : str
            What the messages carry, e.g. ``desired displacements``.

        Returns
        -------
        bool
            True when a line was logged.

        """
        last_time, last_lost = self._logged
        lost = self.lost
        if now - last_time < LOG_PERIOD_S or lost == last_lost:
            return False
        self._logged = (now, lost)
        self._node.get_logger().warning(
            f'{lost - last_lost} {what} lost before this node could serve them ({lost} in '
            f'all): {LOSS_ADVICE}')
        return True
