# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Reader of ``sensor_msgs/msg/JointState``: one field of one joint, one sample per message.

The joint is :attr:`Selection.joint` (by default the message's only joint), the field
:attr:`Selection.joint_field` (``position``, ``velocity`` or ``effort``).
"""

from __future__ import annotations

from typing import Any

from .base import MessageReader, Selection, SelectionError

__all__ = ['JointStateReader']


class JointStateReader(MessageReader):
    """``sensor_msgs/msg/JointState``: one field (position, velocity, effort) of one joint."""

    msgtype = 'sensor_msgs/msg/JointState'
    selectors = ('joint', 'joint_field')

    def value(self, msg: Any, selection: Selection) -> float:
        """Return ``msg.<joint_field>[i]`` where ``msg.name[i]`` is the selected joint."""
        names = [str(name) for name in msg.name]
        joint_option = selection.name('joint')
        if selection.joint is None:
            if len(names) != 1:
                msg_text = (f'it holds {len(names)} joints ({_listing(names)}) and '
                            f'{joint_option} is not set; set {joint_option} to one of them')
                raise SelectionError(msg_text)
            position = 0
        elif selection.joint in names:
            position = names.index(selection.joint)
        else:
            msg_text = (f'it has no joint {selection.joint!r} ({joint_option}); joints found: '
                        f'{_listing(names)}; set {joint_option} to one of them')
            raise SelectionError(msg_text)
        values = getattr(msg, selection.joint_field)
        if position >= len(values):
            field_option = selection.name('joint_field')
            others = [name for name in ('position', 'velocity', 'effort')
                      if name != selection.joint_field and len(getattr(msg, name)) > position]
            msg_text = (f'it has no {selection.joint_field} for joint {names[position]!r}: '
                        f'{selection.joint_field} holds {len(values)} value(s) for '
                        f'{len(names)} joint(s) (its publisher does not fill it); set '
                        f'{field_option} to a filled field '
                        f'({", ".join(others) or "none is filled"})')
            raise SelectionError(msg_text)
        return float(values[position])


def _listing(names: list[str]) -> str:
    return ', '.join(repr(name) for name in names) or 'none'
