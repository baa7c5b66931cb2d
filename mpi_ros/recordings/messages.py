# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Message readers: the selected samples of each bag message, chosen by the topic's message type.

A recording needs the samples of the actuator input x [A] or output s [m]
each message of a topic carries: one number for most types, a chunk of K
samples for a chunked ``std_msgs/msg/Float64MultiArray``. A
:class:`MessageReader` takes them from a decoded message; which number is
described by a :class:`Selection` (a joint and field of a
``sensor_msgs/msg/JointState``, an element or axis of a
``Float64MultiArray``). The bag reader picks the reader by the topic's type
as stored in the bag, through :data:`MESSAGE_READERS`.

Chunked arrays (the multi-axis nodes' layout, :mod:`mpi_ros.array_layout`)
    A ``Float64MultiArray`` whose ``layout.dim`` has two entries is a block of
    ``dim[0].size`` = K samples x ``dim[1].size`` = N axes, row-major from
    ``layout.data_offset`` with the row stride ``dim[1].stride`` (N when it is
    smaller). The selected index is the axis (column, < N); the reader returns
    the K samples of that column, oldest first. A message without ``dim``, or
    with one or more than two entries, is one sample whose elements are
    indexed as before (element k after ``data_offset``); so is a block with
    K = 1. With :attr:`Selection.axes` = N (the data option ``array_axes``,
    set by the identifier for ``axes`` > 1) such a message is read as the
    nodes read it: its values after ``data_offset`` are K x N samples x axes.
    When the samples were taken is the bag reader's business
    (:func:`mpi_ros.recordings.read_bag_signals`).

Adding a message type is one class and one registry line (the type must be in
rosbags' ROS 2 Jazzy typestore)::

    class PointXReader(MessageReader):
        msgtype = 'geometry_msgs/msg/Point'

        def value(self, msg, selection):
            return float(msg.x)

    MESSAGE_READERS = {..., PointXReader.msgtype: PointXReader()}

A type whose messages carry several samples also overrides :meth:`MessageReader.values`.
"""

from __future__ import annotations

import abc
import dataclasses
from dataclasses import dataclass
import functools
from typing import Any, ClassVar, Mapping

import numpy as np
import numpy.typing as npt
from rosbags.typesys import get_typestore, Stores

from ..array_layout import chunk_layout, consecutive_layout
from ..errors import DataError

__all__ = [
    'Selection',
    'SelectionError',
    'MessageReader',
    'Float64Reader',
    'JointStateReader',
    'Float64MultiArrayReader',
    'MESSAGE_READERS',
    'supported_types',
    'typestore',
]


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
    :meth:`value`; one line in :data:`MESSAGE_READERS` registers them. A type
    whose messages carry several samples of the signal (a chunk) also
    overrides :meth:`values`, which the bag reader calls.
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
        Return the selected samples of one message, oldest first.

        Parameters
        ----------
        msg : object
            The message, decoded by rosbags.
        selection : Selection
            What to take from it.

        Returns
        -------
        ndarray of float, shape (K,)
            The K >= 1 samples, in the unit they were published in; by
            default the one number of :meth:`value`.

        Raises
        ------
        SelectionError
            If the message does not hold them; the message says what it holds.

        """
        return np.array([self.value(msg, selection)], dtype=np.float64)


class Float64Reader(MessageReader):
    """``std_msgs/msg/Float64``: the number is ``data``."""

    msgtype = 'std_msgs/msg/Float64'

    def value(self, msg: Any, selection: Selection) -> float:
        """Return ``msg.data``."""
        return float(msg.data)


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


class Float64MultiArrayReader(MessageReader):
    """
    ``std_msgs/msg/Float64MultiArray``: one element of ``data``, or one axis of a chunk.

    A message whose ``layout.dim`` has two entries is a chunk of samples x axes
    (module docstring); any other message is one sample.
    """

    msgtype = 'std_msgs/msg/Float64MultiArray'
    selectors = ('index',)

    def value(self, msg: Any, selection: Selection) -> float:
        """Return ``msg.data[layout.data_offset + index]`` (a one-sample chunk's element)."""
        if len(msg.layout.dim) == 2 or selection.axes is not None:
            samples = self.values(msg, selection)
            if samples.size != 1:
                msg_text = (f'it holds a chunk of {samples.size} samples (samples x axes), '
                            'not one number; read it with values()')
                raise SelectionError(msg_text)
            return float(samples[0])
        return self._element(msg, selection)

    def values(self, msg: Any, selection: Selection) -> npt.NDArray[np.float64]:
        """Return the selected axis of a chunk (K samples), or ``[value]`` for one sample."""
        dims = msg.layout.dim
        offset = int(msg.layout.data_offset)
        size = len(msg.data)
        option = selection.name('index')
        axes_option = selection.name('axes')
        layout = chunk_layout([(int(d.size), int(d.stride)) for d in dims], offset)
        if layout is not None:
            samples, axes, row = layout.samples, layout.axes, layout.row
            stride = f', row stride {row}' if row != axes else ''
            shape = (f'{samples} sample(s) x {axes} axes (layout.dim = samples x axes{stride}'
                     f'{_offset_note(offset, ", ")})')
            if samples < 1 or axes < 1:
                msg_text = (f'its layout announces {shape}: a chunk needs at least one sample '
                            'and one axis; fix layout.dim in the publisher (dim[0] = samples, '
                            'dim[1] = axes) or leave dim empty for one sample per message')
                raise SelectionError(msg_text)
            if not layout.fits(size):
                msg_text = (f'its layout announces {shape}, which needs {layout.needed} values,'
                            f' but data holds {size}; fix layout.dim in the publisher (dim[0] = '
                            'samples, dim[1] = axes) to match the data')
                raise SelectionError(msg_text)
            if selection.axes is not None and axes != selection.axes:
                msg_text = (f'it holds chunks of {shape}, but {axes_option} is '
                            f'{selection.axes}; set {axes_option} to {axes} (one column per '
                            'axis) or record the topic of the other actuators')
                raise SelectionError(msg_text)
        elif selection.axes is not None:
            axes = selection.axes
            layout = consecutive_layout(size, offset, axes)
            if layout is None:
                msg_text = (f'it holds {max(size - offset, 0)} value(s){_offset_note(offset)}'
                            f' and no layout.dim, not whole samples of {axes_option} {axes}'
                            ' axes (samples x axes, row-major); publish K x N values or set '
                            f'layout.dim, or set {axes_option} to the number of axes')
                raise SelectionError(msg_text)
            samples = layout.samples
            shape = (f'{samples} sample(s) x {axes} axes ({axes_option} {axes}, no '
                     f'layout.dim{_offset_note(offset, ", ")})')
        else:
            return np.array([self._element(msg, selection)], dtype=np.float64)
        if selection.index is None:
            if axes != 1:
                msg_text = (f'it holds chunks of {shape} and {option} is not set; set '
                            f'{option} to the axis, one of 0 to {axes - 1}')
                raise SelectionError(msg_text)
            index = 0
        else:
            index = selection.index
        if index >= axes:
            msg_text = (f'{option} {index} is out of range: the message holds {shape}; set '
                        f'{option} to an axis, one of 0 to {axes - 1}')
            raise SelectionError(msg_text)
        return layout.column(msg.data, index)

    @staticmethod
    def _element(msg: Any, selection: Selection) -> float:
        """Return ``msg.data[layout.data_offset + index]`` of a one-sample message."""
        offset = int(msg.layout.data_offset)
        size = len(msg.data) - offset
        option = selection.name('index')
        if selection.index is None:
            if size != 1:
                msg_text = (f'it holds {size} elements and {option} is not set; set {option} '
                            f'to one of 0 to {size - 1}')
                raise SelectionError(msg_text)
            index = 0
        else:
            index = selection.index
        if not 0 <= index < size:
            fix = (f'set {option} to one of 0 to {size - 1}' if size > 0
                   else 'record a topic whose arrays hold the signal')
            msg_text = (f'{option} {index} is out of range: the array holds {max(size, 0)} '
                        f'element(s){_offset_note(offset)}; {fix}')
            raise SelectionError(msg_text)
        return float(msg.data[offset + index])


#: Message type -> reader. A new type is one class above and one line here.
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


def _listing(names: list[str]) -> str:
    return ', '.join(repr(name) for name in names) or 'none'


def _offset_note(offset: int, lead: str = ' after ') -> str:
    return f'{lead}layout.data_offset {offset}' if offset else ''
