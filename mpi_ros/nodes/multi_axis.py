# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Multi-axis compensator node: N actuators, one model each, on samples x axes array topics.

(Slightly over 500 lines: per-axis parameter namespaces, atomic multi-axis updates, the
array message path and diagnostics of one node.)

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
    models; the extensions are single-axis only); ``output.min`` / ``output.max`` (one
    safe range for all axes), ``enabled``, ``diagnostics_period``, ``qos_depth``,
    ``qos_reliability``.

Model updates
    The single-axis rule, per axis: a request is laid over the running values, and every
    axis it touches is validated whole; if all are valid they are applied together
    (bumpless, each axis from its own applied current), otherwise the whole request is
    refused with a reason naming the axis and key, and nothing changes.  So one
    ``set_parameters_atomically`` (the identifier's push) changes several axes
    atomically; ``ros2 param load`` sends the file's ``axis*.model.*`` keys as one group
    too.  The five Gamma keys of an axis in one request describe its whole model (the
    operating point keys it leaves out return to their defaults).  Until every axis has a
    model the node is unconfigured and publishes nothing (diagnostics WARN).
"""

from dataclasses import replace
import math
import time
from typing import Any, Dict, List, Optional, Tuple

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
import numpy as np
from rcl_interfaces.msg import SetParametersResult
from rclpy.node import Node
from rclpy.parameter import Parameter
from std_msgs.msg import Float64MultiArray

from .arrays import ArrayLayoutError, block_of, encode_float64_multiarray
from .loss import LossMonitor
from .parameters import (
    check_parameters, declare_parameters, harden_parameter_services, MODEL_KEYS,
    MODEL_PARAMETERS, normalized, OPERATING_POINT_KEYS, parameter_values, ParameterRejected,
    ParameterSpec, set_parameters_in_groups, specs_by_name,
)
from .qos import loop_qos
from ..compensation import MultiAxisCompensator
from ..errors import MPIError
from ..model import MPIModel
from ..params import OPERATING_POINT_DEFAULTS

__all__ = ['AXES', 'MultiAxisCompensatorNode', 'axis_key', 'axis_parameters']

Type = Parameter.Type

#: The ``axes`` parameter, declared by both compensator nodes.
AXES = ParameterSpec(
    'axes', Type.INTEGER, 1,
    'Number of actuators this node serves: 1 = one actuator on the Float64 topics '
    'desired_displacement / current_command with the model.* keys; N > 1 = N actuators on '
    'the Float64MultiArray topics desired_displacements / current_commands (samples x '
    'axes) with the keys axis0.model.* ... axis<N-1>.model.*',
    value_range=(1, 1024), read_only=True)

#: Most array messages served in one subscription callback.
_DRAIN_LIMIT = 1000
_LIMIT_KEYS = ('output.min', 'output.max')
_COMMON_NAMES = ('output.min', 'output.max', 'enabled', 'diagnostics_period', 'qos_depth',
                 'qos_reliability')
_FAULT_KEYS = ('nonfinite_input', 'out_of_range', 'clamped')


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


class MultiAxisCompensatorNode(Node):
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
        from .compensator import PARAMETERS as SINGLE_AXIS
        common = tuple(spec for spec in SINGLE_AXIS if spec.name in _COMMON_NAMES)
        self._declaring = True
        self._prepared: Optional[Dict[str, Any]] = None
        self._specs = dict(specs_by_name((AXES,) + common))
        self.add_pre_set_parameters_callback(self._complete_request)
        self.add_on_set_parameters_callback(self._validate_parameters)
        self.add_post_set_parameters_callback(self._apply_parameters)
        declare_parameters(self, (AXES,))
        self.axes = int(self.get_parameter('axes').value)
        per_axis = axis_parameters(self.axes)
        self._specs.update(specs_by_name(per_axis))
        self._model_keys = [[axis_key(k, key) for key in MODEL_KEYS + OPERATING_POINT_KEYS]
                            for k in range(self.axes)]
        self._all_model_keys = tuple(key for keys in self._model_keys for key in keys)
        self._groups = (self._all_model_keys, _LIMIT_KEYS)
        declare_parameters(self, per_axis + common)
        harden_parameter_services(self, groups=self._groups, specs=self._specs)
        self._declaring = False

        self._models: List[Optional[MPIModel]] = [None] * self.axes
        self._compensator: Optional[MultiAxisCompensator] = None
        self._model_versions = [0] * self.axes
        self._rejected_updates = 0
        self._last_rejection = ''
        self._messages_in = self._messages_out = self._samples_in = 0
        self._dropped_unconfigured = 0
        self._malformed = 0
        self._last_malformed = ''
        self._last_report: Tuple[float, int, Dict[str, int]] = (time.monotonic(), 0, {})
        self._configure_from_declared()

        reliability = self.get_parameter('qos_reliability').value
        qos = loop_qos(self.get_parameter('qos_depth').value, reliability)
        self._loss = LossMonitor(self, 'desired_displacements', 'current_commands',
                                 reliability)
        self._publisher = self.create_publisher(
            Float64MultiArray, 'current_commands', qos,
            event_callbacks=self._loss.publisher_callbacks())
        self._diagnostics = self.create_publisher(DiagnosticArray, '/diagnostics', 10)
        self._subscription = self.create_subscription(
            Float64MultiArray, 'desired_displacements', self._on_desired_displacements, qos,
            raw=True, event_callbacks=self._loss.subscription_callbacks())
        self._loss.publisher_count = self._subscription.get_publisher_count
        self._timer = self.create_timer(
            self.get_parameter('diagnostics_period').value, self._publish_diagnostics)
        self._second_timer = self.create_timer(1.0, self._every_second)

    # -- public read-only state -------------------------------------------------------
    @property
    def compensator(self) -> Optional[MultiAxisCompensator]:
        """Return the core (one Compensator per axis), or None until every axis has a model."""
        return self._compensator

    @property
    def counters(self) -> Dict[str, int]:
        """
        Message and fault counters, as reported on ``/diagnostics``.

        Returns
        -------
        dict of str to int
            The cores' ``clamped``, ``nonfinite_input``, ``out_of_range`` summed over the
            axes; ``messages_in``, ``messages_out``, ``samples_in``, ``malformed`` (array
            messages that are not samples x axes), the loss counters, ``rejected_updates``.

        """
        counters: Dict[str, int] = dict.fromkeys(_FAULT_KEYS, 0)
        if self._compensator is not None:
            summed = self._compensator.counters
            counters.update((key, summed[key]) for key in _FAULT_KEYS)
        counters.update(
            messages_in=self._messages_in, messages_out=self._messages_out,
            samples_in=self._samples_in, malformed=self._malformed,
            dropped_unconfigured=self._dropped_unconfigured,
            **self._loss.counters(),
            rejected_updates=self._rejected_updates)
        return counters

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
    def set_parameters(self, parameter_list: List[Parameter]) -> List[SetParametersResult]:
        """
        Set parameters like the ``set_parameters`` service: all model keys together.

        Parameters
        ----------
        parameter_list : list of rclpy.parameter.Parameter
            The request.

        Returns
        -------
        list of rcl_interfaces.msg.SetParametersResult
            One result per parameter; the keys of one group share theirs.

        """
        return set_parameters_in_groups(self, parameter_list, groups=self._groups,
                                        specs=self._specs)

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

    def _validate_parameters(self, parameters: List[Parameter]) -> SetParametersResult:
        """Check only: types, ranges, every touched axis's whole model, the limits."""
        try:
            check_parameters(self._specs, parameters, allow_unset=self._declaring)
            if self._declaring:
                return SetParametersResult(successful=True)
            self._prepared = self._candidate(parameters)
        except (ParameterRejected, MPIError) as err:
            self._prepared = None
            self._rejected_updates += 1
            reason = (f'{err}. Nothing was applied; the running models stay. Keys that must '
                      'change together go in one request (ros2 param load FILE, or '
                      'set_parameters_atomically)')
            self._last_rejection = reason
            self.get_logger().warning(f'rejected parameter update: {reason}')
            return SetParametersResult(successful=False, reason=reason)
        return SetParametersResult(successful=True)

    def _candidate(self, parameters: List[Parameter]) -> Dict[str, Any]:
        names = {p.name for p in parameters}
        prepared: Dict[str, Any] = {'models': {}}
        for axis, keys in enumerate(self._model_keys):
            if names.isdisjoint(keys):
                continue
            prepared['models'][axis] = self._axis_model(
                axis, parameter_values(self, keys, parameters))
        if names.intersection(_LIMIT_KEYS):
            values = parameter_values(self, list(_LIMIT_KEYS), parameters)
            prepared['limits'] = _ordered_limits(values['output.min'], values['output.max'])
        for name in ('enabled', 'diagnostics_period'):
            if name in names:
                prepared[name] = parameter_values(self, [name], parameters)[name]
        return prepared

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

    def _apply_parameters(self, parameters: List[Parameter]) -> None:
        prepared, self._prepared = self._prepared, None
        if self._declaring or not prepared:
            return
        compensator = self._compensator
        if 'limits' in prepared and compensator is not None:
            compensator.set_limits(*prepared['limits'])
        if 'enabled' in prepared and compensator is not None:
            compensator.enabled = prepared['enabled']
        self._install(prepared['models'])
        if 'diagnostics_period' in prepared:
            self.destroy_timer(self._timer)
            self._timer = self.create_timer(prepared['diagnostics_period'],
                                            self._publish_diagnostics)

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
            self._compensator = MultiAxisCompensator(
                self._models, output_min=self.get_parameter('output.min').value,
                output_max=self.get_parameter('output.max').value,
                enabled=self.get_parameter('enabled').value)
        axes = ', '.join(str(axis) for axis in sorted(models))
        state = 'compensating' if self._compensator is not None else (
            f'{sum(m is None for m in self._models)} axes still without a model')
        self.get_logger().info(f'model applied to axis {axes} ({state})')

    def _configure_from_declared(self) -> None:
        values = parameter_values(self, list(self._specs))
        _ordered_limits(values['output.min'], values['output.max'])
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
    def _publish_diagnostics(self) -> None:
        self._diagnostics.publish(self.diagnostics())

    def _every_second(self) -> None:
        self._loss.publishers = self._subscription.get_publisher_count()
        self._loss.log(time.monotonic(), 'desired displacement arrays')

    def diagnostics(self) -> DiagnosticArray:
        """
        Build the diagnostics message (and restart the rate window).

        Returns
        -------
        diagnostic_msgs.msg.DiagnosticArray
            One status ``<node name>: feedforward (N axes)``: WARN after a period with
            lost messages, incompatible peers, a queue more than half full, malformed
            arrays or non-finite / out-of-range / clamped inputs, and while an axis has
            no model; else OK.

        """
        now = time.monotonic()
        last_time, last_count, before = self._last_report
        counters = self.counters
        elapsed = now - last_time
        rate = (self._messages_in - last_count) / elapsed if elapsed > 0.0 else 0.0
        self._last_report = (now, self._messages_in, counters)
        status = DiagnosticStatus(name=f'{self.get_name()}: feedforward ({self.axes} axes)',
                                  hardware_id=self.get_fully_qualified_name())
        depth = self.get_parameter('qos_depth').value
        problems = self._loss.period(counters, before, depth, 'desired displacement arrays')
        malformed = counters['malformed'] - before.get('malformed', 0)
        if malformed:
            problems.append(f'{malformed} malformed arrays in the last period (last: '
                            f'{self._last_malformed})')
        faults = {key: counters[key] - before.get(key, 0) for key in _FAULT_KEYS}
        if any(faults.values()):
            problems.append(', '.join(f'{n} {key}' for key, n in faults.items() if n)
                            + ' inputs in the last period')
        missing = [str(axis) for axis, model in enumerate(self._models) if model is None]
        if missing:
            problems.append(f'no model for axis {", ".join(missing)}: unconfigured, no '
                            'commands published; give every axis its axis<k>.model.* keys')
        status.level = DiagnosticStatus.WARN if problems else DiagnosticStatus.OK
        status.message = '; '.join(problems) if problems else 'compensating'
        values: Dict[str, Any] = dict(counters)
        values.update(
            axes=self.axes, model_versions=' '.join(map(str, self._model_versions)),
            last_rejected_update=self._last_rejection, rate_hz=round(rate, 3),
            max_backlog=self._loss.last_backlog, qos_depth=depth,
            input_publishers=self._loss.publishers,
            enabled=self.get_parameter('enabled').value,
            output_min=self.get_parameter('output.min').value,
            output_max=self.get_parameter('output.max').value)
        status.values = [KeyValue(key=key, value=str(value)) for key, value in values.items()]
        array = DiagnosticArray()
        array.header.stamp = self.get_clock().now().to_msg()
        array.status = [status]
        return array


def _ordered_limits(output_min: float, output_max: float) -> Tuple[float, float]:
    if not (math.isfinite(output_min) and math.isfinite(output_max)
            and output_min < output_max):
        msg = (f'output.min must be finite and below output.max; found output.min='
               f'{output_min} A and output.max={output_max} A; set both together with '
               'set_parameters_atomically when moving the range')
        raise ParameterRejected(msg)
    return (output_min, output_max)
