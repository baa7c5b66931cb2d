# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Reader of ``std_msgs/msg/Float64``: one sample per message, the number ``data``.

The compensator nodes' loop topics and the bags :mod:`mpi_ros.recordings.bag_writer`
writes carry this type.
"""

from __future__ import annotations

from typing import Any

from .base import MessageReader, Selection

__all__ = ['Float64Reader']


class Float64Reader(MessageReader):
    """``std_msgs/msg/Float64``: the number is ``data``."""

    msgtype = 'std_msgs/msg/Float64'

    def value(self, msg: Any, selection: Selection) -> float:
        """Return ``msg.data``."""
        return float(msg.data)
