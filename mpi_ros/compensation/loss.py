# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Count the messages a node never got, from what DDS tells: no silent loss.

A keep-last queue that overflows drops its oldest messages without any DDS event; a
reliable writer whose own keep-last history overflows before a reader acknowledged sends
a GAP, which Fast DDS reports to the reader as *sample lost*; a peer with incompatible QoS
(a best-effort publisher on a reliable subscription) exchanges nothing at all.  A
:class:`LossCounter` counts all three for one input topic, from plain numbers the ROS side
hands over (:class:`mpi_ros.nodes.loss.LossMonitor` turns the DDS events into these calls):

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
from typing import Callable, Dict, List, Optional

from .status import LOSS_ADVICE, loss_problems

__all__ = ['LOG_PERIOD_S', 'LossCounter']

#: At most one log line about lost messages per this period [s].
LOG_PERIOD_S = 5.0


class LossCounter:
    """
    Loss counters of one input topic and one output topic of a node.

    Parameters
    ----------
    input_topic, output_topic : str
        Topic names, for the warnings.
    reliability : str
        The node's ``qos_reliability``, for the warnings.

    Examples
    --------
    >>> loss = LossCounter('desired_displacement', 'current_command', 'reliable')
    >>> loss.taken(7)
    >>> loss.delivered()          # handed over by the executor: its number is unknown
    >>> loss.taken(12)            # 8 .. 11: one handed over, three never came
    >>> loss.counters()['lost_sequence_gaps']
    3

    """

    #: Most messages served in one callback in the last closed period (:meth:`period`).
    last_backlog = 0

    def __init__(self, input_topic: str, output_topic: str, reliability: str) -> None:
        self.topics = (input_topic, output_topic)
        self.reliability = reliability
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

    # -- events -------------------------------------------------------------------------
    def message_lost(self, count: int) -> None:
        """Count ``count`` messages DDS reported lost (sample-lost event of the input)."""
        self.lost_dds_events += count

    def incompatible(self, topic: str, total: int, policy: str) -> str:
        """
        Note a peer with incompatible QoS on ``topic``; return the warning to log.

        Parameters
        ----------
        topic : str
            One of :attr:`topics`.
        total : int
            The event's total count of such peers on the topic.
        policy : str
            The policy that does not match, e.g. ``RELIABILITY``.

        Returns
        -------
        str
            A warning naming the topic, the policy and this node's ``qos_reliability``.

        """
        self._incompatible[topic] = max(self._incompatible.get(topic, 0), total)
        return (f'{topic}: a peer with incompatible QoS ({policy.replace("RMW_QOS_POLICY_", "")})'
                f'; it exchanges nothing with this node. This node uses qos_reliability='
                f'{self.reliability}: a best_effort publisher does not reach a reliable '
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

    def report(self, now: float, what: str) -> Optional[str]:
        """
        Return a warning about the messages lost since the last one, at most every 5 s.

        Parameters
        ----------
        now : float
            Steady time [s].
        what : str
            What the messages carry, e.g. ``desired displacements``.

        Returns
        -------
        str or None
            The warning; None when nothing new was lost or the last one is younger than
            :data:`LOG_PERIOD_S`.

        """
        last_time, last_lost = self._logged
        lost = self.lost
        if now - last_time < LOG_PERIOD_S or lost == last_lost:
            return None
        self._logged = (now, lost)
        return (f'{lost - last_lost} {what} lost before this node could serve them ({lost} in '
                f'all): {LOSS_ADVICE}')
