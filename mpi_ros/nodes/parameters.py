# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
The ROS side of the node parameters: descriptors, declaration, grouped set_parameters.

The specs and the checks are plain data and plain Python in
:mod:`mpi_ros.node_parameters`; this module turns a spec into rclpy's
``ParameterDescriptor`` (:func:`descriptor`), declares specs on a node, hands rclpy's
``Parameter`` objects to the checks as (type name, value), and serves ``set_parameters``
with coupled keys kept together.
"""

from typing import Any, Callable, Dict, Iterable, List, Mapping, Optional, Sequence, Tuple

from rcl_interfaces.msg import (FloatingPointRange, IntegerRange, ParameterDescriptor,
                                SetParametersResult)
from rclpy.exceptions import ParameterNotDeclaredException
from rclpy.node import Node
from rclpy.parameter import Parameter

from ..errors import MPIError
from ..node_parameters import ParameterSpec, plain_value, request_steps
from ..node_parameters import spec as core

__all__ = [
    'answer_request',
    'check_parameter',
    'check_parameters',
    'declare_parameters',
    'descriptor',
    'harden_parameter_services',
    'is_null',
    'normalized',
    'parameter_values',
    'set_parameters_in_groups',
]

Type = Parameter.Type


def descriptor(spec: ParameterSpec) -> ParameterDescriptor:
    """
    Build the ROS parameter descriptor of a spec.

    Parameters
    ----------
    spec : ParameterSpec
        The parameter.

    Returns
    -------
    rcl_interfaces.msg.ParameterDescriptor
        Dynamically typed descriptor (types are checked by :func:`check_parameter`)
        with description, unit, range and read-only flag.

    """
    described = ParameterDescriptor(
        name=spec.name, description=spec.described(),
        additional_constraints=spec.all_constraints(), read_only=spec.read_only,
        dynamic_typing=True)
    if spec.value_range is not None and spec.type_ == 'double':
        low, high = spec.value_range
        described.floating_point_range = [FloatingPointRange(
            from_value=float(low), to_value=float(high), step=0.0)]
    if spec.value_range is not None and spec.type_ == 'integer':
        low, high = spec.value_range
        described.integer_range = [IntegerRange(
            from_value=int(low), to_value=int(high), step=0)]
    return described


def declare_parameters(node: Node, specs: Iterable[ParameterSpec]) -> None:
    """
    Declare every spec on ``node`` with its descriptor.

    Register the node's on-set validator *before* calling this: rclpy runs it once per
    key during declaration, which is the only chance to reject a bad override from a
    ``--params-file``.

    An override written as YAML ``null`` (``ros2 param dump`` writes unset parameters so)
    reaches the node as the string ``'null'``; for a parameter that is not a string it
    means "not given": the parameter is declared with its default (unset where it has
    none), so a node starts from a dump of itself.

    Parameters
    ----------
    node : rclpy.node.Node
        The node to declare on.
    specs : iterable of ParameterSpec
        The parameters.

    """
    # rclpy 7.1.6 has no public accessor of the overrides (the --params-file values and
    # the parameter_overrides argument); the dict is only read here.
    overrides: Mapping[str, Parameter] = getattr(node, '_parameter_overrides', {})
    for spec in specs:
        override = overrides.get(spec.name)
        null = override is not None and is_null(spec, override)
        node.declare_parameter(spec.name, spec.default, descriptor(spec),
                               ignore_override=null)


def is_null(spec: ParameterSpec, parameter: Parameter) -> bool:
    """
    Tell whether an incoming parameter is YAML ``null`` (see the core's ``is_null``).

    Parameters
    ----------
    spec : ParameterSpec
        The declared spec of ``parameter.name``.
    parameter : rclpy.parameter.Parameter
        Incoming value.

    Returns
    -------
    bool
        True for an unset value or a null string for a parameter that is not a string.

    """
    return core.is_null(spec, parameter.type_.name.lower(), parameter.value)


def normalized(spec: ParameterSpec, parameter: Parameter) -> Parameter:
    """
    Return ``parameter`` with the types ``ros2 param load`` loses restored.

    Parameters
    ----------
    spec, parameter
        As for :func:`is_null`.

    Returns
    -------
    rclpy.parameter.Parameter
        The same parameter, or one of ``spec.type_`` with the value
        :func:`mpi_ros.node_parameters.normalized` restored.

    """
    found = parameter.type_.name.lower()
    kind, value = core.normalized(spec, found, parameter.value)
    if kind == found:
        return parameter
    return Parameter(parameter.name, Parameter.Type[kind.upper()], value)


def check_parameter(spec: ParameterSpec, parameter: Parameter, *,
                    allow_unset: bool = False) -> None:
    """
    Check one incoming parameter (:func:`mpi_ros.node_parameters.check_value`).

    Parameters
    ----------
    spec, parameter
        As for :func:`is_null`.
    allow_unset : bool
        Accept an unset value (only while declaring a parameter without default).

    """
    core.check_value(spec, parameter.type_.name.lower(), parameter.value,
                     allow_unset=allow_unset)


def check_parameters(specs: Mapping[str, ParameterSpec], parameters: Iterable[Parameter], *,
                     allow_unset: bool = False) -> None:
    """
    Check incoming parameters (:func:`mpi_ros.node_parameters.check_values`).

    Parameters
    ----------
    specs : mapping of str to ParameterSpec
        The node's specs by name.
    parameters : iterable of rclpy.parameter.Parameter
        Incoming values.
    allow_unset : bool
        Accept unset values.

    """
    core.check_values(specs, ((p.name, p.type_.name.lower(), p.value) for p in parameters),
                      allow_unset=allow_unset)


def answer_request(check: Callable[[], Any]) -> SetParametersResult:
    """
    Answer an on-set-parameters request: successful unless `check` raises.

    Parameters
    ----------
    check : callable
        Checks the request; raises :class:`~mpi_ros.errors.MPIError` (a refusal, its text
        the reason) or anything else (the reason names it: no exception may end the node).

    Returns
    -------
    rcl_interfaces.msg.SetParametersResult
        Successful, or not with the reason.

    """
    try:
        check()
    except MPIError as err:
        return SetParametersResult(successful=False, reason=str(err))
    except Exception as err:  # noqa: B902 - no exception may end the node: a refusal
        return SetParametersResult(
            successful=False,
            reason=f'the request could not be checked ({type(err).__name__}: {err})')
    return SetParametersResult(successful=True)


def parameter_values(node: Node, names: Sequence[str],
                     incoming: Sequence[Parameter] = ()) -> Dict[str, Any]:
    """
    Lay ``incoming`` over the node's current values of ``names``.

    Parameters
    ----------
    node : rclpy.node.Node
        Node whose current values are read (unset parameters give ``None``).
    names : sequence of str
        Keys to return.
    incoming : sequence of rclpy.parameter.Parameter
        Values about to be set; they win over the current ones.

    Returns
    -------
    dict
        ``{name: value}`` with Python values (lists for arrays, ``None`` when unset).

    """
    values: Dict[str, Any] = {}
    for name in names:
        if node.has_parameter(name):
            current = node.get_parameter_or(name, Parameter(name, Type.NOT_SET, None))
            values[name] = plain_value(current.value)
        else:
            values[name] = None
    for parameter in incoming:
        if parameter.name in values:
            values[parameter.name] = plain_value(parameter.value)
    return values


def set_parameters_in_groups(node: Node, parameters: Sequence[Parameter], *,
                             groups: Iterable[Iterable[str]] = (),
                             specs: Optional[Mapping[str, ParameterSpec]] = None,
                             ) -> List[SetParametersResult]:
    """
    Set parameters the way the ``set_parameters`` service does, keeping coupled keys together.

    rclpy's ``set_parameters`` (the service behind ``ros2 param load`` and ``ros2 param
    set``) sets one key at a time: the node's callbacks see the keys of a model one by one
    and could only switch through mixed models.  Here the keys of the request that belong
    to one group (e.g. all ``model.*`` keys) are set together in one
    ``set_parameters_atomically`` call, at the position of the group's first key: they
    succeed or fail together and every one of them gets that one result.  Every other key
    is set on its own, as rclpy does; an undeclared key is answered with a refusal and the
    request goes on.  A key given as YAML ``null`` (see :func:`is_null`) whose parameter is
    unset already is answered "left unset" and not set (setting an unset value would
    undeclare the parameter in rclpy).

    Parameters
    ----------
    node : rclpy.node.Node
        The node whose parameters to set.
    parameters : sequence of rclpy.parameter.Parameter
        The request, in order.
    groups : iterable of iterable of str
        Names that are set together (a key belongs to the first group naming it).
    specs : mapping of str to ParameterSpec, optional
        The node's specs by name, to recognise ``null``; None: no ``null`` handling.

    Returns
    -------
    list of rcl_interfaces.msg.SetParametersResult
        One result per parameter, in request order.

    """
    results: List[Optional[SetParametersResult]] = [None] * len(parameters)
    for i, parameter in enumerate(parameters):
        spec = specs.get(parameter.name) if specs is not None else None
        if (spec is not None and is_null(spec, parameter) and node.has_parameter(parameter.name)
                and node.get_parameter(parameter.name).type_ == Type.NOT_SET):
            results[i] = SetParametersResult(
                successful=True, reason=f'{parameter.name} is null: it stays unset')
    answered = [i for i, result in enumerate(results) if result is not None]
    for step in request_steps([p.name for p in parameters], groups, answered):
        try:
            result = node.set_parameters_atomically([parameters[j] for j in step])
        except ParameterNotDeclaredException as err:
            result = SetParametersResult(successful=False, reason=str(err))
        for j in step:
            results[j] = result
    return [result for result in results if result is not None]


def harden_parameter_services(node: Node, *, groups: Iterable[Iterable[str]] = (),
                              specs: Optional[Mapping[str, ParameterSpec]] = None) -> None:
    """
    Answer undecodable ``set_parameters*`` requests with a refusal instead of dying.

    rclpy's parameter service decodes each parameter message outside its ``try``: a
    message with an unknown type (any process on the domain can send one) raises
    ``ValueError`` out of the executor and ends the node.  The wrapped callbacks decode
    the whole request first; if any parameter cannot be decoded, every parameter of the
    request is refused with a reason and nothing is applied (``set_parameters`` would
    otherwise apply the ones before the bad one).  A decoded ``set_parameters`` request
    is then served by :func:`set_parameters_in_groups` with ``groups`` and ``specs``.

    Parameters
    ----------
    node : rclpy.node.Node
        Node whose parameter services to harden (call after the node is created).
    groups : iterable of iterable of str
        Coupled keys, set together within one ``set_parameters`` request.
    specs : mapping of str to ParameterSpec, optional
        The node's specs by name (``null`` handling); None: none.

    """
    grouped: List[Tuple[str, ...]] = [tuple(group) for group in groups]
    for service in node.services:
        name = service.srv_name.rsplit('/', 1)[-1]
        if name not in ('set_parameters', 'set_parameters_atomically'):
            continue
        callback = service.callback
        if name == 'set_parameters':
            callback = _grouped(node, grouped, specs)
        service.callback = _refusing_undecodable(callback, name)


def _grouped(node: Node, groups: Sequence[Sequence[str]],
             specs: Optional[Mapping[str, ParameterSpec]]) -> Any:
    def serve(request: Any, response: Any) -> Any:
        parameters = [Parameter.from_parameter_msg(message) for message in request.parameters]
        response.results = set_parameters_in_groups(node, parameters, groups=groups,
                                                    specs=specs)
        return response

    return serve


def _refusing_undecodable(callback: Any, name: str) -> Any:
    def guarded(request: Any, response: Any) -> Any:
        for i, message in enumerate(request.parameters):
            try:
                Parameter.from_parameter_msg(message)
            except (TypeError, ValueError) as err:
                reason = (f'parameter {message.name!r} (item {i}) cannot be decoded: {err};'
                          ' the whole request was refused, nothing changed')
                refused = SetParametersResult(successful=False, reason=reason)
                if name == 'set_parameters':
                    response.results = [refused for _ in request.parameters]
                else:
                    response.result = refused
                return response
        return callback(request, response)

    return guarded
