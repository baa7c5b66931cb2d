# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Message readers: the selected samples of each bag message, chosen by the topic's type.

One module per message type (:mod:`.scalar` ``std_msgs/msg/Float64``,
:mod:`.joint_state` ``sensor_msgs/msg/JointState``, :mod:`.multi_array`
``std_msgs/msg/Float64MultiArray``), the interface in :mod:`.base`, and the
registry :data:`MESSAGE_READERS` that the bag reader looks a topic's type up in
(as stored in the bag). Adding a message type is one module and one registry
line (the type must be in rosbags' ROS 2 Jazzy typestore)::

    class PointXReader(MessageReader):
        msgtype = 'geometry_msgs/msg/Point'

        def value(self, msg, selection):
            return float(msg.x)

    MESSAGE_READERS = {..., PointXReader.msgtype: PointXReader()}

A type whose messages carry several samples also overrides :meth:`MessageReader.values`
(and :meth:`MessageReader.shape`).
"""

from __future__ import annotations

import functools
from typing import Any

from rosbags.typesys import get_typestore, Stores

from .base import MessageReader, Selection, SelectionError
from .joint_state import JointStateReader
from .multi_array import Float64MultiArrayReader
from .scalar import Float64Reader

__all__ = ['Float64MultiArrayReader', 'Float64Reader', 'JointStateReader', 'MESSAGE_READERS',
           'MessageReader', 'Selection', 'SelectionError', 'supported_types', 'typestore']

#: Message type -> reader. A new type is one module and one line here.
MESSAGE_READERS: dict[str, MessageReader] = {
    Float64Reader.msgtype: Float64Reader(),
    JointStateReader.msgtype: JointStateReader(),
    Float64MultiArrayReader.msgtype: Float64MultiArrayReader(),
}


def supported_types() -> str:
    """
    List the message types :data:`MESSAGE_READERS` reads, for messages.

    Returns
    -------
    str
        E.g. ``'std_msgs/msg/Float64, sensor_msgs/msg/JointState or ...'``.

    """
    names = list(MESSAGE_READERS)
    return names[0] if len(names) == 1 else f'{", ".join(names[:-1])} or {names[-1]}'


@functools.lru_cache(maxsize=1)
def typestore() -> Any:
    """Build rosbags' ROS 2 Jazzy typestore once and return it."""
    return get_typestore(Stores.ROS2_JAZZY)
