# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
The compensator nodes' parameters: Gamma, the operating point, the effects, limits, switches.

The single-axis node (:func:`compensator_parameters`) and the multi-axis node
(:func:`multi_axis_parameters`, :func:`axis_parameters`, :func:`axis_limit_parameters`)
declare these specs; the effect keys are read from the registry
:data:`mpi_ros.extensions.EFFECTS` when a node declares them.  A multi-axis node's keys
are ``axis<k>.`` + a single-axis key (:class:`AxisKeys`, :func:`merge_axes`).
"""

from dataclasses import dataclass, replace
from typing import Any, Iterable, List, Mapping, Sequence, Tuple

from .spec import loop_qos_parameters, ParameterSpec
from ..compensation.adaptation import CHILD_NICE, PRIORITIES
from ..compensation.updates import axis_key, LIMIT_KEYS, model_keys
from ..errors import ParameterRejected
from ..extensions import EFFECTS
from ..operators.model import HYSTERESIS_INITIAL_STATES, IDENTIFIED_INPUT_RANGE, INPUT_OFFSET, \
    MODEL_KEYS, OPERATING_POINT_DEFAULTS, OUTPUT_OFFSET, OUTPUT_SIGN, RECORD_START_STATES
from ..operators.start import START_CHOICES, StartState
from ..units import INPUT_QUANTITIES, INPUT_QUANTITY_KEY

__all__ = [
    'ADAPTATION_PARAMETERS', 'AUTOSTART', 'AXES', 'DEAD_TIME_PREDICTION', 'DIAGNOSTICS_PERIOD',
    'ENABLED',
    'INPUT_MESSAGE', 'INPUT_QUANTITY', 'JOINTS', 'LIMIT_PARAMETERS', 'MESSAGE_TIME',
    'MODEL_PARAMETERS', 'OUTPUT_LAYOUT', 'SAMPLE_PERIOD', 'START_STATE', 'WIRING',
    'AxisKeys', 'axis_limit_parameters', 'axis_parameters', 'compensator_parameters',
    'extension_parameters', 'merge_axes', 'multi_axis_parameters', 'single_axis_keys',
    'wants_multi_axis',
]

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
    ParameterSpec(
        IDENTIFIED_INPUT_RANGE, 'double_array', None,
        "The identification record's lowest and highest input (mpi-ros identify writes it): "
        "where start_state rest_low's sweep turns, and the range output.min/output.max are "
        "judged against; unset: read from the model's thresholds", 'A',
        constraints='two numbers in increasing order, or empty; part of the model: '
                    'validated with the other model.* keys'),
)


#: What the actuator input is: it names the unit of the commands in messages.
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
    'dependence, thermal drift) use it when a message has no usable time, and a dead '
    "time's prediction always (dead_time_prediction)",
    's', value_range=(1.0e-6, 10.0))

START_STATE = ParameterSpec(
    'start_state', 'string', 'rest_low',
    'Where the actuator is before the first command: rest_low (at rest after a sweep up to '
    'the highest identified input and down to the lowest, within output.min and output.max;'
    ' a mode at rest), rest_high (after a sweep down and up to the highest), record (the '
    "identification record's start, record_start.*), or the play states z_H0 [A] separated"
    ' by commas; taken when the core is built (configure), logged at activation',
    constraints=f'{", ".join(START_CHOICES)}, or numbers separated by commas',
    check=lambda name, value: StartState.parse(value, option=name))

MESSAGE_TIME = ParameterSpec(
    'message_time', 'string', 'nominal',
    'Time base of the desired displacements for the lags of extended models, never the '
    'jittered arrival times (a lead filter would differentiate them): nominal (every sample '
    'sample_period after the one before, across messages) or arrival (the same, but a gap '
    'of more than 100 sample periods and 0.1 s between two messages is a pause of the '
    'stream, counted in whole sample periods, for slow lags such as creep)',
    choices=('arrival', 'nominal'), read_only=True)

DEAD_TIME_PREDICTION = ParameterSpec(
    'dead_time_prediction', 'bool', True,
    "true: compensate a model's dead time (model.dead_time) by prediction: Gamma^-1 of the "
    "desired displacement extrapolated the dead time ahead on the stream's own time base "
    '(sample_period spacing; a least-squares line over at least twice the dead time, its '
    'reach bounded by the median step of the window, so a step is not extrapolated; kept in '
    "the model's range); false: Gamma^-1 of the desired displacement itself (the dead time "
    'stays in the tracking error); taken when the core is built (configure)',
    read_only=True)

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
        'adaptation.priority', 'string', PRIORITIES[0],
        "The adaptation process's CPU priority: idle, only CPU time nothing else wants "
        '(the command path keeps its latency; if the machine leaves it too little, it is '
        f'restarted at low by itself and says so); low, niceness {CHILD_NICE} below the node'
        ' (a share of a busy machine). A thread (adaptation.process false) has the'
        " node's priority", choices=PRIORITIES, read_only=True),
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
        DEAD_TIME_PREDICTION,
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
                               DEAD_TIME_PREDICTION, DIAGNOSTICS_PERIOD) + (
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
