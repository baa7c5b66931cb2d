# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Identification from a bag as the identifier node runs it: its parameters and its fit.

The node's parameter specs (:data:`PARAMETERS`; the data parameters are the data options
of ``mpi-ros identify``, :data:`mpi_ros.recordings.DATA_OPTIONS`), the checks of single
values (:func:`check_identifier_value`) and one run (:func:`identify`): read the bag, fit
one axis (:func:`mpi_ros.pipeline.fit_bag`) or N (:func:`mpi_ros.pipeline.fit_bag_axes`),
report, write the parameter YAML if asked, and return the parameters to push.  The push
is the ROS side's (:mod:`mpi_ros.nodes.identifier`).
"""

from collections.abc import Callable, Mapping
from dataclasses import replace
from typing import Any, Dict, List, Tuple

from .compensation.parameters import AXES, ParameterSpec
from .compensation.updates import axis_key
from .errors import DataError, IdentificationError
from .order import format_order
from .params import write_params_yaml
from .pipeline import BagFit, fit_bag, fit_bag_axes, parse_order
from .recordings import DATA_OPTIONS, DataOption, DataOptions, JOINT_FIELDS

__all__ = ['DATA_NAMES', 'DATA_PARAMETERS', 'PARAMETERS', 'check_identifier_value',
           'identify']

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
                  'Longest wait for the target parameter service, and again for its answer',
                  's', value_range=(0.0, 3600.0)),
    ParameterSpec('params_file', 'string', '',
                  'Also write the model as a parameter YAML keyed by the compensator node '
                  'name (empty: do not write)'),
    replace(AXES, description=(
        'Number of actuators in the bag: 1 = one input and one output signal; N > 1 = '
        'Float64MultiArray topics with one element per axis (one sample or a chunk of '
        'samples x axes per message), every axis fitted and all models pushed to a '
        'multi-axis compensator in one request'), read_only=False),
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


def identify(values: Mapping[str, Any], *, info: Callable[[str], Any],
             error: Callable[[str], Any]) -> Tuple['BagFit | List[BagFit]', Dict[str, Any]]:
    """
    Fit, report, and write the YAML if asked: one identifier run up to the push.

    Parameters
    ----------
    values : mapping
        The identifier's parameter values (:data:`PARAMETERS`).
    info, error : callable
        Log a line (the node's logger).

    Returns
    -------
    fitted : BagFit or list of BagFit
        The fit (one per axis when ``axes`` > 1).
    parameters : dict
        The model keys to push (``axis<k>.model.*`` when ``axes`` > 1).

    Raises
    ------
    mpi_ros.errors.MPIError
        ``DataError`` (no or unreadable bag), ``IdentificationError`` (fit refused,
        logged through ``error`` first).

    """
    bag = values['bag']
    if not bag:
        msg = 'no bag given; run with --ros-args -p bag:=PATH'
        raise DataError(msg)
    options = DataOptions.from_mapping({name: values[name] for name in DATA_NAMES},
                                       spelling='parameter')
    order = parse_order(values['order'])
    axes = values['axes']
    if axes > 1:
        info(f'identifying {axes} axes from {bag}, order {format_order(order)}')
    else:
        info(f'identifying from {bag} ({options.input_topic} -> '
             f'{options.output_topic}, order {format_order(order)})')
    try:
        fitted: 'BagFit | List[BagFit]' = (
            fit_bag_axes(bag, axes, options=options, order=order, workers=values['workers'])
            if axes > 1 else fit_bag(bag, options=options, order=order))
    except IdentificationError as err:
        error(f'identification refused the data of {bag}: {err}; no model was '
              'written or pushed')
        raise
    if isinstance(fitted, list):
        parameters: Dict[str, Any] = {}
        for axis, fit in enumerate(fitted):
            info(f'axis {axis}: {fit.summary()}')
            parameters.update({axis_key(axis, key): v for key, v in fit.parameters.items()})
        written = dict(parameters, axes=axes)
        header = f'mpi_ros identifier: {axes} axes\nbag: {bag}'
    else:
        info(fitted.summary())
        parameters = written = fitted.parameters
        header = f'mpi_ros identifier: {fitted.summary()}\nbag: {bag}'
    params_file = values['params_file']
    if params_file:
        write_params_yaml(params_file, written, node_name='compensator', header=header)
        info(f'wrote {params_file}')
    return fitted, parameters
