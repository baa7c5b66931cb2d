# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Compensator node: desired displacement in, current command out, through the inverse (27).

The node holds the Float64 message path and its model's bookkeeping.  The model-update
rule below (null handling, whole-model completion, validation, the bumpless swap) is
:mod:`mpi_ros.compensation.updates`, on plain dicts; the parameter callbacks that convert
to and from it, grouped set_parameters, topics, loss accounting, counters and diagnostics
are shared with the multi-axis node in :mod:`mpi_ros.nodes.compensator_base`.

Topics (relative names, std_msgs/msg/Float64, SI units)
    ``desired_displacement`` (subscribed) [m] and ``current_command`` (published) [A];
    ``/diagnostics`` (diagnostic_msgs/msg/DiagnosticArray) every ``diagnostics_period``.
    A message that is not a CDR Float64 (fewer than 12 bytes, an unknown encapsulation)
    is dropped and counted (``malformed``, ``last_malformed``: diagnostics WARN); a
    non-finite value holds the last command (``nonfinite_input``).

Managed node (lifecycle)
    A :class:`rclpy.lifecycle.LifecycleNode` (the states and transitions are in
    :mod:`mpi_ros.nodes.compensator_base`): configure loads and validates the model of the
    parameters and builds the core, starting where ``start_state`` says (default
    ``rest_low``: at rest after a sweep down to the lowest identified input; ``record``: the
    identification record's ``record_start.*``; see :mod:`mpi_ros.operators.start`);
    activate publishes and logs the start; deactivate publishes nothing
    (inputs taken and dropped, the memory held, so re-activation continues bumplessly);
    cleanup and shutdown drop the core.  ``autostart`` (default true) configures and
    activates at start-up; ``/diagnostics`` reports ``lifecycle_state``.

Model life cycle
    The node has no model (its log says *no model given yet*, its diagnostics *no model:
    unconfigured*, apart from the lifecycle state) unless the four ``model.*`` keys of
    Gamma are given (e.g. ``--params-file params.yaml`` written by ``mpi-ros identify``).
    Without a model it publishes nothing: there is no safe command, and the current
    source keeps its last value. Its diagnostics say so (WARN).
    The model is every ``model.*`` key: Gamma's four arrays, the operating point
    (``model.input_offset`` [A], ``model.output_offset`` [m], ``model.output_sign``
    +1/-1, defaults 0, 0, +1: ``y = y0 + sign * S[H[x - x0]]``) and the extension keys.

Model updates (one rule for every path)
    A request is laid over the current values and the *whole* resulting model is
    validated (``extended_model_from_params`` and its inverse, built once per request:
    :func:`mpi_ros.compensation.updates.prepare`); if it is valid it is applied in one
    swap, otherwise every model key of the request is rejected with a reason naming the
    key and the running model and its parameters stay untouched.
    The model keys of one request always succeed or fail together:

    - ``set_parameters_atomically`` (the identifier's push): the request as it is.
    - ``set_parameters`` (``ros2 param load FILE`` sends all keys of the file in one
      such request; ``ros2 param set`` sends one key): rclpy would hand the callbacks
      the keys one at a time, so the node serves this service itself
      (:func:`mpi_ros.nodes.parameters.set_parameters_in_groups`): the request's
      ``model.*`` keys go through one atomic step at the position of the first one,
      every other key alone, as rclpy does. ``output.min`` and ``output.max`` are
      coupled the same way. A single key that gives a valid model (e.g. a new
      ``model.output_offset``) applies at once; keys that can only change together
      (a new order changes three arrays) go in one request.
    - In-process ``Node.set_parameters`` follows the same rule.

    Nothing is ever held back between requests, so the parameters always describe
    the running model. A request with all four keys of Gamma describes the whole
    model: the pre-set callback adds the default of every operating-point key and the
    "off" value of every extension key the request leaves out. The post-set callback
    swaps the prebuilt model in (bumpless, (14)). ``/diagnostics`` reports
    ``rejected_updates`` and ``last_rejected_update`` (the reason).

``null`` and ``ros2 param dump``
    A YAML ``null`` (how ``ros2 param dump`` writes an unset key) means "unset": at
    start it is ignored (``--params-file`` of a dump of an unconfigured node starts it
    unconfigured); at run time a ``null`` for an unset key is answered "stays unset",
    for an extension key it switches the extension off, for an operating-point key it
    sets the default, and for a key of Gamma it is rejected (a running model cannot be
    removed). An empty list loaded by ``ros2 param load`` is the empty array.

Extended models (:mod:`mpi_ros.extensions`)
    The ``model.creep.*``, ``model.rate_dependence.time_constant``,
    ``model.thermal_drift.*`` and ``model.dead_time`` keys add one extension to Gamma;
    the candidate is built with ``extended_model_from_params`` (a bad key is rejected with
    a reason naming it). Creep, rate dependence and thermal drift plug their per-step inverse
    (the lag's lead filter bounded) into the one :class:`~mpi_ros.compensation.Compensator`, on
    the stream's own time base (``message_time``, :mod:`mpi_ros.compensation.message_time`:
    ``nominal``, the default, ``sample_period`` apart; ``arrival``, the same but a pause of the
    stream counted in whole periods; never the jittered arrival times, which a lead filter
    would differentiate); a dead time has no causal inverse: by default
    (``dead_time_prediction``) the desired displacement is predicted the dead time ahead on
    the same nominal time base (:mod:`mpi_ros.compensation.prediction`, bounded: a step is
    not extrapolated), with ``dead_time_prediction: false`` Gamma alone is compensated and a
    warning is logged. An extension is off while its keys are unset or
    0 / empty. Pushing a plain model (all four core keys, no extension key) switches an
    extension off. Extension keys alone (no core key) change the extension of the running
    Gamma. Every new model, of any kind, is installed into the running compensator
    (:meth:`~mpi_ros.compensation.Compensator.install`): the turning points of the applied
    current are replayed through the new H ((14)), the last command and the counters go
    on; an effect of the same kind keeps its lag states, a new one starts them settled at
    the last command.
    The multi-axis node (``axes`` > 1) applies these rules to each axis's
    ``axis<k>.model.*`` keys (:mod:`mpi_ros.nodes.multi_axis`, which also says which times
    the samples of an array chunk get), calling the same rule once per axis prefix.

A ``--params-file`` with an invalid model, or with output limits that are not
ordered, makes the node refuse to start (exit status 1) rather than run a model
nobody asked for (with ``autostart: false`` it starts, and configure fails instead).
"""

import math
import struct
import sys
import time
from typing import Any, Callable, Dict, List, Optional, Tuple, Union

from rclpy.node import Node
from rclpy.parameter import Parameter
from std_msgs.msg import Float64

from . import adaptation_readings
from .compensator_base import CompensatorNodeBase, DRAIN_LIMIT
from .multi_axis import MultiAxisCompensatorNode
from .parameters import declare_parameters, parameter_values
from .qos import loop_qos
from .spinning import run_node_main
from ..array_layout import FLOAT64_SIZE, malformed_float64
from ..compensation import Compensator
from ..compensation.adaptation import (
    adaptable, Adaptation, AdaptationProcess, AdaptationSettings, AdaptationWorker,
    ReadingSource,
)
from ..compensation.message_time import MessageClock
from ..compensation.multi_axis import InputCounts
from ..compensation.status import single_axis_status, single_axis_values
from ..compensation.updates import (
    apply, LIMIT_KEYS, limits_of, load, model_keys, Prepared, refusal,
)
from ..node_parameters import specs_by_name
from ..node_parameters.compensator import compensator_parameters, wants_multi_axis
from ..units import INPUT_QUANTITY_KEY

__all__ = ['CompensatorNode', 'main', 'make_node']

#: Longest time [s] the adaptation's worker holds the interpreter lock at a time.
_SWITCH_INTERVAL = 5e-4

#: Longest wait [s] for the adaptation's process to open its readings subscription (the
#: node waits at configure, or at the first model, so that the first commands pair).
_READY_TIMEOUT_S = 30.0

#: Most messages served in one subscription callback (patched by tests).
_DRAIN_LIMIT = DRAIN_LIMIT


def __getattr__(name: str) -> Any:
    """Give ``PARAMETERS`` as :func:`parameters` returns it when asked (not at import)."""
    if name == 'PARAMETERS':
        return compensator_parameters()
    msg = f'module {__name__!r} has no attribute {name!r}'
    raise AttributeError(msg)


#: CDR of a Float64: 4-byte encapsulation header (byte 1: 1 = little-endian), the double.
_LITTLE = struct.Struct('<d').unpack_from
_BIG = struct.Struct('>d').unpack_from
_PACK = struct.Struct('<H2xd').pack
#: The encapsulation header CDR_LE as the little-endian unsigned short _PACK writes first.
_CDR_LE = 0x0100


class CompensatorNode(CompensatorNodeBase):
    """
    Feedforward hysteresis compensator: publishes Gamma^-1[desired] per message.

    Parameters
    ----------
    node_name : str
        Node name; ``compensator`` unless remapped.
    **kwargs
        Passed on to :class:`rclpy.node.Node` (``context=``, ``parameter_overrides=``,
        ``namespace=``...).

    Raises
    ------
    mpi_ros.errors.MPIError
        When the declared (``--params-file``) model or limits are invalid.

    """

    def __init__(self, node_name: str = 'compensator', **kwargs: Any) -> None:
        super().__init__(node_name, **kwargs)
        specs = compensator_parameters()
        self._specs = specs_by_name(specs)
        # Keys set together within one set_parameters request (set_parameters_in_groups).
        self._groups = (model_keys(), LIMIT_KEYS)
        self._compensator: Optional[Compensator] = None
        self._extended = False
        self._model_kind = 'none'
        self._model_version = 0
        self._adaptation: Optional[Union[Adaptation, AdaptationProcess]] = None
        self._worker: Optional[Union[AdaptationWorker, AdaptationProcess]] = None
        self._readings: Any = None
        self._record: Optional[Any] = None    # Adaptation.record_command while adapting
        self._own_update = False
        self._inputs = InputCounts()
        self._malformed_readings = 0      # of the adaptation's child, counted in _inputs
        declare_parameters(self, specs)
        self._declared()
        self._adapt = bool(self.get_parameter('adaptation.enabled').value)
        if self._adapt:
            self._adaptation_timer = self.create_timer(0.1, self._adaptation_tick)
        # message_time (mpi_ros.compensation.message_time): nominal reads no clock (each
        # message sample_period after the one before); arrival reads the steady clock
        # (CLOCK_MONOTONIC, without building a Time object per message) and counts only the
        # pauses of the stream, in whole sample periods.  Never the raw arrival times.
        self._arrival_clock: Callable[[], float] = time.monotonic
        self._message_clock = (MessageClock()
                               if self.get_parameter('message_time').value == 'arrival'
                               else None)
        # Last: with autostart, configure (_load: the model) and activate run here.
        self._open_topics(Float64, 'desired_displacement', 'current_command',
                          self._on_desired_displacement, 'desired displacements')

    # -- public read-only state -------------------------------------------------------
    @property
    def model_version(self) -> int:
        """Return how many models were applied so far (0: unconfigured)."""
        return self._model_version

    @property
    def compensator(self) -> Optional[Compensator]:
        """Return the core compensator: plain, extended, or ``None`` while unconfigured."""
        return self._compensator

    @property
    def adaptation(self) -> Optional[Union[Adaptation, AdaptationProcess]]:
        """Online adaptation of the model (``adaptation.enabled`` and a model), else None."""
        return self._adaptation

    def command(self, desired_displacement: float, *,
                stamp: Optional[float] = None) -> Optional[float]:
        """
        Compute (and count) the command for one desired displacement, without publishing.

        Parameters
        ----------
        desired_displacement : float
            Desired displacement [m]; any float, including NaN and +-Inf.
        stamp : float, optional
            Time of the desired displacement [s] (any steady time base); drives the lags
            of an extended model. None: ``sample_period`` after the previous one.

        Returns
        -------
        float or None
            Current command [A], finite and within [output.min, output.max];
            ``None`` without a model or while the lifecycle state is not ``active``.

        """
        self._messages_in += 1
        compensator: Optional[Compensator] = self._live
        if compensator is None:
            self._drop()
            return None
        current = compensator.command(desired_displacement, time=stamp)
        if self._record is not None:
            self._record(current)
        return current

    # -- message path -----------------------------------------------------------------
    def _on_desired_displacement(self, data: bytes) -> None:
        # The lean per-sample path (docs/reliability.md has where its time goes).  The
        # subscription is raw: each message arrives as its CDR bytes (a 4-byte
        # encapsulation header, then the double), is decoded with one struct call and
        # answered with 12 bytes packed by another, published raw: no Float64 object is
        # built either way.  Every queued message is served in this callback (_drain), one
        # by one, in order, each with its own command and, for an extended model with
        # message_time arrival, its time on the stream's clock (nominal spacing; pauses).
        # The bytes are checked before they are decoded (any process on the domain may
        # publish anything): a message that is not a CDR Float64 is counted as malformed
        # (/diagnostics) and dropped.
        publish = self._publisher.handle.publish_raw
        record = self._record
        inputs = self._inputs

        def serve(data: bytes) -> None:
            if len(data) < FLOAT64_SIZE or data[0] != 0 or data[1] > 1:
                inputs.refuse('malformed', malformed_float64(data))
                return
            value = (_LITTLE(data, 4) if data[1] == 1 else _BIG(data, 4))[0]
            compensator = self._live
            if compensator is None:
                self._drop()          # no model, or not active: nothing published
                return
            clock = self._message_clock
            if self._extended and clock is not None:
                stamp = clock.time(self._arrival_clock(), compensator.sample_period)
                current = compensator.command(value, time=stamp)
            else:
                current = compensator.command(value)
            publish(_PACK(_CDR_LE, current))
            self._messages_out += 1
            if record is not None:
                record(current)

        self._drain(data, Float64, serve, raw=True, limit=_DRAIN_LIMIT)

    # -- parameters ---------------------------------------------------------------------
    def _running(self, prefix: str) -> bool:
        return self._compensator is not None

    def _rejection(self, names: List[str], err: Exception) -> str:
        version = None if self._compensator is None else self._model_version
        return refusal(names, err, version=version)

    def _install_prepared(self, prepared: List[Prepared]) -> None:
        update = prepared[0]
        model = apply(update, self._compensator)
        # Lifecycle state unconfigured: the parameters hold it; configure loads it.
        if update.model is not None and self._configured:
            self._installed(model, update.inverse)
        elif update.limits is not None and self._compensator is not None:
            self._check_limits_fit('', self._compensator)

    def _load(self) -> None:
        values = parameter_values(self, list(self._specs))
        limits_of(values)
        model = load(values)
        if model is None:
            self.get_logger().info(
                'no model given yet: publishing nothing until a model arrives (all four '
                'model.* keys of Gamma in one request: ros2 param load, or '
                'set_parameters_atomically, e.g. by the identifier)')
            return
        self._installed(model)

    def _unload(self) -> None:
        self._extended = False
        self._model_kind = 'none'
        self._stop_adaptation()
        if self._message_clock is not None:
            self._message_clock.reset()

    def _installed(self, model: Any, inverse: Any = None) -> None:
        """Count a model swapped in; build the core when there was none (``model`` given)."""
        compensator = self._compensator
        built = compensator is None
        if compensator is None:
            compensator = self._compensator = Compensator(
                model, output_min=self.get_parameter('output.min').value,
                output_max=self.get_parameter('output.max').value,
                enabled=self.get_parameter('enabled').value,
                sample_period=self.get_parameter('sample_period').value, inverse=inverse,
                start=self.get_parameter('start_state').value,
                dead_time_prediction=self.get_parameter('dead_time_prediction').value,
                input_unit=self._input_unit())
        self._warn_if_not_compensated(compensator.model)
        self._check_limits_fit('', compensator)
        self._set_live()
        self._extended = compensator.has_effect
        self._model_version += 1
        self._model_kind = compensator.kind
        self.get_logger().info(
            f'model version {self._model_version} applied ({self._model_kind})'
            + (f'; start state: {compensator.start_description}' if built else ''))
        if self._adapt and not self._own_update:
            self._start_adaptation(compensator.model)

    def _start_words(self) -> str:
        if self._compensator is None:
            return super()._start_words()
        return self._compensator.start_description

    # -- online adaptation ----------------------------------------------------------------
    def _open_loop(self) -> None:
        super()._open_loop()
        # With the adaptation in its child process the child subscribes to the readings
        # itself (mpi_ros.nodes.adaptation_readings): this process never takes one.
        if self._adapt and not self.get_parameter('adaptation.process').value:
            qos = loop_qos(self.get_parameter('qos_depth').value,
                           self.get_parameter('qos_reliability').value)
            self._readings = self.create_subscription(
                Float64, 'displacement', self._on_displacement, qos, raw=True)

    def _close_loop(self) -> None:
        readings, self._readings = self._readings, None
        if readings is not None:
            self.destroy_subscription(readings)
        super()._close_loop()

    def _on_displacement(self, data: bytes) -> None:
        # Every reading queued is taken in this one callback (as the command path does),
        # as CDR bytes, decoded by one struct call and appended to a list.
        adaptation = self._adaptation
        take = self._readings.handle.take_message
        for _ in range(_DRAIN_LIMIT):
            if len(data) < FLOAT64_SIZE or data[0] != 0 or data[1] > 1:
                self._inputs.refuse('malformed', malformed_float64(data))
                if adaptation is not None:
                    # Its place kept: the next reading still answers the next command.
                    adaptation.record_measurement(math.nan)
            elif adaptation is not None:
                adaptation.record_measurement(
                    (_LITTLE(data, 4) if data[1] == 1 else _BIG(data, 4))[0])
            taken = take(Float64, True)
            if taken is None:
                return
            data = taken[0]

    def _start_adaptation(self, model: Any) -> None:
        # A model that arrives from outside (configure, a push) starts the adaptation
        # afresh; the adaptation's own updates continue it.
        if not adaptable(model):
            self._stop_adaptation()
            self.get_logger().warning(
                f'adaptation.enabled: adaptation adapts Gamma with n >= 1, alone or with a'
                f' thermal drift; off for this model ({self._model_kind})')
            return
        if self._adaptation is not None:
            self._adaptation.reset(model)
            self.get_logger().info('adaptation restarted from the new model')
            return
        values = parameter_values(self, [k for k in self._specs if k.startswith('adaptation.')])
        settings = AdaptationSettings.from_values(
            values, self.get_parameter('sample_period').value)

        def on_error(text: str) -> None:
            self.get_logger().error(f'adaptation step failed: {text}')

        if self.get_parameter('adaptation.process').value:
            # Its own process: the command path never waits for a step's interpreter lock,
            # and never serves a reading: the child subscribes to them itself, with this
            # node's QoS on this node's resolved topic; the node sends it the commands.
            source = ReadingSource(
                topic=self.resolve_topic_name('displacement'),
                depth=self.get_parameter('qos_depth').value,
                reliability=self.get_parameter('qos_reliability').value,
                sample_period=settings.sample_period,
                node_name=f'{self.get_name()}_adaptation', namespace=self.get_namespace())
            process = AdaptationProcess(model, settings, on_error=on_error, readings=source,
                                        entry=adaptation_readings.__name__)
            self._adaptation = self._worker = process
        else:
            # A thread shares the interpreter lock with the command path: let it hold the
            # lock for at most 0.5 ms at a time (Python's default is 5 ms).
            sys.setswitchinterval(min(sys.getswitchinterval(), _SWITCH_INTERVAL))
            self._adaptation = Adaptation(model, settings)
            self._worker = AdaptationWorker(self._adaptation, on_error=on_error)
        self._record = self._adaptation.record_command
        self._worker.start()
        if isinstance(self._worker, AdaptationProcess) and not self._worker.wait_ready(
                _READY_TIMEOUT_S):
            # Commands before the child's subscription is open are not paired (dropped).
            self.get_logger().warning(
                f'adaptation: its process did not open the readings subscription within'
                f' {_READY_TIMEOUT_S:g} s; the commands before it does are not paired')
        self.get_logger().info(
            f'adaptation on: readings on {self.resolve_topic_name("displacement")}, paired'
            f' in lock step (delay {settings.delay} samples), memory'
            f' {settings.forgetting_time:g} s, candidates every {settings.period:g} s,'
            f' held out {settings.holdout:g} s, margin {100 * settings.margin:g} %; fitting in'
            + (f' process {self._worker.pid} (which takes the readings;'
               f' {self._worker.priority_words})'
               if isinstance(self._worker, AdaptationProcess) else ' a thread'))
        if isinstance(self._worker, AdaptationProcess) and self._worker.publishers == 0:
            self.get_logger().warning(
                f'adaptation: no publisher of {self.resolve_topic_name("displacement")} yet;'
                ' commands published before the readings reach the adaptation do not pair')

    def _stop_adaptation(self) -> None:
        worker, self._worker = self._worker, None
        if worker is not None:
            worker.stop()
        self._adaptation = None
        self._record = None
        self._malformed_readings = 0

    def _adaptation_tick(self) -> None:
        adaptation = self._adaptation
        if adaptation is None:
            return
        if isinstance(adaptation, AdaptationProcess):
            adaptation.exchange()
            # Malformed readings the child dropped count as this node's malformed inputs.
            inputs, seen = self._inputs, self._malformed_readings
            if adaptation.malformed > seen:
                inputs.malformed += adaptation.malformed - seen
                inputs.last_malformed = adaptation.last_malformed
                self._malformed_readings = adaptation.malformed
        candidate = adaptation.take_candidate()
        if candidate is not None:
            values = candidate.params()
            # A whole model without the input quantity would be a current model: the
            # adaptation changes weights and offsets, never what the input is.
            quantity = self.get_parameter(INPUT_QUANTITY_KEY).value
            if quantity:
                values[INPUT_QUANTITY_KEY] = quantity
            parameters = [Parameter(key, value=value) for key, value in values.items()]
            self._own_update = True
            try:
                results = self.set_parameters(parameters)
            finally:
                self._own_update = False
            refused = [r.reason for r in results if not r.successful]
            adaptation.applied(candidate, not refused, '; '.join(refused))
        for event in adaptation.events():
            self.get_logger().info(f'adaptation: {event}')

    def destroy_node(self) -> None:
        """Stop the adaptation's thread, then destroy the node."""
        self._stop_adaptation()
        super().destroy_node()

    # -- diagnostics --------------------------------------------------------------------
    def _core_counters(self) -> Dict[str, int]:
        return dict(self._compensator.counters) if self._compensator else {}

    def _node_counters(self) -> Dict[str, int]:
        return {'model_version': self._model_version, 'malformed': self._inputs.malformed}

    def _status_name(self) -> str:
        return f'{self.get_name()}: feedforward'

    def _status(self, losses: List[str], counters: Dict[str, int],
                before: Dict[str, int]) -> Tuple[int, str]:
        return single_axis_status(losses, counters, before,
                                  has_model=self._compensator is not None,
                                  enabled=self.get_parameter('enabled').value,
                                  last_malformed=self._inputs.last_malformed)

    def _status_values(self) -> Dict[str, Any]:
        compensator = self._compensator
        malformed = {'last_malformed': self._inputs.last_malformed}
        if compensator is None:
            return malformed
        values = {**single_axis_values(
            self._model_kind, compensator.slow_state if compensator.has_effect else None),
            **malformed}
        if self._adaptation is not None:
            values.update(self._adaptation.status())
        return values


def main(args: Optional[List[str]] = None) -> int:
    """
    Run the compensator node (``ros2 run mpi_ros compensator --ros-args ...``).

    ``args`` is the command line for ``rclpy.init`` (program name first; ``sys.argv`` if
    None).  Returns the exit status: 0 on shutdown (a signal, or the lifecycle transition
    ``shutdown``), 1 when the configured model or limits are invalid (with ``autostart``).

    """
    return run_node_main(make_node, 'compensator', args, until=_finalized)


def _finalized(node: Any) -> Any:
    """Return the future the spin ends with: the node reached ``finalized``."""
    return node.finalized


def make_node(**kwargs: Any) -> Node:
    """
    Build the compensator the parameters ask for: single-axis, or the multi-axis node.

    The multi-axis node (array topics, ``axis<k>.model.*`` keys) serves ``axes`` > 1, and
    any axis count whose ros2_control wiring is asked for (``joints`` given,
    ``output_layout: flat`` or ``input_message: joint_state``: one joint is one axis).
    These are read from the overrides (``-p axes:=8``, ``--params-file``) the way rclpy
    gives them to a node of this name: a short-lived probe node (no parameter services,
    no rosout) is created and destroyed first.

    Parameters
    ----------
    **kwargs
        Passed on to the node (``context=``, ``parameter_overrides=``...).

    Returns
    -------
    rclpy.node.Node
        A :class:`CompensatorNode` or a
        :class:`mpi_ros.nodes.multi_axis.MultiAxisCompensatorNode`.

    """
    probe = Node('compensator', start_parameter_services=False, enable_rosout=False,
                 **kwargs)
    try:
        # rclpy 7.1.6 has no public accessor of the overrides (see declare_parameters).
        overrides = getattr(probe, '_parameter_overrides', {})
        given = {name: override.value for name, override in overrides.items()}
    finally:
        probe.destroy_node()
    if wants_multi_axis(given):
        return MultiAxisCompensatorNode(**kwargs)
    return CompensatorNode(**kwargs)
