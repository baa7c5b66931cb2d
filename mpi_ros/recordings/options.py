# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Data options: which signals of a bag or CSV file are the actuator input and output.

One :class:`DataOptions` holds every choice a reader needs (topics, joint and
field of a ``sensor_msgs/msg/JointState``, index of a
``std_msgs/msg/Float64MultiArray``, CSV columns, scales). The command line
(``mpi-ros identify|simulate|compensate|diagnose``), the identifier node and the
Python API build it once and hand it to :func:`mpi_ros.recordings.read_recording`.
:data:`DATA_OPTIONS` describes each option once; the command line adds its
``--options`` and the identifier node declares its parameters from it.

Messages name an option as the user wrote it: ``--input-topic`` on the command
line, ``input_topic`` for a node parameter or a Python keyword (the
``spelling`` of the options).
"""

from __future__ import annotations

from dataclasses import dataclass, fields
import math
import numbers
from typing import Any, Mapping

from ..errors import DataError
from ..units import INPUT_UNITS, OUTPUT_UNITS, TIME_UNITS

__all__ = ['DataOptions', 'DataOption', 'DATA_OPTIONS', 'JOINT_FIELDS', 'SPELLINGS',
           'show_value']

#: Fields of ``sensor_msgs/msg/JointState`` a signal can be taken from.
JOINT_FIELDS = ('position', 'velocity', 'effort')

#: How messages spell an option: ``keyword`` (Python, ``input_topic=``), ``cli``
#: (``--input-topic``) or ``parameter`` (ROS parameter, ``-p input_topic:=``).
SPELLINGS = ('keyword', 'cli', 'parameter')


@dataclass(frozen=True)
class DataOption:
    """
    Documentation of one data option, shared by the command line and the node.

    Attributes
    ----------
    name : str
        Attribute of :class:`DataOptions` (and node parameter name).
    kind : str
        Value type: ``'str'``, ``'optional_str'``, ``'optional_int'``,
        ``'optional_float'``, ``'float'``, ``'bool'`` or ``'choice'``;
        ``optional_*`` options may be unset (``''``, ``-1`` or ``0.0`` as a
        node parameter).
    description : str
        One-line description.
    unit : str
        Unit of the value, empty when it has none.
    applies : {'bag', 'csv', 'any'}
        Kind of file the option applies to.
    parameter_default : object
        Default as a node parameter (unset optional options are ``''`` or ``-1``).

    """

    name: str
    kind: str
    description: str
    unit: str = ''
    applies: str = 'any'
    parameter_default: Any = None

    @property
    def flag(self) -> str:
        """Command-line spelling, e.g. ``--input-topic``."""
        return '--' + self.name.replace('_', '-')


#: Every data option, in the order the command line lists them.
DATA_OPTIONS = (
    DataOption('input_topic', 'str',
               'bag topic of the input (current): Float64, JointState or Float64MultiArray',
               'A', 'bag', '/current_command'),
    DataOption('output_topic', 'str',
               'bag topic of the output (displacement): Float64, JointState or '
               'Float64MultiArray', 'm', 'bag', '/displacement'),
    DataOption('input_joint', 'optional_str',
               'joint of a sensor_msgs/JointState input topic (unset: its only joint)', '',
               'bag', ''),
    DataOption('output_joint', 'optional_str',
               'joint of a sensor_msgs/JointState output topic (unset: its only joint)', '',
               'bag', ''),
    DataOption('input_field', 'choice',
               'JointState field of the input: position, velocity or effort', '', 'bag',
               'position'),
    DataOption('output_field', 'choice',
               'JointState field of the output: position, velocity or effort', '', 'bag',
               'position'),
    DataOption('input_index', 'optional_int',
               'element of a std_msgs/Float64MultiArray input topic (unset: its only '
               'element)', '', 'bag', -1),
    DataOption('output_index', 'optional_int',
               'element of a std_msgs/Float64MultiArray output topic (unset: its only '
               'element)', '', 'bag', -1),
    DataOption('array_axes', 'optional_int',
               'number of axes N of Float64MultiArray topics without layout.dim: K*N values '
               'are K samples x N axes (unset: such a message is one sample)', '', 'bag', -1),
    DataOption('sample_period', 'optional_float',
               'interval between the samples of a chunked Float64MultiArray message '
               '(layout.dim = samples x axes) (unset: the log time since the previous '
               'message divided by the chunk size)', 's', 'bag', 0.0),
    DataOption('time_column', 'optional_str',
               "CSV column of the time ('' if the file has none: time is the sample index)",
               's', 'csv', 'time'),
    DataOption('input_column', 'optional_str',
               'CSV column of the input (unset: the first column besides the time)', '',
               'csv', ''),
    DataOption('output_column', 'optional_str',
               'CSV column of the output (unset: the next column after the input)', '',
               'csv', ''),
    DataOption('time_scale', 'float',
               'multiply the time by this to get s (> 0): 1e-3 for a CSV time column in ms, '
               '1e-6 in us; for a bag, the factor from its log time', '', 'any', 1.0),
    DataOption('input_scale', 'float', 'multiply the input by this to get A', '', 'any', 1.0),
    DataOption('output_scale', 'float',
               'multiply the output by this to get m (1e-9 for nm)', '', 'any', 1.0),
    DataOption('time_unit', 'optional_str',
               'unit of the CSV time column: s, ms, us or ns (unset: from a suffix of its name, '
               'e.g. time_ms, else s); converted to s', '', 'csv', ''),
    DataOption('input_unit', 'optional_str',
               'unit of the input: A, mA, uA (a current) or V, mV, kV (a voltage) (unset: '
               'from a suffix of its name, e.g. Vplus_V, else A); converted to A or V, and '
               'the model records the input quantity', '', 'any', ''),
    DataOption('output_unit', 'optional_str',
               'unit of the output: m, mm, um, nm or pm (unset: from a suffix of its name, '
               'e.g. D1_nm, else m); converted to m', '', 'any', ''),
    DataOption('drop_nonfinite', 'bool',
               'drop NaN/Inf samples (and empty CSV fields) with a note instead of refusing '
               'the data', '', 'any',
               False),
)

_BY_NAME = {option.name: option for option in DATA_OPTIONS}


@dataclass(frozen=True)
class DataOptions:
    """
    Which signals of a recording are the actuator input and output.

    Every attribute is documented in :data:`DATA_OPTIONS`. Bag options apply
    to bags, CSV options to CSV files; the scales and `drop_nonfinite` to
    both. The options are validated on construction.

    Parameters
    ----------
    input_topic, output_topic : str
        Bag topics of the input x [A] and output s [m]. One topic may serve
        both when the selections differ (two joints or fields of one
        ``JointState`` topic, two indices of one array).
    input_joint, output_joint : str or None
        Joint name in a ``sensor_msgs/msg/JointState`` topic; None takes the
        message's only joint.
    input_field, output_field : {'position', 'velocity', 'effort'}
        Field of the joint in a ``JointState`` topic.
    input_index, output_index : int or None
        Element of a ``std_msgs/msg/Float64MultiArray`` topic (after the
        layout's ``data_offset``); None takes the array's only element. For
        a chunked message (``layout.dim`` = samples x axes) the axis, i.e.
        the column of the block.
    array_axes : int or None
        Number of axes N of ``Float64MultiArray`` messages without
        ``layout.dim``: their K x N values are then read as K samples x N
        axes (row-major), as the multi-axis nodes read them; None reads such
        a message as one sample. A two-entry ``layout.dim`` must agree.
        The identifier sets it to ``axes`` for a multi-axis bag.
    sample_period : float or None
        Interval [s] between the samples of a chunked
        ``Float64MultiArray`` message; None (or 0) infers it per message as
        the log time since the previous message divided by the chunk size
        (see :func:`mpi_ros.recordings.read_bag_signals`).
    time_column : str or None
        CSV time column; None when the file has none.
    input_column, output_column : str or None
        CSV columns; None picks the first column besides the time and the
        next one after it.
    time_scale : float
        Factor from the recorded time to s, > 0: the CSV time column (1e-3
        for ms), or a bag's log time (e.g. 0.1 for a bag recorded during a
        replay at a tenth of the speed). ``sample_period`` is in s after it.
    input_scale, output_scale : float
        Factors from the recorded values to A and m.
    time_unit, input_unit, output_unit : str or None
        The units of the values as recorded, after the scales (see :mod:`mpi_ros.units`);
        None takes them from a suffix of the column, topic or joint name, else s, A, m.
        The values are converted to SI (s, A or V, m) as they are read.
    drop_nonfinite : bool
        Drop NaN/Inf samples (and CSV rows with an empty field), with a note,
        instead of refusing the data.
    spelling : {'keyword', 'cli', 'parameter'}
        How error messages name the options (see :data:`SPELLINGS`).

    Raises
    ------
    DataError
        If a topic is empty, a field is unknown, an index is negative or not
        a whole number, `array_axes` is not a whole number >= 1, the sample
        period is negative or not finite, a scale is zero or not finite, or
        the time scale is negative.

    Examples
    --------
    >>> options = DataOptions(input_topic='/joint_states', input_joint='j1',
    ...                       input_field='effort', output_topic='/joint_states',
    ...                       output_joint='j1', spelling='cli')
    >>> options.name('input_joint'), options.setting('drop_nonfinite')
    ('--input-joint', '--drop-nonfinite')

    """

    input_topic: str = '/current_command'
    output_topic: str = '/displacement'
    input_joint: str | None = None
    output_joint: str | None = None
    input_field: str = 'position'
    output_field: str = 'position'
    input_index: int | None = None
    output_index: int | None = None
    array_axes: int | None = None
    sample_period: float | None = None
    time_column: str | None = 'time'
    input_column: str | None = None
    output_column: str | None = None
    time_scale: float = 1.0
    input_scale: float = 1.0
    output_scale: float = 1.0
    time_unit: str | None = None
    input_unit: str | None = None
    output_unit: str | None = None
    drop_nonfinite: bool = False
    spelling: str = 'keyword'

    def __post_init__(self) -> None:
        """Validate every option; messages name it in the options' spelling."""
        if self.spelling not in SPELLINGS:
            msg = f'spelling must be one of {", ".join(SPELLINGS)}; found {self.spelling!r}'
            raise DataError(msg)
        for name in ('input_topic', 'output_topic'):
            topic = getattr(self, name)
            if not isinstance(topic, str) or not topic.strip():
                msg = (f'{self.name(name)} must be a non-empty topic name; found '
                       f'{show_value(topic)}')
                raise DataError(msg)
        for name in ('input_joint', 'output_joint', 'time_column', 'input_column',
                     'output_column'):
            value = getattr(self, name)
            if value is not None and not isinstance(value, str):
                msg = f'{self.name(name)} must be a name (text); found {show_value(value)}'
                raise DataError(msg)
        for name in ('input_field', 'output_field'):
            if getattr(self, name) not in JOINT_FIELDS:
                msg = (f'{self.name(name)} must be one of {", ".join(JOINT_FIELDS)}; found '
                       f'{show_value(getattr(self, name))}')
                raise DataError(msg)
        for name in ('input_index', 'output_index'):
            value = getattr(self, name)
            whole = isinstance(value, numbers.Integral) and not isinstance(value, bool)
            if value is not None and (not whole or value < 0):
                msg = (f'{self.name(name)} must be a whole number >= 0 (0 is the first '
                       f'element); found {show_value(value)}')
                raise DataError(msg)
            if value is not None:
                object.__setattr__(self, name, int(value))
        axes = self.array_axes
        if axes is not None:
            whole = isinstance(axes, numbers.Integral) and not isinstance(axes, bool)
            if not whole or axes < 1:
                msg = (f'{self.name("array_axes")} must be a whole number >= 1 (the axes of '
                       'an array message without layout.dim) or unset; found '
                       f'{show_value(axes)}')
                raise DataError(msg)
            object.__setattr__(self, 'array_axes', int(axes))
        period = self.sample_period
        if period is not None:
            number = isinstance(period, numbers.Real) and not isinstance(period, bool)
            if not number or not math.isfinite(period) or period < 0:
                msg = (f'{self.name("sample_period")} must be a finite number >= 0 [s] (the '
                       'interval between the samples of a chunked message; 0 or unset '
                       f'infers it from the log times); found {show_value(period)}')
                raise DataError(msg)
            object.__setattr__(self, 'sample_period', float(period) or None)
        for name in ('time_scale', 'input_scale', 'output_scale'):
            value = getattr(self, name)
            number = isinstance(value, numbers.Real) and not isinstance(value, bool)
            if not number or not math.isfinite(value) or value == 0:
                msg = (f'{self.name(name)} must be a finite non-zero number; found '
                       f'{show_value(value)}')
                raise DataError(msg)
            if name == 'time_scale' and value < 0:
                msg = (f'{self.name(name)} must be > 0 (the factor from the recorded time to '
                       f's, e.g. 1e-3 for ms); found {show_value(value)}')
                raise DataError(msg)
            object.__setattr__(self, name, float(value))
        for name, known in (('time_unit', TIME_UNITS), ('input_unit', INPUT_UNITS),
                            ('output_unit', OUTPUT_UNITS)):
            value = getattr(self, name)
            if value is not None and value not in known:
                msg = (f'{self.name(name)} must be one of {", ".join(known)} or unset; found '
                       f'{show_value(value)}')
                raise DataError(msg)
        object.__setattr__(self, 'drop_nonfinite', bool(self.drop_nonfinite))

    def name(self, option: str) -> str:
        """
        Return how the user writes an option.

        Parameters
        ----------
        option : str
            Attribute name, e.g. ``'input_topic'``.

        Returns
        -------
        str
            ``--input-topic`` (``cli``) or ``input_topic`` (``keyword``,
            ``parameter``).

        """
        if self.spelling == 'cli':
            return '--' + option.replace('_', '-')
        return option

    def setting(self, option: str, value: str = '') -> str:
        """
        Return how the user sets an option to a value, for 'what to do' hints.

        Parameters
        ----------
        option : str
            Attribute name, e.g. ``'input_joint'``.
        value : str, optional
            The value as text (ignored for the bool `drop_nonfinite`).

        Returns
        -------
        str
            ``--input-joint NAME``, ``input_joint=NAME`` or
            ``-p input_joint:=NAME``.

        """
        is_bool = _BY_NAME[option].kind == 'bool' if option in _BY_NAME else False
        if self.spelling == 'cli':
            return self.name(option) if is_bool else f'{self.name(option)} {value}'
        if self.spelling == 'parameter':
            return f'-p {option}:={"true" if is_bool else value}'
        return f'{option}={"True" if is_bool else value}'

    @classmethod
    def from_mapping(cls, values: Mapping[str, Any], *, spelling: str) -> DataOptions:
        """
        Build options from argparse or node parameter values.

        Unset optional options are None (argparse), ``''`` (text parameters),
        a negative number (index parameters) or 0 (``sample_period``); an
        empty `time_column` means the CSV file has no time column. Keys that
        are not data options are ignored, missing ones keep their defaults.

        Parameters
        ----------
        values : Mapping[str, Any]
            Option name to value, e.g. ``vars(args)``.
        spelling : {'cli', 'parameter', 'keyword'}
            How messages name the options.

        Returns
        -------
        DataOptions
            The validated options.

        Raises
        ------
        DataError
            If an option is invalid (see :class:`DataOptions`).

        """
        given: dict[str, Any] = {}
        for option in DATA_OPTIONS:
            if option.name not in values:
                continue
            value = values[option.name]
            if option.kind == 'optional_str' and value == '':
                value = None
            elif (option.kind == 'optional_int' and spelling == 'parameter'
                  and isinstance(value, int) and not isinstance(value, bool) and value < 0):
                value = None
            if value is None and option.name not in _OPTIONAL:
                continue
            given[option.name] = value
        return cls(**given, spelling=spelling)


_OPTIONAL = {option.name for option in DATA_OPTIONS if option.kind.startswith('optional')}
_ATTRIBUTES = {item.name for item in fields(DataOptions)}
if set(_BY_NAME) | {'spelling'} != _ATTRIBUTES:  # pragma: no cover - a development error
    raise ImportError('DATA_OPTIONS and DataOptions disagree')


def show_value(value: Any) -> str:
    """
    Format a value for an error message, without numpy reprs.

    Parameters
    ----------
    value : object
        The value found.

    Returns
    -------
    str
        ``repr`` of text, the plain number for numbers (``np.float64(2.0)``
        shows as ``2.0``), ``repr`` otherwise.

    Examples
    --------
    >>> import numpy as np
    >>> show_value(np.float64(2.5)), show_value('x'), show_value(np.int64(3))
    ('2.5', "'x'", '3')

    """
    if isinstance(value, bool):
        return repr(value)
    if isinstance(value, numbers.Integral):
        return repr(int(value))
    if isinstance(value, numbers.Real):
        return repr(float(value))
    return repr(value)
