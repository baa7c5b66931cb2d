# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Multi-axis compensator node: N actuators, one model each, on samples x axes array topics.

Per-axis parameter namespaces, atomic multi-axis updates and the array message path; the
parameter callbacks' frame, topics, loss accounting, counters and diagnostics frame are
shared with the single-axis node (:mod:`mpi_ros.nodes.compensator_base`).

Started by ``mpi-ros compensator --ros-args -p axes:=N`` (N > 1; ``axes`` 1, the default,
is the single-axis node of :mod:`mpi_ros.nodes.compensator` with its Float64 topics).

Topics (relative names, ``std_msgs/msg/Float64MultiArray``, SI units)
    ``desired_displacements`` [m] in, ``current_commands`` [A] out, row-major
    ``samples x axes``: one message carries one sample of every axis or a chunk of K
    samples (``layout.dim = [samples, axes]``, or no ``dim`` and a length that is a multiple
    of N, see :mod:`mpi_ros.nodes.arrays`).  Each input message gives one output message
    of the same shape; column k is exactly what a single-axis compensator with axis k's
    model gives for that column (:class:`mpi_ros.compensation.MultiAxisCompensator`, one
    compiled loop over every axis and sample of a message).  ``/diagnostics`` as the
    single-axis node.

Node parameters
    ``axes`` (read-only); per axis k = 0..N-1 the model keys of the single-axis node under
    ``axis<k>.``: ``axis<k>.model.hysteresis.thresholds``, ``.weights``,
    ``.initial_states``, ``axis<k>.model.superposition.thresholds``, ``.weights``,
    ``axis<k>.model.input_offset``, ``.output_offset``, ``.output_sign`` (plain MPI
    models; the extensions are single-axis only); ``output.min`` / ``output.max`` (the
    node-wide safe range) and, optional per axis, ``axis<k>.output.min`` /
    ``axis<k>.output.max`` (unset: the node-wide value; once set, a key can be changed but
    not unset again while the node runs); ``enabled``, ``diagnostics_period``,
    ``qos_depth``, ``qos_reliability``.  Every axis's range (its own keys, or the
    node-wide ones it falls back to) must be finite with min < max; ``/diagnostics``
    reports ``output_min`` / ``output_max`` as one value, or as space-separated per-axis
    lists when the axes' ranges differ.

