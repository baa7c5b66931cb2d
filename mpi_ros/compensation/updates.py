# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
The model-update policy of the compensator nodes, on plain dicts (no ROS).

A compensator node's parameters describe its running model: Gamma's four ``model.*``
arrays, the operating point, what it knows of its identification record (its start,
``record_start.*``, and its input range, ``model.identified_input_range``; optional) and the
keys of every registered effect (read from the registry :data:`mpi_ros.extensions.EFFECTS`
when used).  A multi-axis node holds the same
keys once per axis under the prefix ``axis<k>.``.  Here, on ``{name: value}`` dicts
(``None``: unset, or YAML ``null`` in a request), is what a request does to them:

:func:`complete` (the pre-set step)
    A ``null`` for a key that is unset already is left out; for an effect key it is the
    key's "off" value, for an operating-point key its default; for a key of Gamma it stays
    (and is refused: a running model cannot be removed); for a record key it is the
    empty array (no record start, no recorded range).  A request with all four keys of
    Gamma describes the *whole* model: every operating-point key it leaves out returns to
    its default, every effect key it leaves out is switched off and a record start or range
    it leaves out is removed.
:func:`prepare` (the on-set step: it only checks)
    The request is laid over the current values and the whole resulting model is
    validated and inverted ((12)-(14), (22)-(25): Gamma^-1 is built here, once per
    request); the output limits are checked too.  A refusal raises
    :class:`~mpi_ros.errors.ParameterRejected` or :class:`~mpi_ros.errors.ModelError` and
    changes nothing; :func:`refusal` words it for the node.
:func:`apply` (the post-set step)
    Swaps the prepared update into a :class:`~mpi_ros.compensation.Compensator`: limits,
    switches, then the model, bumplessly (its turning points replayed through the new H,
    (14)), with the inverse :func:`prepare` built.

