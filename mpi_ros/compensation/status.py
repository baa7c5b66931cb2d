# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
What the compensator nodes report on ``/diagnostics``: levels, messages and key-values.

Computed from plain counters and values; the ROS side only wraps the result in a
``diagnostic_msgs/DiagnosticArray`` (its ``level`` is the byte of :data:`OK` or
:data:`WARN`).  A period WARNs after lost messages, incompatible peers, a queue more than
half full, bad inputs or a missing model; else it is OK.
"""

from collections.abc import Iterable, Mapping, Sequence
from typing import Any

from .compensator import kind_of
from .screening import describe_faults, new_faults
from .updates import axis_key

__all__ = ['LOSS_ADVICE', 'OK', 'RateWindow', 'WARN', 'lifecycle_status', 'loss_problems',
           'multi_axis_status', 'multi_axis_values', 'single_axis_status', 'single_axis_values',
           'state_after', 'status_values']

#: diagnostic_msgs/DiagnosticStatus levels.
OK = 0
WARN = 1

#: What to do about lost messages (diagnostics and log).
LOSS_ADVICE = ('the node did not keep up and its input queue (qos_depth) overflowed, or the '
               'publisher dropped them; raise qos_depth, give the node a core of its own '
               '(taskset), or send chunks of samples (docs/reliability.md)')

Status = tuple[int, str]

#: The lifecycle state a successful transition ends in (any other: ``unconfigured``).
_STATE_AFTER = {'configure': 'inactive', 'activate': 'active', 'deactivate': 'inactive',
                'shutdown': 'finalized'}


class RateWindow:
    """
    The diagnostics period of a node: its message rate and the counters at its start.

    Parameters
    ----------
    now : float
        Steady time [s] the first period starts at.

    Examples
    --------
    >>> window = RateWindow(10.0)
    >>> window.close(12.0, 500, {'messages_in': 500})
    (250.0, {})
    >>> window.close(13.0, 600, {'messages_in': 600})
    (100.0, {'messages_in': 500})

    """

    def __init__(self, now: float) -> None:
        self._start: tuple[float, int, dict[str, int]] = (now, 0, {})

    def close(self, now: float, messages_in: int,
              counters: dict[str, int]) -> tuple[float, dict[str, int]]:
        """
        Close the period at ``now`` and start the next one.

        Parameters
        ----------
        now : float
            Steady time [s].
        messages_in : int
            Messages received so far.
        counters : dict of str to int
            The node's counters now (the next period's start).

        Returns
        -------
        rate : float
            Messages per second in the period (0 for an empty one).
        before : dict of str to int
            The counters at the period's start (empty for the first one).

        """
        start, count, before = self._start
        elapsed = now - start
        rate = (messages_in - count) / elapsed if elapsed > 0.0 else 0.0
        self._start = (now, messages_in, counters)
        return rate, before


def state_after(transition: str) -> str:
    """
    Return the lifecycle state a successful transition ends in.

    Parameters
    ----------
    transition : str
        ``configure``, ``activate``, ``deactivate``, ``cleanup``, ``shutdown``.

    Returns
    -------
    str
        ``inactive``, ``active``, ``inactive``, ``unconfigured``, ``finalized``.

    """
    return _STATE_AFTER.get(transition, 'unconfigured')


def loss_problems(counters: Mapping[str, int], before: Mapping[str, int], depth: int,
                  backlog: int, what: str) -> list[str]:
    """
    Describe the losses of a diagnostics period.

    Parameters
    ----------
    counters, before : mapping of str to int
        The node's counters now and at the start of the period.
    depth : int
        ``qos_depth``.
    backlog : int
        Most messages that waited at once in the period.
    what : str
        What the messages carry, e.g. ``desired displacements``.

    Returns
    -------
    list of str
        One sentence per problem (empty: none): lost messages, incompatible peers,
        a queue more than half full.  Any of them makes the period WARN.

    """
    lost = counters['messages_lost'] - before.get('messages_lost', 0)
    incompatible = counters['incompatible_qos'] - before.get('incompatible_qos', 0)
    parts = []
    if lost > 0:
        parts.append(f'{lost} {what} lost in the last period '
                     f'({counters["messages_lost"]} in all): {LOSS_ADVICE}')
    if incompatible > 0:
        parts.append(f'{incompatible} peers with incompatible QoS in the last period '
                     '(they exchange nothing with this node; see the log)')
    if not parts and depth > 1 and backlog > depth // 2:
        parts.append(f'input queue more than half full ({backlog} of qos_depth={depth} '
                     'messages waiting at once): the node is falling behind; messages '
                     'are lost when it fills')
    return parts


def single_axis_status(losses: Sequence[str], counters: Mapping[str, int],
                       before: Mapping[str, int], *, has_model: bool, enabled: bool,
                       last_malformed: str = '') -> Status:
    """
    Return the level and message of a single-axis compensator's period.

    WARN after a period with losses (:func:`loss_problems`) or malformed messages, while
    unconfigured (``no model``) and after a period with non-finite, out-of-range or clamped
    inputs; else OK.

    Parameters
    ----------
    losses : sequence of str
        :func:`loss_problems` of the period.
    counters, before : mapping of str to int
        The node's counters now and at the start of the period.
    has_model : bool
        Whether a model is installed.
    enabled : bool
        The ``enabled`` parameter.
    last_malformed : str
        Why the last malformed message was dropped (``''``: none yet).

    Returns
    -------
    level : int
        :data:`OK` or :data:`WARN`.
    message : str
        What the period showed.

    """
    faults = new_faults(counters, before)
    if losses:
        return WARN, '; '.join(losses)
    malformed = counters.get('malformed', 0) - before.get('malformed', 0)
    if malformed:
        return WARN, (f'{malformed} malformed messages dropped in the last period (last: '
                      f'{last_malformed})')
    if not has_model:
        return WARN, ('no model: unconfigured, no commands published; give all four model.* '
                      'keys of Gamma in one request (ros2 param load, '
                      'set_parameters_atomically)')
    if any(faults.values()):
        return WARN, f'{describe_faults(faults)} in the last period'
    if not enabled:
        return OK, 'compensation disabled: best linear map'
    return OK, 'compensating'


def multi_axis_status(losses: Sequence[str], counters: Mapping[str, int],
                      before: Mapping[str, int], *, what: str, last_malformed: str,
                      last_missing: str, missing_axes: Sequence[int]) -> Status:
    """
    Return the level and message of a multi-axis compensator's period.

    WARN after a period with losses, malformed arrays, JointStates missing a joint or
    non-finite / out-of-range / clamped inputs, and while an axis has no model; else OK.

    Parameters
    ----------
    losses, counters, before
        As for :func:`single_axis_status`.
    what : str
        What the messages carry.
    last_malformed, last_missing : str
        The last malformed message's and the last incomplete JointState's reasons.
    missing_axes : sequence of int
        The axes without a model.

    Returns
    -------
    (int, str)
        Level and message, as :func:`single_axis_status`.

    """
    problems = list(losses)
    malformed = counters['malformed'] - before.get('malformed', 0)
    if malformed:
        problems.append(f'{malformed} malformed {what} in the last period (last: '
                        f'{last_malformed})')
    missing_joints = counters.get('missing_joints', 0) - before.get('missing_joints', 0)
    if missing_joints:
        problems.append(f'{missing_joints} JointState messages missing a joint of joints '
                        f'in the last period, refused (last: {last_missing})')
    faults = new_faults(counters, before)
    if any(faults.values()):
        problems.append(f'{describe_faults(faults)} in the last period')
    if missing_axes:
        problems.append(f'no model for axis {", ".join(map(str, missing_axes))}: '
                        'unconfigured, no commands published; give every axis its '
                        'axis<k>.model.* keys')
    if problems:
        return WARN, '; '.join(problems)
    return OK, 'compensating'


def lifecycle_status(status: Status | None, state: str) -> Status:
    """
    Return a period's status with the lifecycle state said first when not ``active``.

    Parameters
    ----------
    status : (int, str) or None
        The node's status of the period; None while no model was loaded.
    state : str
        The lifecycle state.

    Returns
    -------
    level : int
        The status's level (:data:`OK` when None).
    message : str
        ``lifecycle state <state>: no commands published`` first when not active.

    """
    level, message = (OK, 'no model loaded') if status is None else status
    if state != 'active':
        note = f'lifecycle state {state}: no commands published'
        message = note if level == OK else f'{note}; {message}'
    return level, message


def status_values(counters: Mapping[str, int], own: Mapping[str, Any], **common: Any,
                  ) -> dict[str, Any]:
    """
    Return the key-values of a diagnostics status, in the order they are reported.

    Parameters
    ----------
    counters : mapping of str to int
        The node's counters (first).
    own : mapping of str to object
        The node's own values (last; they may replace common ones).
    **common
        ``lifecycle_state``, ``last_rejected_update``, ``rate_hz``, ``max_backlog``,
        ``qos_depth``, ``input_publishers``, ``enabled``, ``output_min``,
        ``output_max``, in this order.

    Returns
    -------
    dict
        Key to value (the message shows ``str`` of each).

    """
    values: dict[str, Any] = dict(counters)
    values.update(common)
    values.update(own)
    return values


def single_axis_values(kind: str, slow_state: Iterable[float] | None) -> dict[str, Any]:
    """
    Return a single-axis compensator's own diagnostics values (with a model installed).

    Parameters
    ----------
    kind : str
        The model's effect (:func:`mpi_ros.compensation.kind_of`).
    slow_state : iterable of float or None
        The effect's slow states; None without an effect.

    Returns
    -------
    dict
        ``extension`` and, with an effect, ``slow_state``.

    """
    values: dict[str, Any] = {'extension': kind}
    if slow_state is not None:
        values['slow_state'] = ' '.join(f'{v:.6g}' for v in slow_state)
    return values


def multi_axis_values(models: Sequence[Any], *, model_versions: Sequence[int],
                      joints: Sequence[str], flat: bool,
                      limits: tuple[Sequence[float], Sequence[float]],
                      slow_states: Sequence[Iterable[float] | None],
                      dead_time_prediction: bool = True) -> dict[str, Any]:
    """
    Return a multi-axis compensator's own diagnostics values.

    Parameters
    ----------
    models : sequence
        Each axis's model, None for an axis without one.
    model_versions : sequence of int
        Each axis's model version.
    joints : sequence of str
        The ``joints`` parameter (empty: none).
    flat : bool
        ``output_layout`` is ``flat``.
    limits : (sequence of float, sequence of float)
        Each axis's effective ``output.min`` and ``output.max``.
    slow_states : sequence
        Each axis's slow states (None without an effect); empty while no core runs.
    dead_time_prediction : bool
        Whether a dead time is compensated by prediction (else it is not compensated).

    Returns
    -------
    dict
        ``axes``, ``model_versions``, ``joints``, ``output_layout``, ``output_min``,
        ``output_max`` (one value when all axes share it), ``extension``,
        ``not_compensated`` and ``axis<k>.slow_state``.

    """
    values: dict[str, Any] = {
        'axes': len(models), 'model_versions': ' '.join(map(str, model_versions))}
    if joints:
        values['joints'] = ' '.join(joints)
    values['output_layout'] = 'flat' if flat else 'samples_x_axes'
    for key, limit in zip(('output_min', 'output_max'), limits):
        values[key] = limit[0] if len(set(limit)) == 1 else ' '.join(map(str, limit))
    causes = ['-' if model is None else getattr(model, 'cause', 'none').replace(' + ', '+')
              for model in models]
    values['extension'] = ' '.join(causes)
    uncompensated = [str(axis) for axis, model in enumerate(models)
                     if model is not None and kind_of(
                         model, dead_time_prediction=dead_time_prediction).endswith(
                             '(not compensated)')]
    if uncompensated:
        values['not_compensated'] = ' '.join(uncompensated)
    for axis, slow_state in enumerate(slow_states):
        if slow_state is not None:
            values[axis_key(axis, 'slow_state')] = ' '.join(f'{v:.6g}' for v in slow_state)
    return values
