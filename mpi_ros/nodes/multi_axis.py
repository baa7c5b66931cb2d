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
    of N, see :mod:`mpi_ros.array_layout`).  Each input message gives one output message
    of the same shape; column k is exactly what a single-axis compensator with axis k's
    model gives for that column (:class:`mpi_ros.compensation.MultiAxisCompensator`, one
    compiled loop over every axis and sample of a message).  ``/diagnostics`` as the
    single-axis node.

ros2_control (``joints``, ``output_layout``, ``input_message``, read-only)
    ``output_layout: flat`` publishes what ``forward_command_controller`` takes on
    ``~/commands``: one message per sample, ``data[k]`` the command of axis k (the joint
    ``joints[k]``), empty ``layout.dim``, ``data_offset`` 0.  ``input_message: joint_state``
    subscribes ``desired_joint_states`` (``sensor_msgs/JointState``): each joint's
    ``position`` [m] mapped by name to the ``joints`` order; joints not in ``joints`` are
    ignored; a message missing one is refused (``missing_joints``, WARN), one whose
    positions do not match its names, or that cannot be deserialised (it is taken raw), is
    ``malformed``.

Node parameters
    ``axes`` (read-only); per axis k = 0..N-1 every model key of the single-axis node under
    ``axis<k>.``: ``axis<k>.model.hysteresis.thresholds``, ``.weights``,
    ``axis<k>.model.superposition.thresholds``, ``.weights``,
    ``axis<k>.model.input_offset``, ``.output_offset``, ``.output_sign``, the record start
    ``axis<k>.record_start.hysteresis.initial_states`` and the extension
    keys of the effect registry (``axis<k>.model.creep.time_constants``, ``.weights``,
    ``axis<k>.model.rate_dependence.time_constant``, ``axis<k>.model.thermal_drift.*``,
    ``axis<k>.model.dead_time``: declared from :data:`mpi_ros.extensions.EFFECTS`, unset by
    default); ``output.min`` / ``output.max`` (the node-wide safe range) and, optional per
    axis, ``axis<k>.output.min`` / ``axis<k>.output.max`` (unset: the node-wide value; once
    set, a key can be changed but not unset again while the node runs); ``enabled``,
    ``sample_period``, ``start_state`` (where every axis starts, as for the single-axis
    node; explicit states apply to every axis), ``message_time``, ``dead_time_prediction``,
    ``diagnostics_period``,
    ``qos_depth``,
    ``qos_reliability``.  Every axis's range (its own keys, or the node-wide ones it falls
    back to) must be finite with min < max; ``/diagnostics`` reports ``output_min`` /
    ``output_max`` as one value, or as space-separated per-axis lists when the axes'
    ranges differ, and ``extension``, each axis's model kind as a space-separated list
    (``none``, ``creep``, ``rate_dependence``, ``thermal_drift``, ``dead_time``; with
    ``dead_time_prediction`` false a dead time is not compensated, see
    ``not_compensated``), with ``axis<k>.slow_state`` for each
    axis whose effect has lags.

Extended models per axis
    Each axis follows the single-axis node's rules for its own keys (module docstring of
    :mod:`mpi_ros.nodes.compensator`): an extension is off while its keys are unset or 0 /
    empty; at most one extension per axis; a request with all four Gamma keys of an axis
    describes that axis's whole model (its operating-point keys left out return to their
    defaults, its extension keys left out switch its extension off); extension keys alone
    change the extension of the axis's running Gamma (an axis without Gamma refuses them);
    a YAML ``null`` switches an extension key off, resets an operating-point key, leaves an
    unset key unset and is refused for a key of Gamma; a swap within the same kind keeps
    the slow states, a change of kind starts them settled at the axis's last command.  A
    dead time cannot be inverted: by default (``dead_time_prediction``) that axis drives
    Gamma^-1 of its desired displacement predicted the dead time ahead
    (:mod:`mpi_ros.compensation.prediction`); with it false it compensates its Gamma alone
    (a warning is logged).  The plain axes keep the compiled loop; an axis with an effect
    or a predicted dead time is stepped by its own compensator, sample by sample, next to
    it.

