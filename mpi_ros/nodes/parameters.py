# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Parameter declarations and per-key validation shared by the mpi_ros nodes.

(Over 500 lines: the parameter specs of all nodes and the request handling they share -
type checks, CLI value forms, grouped set_parameters - are kept in one place on purpose.)

Every node describes its parameters once, as a tuple of :class:`ParameterSpec`,
and declares them with :func:`declare_parameters`. The specs are declared with
``dynamic_typing=True`` on purpose: rclpy's own static type check answers
``Wrong parameter type, expected ...`` without naming the parameter, which is
useless in a ``set_parameters_atomically`` call carrying five arrays. The nodes'
on-set validators call :func:`check_parameter` instead, which rejects every type
but the declared one (and an unset value) with a reason that names the key.
"""

from dataclasses import dataclass
import math
import re
from typing import Any, Dict, Iterable, List, Mapping, Optional, Sequence, Tuple

from rcl_interfaces.msg import (FloatingPointRange, IntegerRange, ParameterDescriptor,
                                SetParametersResult)
from rclpy.exceptions import ParameterNotDeclaredException
from rclpy.node import Node
from rclpy.parameter import Parameter
import yaml

from .qos import RELIABILITY
from ..errors import ParameterRejected
from ..extensions import EFFECTS
from ..params import (INPUT_OFFSET, MODEL_KEYS, OPERATING_POINT_DEFAULTS, OPERATING_POINT_KEYS,
                      OUTPUT_OFFSET, OUTPUT_SIGN)

__all__ = [
    'harden_parameter_services',
    'extension_parameters',
    'MODEL_KEYS',
    'MODEL_PARAMETERS',
    'NULL_STRINGS',
    'OPERATING_POINT_KEYS',
    'RCLPY_PARAMETERS',
    'ParameterSpec',
    'ParameterRejected',
    'check_parameter',
    'check_parameters',
    'declare_parameters',
    'is_null',
    'loop_qos_parameters',
    'normalized',
    'parameter_values',
    'plain_value',
    'set_parameters_in_groups',
    'specs_by_name',
]

Type = Parameter.Type

_TYPE_WORDS = {
    Type.BOOL: 'a bool (true/false)',
    Type.INTEGER: 'an integer',
    Type.DOUBLE: 'a double',
    Type.STRING: 'a string',
    Type.DOUBLE_ARRAY: 'an array of doubles',
    Type.INTEGER_ARRAY: 'an array of integers',
    Type.STRING_ARRAY: 'an array of strings',
}

#: Parameters every rclpy node declares itself.  The nodes do not let them change; the
#: compensator accepts its current value back, so a ``ros2 param dump`` loads back.
RCLPY_PARAMETERS = ('use_sim_time', 'start_type_description_service')

#: (expected, found) type pairs that are a YAML spelling slip, with the fix.
_TYPE_HINTS = {
    (Type.DOUBLE, Type.INTEGER): ' (write 2.0, not 2)',
    (Type.DOUBLE_ARRAY, Type.INTEGER_ARRAY): ' (write [0.0, 1.0], not [0, 1])',
}

#: How an unset value arrives when it was written as YAML ``null`` (what ``ros2 param dump``
#: writes for an unset parameter): ``--params-file`` (the rcl YAML parser) gives the string
#: ``'null'`` (or ``'~'``, as spelled), ``ros2 param load`` (``str(None)`` re-parsed) gives
#: ``'None'``.  For a parameter that is not a string, these strings mean "unset".
NULL_STRINGS = ('null', 'Null', 'NULL', '~', 'None')

#: How Python writes a float without a dot (``repr(1e-05) == '1e-05'``).
_DOTLESS_FLOAT = re.compile(r'[-+]?[0-9]+e[-+]?[0-9]+')

_ARRAY_TYPES = (Type.BYTE_ARRAY, Type.BOOL_ARRAY, Type.INTEGER_ARRAY, Type.DOUBLE_ARRAY,
                Type.STRING_ARRAY)


@dataclass(frozen=True)
class ParameterSpec:
    """
    One node parameter: name, type, default and documentation.

    Attributes
    ----------
    name : str
        Parameter key, e.g. ``output.min``.
    type_ : rclpy.parameter.Parameter.Type
        The only type the parameter accepts.
    default : object or None
        Default value; ``None`` declares the parameter unset (no default).
    description : str
        What the parameter does, shown by ``ros2 param describe``.
    unit : str
        SI unit (REP 103), empty when dimensionless; appended to the description.
    value_range : tuple of (number, number) or None
        Inclusive range for DOUBLE and INTEGER parameters.
    read_only : bool
        True when the value can only be given at start-up.
    choices : tuple of str
        Allowed values of a STRING parameter; empty for any string.
    constraints : str
        Extra constraints in words (``ros2 param describe`` shows them).

    """

    name: str
    type_: Type
    default: Any
    description: str
    unit: str = ''
    value_range: Optional[Tuple[float, float]] = None
    read_only: bool = False
    choices: Tuple[str, ...] = ()
    constraints: str = ''

    def descriptor(self) -> ParameterDescriptor:
        """
        Build the ROS parameter descriptor of this spec.

        Returns
        -------
        rcl_interfaces.msg.ParameterDescriptor
            Dynamically typed descriptor (types are checked by :func:`check_parameter`)
            with description, unit, range and read-only flag.

        """
        unit = f' [{self.unit}]' if self.unit else ''
        constraints = self.constraints
        if self.choices:
            constraints = ('one of: ' + ', '.join(self.choices) + '. ' + constraints).strip()
        descriptor = ParameterDescriptor(
            name=self.name,
            description=f'{self.description}{unit} (type: {self.type_.name.lower()})',
            additional_constraints=constraints,
            read_only=self.read_only,
            dynamic_typing=True,
        )
        if self.value_range is not None and self.type_ == Type.DOUBLE:
            descriptor.floating_point_range = [FloatingPointRange(
                from_value=float(self.value_range[0]),
                to_value=float(self.value_range[1]),
                step=0.0,
            )]
        if self.value_range is not None and self.type_ == Type.INTEGER:
            descriptor.integer_range = [IntegerRange(
                from_value=int(self.value_range[0]),
                to_value=int(self.value_range[1]),
                step=0,
            )]
        return descriptor


#: The five keys of Gamma = S o H; a model needs all of them (no defaults).

MODEL_PARAMETERS = (
    ParameterSpec(
        'model.hysteresis.thresholds', Type.DOUBLE_ARRAY, None,
        'Play-operator thresholds r_H of the hysteresis operator H (5), ascending, '
        'first one 0', 'A'),
    ParameterSpec(
        'model.hysteresis.weights', Type.DOUBLE_ARRAY, None,
        'Play-operator weights w_H, one per threshold, w_H0 > 0 and the rest >= 0 (8)', ''),
    ParameterSpec(
        'model.hysteresis.initial_states', Type.DOUBLE_ARRAY, None,
        'Initial states z_H0 of the play operators (their outputs at start), '
        'one per threshold', 'A'),
    ParameterSpec(
        'model.superposition.thresholds', Type.DOUBLE_ARRAY, None,
        'One-sided dead-zone thresholds r_S of the superposition operator S (18), '
        'ascending, exactly one 0', 'A'),
    ParameterSpec(
        'model.superposition.weights', Type.DOUBLE_ARRAY, None,
        'Dead-zone weights w_S, one per threshold, satisfying (19)', 'm/A'),
    ParameterSpec(
        INPUT_OFFSET, Type.DOUBLE, OPERATING_POINT_DEFAULTS[INPUT_OFFSET],
        'Operating point: input x0 at which the plays of H are centred; the model is '
        'y = y0 + sign * S[H[x - x0]]', 'A',
        constraints='part of the model: validated with the other model.* keys'),
    ParameterSpec(
        OUTPUT_OFFSET, Type.DOUBLE, OPERATING_POINT_DEFAULTS[OUTPUT_OFFSET],
        'Operating point: sensor reading y0 the model adds (the sensor zero)', 'm',
        constraints='part of the model: validated with the other model.* keys'),
    ParameterSpec(
        OUTPUT_SIGN, Type.INTEGER, OPERATING_POINT_DEFAULTS[OUTPUT_SIGN],
        'Operating point: +1 when the sensor rises as the actuator extends, -1 when it '
        'falls',
        constraints='1 or -1; part of the model: validated with the other model.* keys'),
)


def extension_parameters() -> Tuple[ParameterSpec, ...]:
    """
    Return the node parameters of every registered effect (declared unset).

    Read from the registry :data:`mpi_ros.extensions.EFFECTS` when called (a node calls it
    when it declares its parameters): each effect module states its keys, types, units,
    ranges and "off" values once.  An effect is off while all its keys are unset or hold
    their "off" values.

    Returns
    -------
    tuple of ParameterSpec
        One per effect key, in registry order.

    """
    types = {'double': Type.DOUBLE, 'double_array': Type.DOUBLE_ARRAY}
    return tuple(ParameterSpec(p.key, types[p.kind], None, p.description, p.unit,
                               value_range=p.value_range)
                 for effect in EFFECTS.values() for p in effect.parameters)


def loop_qos_parameters(topics: str) -> Tuple[ParameterSpec, ParameterSpec]:
    """
    Return the ``qos_depth`` and ``qos_reliability`` specs of a node's loop topics.

    Parameters
    ----------
    topics : str
        The topics they apply to, for the descriptions (e.g. ``'a and b'``).

    Returns
    -------
    tuple of ParameterSpec
        Both read-only; the node builds its QoS with :func:`mpi_ros.nodes.qos.loop_qos`.

    """
    return (
        ParameterSpec('qos_depth', Type.INTEGER, 10000,
                      f'History depth (keep-last) of {topics}; 10000 holds 1 s of a '
                      '10 kHz stream (a stall that long loses nothing)',
                      value_range=(1, 100000), read_only=True),
        ParameterSpec('qos_reliability', Type.STRING, 'reliable',
                      f'Reliability of {topics}: reliable (nothing lost) or best_effort '
                      '(less work per message at high rates; must match the peers: a '
                      'best_effort publisher does not reach a reliable subscription)',
                      choices=tuple(RELIABILITY), read_only=True),
    )


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
        node.declare_parameter(spec.name, spec.default, spec.descriptor(),
                               ignore_override=null)


def is_null(spec: ParameterSpec, parameter: Parameter) -> bool:
    """
    Tell whether an incoming value is YAML ``null`` for a parameter that is not a string.

    Parameters
    ----------
    spec : ParameterSpec
        The declared spec of ``parameter.name``.
    parameter : rclpy.parameter.Parameter
        Incoming value.

    Returns
    -------
    bool
        True for an unset value, and for one of :data:`NULL_STRINGS` when ``spec`` is
        not a string parameter.

    """
    if parameter.type_ == Type.NOT_SET:
        return True
    return (spec.type_ != Type.STRING and parameter.type_ == Type.STRING
            and parameter.value in NULL_STRINGS)


def normalized(spec: ParameterSpec, parameter: Parameter) -> Parameter:
    """
    Return ``parameter`` with the types that ``ros2 param load`` loses restored.

    ``ros2 param load`` (rclpy's ``parameter_dict_from_yaml_file``) re-parses every value
    from Python's ``str()`` of it, and ``ros2 param set`` parses its text the same way
    (``rclpy.parameter.get_parameter_value``).  That loses two types:

    - an empty list ``[]`` comes back as an empty *bool* array;
    - a float that Python writes without a dot (``1e-05``, ``-6e-06``: typical weights
      in m/A) is a *string* to PyYAML, so it comes back as a string, a list of them as
      a string array, and a list mixing them with other floats as one string.

    For a double or double-array parameter exactly these forms are turned back into
    doubles: a string (or every item of a string array) in Python's dot-less float
    notation, or a string holding a YAML list of floats of which at least one is in that
    notation.  Everything else stays as it came (integers, ``'[0.0, 1.0]'``, ...) and is
    refused by :func:`check_parameter`.

    Parameters
    ----------
    spec : ParameterSpec
        The declared spec of ``parameter.name``.
    parameter : rclpy.parameter.Parameter
        Incoming value.

    Returns
    -------
    rclpy.parameter.Parameter
        The same parameter, or one of ``spec.type_`` with the same value.

    """
    found = parameter.type_
    if found == spec.type_ or is_null(spec, parameter):
        return parameter
    if spec.type_ in _ARRAY_TYPES and found in _ARRAY_TYPES and len(parameter.value) == 0:
        return Parameter(parameter.name, spec.type_, [])
    if spec.type_ == Type.DOUBLE and found == Type.STRING and _dotless(parameter.value):
        return Parameter(parameter.name, Type.DOUBLE, float(parameter.value))
    if spec.type_ == Type.DOUBLE_ARRAY and found == Type.STRING_ARRAY:
        items = list(parameter.value)
        if all(_dotless(item) for item in items):
            return Parameter(parameter.name, Type.DOUBLE_ARRAY, [float(v) for v in items])
    if spec.type_ == Type.DOUBLE_ARRAY and found == Type.STRING:
        parsed = _yaml_list(parameter.value)
        if (parsed and all(isinstance(v, float) or _dotless(v) for v in parsed)
                and any(_dotless(v) for v in parsed)):
            return Parameter(parameter.name, Type.DOUBLE_ARRAY, [float(v) for v in parsed])
    return parameter


def check_parameter(spec: ParameterSpec, parameter: Parameter, *,
                    allow_unset: bool = False) -> None:
    """
    Check one incoming value against its spec (type, finiteness, range, choices).

    Parameters
    ----------
    spec : ParameterSpec
        The declared spec of ``parameter.name``.
    parameter : rclpy.parameter.Parameter
        Incoming value.
    allow_unset : bool
        Accept an unset value (only while declaring a parameter without default).

    Raises
    ------
    ParameterRejected
        With a message that names the parameter, the expectation and the finding.

    """
    found = parameter.type_
    if is_null(spec, parameter):
        if allow_unset:
            return
        msg = (f'{spec.name} cannot be unset (null) while the node runs; expected '
               f'{_TYPE_WORDS[spec.type_]}; give a value or leave the key out')
        raise ParameterRejected(msg)
    if found != spec.type_:
        hint = _TYPE_HINTS.get((spec.type_, found), '')
        value = parameter.value
        shown = list(value) if found in _ARRAY_TYPES else value
        msg = (f'{spec.name} must be {_TYPE_WORDS[spec.type_]}{hint}; '
               f'found {found.name.lower()} {shown!r}')
        raise ParameterRejected(msg)
    value = parameter.value
    if spec.type_ == Type.DOUBLE:
        if not math.isfinite(value):
            msg = f'{spec.name} must be finite; found {value!r}'
            raise ParameterRejected(msg)
    if spec.type_ == Type.DOUBLE_ARRAY:
        for index, item in enumerate(value):
            if not math.isfinite(item):
                msg = f'{spec.name}[{index}] must be finite; found {item!r}'
                raise ParameterRejected(msg)
    if spec.value_range is not None and spec.type_ in (Type.DOUBLE, Type.INTEGER):
        low, high = spec.value_range
        if not low <= value <= high:
            unit = f' {spec.unit}' if spec.unit else ''
            msg = (f'{spec.name} must lie in [{low}, {high}]{unit}; found {value!r}')
            raise ParameterRejected(msg)
    if spec.choices and value not in spec.choices:
        msg = (f'{spec.name} must be one of {", ".join(spec.choices)}; found {value!r}')
        raise ParameterRejected(msg)


def check_parameters(specs: Mapping[str, ParameterSpec], parameters: Iterable[Parameter], *,
                     allow_unset: bool = False) -> None:
    """
    Check every incoming parameter against its spec; an undeclared name is rejected too.

    Parameters
    ----------
    specs : mapping of str to ParameterSpec
        The node's specs by name (:func:`specs_by_name`).
    parameters : iterable of rclpy.parameter.Parameter
        Incoming values.
    allow_unset : bool
        Accept unset values (see :func:`check_parameter`).

    Raises
    ------
    ParameterRejected
        At the first parameter that fails, naming it.

    """
    for parameter in parameters:
        spec = specs.get(parameter.name)
        if spec is None and parameter.name in RCLPY_PARAMETERS:
            msg = (f"{parameter.name} is rclpy's own parameter and cannot be changed on this "
                   'node; leave it out of the request')
            raise ParameterRejected(msg)
        if spec is None:
            msg = f'{parameter.name} is not a parameter of this node'
            raise ParameterRejected(msg)
        check_parameter(spec, parameter, allow_unset=allow_unset)


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


def specs_by_name(specs: Iterable[ParameterSpec]) -> Mapping[str, ParameterSpec]:
    """
    Index specs by parameter name.

    Parameters
    ----------
    specs : iterable of ParameterSpec
        The parameters.

    Returns
    -------
    dict
        ``{spec.name: spec}``.

    """
    return {spec.name: spec for spec in specs}


def _dotless(item: Any) -> bool:
    """Tell whether ``item`` is a string in Python's dot-less float notation (``1e-05``)."""
    return isinstance(item, str) and _DOTLESS_FLOAT.fullmatch(item.strip()) is not None


def _yaml_list(text: str) -> Optional[List[Any]]:
    try:
        value = yaml.safe_load(text)
    except yaml.YAMLError:
        return None
    return value if isinstance(value, list) else None


def plain_value(value: Any) -> Any:
    """Turn rclpy's array values (array.array, tuples) into lists (the dicts of the core)."""
    if value is None or isinstance(value, (bool, int, float, str)):
        return value
    return list(value)


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
    groups = [frozenset(group) for group in groups]
    results: List[Optional[SetParametersResult]] = [None] * len(parameters)
    for i, parameter in enumerate(parameters):
        spec = specs.get(parameter.name) if specs is not None else None
        if (spec is not None and is_null(spec, parameter) and node.has_parameter(parameter.name)
                and node.get_parameter(parameter.name).type_ == Type.NOT_SET):
            results[i] = SetParametersResult(
                successful=True, reason=f'{parameter.name} is null: it stays unset')
    for i, parameter in enumerate(parameters):
        if results[i] is not None:
            continue
        group = next((g for g in groups if parameter.name in g), frozenset())
        members = [j for j, other in enumerate(parameters)
                   if results[j] is None and (j == i or other.name in group)]
        try:
            result = node.set_parameters_atomically([parameters[j] for j in members])
        except ParameterNotDeclaredException as err:
            result = SetParametersResult(successful=False, reason=str(err))
        for j in members:
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
