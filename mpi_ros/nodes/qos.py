# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Quality of service of the loop topics (``desired_displacement``, ``current_command``, ...).

Production code: the nodes build their publishers and subscriptions with :func:`loop_qos`
from their ``qos_depth`` and ``qos_reliability`` parameters.
"""

from rclpy.qos import HistoryPolicy, QoSProfile, ReliabilityPolicy

__all__ = ['loop_qos', 'RELIABILITY']


#: ``qos_reliability`` parameter value -> rclpy policy.
RELIABILITY = {'reliable': ReliabilityPolicy.RELIABLE,
               'best_effort': ReliabilityPolicy.BEST_EFFORT}


def loop_qos(depth: int = 10000, reliability: str = 'reliable') -> QoSProfile:
    """
    Return the QoS of the loop topics (keep-last ``depth``), as the nodes build it.

    Parameters
    ----------
    depth : int
        History depth: 10000 (the nodes' default ``qos_depth``) holds 1 s of a 10 kHz
        stream, so a subscriber or the node may stall that long without a lost sample.
    reliability : str
        ``reliable`` (default: nothing lost) or ``best_effort`` (a reliable Fast DDS
        writer wakes its event thread on every sample; at 10 kHz that is measurable, see
        docs/reliability.md).  A best-effort publisher does not match a reliable
        subscription.

    Returns
    -------
    rclpy.qos.QoSProfile
        Keep-last ``depth``, volatile, with the given reliability.

    """
    return QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=depth,
                      reliability=RELIABILITY[reliability])