Time stamps of a chunk (``message_time``, :mod:`mpi_ros.compensation.message_time`)
    An array message of K samples arrives at one time; its samples are the stream's own
    time base, never the jittered arrivals.  With ``nominal`` (the default) the lags see
    ``sample_period`` between every two samples, across messages too (no clock is read).
    With ``arrival`` the same, but a message that comes more than the pause threshold
    (100 sample periods, at least 0.1 s) after the previous one starts after the pause,
    counted in whole sample periods (:class:`mpi_ros.compensation.message_time.MessageClock`;
    the first message's last sample is at its arrival on the steady clock).  The clock is
    read only while some axis has an effect with lags.

Model updates
    The single-axis rule, per axis: a request is laid over the running values, and every
    axis it touches is validated whole; if all are valid they are applied together
    (bumpless, each axis from its own applied current), otherwise the whole request is
    refused with a reason naming the axis and key, and nothing changes.  So one
    ``set_parameters_atomically`` (the identifier's push) changes several axes
    atomically; ``ros2 param load`` sends the file's ``axis*.model.*`` keys as one group
    too.  The four Gamma keys of an axis in one request describe its whole model (see
    Extended models per axis).  The output limits,
    node-wide and per axis, belong to the same request: a request that sets a model and its
    limits is applied whole (limits first, then the model) or refused whole, and in a
    ``set_parameters`` request (``ros2 param load``) the model keys and every limit key form
    one group.  Until every axis has a model the node is unconfigured and publishes nothing
    (diagnostics WARN).
"""

import time
from typing import Any, Callable, Dict, List, Optional, Tuple

import numpy as np
from rclpy.serialization import deserialize_message
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray

from .compensator_base import CompensatorNodeBase, DRAIN_LIMIT
from .parameters import declare_parameters, parameter_values
from ..array_layout import (
    ArrayLayoutError, block_of, encode_flat_float64_multiarray, encode_float64_multiarray,
)
from ..compensation import MultiAxisCompensator
from ..compensation.message_time import MessageClock
from ..compensation.multi_axis import (
    AxisModels, InputCounts, joint_input, joint_names, JointOrder,
    reported_counters,
)
from ..compensation.status import multi_axis_status, multi_axis_values
from ..compensation.updates import apply, axis_key, load_axes, Prepared, refusal
from ..errors import ParameterRejected
from ..node_parameters import specs_by_name
from ..node_parameters.compensator import (
    AXES, axis_limit_parameters, axis_parameters, AxisKeys, INPUT_MESSAGE, JOINTS,
    multi_axis_parameters, OUTPUT_LAYOUT, single_axis_keys, WIRING,
)

__all__ = ['AXES', 'INPUT_MESSAGE', 'JOINTS', 'MultiAxisCompensatorNode', 'OUTPUT_LAYOUT',
           'axis_key', 'axis_parameters', 'joint_names']

#: Most messages served in one subscription callback (patched by tests).
_DRAIN_LIMIT = DRAIN_LIMIT


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
        self._specs = dict(specs_by_name((AXES,) + multi_axis_parameters() + WIRING))
        declare_parameters(self, (AXES,))
        self.axes = int(self.get_parameter('axes').value)
        # A single-axis file (mpi-ros identify's) would be ignored here: refuse it.
        # rclpy 7.1.6 has no public accessor of the overrides (see declare_parameters).
        stray = single_axis_keys(getattr(self, '_parameter_overrides', {}))
        if stray:
            shown = ', '.join(stray[:2]) + (f' and {len(stray) - 2} more' if len(stray) > 2
                                            else '')
            msg = (f'single-axis model keys given ({shown}) to a node serving {self.axes} '
                   'axes, which reads axis<k>.model.* only: they would be ignored and the '
                   'axes left without a model; merge one identified file per axis with '
                   '`mpi-ros merge-axes a.yaml b.yaml -o axes.yaml`, or run with axes:=1')
            raise ParameterRejected(msg)
        per_axis = axis_parameters(self.axes) + axis_limit_parameters(self.axes)
        self._specs.update(specs_by_name(per_axis))
        self._keys = AxisKeys.of(self.axes)
        self._rule.prefixes = self._keys.prefixes
        # Models and limits of one set_parameters request succeed or fail together.
        self._groups = (self._keys.group(),)
        declare_parameters(self, per_axis + multi_axis_parameters() + WIRING)
        self._declared()
        self.joints = joint_names(self.get_parameter('joints').value, self.axes)
        self._flat = self.get_parameter('output_layout').value == 'flat'
        joint_state = joint_input(self.joints, self.get_parameter('input_message').value)

        self._axis_models = AxisModels(
            self.axes, dead_time_prediction=self.get_parameter('dead_time_prediction').value)
        self._compensator: Optional[MultiAxisCompensator] = None
        # message_time: arrival reads the steady clock (CLOCK_MONOTONIC) per message while
        # some axis has an effect with lags (_timed) and counts only the stream's pauses
        # (MessageClock); nominal never reads it.
        self._arrival_clock: Optional[Callable[[], float]] = (
            time.monotonic if self.get_parameter('message_time').value == 'arrival' else None)
        self._timed = False
        self._message_clock = MessageClock()
        self._inputs = InputCounts()
        self._joint_order = JointOrder(self.joints or ())
        # Last: with autostart, configure (_load: the models) and activate run here.
        if joint_state:
            self._open_topics(Float64MultiArray, 'desired_joint_states', 'current_commands',
                              self._on_joint_states, 'desired joint states',
                              input_type=JointState)
        else:
            self._open_topics(Float64MultiArray, 'desired_displacements', 'current_commands',
                              self._on_desired_displacements, 'desired displacement arrays')

    # -- public read-only state -------------------------------------------------------
    @property
    def compensator(self) -> Optional[MultiAxisCompensator]:
        """Return the core (one Compensator per axis), or None until every axis has a model."""
        return self._compensator

    def command(self, block: Any, *, times: Any = None) -> Any:
        """
        Compute (and count) the commands of one samples x axes block, without publishing.

        Parameters
        ----------
        block : array_like of float, shape (K, N)
            Desired displacements [m].
        times : array_like of float, shape (K,), optional
            Time stamp [s] of each sample, for the lags of the axes with an effect; None:
            ``sample_period`` apart.

        Returns
        -------
        ndarray of float, shape (K, N), or None
            Current commands [A]; None until every axis has a model, and while the
            lifecycle state is not ``active``.

        """
        compensator = self._live
        if compensator is None:
            return None
        return compensator.command(np.asarray(block, dtype=np.float64), times)

    # -- message path -----------------------------------------------------------------
    def _on_desired_displacements(self, data: bytes) -> None:
        # As the single-axis node: raw messages, every queued one served here, sequence
        # numbers of the ones taken here checked for gaps.  A block is decoded by one
        # numpy view of the bytes and answered by one tobytes (mpi_ros.array_layout).
        inputs = self._inputs

        def serve(data: bytes) -> None:
            try:
                block = block_of(data, self.axes)
            except ArrayLayoutError as err:
                inputs.refuse('malformed', str(err))
                return
            inputs.samples += block.shape[0]
            self._serve(block)

        self._drain(data, Float64MultiArray, serve, raw=True, limit=_DRAIN_LIMIT)

    def _on_joint_states(self, data: bytes) -> None:
        # input_message joint_state: raw JointStates, deserialised here so that one that
        # cannot be is counted as malformed (rclpy would drop it without a word), each
        # one sample of every axis; queued ones taken here as in the array loop.
        self._drain(data, JointState, self._serve_joint_state, raw=True,
                    limit=_DRAIN_LIMIT)

    def _serve_joint_state(self, data: bytes) -> None:
        # The 1 x N block of a JointState in axis order, or None (refused, counted).
        try:
            msg = deserialize_message(data, JointState)
        except Exception as err:  # noqa: B902 - any undecodable message is malformed
            self._inputs.refuse('malformed', f'not a JointState ({len(data)} bytes): {err}')
            return
        block, fault, reason = self._joint_order.block(msg.name, msg.position)
        if block is None:
            self._inputs.refuse(fault, reason)
            return
        self._inputs.samples += 1
        self._serve(block)

    def _serve(self, block: Any) -> None:
        """Command one block and publish it in the output layout (no model or inactive: drop)."""
        compensator = self._live
        if compensator is None:
            self._drop()
            return
        commands = (self._timed_command(compensator, block) if self._timed
                    else compensator.command(block))
        publish = self._publisher.handle.publish_raw
        if self._flat:
            for row in commands:
                publish(encode_flat_float64_multiarray(row))
            self._messages_out += commands.shape[0]
        else:
            publish(encode_float64_multiarray(commands))
            self._messages_out += 1

    def _timed_command(self, compensator: MultiAxisCompensator, block: Any) -> Any:
        """Command a block with its samples' stream times (message_time: arrival)."""
        clock = self._arrival_clock
        now = clock() if clock is not None else 0.0      # _timed: always a clock
        return compensator.command(block, self._message_clock.times(
            now, block.shape[0], compensator.sample_period))

    # -- parameters ---------------------------------------------------------------------
    def _running(self, prefix: str) -> bool:
        return self._axis_models.models[self._keys.prefixes.index(prefix)] is not None

    def _rejection(self, names: List[str], err: Exception) -> str:
        return refusal(names, err, version=None, axes=True)

    def _install_prepared(self, prepared: List[Prepared]) -> None:
        compensator = self._compensator
        axes = compensator.axes if compensator is not None else None
        models = {}
        for update in prepared:
            axis = self._keys.prefixes.index(update.prefix)
            apply(update, axes[axis] if axes is not None else None)
            if update.model is not None:
                models[axis] = update.model
                self._axis_models.inverses[axis] = update.inverse
        # Lifecycle state unconfigured: the parameters hold them; configure loads them.
        if self._configured:
            self._install(models, installed=compensator is not None)
            self._check_axes_limits()

    def _check_axes_limits(self) -> None:
        """Warn about each axis whose limits cut its model's identified range."""
        if self._compensator is not None:
            for prefix, core in zip(self._keys.prefixes, self._compensator.axes):
                self._check_limits_fit(prefix, core)

    def _load(self) -> None:
        self._install(load_axes(parameter_values(self, list(self._specs)), self._keys.prefixes))
        self._check_axes_limits()
        if self._compensator is None:
            self.get_logger().info(
                f'{self.axes} axes, {len(self._axis_models.missing)} without a model: publishing '
                'nothing until every axis has one (axis<k>.model.* keys, e.g. pushed by the '
                'identifier)')

    def _unload(self) -> None:
        self._axis_models.reset()
        self._timed = False
        self._message_clock.reset()

    def _effective_limits(self) -> Tuple[List[float], List[float]]:
        """Return each axis's applied range [A]: its own keys, else the node-wide ones."""
        return self._keys.effective_limits(parameter_values(self, self._keys.all_limits))

    def _install(self, models: Dict[int, Any], *, installed: bool = False) -> None:
        """Note validated axis models (``installed``: swapped into the core already)."""
        if not models:
            return
        for axis, model in models.items():
            self._warn_if_not_compensated(model, f'axis {axis}: ')
            self._axis_models.note(axis, model)
            if self._compensator is not None and not installed:
                self._compensator.install(axis, model)
        built = self._compensator is None and not self._axis_models.missing
        if built:
            lows, highs = self._effective_limits()
            self._compensator = MultiAxisCompensator(
                self._axis_models.models, output_min=lows, output_max=highs,
                enabled=self.get_parameter('enabled').value,
                sample_period=self.get_parameter('sample_period').value,
                inverses=self._axis_models.inverses,
                start=self.get_parameter('start_state').value,
                dead_time_prediction=self._axis_models.dead_time_prediction,
                input_units=[self._input_unit(p) for p in self._keys.prefixes])
        self._set_live()
        compensator = self._compensator
        self._timed = (compensator is not None and self._arrival_clock is not None
                       and any(axis.has_effect for axis in compensator.axes))
        self.get_logger().info(self._axis_models.applied(models, compensator is not None))
        if built:
            self.get_logger().info(f'start state: {self._start_words()}')

    def _start_words(self) -> str:
        if self._compensator is None:
            return super()._start_words()
        return '; '.join(f'axis {k}: {axis.start_description}'
                         for k, axis in enumerate(self._compensator.axes))

    # -- diagnostics --------------------------------------------------------------------
    def _core_counters(self) -> Dict[str, int]:
        return reported_counters(self._compensator)

    def _node_counters(self) -> Dict[str, int]:
        return self._inputs.counters(joints=bool(self.joints))

    def _status_name(self) -> str:
        return f'{self.get_name()}: feedforward ({self.axes} axes)'

    def _status(self, losses: List[str], counters: Dict[str, int],
                before: Dict[str, int]) -> Tuple[int, str]:
        return multi_axis_status(
            losses, counters, before, what=self._what,
            last_malformed=self._inputs.last_malformed, last_missing=self._inputs.last_missing,
            missing_axes=self._axis_models.missing)

    def _status_values(self) -> Dict[str, Any]:
        compensator = self._compensator
        models = self._axis_models
        return multi_axis_values(
            models.models, model_versions=models.versions, joints=self.joints or (),
            flat=self._flat, limits=self._effective_limits(),
            slow_states=[] if compensator is None else compensator.slow_states,
            dead_time_prediction=self._axis_models.dead_time_prediction)
