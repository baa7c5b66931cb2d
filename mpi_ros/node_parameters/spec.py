# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Node parameters as plain data: the spec of one parameter, the forms a value arrives in, the checks.

Every node describes its parameters once, as a tuple of :class:`ParameterSpec` (name,
type, default, description, unit, range, read-only flag); the ROS side only turns a spec
into rclpy's descriptor (:mod:`mpi_ros.nodes.parameters`).  A value is checked here as
plain Python: its type name (rclpy's ``Parameter.Type`` names in lower case, e.g.
``'double_array'``, ``'not_set'``) and its value.  The specs are declared with dynamic
typing on purpose: rclpy's own static type check answers ``Wrong parameter type,
expected ...`` without naming the parameter, which is useless in a
``set_parameters_atomically`` call carrying five arrays.  :func:`check_value` instead
rejects every type but the declared one (and an unset value) with a reason that names
the key.
"""

from dataclasses import dataclass, field
import math
import re
from typing import Any, Callable, Collection, Iterable, List, Mapping, Optional, Sequence, \
    Tuple

import numpy as np
import yaml

from ..errors import ModelError, ParameterPushError, ParameterRejected

__all__ = [
    'ARRAY_KINDS', 'NULL_STRINGS', 'RCLPY_PARAMETERS', 'RELIABILITIES',
    'ParameterSpec', 'check_value', 'check_values', 'is_null', 'loop_qos_parameters',
    'normalized', 'plain_value', 'request_steps', 'specs_by_name', 'typed_value',
]

_TYPE_WORDS = {
    'bool': 'a bool (true/false)',
    'integer': 'an integer',
    'double': 'a double',
    'string': 'a string',
    'double_array': 'an array of doubles',
    'integer_array': 'an array of integers',
    'string_array': 'an array of strings',
}

#: Parameters every rclpy node declares itself.  The nodes do not let them change; the
#: compensator accepts its current value back, so a ``ros2 param dump`` loads back.
RCLPY_PARAMETERS = ('use_sim_time', 'start_type_description_service')

#: The values of ``qos_reliability`` (the ROS side maps them to rclpy's policies).
RELIABILITIES = ('reliable', 'best_effort')

#: (expected, found) type pairs that are a YAML spelling slip, with the fix.
_TYPE_HINTS = {
    ('double', 'integer'): ' (write 2.0, not 2)',
    ('double_array', 'integer_array'): ' (write [0.0, 1.0], not [0, 1])',
}

#: How an unset value arrives when it was written as YAML ``null`` (what ``ros2 param dump``
#: writes for an unset parameter): ``--params-file`` (the rcl YAML parser) gives the string
#: ``'null'`` (or ``'~'``, as spelled), ``ros2 param load`` (``str(None)`` re-parsed) gives
#: ``'None'``.  For a parameter that is not a string, these strings mean "unset".
NULL_STRINGS = ('null', 'Null', 'NULL', '~', 'None')

#: How Python writes a float without a dot (``repr(1e-05) == '1e-05'``).
_DOTLESS_FLOAT = re.compile(r'[-+]?[0-9]+e[-+]?[0-9]+')

#: The array type names.
ARRAY_KINDS = ('byte_array', 'bool_array', 'integer_array', 'double_array', 'string_array')


@dataclass(frozen=True)
class ParameterSpec:
    """
    One node parameter: name, type, default and documentation.

    Attributes
    ----------
    name : str
        Parameter key, e.g. ``output.min``.
    type_ : str
        The only type the parameter accepts: rclpy's ``Parameter.Type`` name in lower case
        (``'bool'``, ``'integer'``, ``'double'``, ``'string'``, ``'double_array'``, ...).
    default : object or None
        Default value; ``None`` declares the parameter unset (no default).
    description : str
        What the parameter does, shown by ``ros2 param describe``.
    unit : str
        SI unit (REP 103), empty when dimensionless; appended to the description.
    value_range : tuple of (number, number) or None
        Inclusive range for double and integer parameters.
    read_only : bool
        True when the value can only be given at start-up.
    choices : tuple of str
        Allowed values of a string parameter; empty for any string.
    constraints : str
        Extra constraints in words (``ros2 param describe`` shows them).
    check : callable or None
        A check of the value beyond type, range and choices: called as
        ``check(name, value)``, it raises :class:`~mpi_ros.errors.ModelError` with the
        reason (e.g. ``start_state``'s form); not compared.

    """

    name: str
    type_: str
    default: Any
    description: str
    unit: str = ''
    value_range: Optional[Tuple[float, float]] = None
    read_only: bool = False
    choices: Tuple[str, ...] = ()
    constraints: str = ''
    check: Optional[Callable[[str, Any], Any]] = field(default=None, compare=False,
                                                       repr=False)

    def described(self) -> str:
        """
        Return the description ``ros2 param describe`` shows: text, unit and type.

        Returns
        -------
        str
            E.g. ``'Lower output limit [A] (type: double)'``.

        """
        unit = f' [{self.unit}]' if self.unit else ''
        return f'{self.description}{unit} (type: {self.type_})'

    def all_constraints(self) -> str:
        """
        Return the constraints in words: the choices (if any), then :attr:`constraints`.

        Returns
        -------
        str
            The descriptor's ``additional_constraints``.

        """
        if not self.choices:
            return self.constraints
        return ('one of: ' + ', '.join(self.choices) + '. ' + self.constraints).strip()


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
        Both read-only; the node builds its QoS with ``mpi_ros.nodes.qos.loop_qos``.

    """
    return (
        ParameterSpec('qos_depth', 'integer', 10000,
                      f'History depth (keep-last) of {topics}; 10000 holds 1 s of a '
                      '10 kHz stream (a stall that long loses nothing)',
                      value_range=(1, 100000), read_only=True),
        ParameterSpec('qos_reliability', 'string', 'reliable',
                      f'Reliability of {topics}: reliable (nothing lost) or best_effort '
                      '(less work per message at high rates; must match the peers: a '
                      'best_effort publisher does not reach a reliable subscription)',
                      choices=RELIABILITIES, read_only=True),
    )


def is_null(spec: ParameterSpec, kind: str, value: Any) -> bool:
    """
    Tell whether an incoming value is YAML ``null`` for a parameter that is not a string.

    Parameters
    ----------
    spec : ParameterSpec
        The declared spec of the parameter.
    kind : str
        The incoming value's type name (``'not_set'`` when unset).
    value : object
        The incoming value.

    Returns
    -------
    bool
        True for an unset value, and for one of :data:`NULL_STRINGS` when ``spec`` is
        not a string parameter.

    """
    if kind == 'not_set':
        return True
    return spec.type_ != 'string' and kind == 'string' and value in NULL_STRINGS


def normalized(spec: ParameterSpec, kind: str, value: Any) -> Tuple[str, Any]:
    """
    Return an incoming value with the types that ``ros2 param load`` loses restored.

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
    refused by :func:`check_value`.

    Parameters
    ----------
    spec, kind, value
        As for :func:`is_null`.

    Returns
    -------
    kind : str
        ``kind``, or ``spec.type_`` when the value was restored.
    value : object
        The value, restored or as it came.

    """
    if kind == spec.type_ or is_null(spec, kind, value):
        return kind, value
    if spec.type_ in ARRAY_KINDS and kind in ARRAY_KINDS and len(value) == 0:
        return spec.type_, []
    if spec.type_ == 'double' and kind == 'string' and _dotless(value):
        return 'double', float(value)
    if spec.type_ == 'double_array' and kind == 'string_array':
        items = list(value)
        if all(_dotless(item) for item in items):
            return 'double_array', [float(v) for v in items]
    if spec.type_ == 'double_array' and kind == 'string':
        parsed = _yaml_list(value)
        if (parsed and all(isinstance(v, float) or _dotless(v) for v in parsed)
                and any(_dotless(v) for v in parsed)):
            return 'double_array', [float(v) for v in parsed]
    return kind, value


def check_value(spec: ParameterSpec, kind: str, value: Any, *,
                allow_unset: bool = False) -> None:
    """
    Check one incoming value against its spec (type, finiteness, range, choices).

    Parameters
    ----------
    spec, kind, value
        As for :func:`is_null`.
    allow_unset : bool
        Accept an unset value (only while declaring a parameter without default).

    Raises
    ------
    ParameterRejected
        With a message that names the parameter, the expectation and the finding.

    """
    if is_null(spec, kind, value):
        if allow_unset:
            return
        msg = (f'{spec.name} cannot be unset (null) while the node runs; expected '
               f'{_TYPE_WORDS[spec.type_]}; give a value or leave the key out')
        raise ParameterRejected(msg)
    if kind != spec.type_:
        hint = _TYPE_HINTS.get((spec.type_, kind), '')
        shown = list(value) if kind in ARRAY_KINDS else value
        msg = (f'{spec.name} must be {_TYPE_WORDS[spec.type_]}{hint}; '
               f'found {kind} {shown!r}')
        raise ParameterRejected(msg)
    if spec.type_ == 'double':
        if not math.isfinite(value):
            msg = f'{spec.name} must be finite; found {value!r}'
            raise ParameterRejected(msg)
    if spec.type_ == 'double_array':
        for index, item in enumerate(value):
            if not math.isfinite(item):
                msg = f'{spec.name}[{index}] must be finite; found {item!r}'
                raise ParameterRejected(msg)
    if spec.value_range is not None and spec.type_ in ('double', 'integer'):
        low, high = spec.value_range
        if not low <= value <= high:
            unit = f' {spec.unit}' if spec.unit else ''
            msg = (f'{spec.name} must lie in [{low}, {high}]{unit}; found {value!r}')
            raise ParameterRejected(msg)
    if spec.choices and value not in spec.choices:
        msg = (f'{spec.name} must be one of {", ".join(spec.choices)}; found {value!r}')
        raise ParameterRejected(msg)
    if spec.check is not None:
        try:
            spec.check(spec.name, value)
        except ModelError as err:
            raise ParameterRejected(str(err)) from err


def check_values(specs: Mapping[str, ParameterSpec], values: Iterable[Tuple[str, str, Any]],
                 *, allow_unset: bool = False) -> None:
    """
    Check every incoming value against its spec; an undeclared name is rejected too.

    Parameters
    ----------
    specs : mapping of str to ParameterSpec
        The node's specs by name (:func:`specs_by_name`).
    values : iterable of (str, str, object)
        Incoming values: name, type name, value.
    allow_unset : bool
        Accept unset values (see :func:`check_value`).

    Raises
    ------
    ParameterRejected
        At the first value that fails, naming it.

    """
    for name, kind, value in values:
        spec = specs.get(name)
        if spec is None and name in RCLPY_PARAMETERS:
            msg = (f"{name} is rclpy's own parameter and cannot be changed on this "
                   'node; leave it out of the request')
            raise ParameterRejected(msg)
        if spec is None:
            msg = f'{name} is not a parameter of this node'
            raise ParameterRejected(msg)
        check_value(spec, kind, value, allow_unset=allow_unset)


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


def plain_value(value: Any) -> Any:
    """Turn rclpy's array values (array.array, tuples) into lists (the dicts of the core)."""
    if value is None or isinstance(value, (bool, int, float, str)):
        return value
    return list(value)


def typed_value(name: str, value: Any) -> Tuple[str, Any]:
    """
    Return the parameter type name and value a model key is sent as (the identifier's push).

    Parameters
    ----------
    name : str
        The key, for the message.
    value : int, float, str or sequence of float
        Its value (numpy scalars too).

    Returns
    -------
    kind : str
        ``'integer'`` for an integer (``model.output_sign``), ``'double'`` for another
        scalar, ``'string'`` for text (``model.input_quantity``), ``'double_array'`` for a
        sequence.
    value : int, float or list of float
        The value as that type.

    Raises
    ------
    ParameterPushError
        For a bool (not a number).

    Examples
    --------
    >>> typed_value('model.output_sign', -1), typed_value('model.dead_time', 0.5)
    (('integer', -1), ('double', 0.5))

    """
    if isinstance(value, bool):
        msg = f'{name} must be a number or a list of numbers; found bool {value!r}'
        raise ParameterPushError(msg)
    if isinstance(value, (int, np.integer)):
        return 'integer', int(value)
    if isinstance(value, (float, np.floating)):
        return 'double', float(value)
    if isinstance(value, str):
        return 'string', value
    return 'double_array', [float(v) for v in value]


def request_steps(names: Sequence[str], groups: Iterable[Iterable[str]],
                  answered: Collection[int] = ()) -> List[List[int]]:
    """
    Split a ``set_parameters`` request into its steps: coupled keys together.

    Parameters
    ----------
    names : sequence of str
        The request's names, in order.
    groups : iterable of iterable of str
        Names that are set together (a key belongs to the first group naming it).
    answered : collection of int
        Positions answered already (they take no step).

    Returns
    -------
    list of list of int
        The positions of each step, in order: the keys of one group together at the
        position of the group's first key, every other key alone.

    Examples
    --------
    >>> request_steps(['enabled', 'model.a', 'output.min', 'model.b'], [('model.a', 'model.b')])
    [[0], [1, 3], [2]]

    """
    sets = [frozenset(group) for group in groups]
    done = set(answered)
    steps = []
    for i, name in enumerate(names):
        if i in done:
            continue
        group = next((g for g in sets if name in g), frozenset())
        step = [j for j, other in enumerate(names) if j not in done and (j == i or other in group)]
        done.update(step)
        steps.append(step)
    return steps


def _dotless(item: Any) -> bool:
    """Tell whether ``item`` is a string in Python's dot-less float notation (``1e-05``)."""
    return isinstance(item, str) and _DOTLESS_FLOAT.fullmatch(item.strip()) is not None


def _yaml_list(text: str) -> Optional[List[Any]]:
    try:
        value = yaml.safe_load(text)
    except yaml.YAMLError:
        return None
    return value if isinstance(value, list) else None
