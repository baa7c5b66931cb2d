# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Node parameters as plain data: specs, the forms a value arrives in, and the checks.

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

from dataclasses import dataclass, replace
import math
import re
from typing import Any, Collection, Iterable, List, Mapping, Optional, Sequence, Tuple

import numpy as np
import yaml

from .updates import axis_key, LIMIT_KEYS, model_keys
from ..errors import ModelError, ParameterPushError, ParameterRejected
from ..extensions import EFFECTS
from ..operators.model import HYSTERESIS_INITIAL_STATES, INPUT_OFFSET, MODEL_KEYS, \
    OPERATING_POINT_DEFAULTS, OUTPUT_OFFSET, OUTPUT_SIGN, RECORD_START_STATES
from ..operators.start import START_CHOICES, StartState
from ..units import INPUT_QUANTITIES, INPUT_QUANTITY_KEY

__all__ = [
    'ADAPTATION_PARAMETERS', 'AUTOSTART', 'AXES', 'DIAGNOSTICS_PERIOD', 'ENABLED',
    'INPUT_MESSAGE', 'INPUT_QUANTITY', 'JOINTS',
    'LIMIT_PARAMETERS', 'MESSAGE_TIME', 'OUTPUT_LAYOUT', 'SAMPLE_PERIOD', 'START_STATE',
    'WIRING',
    'axis_limit_parameters', 'axis_parameters', 'compensator_parameters',
    'multi_axis_parameters',
    'ARRAY_KINDS', 'MODEL_PARAMETERS', 'NULL_STRINGS', 'RCLPY_PARAMETERS', 'RELIABILITIES',
    'AxisKeys', 'ParameterSpec', 'check_value', 'check_values', 'extension_parameters',
    'is_null', 'loop_qos_parameters', 'merge_axes', 'normalized', 'plain_value',
    'request_steps', 'single_axis_keys', 'specs_by_name', 'typed_value', 'wants_multi_axis',
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


#: The four arrays of Gamma = S o H (a model needs all of them, no defaults), the operating
#: point, and the identification record's start (optional; used by ``start_state: record``).

MODEL_PARAMETERS = (
    ParameterSpec(
        'model.hysteresis.thresholds', 'double_array', None,
        'Play-operator thresholds r_H of the hysteresis operator H (5), ascending, '
        'first one 0', 'A'),
    ParameterSpec(
        'model.hysteresis.weights', 'double_array', None,
        'Play-operator weights w_H, one per threshold, w_H0 > 0 and the rest >= 0 (8)', ''),
    ParameterSpec(
        'model.superposition.thresholds', 'double_array', None,
        'One-sided dead-zone thresholds r_S of the superposition operator S (18), '
        'ascending, exactly one 0', 'A'),
    ParameterSpec(
        'model.superposition.weights', 'double_array', None,
        'Dead-zone weights w_S, one per threshold, satisfying (19)', 'm/A'),
    ParameterSpec(
        INPUT_OFFSET, 'double', OPERATING_POINT_DEFAULTS[INPUT_OFFSET],
        'Operating point: input x0 at which the plays of H are centred; the model is '
        'y = y0 + sign * S[H[x - x0]]', 'A',
        constraints='part of the model: validated with the other model.* keys'),
    ParameterSpec(
        OUTPUT_OFFSET, 'double', OPERATING_POINT_DEFAULTS[OUTPUT_OFFSET],
        'Operating point: sensor reading y0 the model adds (the sensor zero)', 'm',
        constraints='part of the model: validated with the other model.* keys'),
    ParameterSpec(
        OUTPUT_SIGN, 'integer', OPERATING_POINT_DEFAULTS[OUTPUT_SIGN],
        'Operating point: +1 when the sensor rises as the actuator extends, -1 when it '
        'falls',
        constraints='1 or -1; part of the model: validated with the other model.* keys'),
    ParameterSpec(
        RECORD_START_STATES, 'double_array', None,
        "The identification record's start: the play operators' states z_H0 at its first "
        'sample, one per threshold (mpi-ros identify writes it); the node starts there only '
        'with start_state record', 'A'),
    ParameterSpec(
        HYSTERESIS_INITIAL_STATES, 'double_array', None,
        f'Where files written before {RECORD_START_STATES} hold the record start (read as '
        'it when that is unset)', 'A'),
)


#: What the actuator input is (issue 27): it names the unit of the commands in messages.
INPUT_QUANTITY = ParameterSpec(
    INPUT_QUANTITY_KEY, 'string', 'current',
    'The actuator input the model maps to displacement: current (commands in A, a coil) or '
    'voltage (commands in V, a piezo stack); written by mpi-ros identify from the unit of '
    'the input; names the unit in messages (the arithmetic is the same); a whole model '
    'pushed without it is a current model',
    choices=tuple(INPUT_QUANTITIES))


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
    return tuple(ParameterSpec(p.key, p.kind, None, p.description, p.unit,
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


#: The compensator nodes' own parameters.

#: The ``axes`` parameter, declared by both compensator nodes.
AXES = ParameterSpec(
    'axes', 'integer', 1,
    'Number of actuators this node serves: 1 = one actuator on the Float64 topics '
    'desired_displacement / current_command with the model.* keys; N > 1 = N actuators on '
    'the Float64MultiArray topics desired_displacements / current_commands (samples x '
    'axes) with the keys axis0.model.* ... axis<N-1>.model.*',
    value_range=(1, 1024), read_only=True)

#: ``output.min`` and ``output.max``: the safe current range of every command.
LIMIT_PARAMETERS = (
    ParameterSpec(
        'output.min', 'double', 0.0,
        'Lowest current command ever published (safe actuator range); '
        'must be below output.max', 'A', value_range=(-1.0e3, 1.0e3)),
    ParameterSpec(
        'output.max', 'double', 2.0,
        'Highest current command ever published (safe actuator range); '
        'must be above output.min', 'A', value_range=(-1.0e3, 1.0e3)),
)

AUTOSTART = ParameterSpec(
    'autostart', 'bool', True,
    'Managed (lifecycle) node: true = configure and activate at start-up (a plain node '
    'to ros2 run and launch); false = start unconfigured and wait for the lifecycle '
    'transitions (ros2 lifecycle set <node> configure, then activate; a lifecycle manager)',
    read_only=True)

ENABLED = ParameterSpec(
    'enabled', 'bool', True,
    'true: invert the MPI model (27); false: pass the best linear map of the '
    'model instead, for comparison')

DIAGNOSTICS_PERIOD = ParameterSpec(
    'diagnostics_period', 'double', 1.0,
    'Period of the DiagnosticArray on /diagnostics', 's', value_range=(0.01, 3600.0))

SAMPLE_PERIOD = ParameterSpec(
    'sample_period', 'double', 1.0e-3,
    'Nominal interval between desired displacements; extended models (creep, rate '
    'dependence, thermal drift) use it when a message has no usable time',
    's', value_range=(1.0e-6, 10.0))

START_STATE = ParameterSpec(
    'start_state', 'string', 'rest_low',
    'Where the actuator is before the first command: rest_low (at rest after a descent to '
    'the lowest identified input, raised to output.min; a mode at rest), rest_high (after an '
    "ascent to the highest, lowered to output.max), record (the identification record's "
    'start, record_start.*), or the play states z_H0 [A] separated by commas; taken when '
    'the core is built (configure), logged at activation',
    constraints=f'{", ".join(START_CHOICES)}, or numbers separated by commas')

MESSAGE_TIME = ParameterSpec(
    'message_time', 'string', 'nominal',
    'Time base of the desired displacements for the lags of extended models, never the '
    'jittered arrival times (a lead filter would differentiate them): nominal (every sample '
    'sample_period after the one before, across messages) or arrival (the same, but a gap '
    'of more than 100 sample periods and 0.1 s between two messages is a pause of the '
    'stream, counted in whole sample periods, for slow lags such as creep)',
    choices=('arrival', 'nominal'), read_only=True)

#: The joint name of each axis (ros2_control); read-only.
JOINTS = ParameterSpec(
    'joints', 'string_array', None,
    'Joint name of each axis, in axis order: the joints parameter of the ros2_control '
    'forward_command_controller that takes current_commands (output_layout flat), and the '
    'names input_message joint_state maps by; unset: no names',
    read_only=True, constraints='as many unique, non-empty names as axes')

#: What current_commands carries; read-only.
OUTPUT_LAYOUT = ParameterSpec(
    'output_layout', 'string', 'samples_x_axes',
    'Layout of current_commands: samples_x_axes (one message per input message, '
    'layout.dim = [samples, axes]) or flat (what ros2_control forward_command_controller '
    'takes on ~/commands: one message per sample holding one value per axis in axis (joints) '
    'order, empty layout.dim, data_offset 0)',
    choices=('samples_x_axes', 'flat'), read_only=True)

#: What the node subscribes to; read-only.
INPUT_MESSAGE = ParameterSpec(
    'input_message', 'string', 'array',
    'Input: array (std_msgs/Float64MultiArray, samples x axes, on desired_displacements) '
    'or joint_state (sensor_msgs/JointState on desired_joint_states: the position [m] of '
    'each joint, mapped by name to the joints order; needs joints; a message missing a '
    'joint is refused and counted, missing_joints)',
    choices=('array', 'joint_state'), read_only=True)

#: The ros2_control options, declared by the multi-axis node only.
WIRING = (JOINTS, OUTPUT_LAYOUT, INPUT_MESSAGE)

#: Online adaptation (:mod:`mpi_ros.compensation.adaptation`); read-only: given at start-up.
ADAPTATION_PARAMETERS = (
    ParameterSpec(
        'adaptation.enabled', 'bool', False,
        'true: subscribe to the measured displacement (displacement, std_msgs/Float64, one '
        'reading per command, in order) and adapt the running model: recursive QP on '
        'forgetting Gram matrices, a candidate applied through the ordinary parameter '
        'validation only when it is better on the newest readings it was not fitted to',
        read_only=True),
    ParameterSpec(
        'adaptation.forgetting_time', 'double', 20.0,
        'Memory of the recursive fit (exponential forgetting)', 's',
        value_range=(0.1, 1.0e5), read_only=True),
    ParameterSpec(
        'adaptation.offset_time', 'double', 1.0,
        'Memory of the operating point (the constant term): a zero drifts faster than a '
        'shape changes', 's', value_range=(0.01, 1.0e5), read_only=True),
    ParameterSpec(
        'adaptation.holdout', 'double', 5.0,
        'Newest readings held out of the fit; a candidate must win there', 's',
        value_range=(0.01, 1.0e4), read_only=True),
    ParameterSpec(
        'adaptation.period', 'double', 1.0,
        'Interval between candidate solves', 's', value_range=(0.01, 1.0e4), read_only=True),
    ParameterSpec(
        'adaptation.margin', 'double', 0.1,
        "A candidate's held-out RMS error must be at most 1 - margin of the running model's",
        value_range=(0.0, 0.99), read_only=True),
    ParameterSpec(
        'adaptation.max_step', 'double', 0.05,
        'Largest change of the modelled displacement per update, fraction of the '
        'displacement range', value_range=(1.0e-6, 1.0), read_only=True),
    ParameterSpec(
        'adaptation.min_excitation', 'double', 0.3,
        'Fraction of the identified input range the recent commands must span; below it '
        'adaptation pauses (a hold, a tiny motion)', value_range=(0.0, 0.99),
        read_only=True),
    ParameterSpec(
        'adaptation.delay', 'integer', 0,
        'Samples by which the displacement readings lag the commands (0: lock step, the '
        'k-th reading answers the k-th command)', value_range=(0, 100000), read_only=True),
    ParameterSpec(
        'adaptation.process', 'bool', True,
        'true: the adaptation fits in a child process (the command path never waits for '
        'it); false: in a thread of the node, sharing the interpreter lock',
        read_only=True),
    ParameterSpec(
        'adaptation.hysteresis', 'bool', False,
        "false: adapt S' (gain, shape) and the operating point; true: the weights of H too",
        read_only=True),
)


def compensator_parameters() -> Tuple[ParameterSpec, ...]:
    """
    Return the node's parameter specs, the effect keys read from the registry now.

    Returns
    -------
    tuple of ParameterSpec
        Gamma and the operating point, every registered effect's keys, the limits and
        the node's switches (also as the module attribute ``PARAMETERS``).

    """
    return MODEL_PARAMETERS + extension_parameters() + (INPUT_QUANTITY,) + LIMIT_PARAMETERS + (
        ENABLED,
        SAMPLE_PERIOD,
        START_STATE,
        MESSAGE_TIME,
        DIAGNOSTICS_PERIOD,
        *loop_qos_parameters('desired_displacement and current_command'),
        AXES,
        AUTOSTART,
    ) + ADAPTATION_PARAMETERS


def multi_axis_parameters() -> Tuple[ParameterSpec, ...]:
    """
    Return the multi-axis node's node-wide specs (the single-axis node's, less its model keys).

    Returns
    -------
    tuple of ParameterSpec
        The limits, the switches, the loop QoS and ``autostart``.

    """
    return LIMIT_PARAMETERS + (ENABLED, SAMPLE_PERIOD, START_STATE, MESSAGE_TIME,
                               DIAGNOSTICS_PERIOD) + (
        loop_qos_parameters('desired_displacements and current_commands')) + (AUTOSTART,)


def axis_parameters(axes: int) -> Tuple[ParameterSpec, ...]:
    """
    Return the specs of every axis's model keys.

    Parameters
    ----------
    axes : int
        Number of axes.

    Returns
    -------
    tuple of ParameterSpec
        ``MODEL_PARAMETERS`` (Gamma and the operating point) and the effect registry's keys
        (unset, read from the registry now) once per axis, renamed.

    """
    specs = MODEL_PARAMETERS + extension_parameters() + (INPUT_QUANTITY,)
    return tuple(replace(spec, name=axis_key(k, spec.name),
                         description=f'Axis {k}: {spec.description}')
                 for k in range(axes) for spec in specs)


def axis_limit_parameters(axes: int) -> Tuple[ParameterSpec, ...]:
    """
    Return ``axis<k>.output.min`` / ``.max`` per axis: unset (node-wide) by default.

    ``axes`` is the number of axes; two specs per axis are returned.

    """
    words = {'output.min': ('lowest', 'below'), 'output.max': ('highest', 'above')}
    specs = []
    for k in range(axes):
        for spec in LIMIT_PARAMETERS:
            word, side = words[spec.name]
            other = 'output.max' if spec.name == 'output.min' else 'output.min'
            specs.append(replace(
                spec, name=axis_key(k, spec.name), default=None,
                description=(f'Axis {k}: {word} current command of this axis (its '
                             f'safe actuator range); unset: {spec.name}; must be {side} '
                             f'axis{k}.{other} (or {other} when that is unset)')))
    return tuple(specs)


@dataclass(frozen=True)
class AxisKeys:
    """
    The parameter names of the axes of a multi-axis compensator node.

    Attributes
    ----------
    prefixes : tuple of str
        Each axis's model prefix, ``axis<k>.``.
    limits : tuple of (str, str)
        Each axis's own ``output.min`` and ``output.max`` keys.

    Examples
    --------
    >>> keys = AxisKeys.of(2)
    >>> keys.prefixes
    ('axis0.', 'axis1.')
    >>> keys.all_limits
    ('output.min', 'output.max', 'axis0.output.min', 'axis0.output.max', \
'axis1.output.min', 'axis1.output.max')

    """

    prefixes: Tuple[str, ...]
    limits: Tuple[Tuple[str, str], ...]

    @classmethod
    def of(cls, axes: int) -> 'AxisKeys':
        """Return the keys of ``axes`` axes."""
        return cls(tuple(axis_key(k, '') for k in range(axes)),
                   tuple((axis_key(k, 'output.min'), axis_key(k, 'output.max'))
                         for k in range(axes)))

    @property
    def all_limits(self) -> Tuple[str, ...]:
        """Return the node-wide limit keys, then each axis's."""
        return LIMIT_KEYS + tuple(key for keys in self.limits for key in keys)

    def group(self) -> Tuple[str, ...]:
        """
        Return the keys one ``set_parameters`` request sets together.

        Every model key of every axis (read from the effect registry now) and every limit
        key: the models and limits of a request succeed or fail together.
        """
        return tuple(prefix + key for prefix in self.prefixes
                     for key in model_keys()) + self.all_limits

    def effective_limits(self, values: Mapping[str, Any]) -> Tuple[List[float], List[float]]:
        """
        Return each axis's applied range [A]: its own keys, else the node-wide ones.

        Parameters
        ----------
        values : mapping of str to value
            The node's values of :attr:`all_limits` (None: unset).

        Returns
        -------
        lows, highs : list of float
            ``output.min`` and ``output.max`` of each axis.

        """
        pairs = [tuple(values[key] if values[key] is not None else values[common]
                       for key, common in zip(keys, LIMIT_KEYS)) for keys in self.limits]
        return [pair[0] for pair in pairs], [pair[1] for pair in pairs]


def wants_multi_axis(given: Mapping[str, Any]) -> bool:
    """
    Tell whether a compensator's start-up values ask for the multi-axis node.

    Parameters
    ----------
    given : mapping of str to value
        The values given at start (``-p``, ``--params-file``) by name; a missing name
        was not given.

    Returns
    -------
    bool
        True for ``axes`` > 1 and for any ros2_control wiring (``joints`` given,
        ``output_layout: flat`` or ``input_message: joint_state``: one joint is one axis).

    Examples
    --------
    >>> wants_multi_axis({'axes': 1}), wants_multi_axis({'output_layout': 'flat'})
    (False, True)

    """
    axes, joints = given.get('axes'), given.get('joints')
    return bool((isinstance(axes, int) and axes > 1)
                or (isinstance(joints, (list, tuple)) and len(joints) > 0)
                or given.get('output_layout') == 'flat'
                or given.get('input_message') == 'joint_state')


def single_axis_keys(names: Iterable[str]) -> List[str]:
    """
    Return the single-axis model keys among parameter names (a multi-axis node's mistake).

    Parameters
    ----------
    names : iterable of str
        Parameter names given to a node (``-p``, ``--params-file``).

    Returns
    -------
    list of str
        The names that are a single-axis model's keys (``model.*`` of Gamma, the operating
        point, an effect, ``model.input_quantity``), sorted.

    Examples
    --------
    >>> single_axis_keys(['axes', 'model.dead_time', 'axis0.model.dead_time'])
    ['model.dead_time']

    """
    keys = set(model_keys()) | {INPUT_QUANTITY_KEY}
    return sorted(name for name in names if name in keys)


def merge_axes(per_axis: Sequence[Mapping[str, Any]]) -> dict[str, Any]:
    """
    Merge single-axis parameter sets (``mpi-ros identify`` files) into one multi-axis set.

    Parameters
    ----------
    per_axis : sequence of mapping
        One flat parameter set per axis, in axis order: its model keys and its
        ``output.min`` / ``output.max``.

    Returns
    -------
    dict
        ``axes`` and, per axis ``k``, ``axis<k>.model.*`` and ``axis<k>.output.min`` /
        ``axis<k>.output.max``: what the multi-axis compensator reads.

    Raises
    ------
    ParameterRejected
        With fewer than two sets, a set without the keys of Gamma, or with keys a
        multi-axis node would not read (already per axis, or other node parameters).

    Examples
    --------
    >>> gamma = dict.fromkeys(MODEL_KEYS, [0.0])
    >>> merged = merge_axes([dict(gamma, **{'output.max': 1.5}), gamma])
    >>> merged['axes'], merged['axis0.output.max'], 'axis1.output.max' in merged
    (2, 1.5, False)

    """
    if len(per_axis) < 2:
        msg = f'merging axes needs at least two parameter sets; found {len(per_axis)}'
        raise ParameterRejected(msg)
    keys = set(model_keys()) | {INPUT_QUANTITY_KEY} | set(LIMIT_KEYS)
    merged: dict[str, Any] = {'axes': len(per_axis)}
    for axis, parameters in enumerate(per_axis):
        missing = [key for key in MODEL_KEYS if key not in parameters]
        if missing:
            msg = f'axis {axis} has no model: missing {", ".join(missing)}'
            raise ParameterRejected(msg)
        foreign = sorted(set(parameters) - keys)
        if foreign:
            msg = (f'axis {axis}: {", ".join(foreign)} are not single-axis model keys or '
                   'output limits; give files written by mpi-ros identify (one actuator each)')
            raise ParameterRejected(msg)
        merged.update({axis_key(axis, key): value for key, value in parameters.items()})
    return merged


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
    if spec.name == START_STATE.name:
        try:
            StartState.parse(value, option=spec.name)
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
