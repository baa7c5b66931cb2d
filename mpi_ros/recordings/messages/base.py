# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
What a message reader takes from a decoded bag message, and the reader interface.

A recording needs the samples of the actuator input x [A] or output s [m] each
message of a topic carries: one number for most types, a chunk of K samples for
a chunked ``std_msgs/msg/Float64MultiArray``. A :class:`MessageReader` takes
them from a decoded message; which number is described by a :class:`Selection`
(a joint and field of a ``sensor_msgs/msg/JointState``, an element or axis of a
``Float64MultiArray``). A message that does not hold the selected number raises
:class:`SelectionError`.
"""

from __future__ import annotations

import abc
import dataclasses
from dataclasses import dataclass
from typing import Any, ClassVar, Mapping

import numpy as np
import numpy.typing as npt

from ...errors import DataError

__all__ = ['MessageReader', 'Selection', 'SelectionError']


class SelectionError(DataError):
    """A message does not hold the selected number (joint, field or index)."""


@dataclass(frozen=True)
class Selection:
    """
    Which number to take from each message of one topic.

    Attributes
    ----------
    topic : str
        Topic name in the bag.
    joint : str or None
        Joint name in a ``JointState``; None takes the message's only joint.
    joint_field : {'position', 'velocity', 'effort'}
        Field of the joint in a ``JointState``.
    index : int or None
        Element of a ``Float64MultiArray`` after ``layout.data_offset``, or
        the axis (column) of a chunked one (``layout.dim`` = samples x axes);
        None takes the array's only element (the only axis of a chunk).
    axes : int or None
        Number of axes N of a ``Float64MultiArray`` without ``layout.dim``:
        its values are then K x N samples x axes (row-major, K >= 1), as the
        multi-axis nodes accept them; None reads such a message as one
        sample (element `index`). A two-entry ``layout.dim`` must agree with
        it. Other types ignore it.
    names : Mapping[str, str]
        How the user writes the options behind ``topic``, ``joint``,
        ``joint_field``, ``index`` and ``axes`` (e.g. ``'--input-joint'``),
        for messages.

    """

    topic: str
    joint: str | None = None
    joint_field: str = 'position'
    index: int | None = None
    axes: int | None = None
    names: Mapping[str, str] = dataclasses.field(default_factory=dict, compare=False)

    def name(self, attribute: str) -> str:
        """Return how the user writes the option behind `attribute`."""
        return self.names.get(attribute, attribute)

    @property
    def label(self) -> str:
        """Topic, with the joint, field or index when one is selected."""
        parts = [part for part in (self.joint, None if self.joint is None else self.joint_field,
                                   None if self.index is None else f'[{self.index}]') if part]
        return f'{self.topic} {" ".join(parts)}' if parts else self.topic


class MessageReader(abc.ABC):
    """
    Take the selected number(s) from one decoded message of one type.

    Subclasses set :attr:`msgtype` and :attr:`selectors` and implement
    :meth:`value`; one line in :data:`mpi_ros.recordings.messages.MESSAGE_READERS`
    registers them. A type whose messages carry several samples of the signal
    (a chunk) also overrides :meth:`values`, which the bag reader calls, and
    :meth:`shape`, which the bag reader checks across the two topics.
    """

    #: Message type the reader decodes, as stored in the bag.
    msgtype: ClassVar[str]
    #: Attributes of :class:`Selection` the type uses (``joint``, ``joint_field``,
    #: ``index``); setting another one for a topic of this type is an error.
    selectors: ClassVar[tuple[str, ...]] = ()

    @abc.abstractmethod
    def value(self, msg: Any, selection: Selection) -> float:
        """
        Return the selected number of one message.

        Parameters
        ----------
        msg : object
            The message, decoded by rosbags.
        selection : Selection
            What to take from it.

        Returns
        -------
        float
            The number, in the unit it was published in.

        Raises
        ------
        SelectionError
            If the message does not hold it; the message says what it holds.

        """

    def values(self, msg: Any, selection: Selection) -> npt.NDArray[np.float64]:
        """
        Return the selected samples of one message, oldest first: K >= 1 numbers.

        `msg` and `selection` are those of :meth:`value`, and so is the
        :class:`SelectionError` when the message does not hold them. The default
        is the one number of :meth:`value`.

        Returns
        -------
        ndarray of float, shape (K,)
            The samples, in the unit they were published in.

        """
        return np.array([self.value(msg, selection)], dtype=np.float64)

    def shape(self, msg: Any) -> tuple[str, int] | None:
        """
        Return how a topic's first message lays out its values, for the check across topics.

        Parameters
        ----------
        msg : object
            The first message of the topic, decoded by rosbags.

        Returns
        -------
        tuple of (str, int) or None
            ``('chunk', axes)`` for a block of samples x axes, ``('flat', values)``
            for values without a layout, ``('other', 0)`` otherwise; None (the
            default) for a type that holds one sample per message.

        """
        return None