Model updates
    The single-axis rule, per axis: a request is laid over the running values, and every
    axis it touches is validated whole; if all are valid they are applied together
    (bumpless, each axis from its own applied current), otherwise the whole request is
    refused with a reason naming the axis and key, and nothing changes.  So one
    ``set_parameters_atomically`` (the identifier's push) changes several axes
    atomically; ``ros2 param load`` sends the file's ``axis*.model.*`` keys as one group
    too.  The five Gamma keys of an axis in one request describe its whole model (the
    operating point keys it leaves out return to their defaults).  The output limits,
    node-wide and per axis, belong to the same request: a request that sets a model and its
    limits is applied whole (limits first, then the model) or refused whole, and in a
    ``set_parameters`` request (``ros2 param load``) the model keys and every limit key form
    one group.  Until every axis has a model the node is unconfigured and publishes nothing
    (diagnostics WARN).
"""

from dataclasses import replace
from typing import Any, Dict, List, Optional, Tuple

from diagnostic_msgs.msg import DiagnosticStatus
import numpy as np
from rclpy.parameter import Parameter
from std_msgs.msg import Float64MultiArray

from .arrays import ArrayLayoutError, block_of, encode_float64_multiarray
from .compensator_base import (
    AXES, CompensatorNodeBase, describe_faults, DIAGNOSTICS_PERIOD, DRAIN_LIMIT, ENABLED,
    FAULT_KEYS, LIMIT_KEYS, LIMIT_PARAMETERS, new_faults, ordered_limits,
)
from .parameters import (
    declare_parameters, loop_qos_parameters, MODEL_KEYS, MODEL_PARAMETERS, normalized,
    OPERATING_POINT_KEYS, parameter_values, ParameterRejected, ParameterSpec, specs_by_name,
)
from ..compensation import MultiAxisCompensator
from ..errors import MPIError
from ..model import MPIModel
from ..params import OPERATING_POINT_DEFAULTS

__all__ = ['AXES', 'MultiAxisCompensatorNode', 'axis_key', 'axis_parameters']

Type = Parameter.Type

#: Most array messages served in one subscription callback.
_DRAIN_LIMIT = DRAIN_LIMIT
#: The node-wide parameters (the single-axis node's, less the extended-model ones).
_COMMON = LIMIT_PARAMETERS + (ENABLED, DIAGNOSTICS_PERIOD) + loop_qos_parameters(
    'desired_displacements and current_commands')


def axis_key(axis: int, key: str) -> str:
    """
    Return the parameter name of a model key for one axis.

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
        ``MODEL_PARAMETERS`` (Gamma and the operating point) once per axis, renamed.

    """
    return tuple(replace(spec, name=axis_key(k, spec.name),
                         description=f'Axis {k}: {spec.description}')
                 for k in range(axes) for spec in MODEL_PARAMETERS)


class MultiAxisCompensatorNode(CompensatorNodeBase):
    """
    Feedforward compensator for N actuators on array topics (see the module docstring).

    Parameters
    ----------
    node_name : str
        Node name; ``compensator`` unless remapped.
    **kwargs
        Passed on to :class:`rclpy.node.Node` (``context=``, ``parameter_overrides=``...).

    Raises
    ------
    mpi_ros.errors.MPIError
        When the declared models or limits are invalid.

    """

    def __init__(self, node_name: str = 'compensator', **kwargs: Any) -> None:
        super().__init__(node_name, **kwargs)
        self._specs = dict(specs_by_name((AXES,) + _COMMON))
        declare_parameters(self, (AXES,))
        self.axes = int(self.get_parameter('axes').value)
        per_axis = axis_parameters(self.axes) + _axis_limit_parameters(self.axes)
        self._specs.update(specs_by_name(per_axis))
        self._model_keys = [[axis_key(k, key) for key in MODEL_KEYS + OPERATING_POINT_KEYS]
                            for k in range(self.axes)]
        self._limit_keys = [(axis_key(k, 'output.min'), axis_key(k, 'output.max'))
                            for k in range(self.axes)]
        self._all_limit_keys = LIMIT_KEYS + tuple(
            key for keys in self._limit_keys for key in keys)
        # Models and limits of one set_parameters request succeed or fail together.
        self._groups = (tuple(key for keys in self._model_keys for key in keys)
                        + self._all_limit_keys,)
        declare_parameters(self, per_axis + _COMMON)
        self._declared()

        self._models: List[Optional[MPIModel]] = [None] * self.axes
        self._compensator: Optional[MultiAxisCompensator] = None
        self._model_versions = [0] * self.axes
        self._samples_in = 0
        self._malformed = 0
        self._last_malformed = ''
        self._configure_from_declared()
        self._open_topics(Float64MultiArray, 'desired_displacements', 'current_commands',
                          self._on_desired_displacements, 'desired displacement arrays')

    # -- public read-only state -------------------------------------------------------
    @property
    def compensator(self) -> Optional[MultiAxisCompensator]:
        """Return the core (one Compensator per axis), or None until every axis has a model."""
        return self._compensator

    def command(self, block: Any) -> Any:
        """
        Compute (and count) the commands of one samples x axes block, without publishing.

        Parameters
        ----------
        block : array_like of float, shape (K, N)
            Desired displacements [m].

        Returns
        -------
        ndarray of float, shape (K, N), or None
            Current commands [A]; None while unconfigured.

        """
        compensator = self._compensator
        if compensator is None:
            return None
        return compensator.command(np.asarray(block, dtype=np.float64))

    # -- message path -----------------------------------------------------------------
    def _on_desired_displacements(self, data: bytes) -> None:
        # As the single-axis node: raw messages, every queued one served here, sequence
        # numbers of the ones taken here checked for gaps.  A block is decoded by one
        # numpy view of the bytes and answered by one tobytes (mpi_ros.nodes.arrays).
        take = self._subscription.handle.take_message
        publish = self._publisher.handle.publish_raw
        loss = self._loss
        loss.delivered()
        served = 0
        while True:
            self._messages_in += 1
            try:
                block = block_of(data, self.axes)
            except ArrayLayoutError as err:
                self._malformed += 1
                self._last_malformed = str(err)
            else:
                self._samples_in += block.shape[0]
                compensator = self._compensator
                if compensator is None:
                    self._dropped_unconfigured += 1
                else:
                    publish(encode_float64_multiarray(compensator.command(block)))
                    self._messages_out += 1
            served += 1
            if served >= _DRAIN_LIMIT:
                break
            taken = take(Float64MultiArray, True)
            if taken is None:
                break
            data, info = taken
            loss.taken(info['publication_sequence_number'])
        loss.served(served)

    # -- parameters ---------------------------------------------------------------------
    def _complete_request(self, parameters: List[Parameter]) -> List[Parameter]:
        """Pre-set: normalise values; the five Gamma keys of an axis describe its model."""
        completed = [normalized(self._specs[p.name], p) if p.name in self._specs else p
                     for p in parameters]
        if self._declaring:
            return completed
        names = {p.name for p in completed}
        for axis in range(self.axes):
            if not names.issuperset(axis_key(axis, key) for key in MODEL_KEYS):
                continue
            for key in OPERATING_POINT_KEYS:
                name, default = axis_key(axis, key), OPERATING_POINT_DEFAULTS[key]
                if name not in names and self.get_parameter(name).value != default:
                    completed.append(Parameter(name, self._specs[name].type_, default))
        return completed

    def _rejection(self, parameters: List[Parameter], err: Exception) -> str:
        return (f'{err}. Nothing was applied; the running models stay. Keys that must '
                'change together go in one request (ros2 param load FILE, or '
                'set_parameters_atomically)')

    def _model_candidate(self, names: Any, parameters: List[Parameter]) -> Dict[str, Any]:
        """Build every touched axis's whole model, checked and inverted."""
        models = {}
        for axis, keys in enumerate(self._model_keys):
            if names.isdisjoint(keys):
                continue
            models[axis] = self._axis_model(axis, parameter_values(self, keys, parameters))
        return {'models': models}

    def _axis_model(self, axis: int, values: Dict[str, Any]) -> MPIModel:
        prefix = axis_key(axis, '')
        params = {name[len(prefix):]: value for name, value in values.items()}
        missing = [axis_key(axis, key) for key in MODEL_KEYS if params[key] is None]
        if missing:
            msg = (f'axis {axis} has no model yet, and a model needs all five keys of Gamma;'
                   f' missing: {", ".join(missing)}')
            raise ParameterRejected(msg)
        try:
            model = MPIModel.from_params(params)
            model.inverse()       # (12)-(14), (22)-(25) must exist before the swap
        except MPIError as err:
            msg = f'axis {axis} ({prefix}model.*): {err}'
            raise ParameterRejected(msg) from err
        return model

    def _install_prepared(self, prepared: Dict[str, Any]) -> None:
        self._install(prepared['models'])

    def _limits_candidate(self, names: Any, parameters: List[Parameter]) -> Any:
        """Return {axis: (min, max)} of every axis whose range the request touches."""
        if names.isdisjoint(self._all_limit_keys):
            return None
        axes = range(self.axes) if not names.isdisjoint(LIMIT_KEYS) else [
            axis for axis, keys in enumerate(self._limit_keys) if not names.isdisjoint(keys)]
        return self._axis_limits(parameter_values(self, self._all_limit_keys, parameters),
                                 axes)

    def _axis_limits(self, values: Dict[str, Any], axes: Any) -> Dict[int, Tuple[float, float]]:
        """Check the node-wide range and each axis's own (or inherited) range."""
        ordered_limits(values['output.min'], values['output.max'])
        limits = {}
        for axis in axes:
            names = tuple(key if values[key] is not None else common
                          for key, common in zip(self._limit_keys[axis], LIMIT_KEYS))
            limits[axis] = ordered_limits(values[names[0]], values[names[1]], names=names)
        return limits

    def _set_limits(self, limits: Any) -> None:
        compensator = self._compensator
        if compensator is not None:
            for axis, (low, high) in limits.items():
                compensator.set_limits(low, high, axis=axis)

    def _effective_limits(self) -> Tuple[List[float], List[float]]:
        """Return each axis's applied range [A]: its own keys, else the node-wide ones."""
        values = parameter_values(self, self._all_limit_keys)
        pairs = [tuple(values[key] if values[key] is not None else values[common]
                       for key, common in zip(keys, LIMIT_KEYS)) for keys in self._limit_keys]
        return [pair[0] for pair in pairs], [pair[1] for pair in pairs]

    def _install(self, models: Dict[int, MPIModel]) -> None:
        """Apply validated axis models: install into running axes, or build the core."""
        if not models:
            return
        for axis, model in models.items():
            self._models[axis] = model
            self._model_versions[axis] += 1
            if self._compensator is not None:
                self._compensator.install(axis, model)
        if self._compensator is None and all(m is not None for m in self._models):
            lows, highs = self._effective_limits()
            self._compensator = MultiAxisCompensator(
                self._models, output_min=lows, output_max=highs,
                enabled=self.get_parameter('enabled').value)
        axes = ', '.join(str(axis) for axis in sorted(models))
        state = 'compensating' if self._compensator is not None else (
            f'{sum(m is None for m in self._models)} axes still without a model')
        self.get_logger().info(f'model applied to axis {axes} ({state})')

    def _configure_from_declared(self) -> None:
        values = parameter_values(self, list(self._specs))
        self._axis_limits(values, range(self.axes))
        models = {}
        for axis, keys in enumerate(self._model_keys):
            given = [key for key in keys[:len(MODEL_KEYS)] if values[key] is not None]
            if given:
                models[axis] = self._axis_model(axis, {key: values[key] for key in keys})
        self._install(models)
        if self._compensator is None:
            self.get_logger().info(
                f'{self.axes} axes, {self.axes - len(models)} without a model: publishing '
                'nothing until every axis has one (axis<k>.model.* keys, e.g. pushed by the '
                'identifier)')

    # -- diagnostics --------------------------------------------------------------------
    def _core_counters(self) -> Dict[str, int]:
        counters: Dict[str, int] = dict.fromkeys(FAULT_KEYS, 0)
        if self._compensator is not None:
            summed = self._compensator.counters
            counters.update((key, summed[key]) for key in FAULT_KEYS)
        return counters

    def _node_counters(self) -> Dict[str, int]:
        return {'samples_in': self._samples_in, 'malformed': self._malformed}

    def _status_name(self) -> str:
        return f'{self.get_name()}: feedforward ({self.axes} axes)'

    def _status(self, losses: List[str], counters: Dict[str, int],
                before: Dict[str, int]) -> Tuple[Any, str]:
        """
        Return the level and message of a diagnostics period.

        WARN after a period with lost messages, incompatible peers, a queue more than half
        full, malformed arrays or non-finite / out-of-range / clamped inputs, and while an
        axis has no model; else OK.
        """
        problems = list(losses)
        malformed = counters['malformed'] - before.get('malformed', 0)
        if malformed:
            problems.append(f'{malformed} malformed arrays in the last period (last: '
                            f'{self._last_malformed})')
        faults = new_faults(counters, before)
        if any(faults.values()):
            problems.append(f'{describe_faults(faults)} in the last period')
        missing = [str(axis) for axis, model in enumerate(self._models) if model is None]
        if missing:
            problems.append(f'no model for axis {", ".join(missing)}: unconfigured, no '
                            'commands published; give every axis its axis<k>.model.* keys')
        if problems:
            return DiagnosticStatus.WARN, '; '.join(problems)
        return DiagnosticStatus.OK, 'compensating'

    def _status_values(self) -> Dict[str, Any]:
        values: Dict[str, Any] = {
            'axes': self.axes, 'model_versions': ' '.join(map(str, self._model_versions))}
        for key, limits in zip(('output_min', 'output_max'), self._effective_limits()):
            values[key] = limits[0] if len(set(limits)) == 1 else ' '.join(map(str, limits))
        return values


def _axis_limit_parameters(axes: int) -> Tuple[ParameterSpec, ...]:
    """Return ``axis<k>.output.min`` / ``.max`` per axis: unset (node-wide) by default."""
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