:func:`load` reads a model from declared values (a node's configure).

:class:`UpdateRule` is the rule of one node, over all its models (one prefix each): what
its three parameter callbacks share between calls (the prepared updates, the refusals).
"""

from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass, field
import math
import re
from typing import Any

import numpy as np

from .compensator import Compensator, gamma_of, inverse_step_of
from .prediction import prediction_horizon
from ..errors import ModelError, MPIError, ParameterRejected
from ..extensions import extended_model_from_params
from ..extensions.effect import effect_keys, effect_off_values
from ..operators.model import HYSTERESIS_INITIAL_STATES, IDENTIFIED_INPUT_RANGE, MODEL_KEYS, \
    MPIModel, OPERATING_POINT_DEFAULTS, OPERATING_POINT_KEYS, RECORD_START_STATES
from ..operators.usability import check_usable, usability_sweep
from ..units import INPUT_QUANTITY_KEY

__all__ = ['LIMIT_KEYS', 'PLAIN_KEYS', 'RECORD_KEYS', 'START_KEYS', 'Prepared', 'UpdateRule',
           'apply', 'axis_key', 'complete', 'is_off', 'limits_of', 'load', 'load_axes',
           'model_keys', 'model_params', 'ordered_limits', 'prepare', 'refusal', 'touches',
           'uncompensated', 'usable']

#: The two output limits [A]; node-wide without a prefix, one axis's under ``axis<k>.``.
LIMIT_KEYS = ('output.min', 'output.max')
#: The record start of Gamma's plays (its mode's deflection is the resonance effect's key);
#: optional, the empty array when absent.
START_KEYS = (RECORD_START_STATES, HYSTERESIS_INITIAL_STATES)
#: What a model knows of its identification record: its start and its input range;
#: optional, the empty array when absent (a whole model pushed without one removes it).
RECORD_KEYS = START_KEYS + (IDENTIFIED_INPUT_RANGE,)
#: Node-wide keys whose new value is handed on as it is.
PLAIN_KEYS = ('enabled', 'sample_period', 'diagnostics_period')
#: A single-axis model key at the start of a word, as core error messages name it.
_MODEL_KEY = re.compile(r'(?<![\w.])(?=model\.\w)')
_AXIS = re.compile(r'axis(\d+)\.')


@dataclass(frozen=True)
class Prepared:
    """
    A checked update of one model (one prefix), ready to swap in.

    Attributes
    ----------
    prefix : str
        ``''`` for the single-axis node, ``'axis<k>.'`` for an axis.
    model : MPIModel, extended model or None
        The validated whole model; None when the request changes no model key.
    inverse : MPIModel or None
        Gamma^-1 of ``model`` (built once, by :func:`prepare`).
    limits : tuple of (float, float) or None
        The checked output range [A] the request sets, or None.
    switches : dict
        The :data:`PLAIN_KEYS` the request sets, with their values.

    """

    prefix: str = ''
    model: Any = None
    inverse: MPIModel | None = None
    limits: tuple[float, float] | None = None
    switches: dict[str, Any] = field(default_factory=dict)

    def __bool__(self) -> bool:
        """Tell whether there is anything to apply."""
        return self.model is not None or self.limits is not None or bool(self.switches)


class UpdateRule:
    """
    One node's model-update rule over its models: complete, prepare, take; the refusals.

    The node's three parameter callbacks call it in turn: the pre-set one
    :meth:`complete`, the on-set one :meth:`prepare` (or :meth:`refuse` with the
    reason), the post-set one :meth:`take`.  What the on-set step prepared waits here for
    the post-set step; the refusals are counted for ``/diagnostics``.

    Parameters
    ----------
    prefixes : iterable of str
        The prefix of each model: ``('',)`` for the single-axis node, ``('axis0.', ...)``
        for the axes of a multi-axis node.

    Attributes
    ----------
    prefixes : tuple of str
        As given (a multi-axis node sets them once it knows its axes).
    rejected : int
        Requests refused so far (``rejected_updates``).
    last_rejection : str
        The reason of the last refusal (``last_rejected_update``), ``''`` before one.

    """

    def __init__(self, prefixes: Iterable[str] = ('',)) -> None:
        self.prefixes = tuple(prefixes)
        self.rejected = 0
        self.last_rejection = ''
        self._prepared: list[Prepared] = []

    @staticmethod
    def current_keys(prefix: str) -> list[str]:
        """
        Return the keys whose current values :meth:`complete` and :meth:`prepare` need.

        Parameters
        ----------
        prefix : str
            A model's prefix.

        Returns
        -------
        list of str
            Its model keys, its ``model.input_quantity`` and output limits and, for an axis,
            the node-wide limits.

        """
        return [prefix + key for key in model_keys() + (INPUT_QUANTITY_KEY,) + LIMIT_KEYS] + (
            list(LIMIT_KEYS) if prefix else [])

    def complete(self, current: Callable[[str], Mapping[str, Any]],
                 request: Mapping[str, Any]) -> dict[str, Any]:
        """
        Resolve ``null`` and complete whole models (:func:`complete`, for every prefix).

        Parameters
        ----------
        current : callable
            Returns the current values of :meth:`current_keys` of a prefix.
        request : mapping of str to value
            The request, in order; None is YAML ``null``.

        Returns
        -------
        dict
            The request to set, in order; a value left as it came is the same object.

        """
        completed = dict(request)
        for prefix in self.prefixes:
            completed = complete(current(prefix), completed, prefix)
        return completed

    def prepare(self, current: Callable[[str], Mapping[str, Any]],
                request: Mapping[str, Any], running: Callable[[str], bool]) -> None:
        """
        Check a request and keep its updates for :meth:`take` (:func:`prepare` per prefix).

        Parameters
        ----------
        current : callable
            As for :meth:`complete`.
        request : mapping of str to value
            The keys about to be set.
        running : callable
            Tells whether the model of a prefix runs.

        Raises
        ------
        ParameterRejected, ModelError
            As :func:`prepare`; nothing is kept.

        """
        self._prepared = []
        self._prepared = [prepare(current(prefix), request, prefix, running=running(prefix))
                          for prefix in self.prefixes if touches(request, prefix)]

    def refuse(self, reason: str) -> None:
        """Drop what was prepared and count a refusal with its reason."""
        self._prepared = []
        self.rejected += 1
        self.last_rejection = reason

    def take(self) -> list[Prepared]:
        """Return what :meth:`prepare` kept, and forget it (the post-set step)."""
        prepared, self._prepared = self._prepared, []
        return prepared


def axis_key(axis: int, key: str) -> str:
    """
    Return the parameter name of a key for one axis.

    Parameters
    ----------
    axis : int
        Axis index, from 0.
    key : str
        Single-axis key, e.g. ``model.hysteresis.weights``.

    Returns
    -------
    str
        e.g. ``axis2.model.hysteresis.weights``.

    Examples
    --------
    >>> axis_key(2, 'model.hysteresis.weights')
    'axis2.model.hysteresis.weights'

    """
    return f'axis{axis}.{key}'


def model_keys() -> tuple[str, ...]:
    """
    Return one model's keys (single-axis names), read from the effect registry now.

    Returns
    -------
    tuple of str
        Gamma's four, the operating point's three, the record's (start, input range), then
        every registered effect's keys.

    """
    return MODEL_KEYS + OPERATING_POINT_KEYS + RECORD_KEYS + effect_keys()


def is_off(value: Any) -> bool:
    """
    Tell whether an effect key's value is unset or its "off" value (0, empty).

    Parameters
    ----------
    value : float, list of float or None
        The key's value.

    Returns
    -------
    bool
        True for None, 0.0 and an empty list.

    Examples
    --------
    >>> is_off(None), is_off(0.0), is_off([]), is_off([0.1])
    (True, True, True, False)

    """
    if value is None:
        return True
    if isinstance(value, (int, float)):
        return value == 0.0
    return len(value) == 0


def model_params(values: Mapping[str, Any], prefix: str = '') -> dict[str, Any] | None:
    """
    Return the flat parameters of the model that a set of key values describes.

    Parameters
    ----------
    values : mapping of str to value
        Values (None: unset) of the model keys named ``prefix + key``.
    prefix : str
        ``''`` for the single-axis node, ``'axis<k>.'`` for an axis.

    Returns
    -------
    dict or None
        ``{key: value}`` with the single-axis keys: Gamma, the operating point and the
        keys of every effect that is not off (for
        :func:`mpi_ros.extensions.extended_model_from_params`); None when a key of Gamma
        is unset.

    """
    if any(values[prefix + key] is None for key in MODEL_KEYS):
        return None
    params = {key: values[prefix + key] for key in MODEL_KEYS + OPERATING_POINT_KEYS}
    params.update({key: values[prefix + key] for key in RECORD_KEYS
                   if not is_off(values.get(prefix + key))})
    keys_of = _effect_keys_by_name()
    for keys in keys_of.values():
        if not all(is_off(values.get(prefix + key)) for key in keys):
            params.update({key: values[prefix + key] for key in keys
                           if values.get(prefix + key) is not None})
    return params


def complete(current: Mapping[str, Any], request: Mapping[str, Any],
             prefix: str = '') -> dict[str, Any]:
    """
    Resolve the ``null`` values of a request and complete a whole model (pre-set).

    Parameters
    ----------
    current : mapping of str to value
        The node's current values (None: unset), at least of the model keys.
    request : mapping of str to value
        The request, in order; None is YAML ``null``.
    prefix : str
        The model's prefix (``''`` or ``'axis<k>.'``); keys of other prefixes pass as
        they are.

    Returns
    -------
    dict
        The request to set, in order: a ``null`` for an unset key left out, one for an
        effect key its "off" value, one for an operating-point key its default (one for a
        key of Gamma stays None: it is refused); then, when all four keys of Gamma are in
        it, the default of every operating-point key and the "off" value of every set
        effect or record-start key it leaves out.

    Examples
    --------
    >>> current = dict.fromkeys(model_keys())
    >>> current['model.input_offset'] = 0.5
    >>> complete(current, {'model.dead_time': None, 'model.input_offset': None})
    {'model.input_offset': 0.0}

    """
    off = {**effect_off_values(), **{key: [] for key in RECORD_KEYS}}
    keys = set(model_keys())
    completed: dict[str, Any] = {}
    for name, value in request.items():
        key = name[len(prefix):] if name.startswith(prefix) else None
        if value is None and key in keys:
            if current.get(name) is None:
                continue
            if key in off:
                value = _copy(off[key])
            elif key in OPERATING_POINT_DEFAULTS:
                value = OPERATING_POINT_DEFAULTS[key]
        completed[name] = value
    if not all(prefix + key in completed for key in MODEL_KEYS):
        return completed
    for key, default in OPERATING_POINT_DEFAULTS.items():
        name = prefix + key
        if name not in completed and current.get(name) != default:
            completed[name] = default
    for key, value in off.items():
        name = prefix + key
        if name not in completed and not is_off(current.get(name)):
            completed[name] = _copy(value)
    name = prefix + INPUT_QUANTITY_KEY          # a whole model without it: a current model
    if name not in completed and current.get(name) not in (None, 'current'):
        completed[name] = 'current'
    return completed


def prepare(current: Mapping[str, Any], request: Mapping[str, Any], prefix: str = '', *,
            running: bool = True) -> Prepared:
    """
    Check a request against the current values and prebuild its model (on-set: no change).

    Parameters
    ----------
    current : mapping of str to value
        The node's current values (None: unset): the model keys under ``prefix``, the
        node-wide :data:`LIMIT_KEYS` and, for an axis, its own (None: the node-wide ones).
    request : mapping of str to value
        The keys about to be set (after :func:`complete`).
    prefix : str
        ``''`` for the single-axis node, ``'axis<k>.'`` for one axis of a multi-axis node
        (which calls this once per axis).
    running : bool
        Whether a model of this prefix is running.  Without one, a request that changes
        none of its model keys (a dump of the node loaded back) prepares no model.

    Returns
    -------
    Prepared
        The whole model of ``prefix`` with its Gamma^-1 when the request sets one of its
        keys, the checked limits when it sets a limit, and its :data:`PLAIN_KEYS`.

    Raises
    ------
    ParameterRejected
        A model without all four keys of Gamma, an invalid model of an axis (naming the
        axis and key), unordered or non-finite limits.
    ModelError
        An invalid single-axis model (the message names the key).

    """
    values = {**current, **request}
    keys = set(model_keys())
    touched = [name for name in request
               if name.startswith(prefix) and name[len(prefix):] in keys]
    model = inverse = None
    if touched and (running or any(request[name] != current.get(name) for name in touched)):
        model, inverse = _whole_model(values, prefix, sorted(touched), loading=False)
    limits = None
    own = tuple(prefix + key for key in LIMIT_KEYS)
    if any(name in request for name in LIMIT_KEYS + own):
        limits = limits_of(values, prefix)
    switches = {name: request[name] for name in PLAIN_KEYS if name in request}
    return Prepared(prefix, model, inverse, limits, switches)


def apply(prepared: Prepared, compensator: Compensator | None) -> Any:
    """
    Swap a prepared update into a running compensator (post-set), bumplessly.

    Parameters
    ----------
    prepared : Prepared
        What :func:`prepare` returned.
    compensator : Compensator or None
        The running core of the prefix (one axis of a multi-axis core); None: nothing
        runs yet.

    Returns
    -------
    MPIModel, extended model or None
        The model to install where there was no compensator (the node builds its core
        from it); None when there was one (the model, if any, is installed) or the update
        has no model.

    """
    if compensator is None:
        return prepared.model
    if prepared.limits is not None:
        compensator.set_limits(*prepared.limits)
    if 'enabled' in prepared.switches:
        compensator.enabled = prepared.switches['enabled']
    if 'sample_period' in prepared.switches:
        compensator.sample_period = float(prepared.switches['sample_period'])
    if prepared.model is not None:
        compensator.install(prepared.model, inverse=prepared.inverse)
    return None


def load(values: Mapping[str, Any], prefix: str = '') -> Any:
    """
    Read the model that declared values describe (a node's configure).

    Parameters
    ----------
    values : mapping of str to value
        Every key's value (None: unset).
    prefix : str
        ``''`` or ``'axis<k>.'``.

    Returns
    -------
    MPIModel, extended model or None
        The validated model; None when no key of Gamma and no effect is given.

    Raises
    ------
    ParameterRejected
        An effect without Gamma, an incomplete Gamma, an invalid model of an axis.
    ModelError
        An invalid single-axis model.

    """
    given = [prefix + key for key in MODEL_KEYS if values[prefix + key] is not None]
    effects = [prefix + key for key in effect_keys() if not is_off(values.get(prefix + key))]
    if not given and not effects:
        return None
    return _whole_model(values, prefix, given + effects, loading=True)[0]


def load_axes(values: Mapping[str, Any], prefixes: Iterable[str]) -> dict[int, Any]:
    """
    Check every axis's output range, then read the models of the axes that have one.

    Parameters
    ----------
    values : mapping of str to value
        Declared values of a multi-axis node (None: unset).
    prefixes : iterable of str
        Each axis's prefix, in axis order.

    Returns
    -------
    dict of int to model
        The model of each axis that has one (:func:`load`), by axis.

    Raises
    ------
    ParameterRejected, ModelError
        As :func:`limits_of` (first, for every axis) and :func:`load`.

    """
    prefixes = tuple(prefixes)
    for prefix in prefixes:
        limits_of(values, prefix)
    models = {axis: load(values, prefix) for axis, prefix in enumerate(prefixes)}
    return {axis: model for axis, model in models.items() if model is not None}


def ordered_limits(output_min: float, output_max: float, *,
                   names: tuple[str, str] = LIMIT_KEYS) -> tuple[float, float]:
    """
    Check a safe current range: both finite, the first below the second.

    Parameters
    ----------
    output_min, output_max : float
        Lowest and highest current command [A].
    names : tuple of str
        The two parameter names, as the user writes them (for the message).

    Returns
    -------
    tuple of float
        ``(output_min, output_max)``.

    Raises
    ------
    ParameterRejected
        Naming both parameters, their values and what to do.

    """
    low, high = names
    if not (math.isfinite(output_min) and math.isfinite(output_max)):
        msg = f'{low} and {high} must be finite; found {output_min}, {output_max}'
        raise ParameterRejected(msg)
    if not output_min < output_max:
        msg = (f'{low} must be below {high}; found {low}={output_min} A and '
               f'{high}={output_max} A; set both together with '
               'set_parameters_atomically when moving the range')
        raise ParameterRejected(msg)
    return (output_min, output_max)


def refusal(names: list[str], err: Exception, *, version: int | None,
            axes: bool = False) -> str:
    """
    Word a refused request: what was refused, why, and that the running model stays.

    Parameters
    ----------
    names : list of str
        The request's names.
    err : Exception
        Why it was refused.
    version : int or None
        The running model's version; None: no model runs.
    axes : bool
        True for a multi-axis node (its models stay).

    Returns
    -------
    str
        The reason the node answers and reports as ``last_rejected_update``.

    """
    if axes:
        return (f'{err}. Nothing was applied; the running models stay. Keys that must '
                'change together go in one request (ros2 param load FILE, or '
                'set_parameters_atomically)')
    keys = set(model_keys())
    model_names = [name for name in names if name in keys]
    if not model_names:
        return str(err)
    changed = (', '.join(model_names) if len(model_names) <= 2
               else f'model update ({len(model_names)} model.* keys)')
    stays = ('the node stays unconfigured' if version is None
             else f'the running model (version {version}) stays')
    return (f'{changed} rejected, the whole model was checked: {err}. Nothing was '
            f'applied; {stays}. Keys that must change together (e.g. a new order) go '
            'in one request: ros2 param load FILE, or set_parameters_atomically')


def touches(request: Mapping[str, Any], prefix: str) -> bool:
    """
    Tell whether a request concerns the model of ``prefix`` (its keys, limits, switches).

    Parameters
    ----------
    request : mapping of str to value
        The request.
    prefix : str
        ``''`` or ``'axis<k>.'``.

    Returns
    -------
    bool
        True when a name starts with ``prefix`` or is a node-wide limit or switch.

    Examples
    --------
    >>> touches({'axis1.model.dead_time': 0.0}, 'axis0.'), touches({'enabled': 1}, 'axis0.')
    (False, True)

    """
    return any(name.startswith(prefix) or name in LIMIT_KEYS or name in PLAIN_KEYS
               for name in request)


def uncompensated(model: Any, *, dead_time_prediction: bool = True) -> str | None:
    """
    Say why a model's effect is not compensated (a dead time, a mode: no causal inverse).

    Parameters
    ----------
    model : MPIModel or extended model
        A model.
    dead_time_prediction : bool
        Whether the compensator predicts over a dead time (its default): then a dead time
        is compensated (by prediction) and not named here.

    Returns
    -------
    str or None
        The warning; None when the whole model is compensated.

    """
    if isinstance(model, MPIModel):
        return None
    if inverse_step_of(model) is None:
        left, kept = [model], 'Gamma only'
    else:                                  # a composite: the parts without a causal inverse
        left = [part for part in getattr(model, 'parts', ()) if part.inverse_step() is None]
        kept = 'the other stages'
    if dead_time_prediction:
        left = [part for part in left if prediction_horizon(part) <= 0.0]
    if not left:
        return None
    what = '; '.join(getattr(part, 'uncompensated_effect',
                             'the displacement lags the desired one by it') for part in left)
    names = ' and '.join(part.cause for part in left)
    return f'{names} cannot be inverted causally: compensating {kept}; {what}'


def _whole_model(values: Mapping[str, Any], prefix: str, given: list[str], *,
                 loading: bool) -> tuple[Any, MPIModel | None]:
    """Build the whole model of ``prefix`` and its Gamma^-1 (not loading a single axis)."""
    missing = [prefix + key for key in MODEL_KEYS if values[prefix + key] is None]
    axis = _AXIS.fullmatch(prefix)
    if missing and axis is not None:
        msg = (f'axis {axis.group(1)} has no model yet, so {_listed(given)} cannot apply: '
               f'a model needs all four keys of Gamma; missing: {", ".join(missing)}; give '
               'them in the same request')
        raise ParameterRejected(msg)
    if missing and loading and len(missing) == len(MODEL_KEYS):
        msg = (f'{given[0]}: a model extension needs the four model.* keys of Gamma; add '
               'them to the parameters')
        raise ParameterRejected(msg)
    if missing:
        msg = (f'incomplete model in the parameters: missing {", ".join(missing)}' if loading
               else 'the node has no model yet, and a model needs all four keys of Gamma; '
               f'missing: {", ".join(missing)}')
        raise ParameterRejected(msg)
    params = model_params(values, prefix) or {}
    limits = limits_of(values, prefix)
    if axis is None:
        model = extended_model_from_params(params)
        inverse = gamma_of(model).inverse()                    # (12)-(14), (22)-(25)
        usable(model, inverse, limits)
        return model, None if loading else inverse
    try:
        model = extended_model_from_params(params)
        inverse = gamma_of(model).inverse()        # (12)-(14), (22)-(25), once
        usable(model, inverse, limits)
        return model, inverse
    except MPIError as err:
        named = _MODEL_KEY.sub(prefix, str(err))
        msg = f'axis {axis.group(1)} ({prefix}model.*): {named}'
        raise ParameterRejected(msg) from err


def usable(model: Any, inverse: MPIModel, limits: tuple[float, float]) -> None:
    """
    Prove that a model runs in a compensator with these output limits (sandboxed).

    Gamma and Gamma^-1 run over the current range ``limits``
    (:func:`mpi_ros.operators.usability.check_usable`), then a trial
    :class:`~mpi_ros.compensation.Compensator` of the model (the one the node would
    install) commands a sweep of its displacement range from the model's initial states:
    every inverse must be finite (none held) and every command inside the limits.  Any
    exception on the way is a refusal.

    Parameters
    ----------
    model : MPIModel or extended model
        The validated forward model.
    inverse : MPIModel
        Its Gamma^-1.
    limits : tuple of float
        ``(output.min, output.max)`` [A].

    Raises
    ------
    ModelError
        Naming the key (``model.*``) and what went wrong.

    """
    gamma = gamma_of(model)
    check_usable(gamma.hysteresis, gamma.superposition, input_offset=gamma.input_offset,
                 output_offset=gamma.output_offset, output_sign=gamma.output_sign,
                 current_range=limits)
    low, high = limits
    try:
        with np.errstate(all='ignore'):
            trial = Compensator(model, output_min=low, output_max=high, inverse=inverse)
            commands = trial.command_batch(usability_sweep(*trial.displacement_range))
    except MPIError:
        raise
    except Exception as err:  # noqa: B902 - the sandbox: any failure is a refusal
        msg = (f'model.* (the whole model): a compensator of it with output limits {low:g} to '
               f'{high:g} A failed ({type(err).__name__}: {err}); re-run identify')
        raise ModelError(msg) from err
    held = trial.counters['nonfinite_command']
    if held:
        msg = (f'model.* (the whole model): its inverse is not finite for {held} of '
               f'{commands.size} desired displacements over its range (the compensator would '
               'hold its last command); check model.hysteresis.initial_states and the '
               'offsets, or re-run identify')
        raise ModelError(msg)
    bad = np.flatnonzero(~((commands >= low) & (commands <= high)))
    if bad.size:
        msg = (f'model.* (the whole model): a compensator of it commands {commands[bad[0]]!r} A '
               f'({bad.size} of {commands.size} commands over its displacement range), '
               f'not inside the output limits {low:g} to {high:g} A; re-run identify')
        raise ModelError(msg)


def limits_of(values: Mapping[str, Any], prefix: str = '') -> tuple[float, float]:
    """
    Check the node-wide output range and, for an axis, its own (or inherited) one.

    Parameters
    ----------
    values : mapping of str to value
        The node's values: :data:`LIMIT_KEYS` and, for an axis, its own (None: inherited).
    prefix : str
        ``''`` or ``'axis<k>.'``.

    Returns
    -------
    tuple of float
        The range [A] of the prefix.

    Raises
    ------
    ParameterRejected
        Naming the keys (see :func:`ordered_limits`).

    """
    limits = ordered_limits(values['output.min'], values['output.max'])
    if not prefix:
        return limits
    low, high = (prefix + key if values.get(prefix + key) is not None else key
                 for key in LIMIT_KEYS)
    return ordered_limits(values[low], values[high], names=(low, high))


def _effect_keys_by_name() -> dict[str, tuple[str, ...]]:
    """Return each registered effect's keys (read now, not at import)."""
    from ..extensions import EFFECTS
    return {name: effect.keys for name, effect in EFFECTS.items()}


def _listed(names: list[str]) -> str:
    """Name the given keys: up to two by name, else how many."""
    if len(names) <= 2:
        return ', '.join(names)
    return f'{len(names)} keys ({names[0]}, ...)'


def _copy(value: Any) -> Any:
    return list(value) if isinstance(value, list) else value
