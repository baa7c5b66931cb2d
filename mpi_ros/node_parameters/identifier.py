# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
The identifier node's parameters: the bag, the data options, the order, the push.

The data parameters are the data options of ``mpi-ros identify``
(:data:`mpi_ros.recordings.DATA_OPTIONS`), one spec each; :func:`check_identifier_value`
checks a single value beyond its type, :func:`parse_order` the ``order``.  The node's
run is :func:`mpi_ros.pipeline.identify_bag`.
"""

from dataclasses import replace
from typing import Any

from .compensator import AXES
from .spec import ParameterSpec
from ..errors import IdentificationError, ParameterRejected
from ..order import Order, parse_order as parse_order_text
from ..recordings import DATA_OPTIONS, DataOption, DataOptions, JOINT_FIELDS

__all__ = ['DATA_NAMES', 'DATA_PARAMETERS', 'PARAMETERS', 'check_identifier_value',
           'parse_order']

_KINDS = {'str': 'string', 'optional_str': 'string', 'choice': 'string',
          'optional_int': 'integer', 'optional_float': 'double', 'float': 'double',
          'bool': 'bool'}
_UNSET = {'optional_str': "''", 'optional_int': '-1', 'optional_float': '0'}


def _data_parameter(option: DataOption) -> ParameterSpec:
    """Return the node parameter of one shared data option."""
    description = option.description[0].upper() + option.description[1:]
    if option.kind.startswith('optional'):
        description = description.replace('(unset:', f'({_UNSET[option.kind]}:')
    if option.applies != 'any':
        description += f'; {option.applies} only'
    return ParameterSpec(
        option.name, _KINDS[option.kind], option.parameter_default, description, option.unit,
        value_range=(-1, 2**31 - 1) if option.kind == 'optional_int' else None,
        choices=JOINT_FIELDS if option.kind == 'choice' else ())


#: The data parameters: one per shared data option, in the command line's order.
DATA_PARAMETERS = tuple(_data_parameter(option) for option in DATA_OPTIONS)

#: The identifier node's parameters.
PARAMETERS = (
    ParameterSpec('bag', 'string', '',
                  'Path of the rosbag2 bag (directory, or .mcap/.db3 file) to identify from '
                  '(a .csv file is read with the CSV data parameters)'),
    *DATA_PARAMETERS,
    ParameterSpec('order', 'string', 'auto',
                  "Model orders: 'auto' (selection by the fit errors), 'N,L' or 'N L' (N play "
                  'operators in H, L dead-zone operators in S)'),
    ParameterSpec('target_node', 'string', '/compensator',
                  'Fully qualified name of the node that receives the model'),
    ParameterSpec('push', 'bool', True,
                  'Push the fitted model to target_node (false: only fit and report)'),
    ParameterSpec('service_timeout', 'double', 10.0,
                  'Longest wait for the target parameter service, again for its answer, and'
                  ' (if the answer is lost) for reading the pushed values back',
                  's', value_range=(0.0, 3600.0)),
    ParameterSpec('params_file', 'string', '',
                  'Also write the model as a parameter YAML keyed by the compensator node '
                  'name (empty: do not write)'),
    replace(AXES, description=(
        'Number of actuators in the bag: 1 = one input and one output signal; N > 1 = '
        'Float64MultiArray topics with one element per axis (one sample or a chunk of '
        'samples x axes per message), every axis fitted and all models pushed to a '
        'multi-axis compensator in one request'), read_only=False),
    ParameterSpec('diagnose', 'bool', False,
                  'Also diagnose the bag (mpi-ros diagnose: the first 60 % trains, the rest '
                  'validates) and deliver the extended model when it names an effect with a '
                  'clear gain (not weak, not tied); else the identified model'),
    ParameterSpec('workers', 'integer', 0,
                  'axes > 1: processes fitting axes in parallel (0: one per CPU, at most '
                  'one per axis; 1: in this process)', value_range=(0, 1024)),
)

#: The names of the data parameters.
DATA_NAMES = frozenset(spec.name for spec in DATA_PARAMETERS)


def check_identifier_value(name: str, value: Any) -> None:
    """
    Check one identifier parameter beyond its type: the order's form, a data option.

    Parameters
    ----------
    name : str
        Parameter name.
    value : object
        Its new value (of the declared type).

    Raises
    ------
    mpi_ros.errors.MPIError
        When ``order`` cannot be parsed or a data option is refused, saying why.

    """
    if name == 'order':
        parse_order(value)
    elif name in DATA_NAMES:
        DataOptions.from_mapping({name: value}, spelling='parameter')


def parse_order(text: str) -> Order:
    """
    Parse the ``order`` parameter with :func:`mpi_ros.order.parse_order`.

    Parameters
    ----------
    text : str
        ``auto``, ``N,L`` or ``N L``, with N >= 1 and L >= 1.

    Returns
    -------
    str or tuple of (int, int)
        ``'auto'`` or ``(n, l)``.

    Raises
    ------
    mpi_ros.errors.ParameterRejected
        For anything else; the message names ``order``.

    """
    try:
        return parse_order_text(text, option='order')
    except IdentificationError as err:
        raise ParameterRejected(str(err)) from err
