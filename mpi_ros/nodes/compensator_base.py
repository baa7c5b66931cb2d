# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
What the two compensator nodes share: parameter rule, topics, loss, counters, diagnostics.

:class:`CompensatorNodeBase` is the shell of both compensator nodes,
:class:`~mpi_ros.nodes.compensator.CompensatorNode` (one actuator, ``std_msgs/Float64``) and
:class:`~mpi_ros.nodes.multi_axis.MultiAxisCompensatorNode` (N actuators,
``std_msgs/Float64MultiArray``).  It holds

- the parameter rule's frame: the three parameter callbacks registered before any key is
  declared (rclpy runs the validator once per key while declaring, so a bad
  ``--params-file`` override is rejected there), the validator that only checks and has
  the core keep the prepared candidate and count the refusals
  (:class:`~mpi_ros.compensation.updates.UpdateRule`: ``rejected_updates``,
  ``last_rejected_update``; the node logs the warning), the post-set swap, the re-created
  diagnostics timer on ``diagnostics_period``, and the grouped ``set_parameters`` (model
  keys and the output limits set together,
  :func:`mpi_ros.nodes.parameters.set_parameters_in_groups`);
- the topics: the raw subscription and publisher of the loop with their
  :class:`~mpi_ros.nodes.loss.LossMonitor`, ``/diagnostics`` and the two timers;
- the lifecycle (a managed node, :class:`rclpy.lifecycle.LifecycleNode`): configure loads
  the model(s) from the parameters and opens the loop topics, activate starts publishing,
  deactivate stops it (inputs are taken and dropped, the turning-point memory is held),
  cleanup closes the topics and drops the core, shutdown does the same and completes
  :attr:`CompensatorNodeBase.finalized`; ``autostart`` (default true) configures and
  activates at start-up;
- the message counters, the once-a-second log of losses and bad inputs (throttled by
  the core's :class:`~mpi_ros.compensation.loss.LossCounter` and
  :class:`~mpi_ros.compensation.screening.FaultLog`, which also word them), and the frame
  of the diagnostics message (the core's
  :class:`~mpi_ros.compensation.status.RateWindow`, loss problems, common values);
- the conversion between rclpy's ``Parameter`` and the dicts of the model-update rule
  (:mod:`mpi_ros.compensation.updates`: null handling and whole-model completion in the
  pre-set callback, :func:`~mpi_ros.compensation.updates.prepare` per model prefix touched
  in the on-set callback - ``''`` for the single-axis node, ``axis<k>.`` for each axis -,
  :func:`~mpi_ros.compensation.updates.apply` in the post-set callback), and the
  parameters ``sample_period`` and ``message_time`` of the extensions' lags.

Each node keeps what differs: its message type and its drain loop (decode, command,
encode, publish: the per-message path stays in the node so that it costs no extra Python
call per message), its parameter specs and model prefixes, its core's installation,
what configure loads and cleanup drops, and its diagnostics status.

Lifecycle states (what each publishes on the loop's output topic)
    ``unconfigured``: no loop topics, no core, nothing published; parameter pushes are
    validated by the same rule as in every state and stored; configure loads them.
    ``inactive``: loop topics open, core built (turning-point memory at the model's start
    state after configure, held after a deactivation); every input is taken and dropped
    (counted ``dropped_inactive``, never replayed later), nothing is published; pushes are
    installed into the core as while active.  ``active``: one command per input.
    ``finalized``: as unconfigured; the node's main returns (the process exits 0).
    ``/diagnostics`` reports ``lifecycle_state`` in every state.
"""

import time
import traceback
from typing import Any, Callable, Dict, List, Mapping, Optional, Tuple

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from rcl_interfaces.msg import SetParametersResult
from rclpy.impl.implementation_singleton import rclpy_implementation as _rclpy
from rclpy.lifecycle import LifecycleNode, LifecycleState, TransitionCallbackReturn
from rclpy.parameter import Parameter
from rclpy.task import Future

from .loss import LossMonitor
from .parameters import (
    check_parameters, harden_parameter_services, is_null, normalized, parameter_values,
    set_parameters_in_groups,
)
from .qos import loop_qos
from ..compensation.limits import limits_shortfall
from ..compensation.screening import FaultLog
from ..compensation.status import lifecycle_status, RateWindow, state_after, status_values
from ..compensation.updates import Prepared, uncompensated, UpdateRule
from ..errors import MPIError, ParameterRejected
from ..node_parameters import ParameterSpec, plain_value
from ..units import INPUT_QUANTITY_KEY, input_unit_of

__all__ = ['CompensatorNodeBase', 'DRAIN_LIMIT']


#: Most messages served in one subscription callback (a flood still lets a stop through).
DRAIN_LIMIT = 1000


class CompensatorNodeBase(LifecycleNode):
    """
    Shell shared by the compensator nodes (see the module docstring).

    A node subclass sets ``self._specs`` and ``self._groups`` before it declares its
    parameters, then calls :meth:`_declared`, sets up its own state, and calls
    :meth:`_open_topics` with its drain loop last (which runs ``autostart``).  It fills the
    hooks below (``_load``, ``_unload``, ``_running``, ``_install_prepared``,
    ``_rejection``, ``_core_counters``, ``_node_counters``,
    ``_status``, ``_status_values``, ``_status_name``).

    Parameters
    ----------
    node_name : str
        Node name.
    **kwargs
        Passed on to :class:`rclpy.lifecycle.LifecycleNode` (``context=``,
        ``parameter_overrides=``...).

    Attributes
    ----------
    finalized : rclpy.task.Future
        Done once the node reached the lifecycle state ``finalized`` (its main then ends).

    """

    def __init__(self, node_name: str, **kwargs: Any) -> None:
        super().__init__(node_name, **kwargs)
        self._declaring = True
        # The model-update rule's state between the callbacks; its prefixes are the
        # node's models ('' here; a multi-axis node sets axis<k>. once it knows N).
        self._rule = UpdateRule()
        self._specs: Mapping[str, ParameterSpec] = {}
        self._groups: Tuple[Tuple[str, ...], ...] = ()
        self._compensator: Any = None
        # The core that serves messages: the compensator while active, else None.
        self._live: Any = None
        self._configured = False
        self._active = False
        self._loop: Optional[Tuple[Any, ...]] = None
        self._subscription: Any = None
        self._publisher: Any = None
        self._transition_error: Optional[Exception] = None
        self.finalized = Future()
        self._messages_in = 0
        self._messages_out = 0
        self._dropped_unconfigured = 0
        self._dropped_inactive = 0
        self._what = 'desired displacements'
        self._window = RateWindow(time.monotonic())
        self._fault_log = FaultLog()
        # What the output limits cut of each model's identified range, by label.
        self._limits_notes: Dict[str, str] = {}
        # Validator first: rclpy runs it once per key while declaring (a bad
        # --params-file override is rejected there), then once per request.
        self.add_pre_set_parameters_callback(self._complete_request)
        self.add_on_set_parameters_callback(self._validate_parameters)
        self.add_post_set_parameters_callback(self._apply_parameters)
        self._guard_change_state()

    def _guard_change_state(self) -> None:
        """
        Answer a transition the current state does not have with ``success: false``.

        rclpy 7.1.6's ``change_state`` service raises ``RCLError`` out of the executor for
        a transition *id* that the current state does not offer (e.g. activate while
        unconfigured; a label is answered false), which would end the node.
        """
        service = getattr(self, '_service_change_state', None)   # rclpy 7.1.6: private
        if service is None:
            return
        callback = service.callback

        def guarded(request: Any, response: Any) -> Any:
            try:
                return callback(request, response)
            except _rclpy.RCLError as err:
                transition = request.transition
                self.get_logger().warning(
                    f'lifecycle: transition {transition.id} {transition.label!r} refused in '
                    f'state {self.lifecycle_state}: {err}; ros2 lifecycle list '
                    f'{self.get_fully_qualified_name()} lists the available ones')
                response.success = False
                return response

        service.callback = guarded

    def destroy_node(self) -> None:
        """Destroy the node, and its lifecycle state machine now rather than when collected."""
        super().destroy_node()
        # rclpy 7.1.6 leaves the state machine to the garbage collector, which may run its
        # rcl finaliser anywhere later, e.g. in a child process forked by a test.
        self._state_machine.destroy_when_not_in_use()

    def _declared(self) -> None:
        """Close the declaration phase: serve set_parameters in groups from now on."""
        harden_parameter_services(self, groups=self._groups, specs=self._specs)
        self._declaring = False

    def _open_topics(self, message_type: Any, input_topic: str, output_topic: str,
                     callback: Callable[[Any], None], what: str, *,
                     input_type: Any = None, raw: bool = True) -> None:
        """
        Open /diagnostics and the timers, note the loop topics, and run ``autostart``.

        The loop topics (``input_topic`` of ``input_type``, default ``message_type``,
        subscribed raw unless ``raw`` is False; ``output_topic`` of ``message_type``) are
        created by configure and destroyed by cleanup (:meth:`_open_loop`).
        """
        self._what = what
        self._loop = (message_type, input_topic, output_topic, callback,
                      message_type if input_type is None else input_type, raw)
        reliability = self.get_parameter('qos_reliability').value
        # Counts what never arrived (sequence gaps, DDS sample-lost, incompatible peers).
        self._loss = LossMonitor(self, input_topic, output_topic, reliability)
        self._diagnostics = self.create_publisher(DiagnosticArray, '/diagnostics', 10)
        self._timer = self.create_timer(
            self.get_parameter('diagnostics_period').value, self._publish_diagnostics)
        self._second_timer = self.create_timer(1.0, self._every_second)
        if self.get_parameter('autostart').value:
            self._autostart()

    def _autostart(self) -> None:
        """Configure and activate now; raise what made configure fail (refuse to start)."""
        if self.trigger_configure() != TransitionCallbackReturn.SUCCESS:
            error = self._transition_error
            self.destroy_node()
            if error is not None:
                raise error
            msg = 'configure failed at start-up (autostart); see the log'
            raise ParameterRejected(msg)
        if self.trigger_activate() != TransitionCallbackReturn.SUCCESS:
            self.destroy_node()
            msg = 'activate failed at start-up (autostart); see the log'
            raise ParameterRejected(msg)

    def _open_loop(self) -> None:
        """Create the loop's publisher and (raw) subscription with their loss monitor."""
        assert self._loop is not None   # noqa: S101 - _open_topics ran in __init__
        message_type, input_topic, output_topic, callback, input_type, raw = self._loop
        reliability = self.get_parameter('qos_reliability').value
        qos = loop_qos(self.get_parameter('qos_depth').value, reliability)
        self._loss.restart()
        self._publisher = self.create_publisher(
            message_type, output_topic, qos, event_callbacks=self._loss.publisher_callbacks())
        self._subscription = self.create_subscription(
            input_type, input_topic, callback, qos, raw=raw,
            event_callbacks=self._loss.subscription_callbacks())
        self._loss.publisher_count = self._subscription.get_publisher_count

    def _close_loop(self) -> None:
        """Destroy the loop's subscription and publisher (if open)."""
        subscription, self._subscription = self._subscription, None
        publisher, self._publisher = self._publisher, None
        if subscription is not None:
            self.destroy_subscription(subscription)
            self._loss.publishers = 0
        if publisher is not None:
            self.destroy_publisher(publisher)

    def _set_live(self) -> None:
        """Serve messages with the core while active; drop them otherwise."""
        self._live = self._compensator if self._active else None

    def _drop(self) -> None:
        """Count an input that got no command: not active, or no model."""
        if self._active:
            self._dropped_unconfigured += 1
        else:
            self._dropped_inactive += 1

    # -- lifecycle ----------------------------------------------------------------------
    @property
    def lifecycle_state(self) -> str:
        """
        Return the lifecycle state's label.

        ``unconfigured``, ``inactive``, ``active``, ``finalized`` (or a transition state,
        e.g. ``configuring``, while a transition runs).
        """
        # rclpy 7.1.6 has no public accessor of the state machine's current state.
        return str(self._state_machine.current_state[1])

    def on_configure(self, state: LifecycleState) -> TransitionCallbackReturn:
        """Load and validate the model(s) from the parameters, build the core, open topics."""
        return self._transition('configure', self._configure)

    def on_activate(self, state: LifecycleState) -> TransitionCallbackReturn:
        """Start publishing: one command per input, from the memory the core holds."""
        return self._transition('activate', lambda: self._switch(True))

    def on_deactivate(self, state: LifecycleState) -> TransitionCallbackReturn:
        """Stop publishing: inputs are taken and dropped, the memory is held."""
        return self._transition('deactivate', lambda: self._switch(False))

    def on_cleanup(self, state: LifecycleState) -> TransitionCallbackReturn:
        """Close the loop topics and drop the core (back to the state after creation)."""
        return self._transition('cleanup', self._release)

    def on_shutdown(self, state: LifecycleState) -> TransitionCallbackReturn:
        """Release everything from any state and let the node's main end."""
        return self._transition('shutdown', self._finalize)

    def on_error(self, state: LifecycleState) -> TransitionCallbackReturn:
        """Release everything after a transition raised; the node goes to unconfigured."""
        self._release()           # keeps _transition_error: what raised (for autostart)
        self.get_logger().info('lifecycle: error processing done, state unconfigured')
        return TransitionCallbackReturn.SUCCESS

    def _transition(self, name: str, action: Callable[[], None]) -> TransitionCallbackReturn:
        """Run one transition's work: a refusal fails it, anything else is an error."""
        self._transition_error = None
        try:
            action()
        except (ParameterRejected, MPIError) as err:
            self._transition_error = err
            self.get_logger().error(f'lifecycle: {name} failed: {err}')
            return TransitionCallbackReturn.FAILURE
        except Exception as err:  # noqa: B902 - rclpy would swallow it without a word
            self._transition_error = err
            self.get_logger().error(
                f'lifecycle: {name} raised {type(err).__name__}: {err}\n'
                f'{traceback.format_exc()}')
            return TransitionCallbackReturn.ERROR
        self.get_logger().info(f'lifecycle: {name} done, state {state_after(name)}')
        return TransitionCallbackReturn.SUCCESS

    def _configure(self) -> None:
        self._configured = True
        try:
            self._load()
            self._open_loop()
        except BaseException:
            self._release()
            raise
        self._set_live()

    def _switch(self, active: bool) -> None:
        self._active = active
        self._set_live()
        if active:
            self.get_logger().info(f'start state: {self._start_words()}')

    def _start_words(self) -> str:
        """Say where the core started (or will start, once a model arrives)."""
        return (f"{self.get_parameter('start_state').value} (taken when the core is built, "
                'at the first model)')

    def _release(self) -> None:
        self._active = False
        self._configured = False
        self._close_loop()
        self._unload()
        self._compensator = None
        self._set_live()

    def _finalize(self) -> None:
        self._release()
        if not self.finalized.done():
            self.finalized.set_result(True)

    # -- public read-only state -------------------------------------------------------
    @property
    def counters(self) -> Dict[str, int]:
        """
        Message and fault counters, as reported on ``/diagnostics``.

        Returns
        -------
        dict of str to int
            The core's ``clamped``, ``nonfinite_input``, ``out_of_range`` (summed over the
            axes of a multi-axis node; and ``bad_time`` for an extended model) plus
            ``messages_in``, ``messages_out``, ``dropped_unconfigured`` (no model),
            ``dropped_inactive`` (lifecycle state not active), ``messages_lost``
            (messages that never reached the node: the larger of ``lost_sequence_gaps``,
            jumps of the publisher's sequence number, and ``lost_dds_events``, what DDS
            reported lost), ``incompatible_qos`` (peers whose QoS cannot match),
            ``rejected_updates``, and the node's own (``model_version``; ``samples_in``,
            ``malformed``).

        """
        counters = self._core_counters()
        counters.update(
            messages_in=self._messages_in,
            messages_out=self._messages_out,
            dropped_unconfigured=self._dropped_unconfigured,
            dropped_inactive=self._dropped_inactive,
            **self._loss.counters(),
            rejected_updates=self._rule.rejected,
        )
        counters.update(self._node_counters())
        return counters

    def _drain(self, first: Any, message_type: Any, serve: Callable[[Any], None], *,
               raw: bool, limit: int = DRAIN_LIMIT) -> None:
        """
        Serve ``first`` and the messages queued behind it, in order, in this one callback.

        rclpy rebuilds its wait set on every spin, which alone would cap a node far below
        10 kHz, so every message already queued is taken here (at most ``limit``, so that
        a flood still lets the spin loop see a stop request; the ones left keep their
        events).  The messages taken here carry the publisher's
        sequence number: a jump counts lost messages (:mod:`mpi_ros.nodes.loss`).

        Parameters
        ----------
        first : object
            The message the subscription delivered (CDR bytes when ``raw``).
        message_type : type
            Its type, to take the queued ones.
        serve : callable
            Serves one message (counting and publishing what it must).
        raw : bool
            Take the queued messages as CDR bytes.
        limit : int
            Most messages served in this call.

        """
        take = self._subscription.handle.take_message
        loss = self._loss
        loss.delivered()
        served, message = 0, first
        while True:
            self._messages_in += 1
            serve(message)
            served += 1
            if served >= limit:
                break
            taken = take(message_type, raw)
            if taken is None:
                break
            message, info = taken
            loss.taken(info['publication_sequence_number'])
        loss.served(served)

    # -- parameters ---------------------------------------------------------------------
    def set_parameters(self, parameter_list: List[Parameter]) -> List[SetParametersResult]:
        """
        Set parameters like the ``set_parameters`` service: model keys together.

        rclpy's ``Node.set_parameters`` sets one key at a time; here, as in the node's
        ``set_parameters`` service, the request's model keys (and the two output limits)
        are set in one atomic step each, so a model is applied whole or not at all (see
        the node's module docstring).

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

    def _current(self, prefix: str) -> Dict[str, Any]:
        """Return the current values of one model's keys and of the limits it uses."""
        return parameter_values(self, UpdateRule.current_keys(prefix))

    def _complete_request(self, parameters: List[Parameter]) -> List[Parameter]:
        """Pre-set: normalise values, resolve null, complete whole models (updates.complete)."""
        specs = self._specs
        given = [normalized(specs[p.name], p) if p.name in specs else p for p in parameters]
        if self._declaring:
            return given
        try:
            request = {p.name: None if p.name in specs and is_null(specs[p.name], p)
                       else plain_value(p.value) for p in given}
            completed = self._rule.complete(self._current, request)
        except Exception:  # noqa: B902 - never end the node: the validator refuses it
            return given
        original = {p.name: p for p in given}
        return [original[name] if name in request and value is request[name]
                else Parameter(name, Parameter.Type[specs[name].type_.upper()], value)
                for name, value in completed.items()]

    def _validate_parameters(self, parameters: List[Parameter]) -> SetParametersResult:
        """Check only: type, range, whole model(s) and limits; keep the candidate for apply."""
        try:
            # rclpy's own keys (use_sim_time) are accepted back at their value only (a
            # ros2 param dump loaded back); any change is refused by check_parameters.
            checked = [p for p in parameters if p.name in self._specs or not (
                self.has_parameter(p.name) and _same(self.get_parameter(p.name), p))]
            check_parameters(self._specs, checked, allow_unset=self._declaring)
            if self._declaring:
                # One key at a time, the others not declared yet: cross-key checks
                # run once all keys are declared (the node's _load).
                return SetParametersResult(successful=True)
            request = {p.name: plain_value(p.value) for p in parameters}
            self._rule.prepare(self._current, request, self._running)
        except (ParameterRejected, MPIError) as err:
            return self._refuse(parameters, err)
        except Exception as err:  # noqa: B902 - no exception may end the node: a refusal
            return self._refuse(parameters, ParameterRejected(
                f'the request could not be checked ({type(err).__name__}: {err})'))
        return SetParametersResult(successful=True)

    def _refuse(self, parameters: List[Parameter], err: Exception) -> SetParametersResult:
        """Count and log a refused request; return the answer naming the reason."""
        reason = self._rejection([p.name for p in parameters], err)
        self._rule.refuse(reason)
        self.get_logger().warning(f'rejected parameter update: {reason}')
        return SetParametersResult(successful=False, reason=reason)

    def _apply_parameters(self, parameters: List[Parameter]) -> None:
        """Swap in what the validator prepared (post-set: the values are stored)."""
        prepared = self._rule.take()
        if self._declaring or not any(prepared):
            return
        try:
            self._install_prepared(prepared)
        except Exception as err:  # noqa: B902 - validated whole before; never end the node
            # The validator built the same compensator in its sandbox, so this is not
            # expected; the running core keeps its last consistent model.
            self.get_logger().error(
                f'installing the validated update raised {type(err).__name__}: {err}; '
                f'the core keeps its model\n{traceback.format_exc()}')
            return
        period = prepared[0].switches.get('diagnostics_period')
        if period is not None:
            self.destroy_timer(self._timer)
            self._timer = self.create_timer(period, self._publish_diagnostics)

    def _warn_if_not_compensated(self, model: Any, where: str = '') -> None:
        """Warn when a model's effect cannot be compensated (a dead time not predicted, a mode)."""
        warning = uncompensated(
            model, dead_time_prediction=self.get_parameter('dead_time_prediction').value)
        if warning is not None:
            self.get_logger().warning(where + warning)

    def _check_limits_fit(self, prefix: str, compensator: Any) -> None:
        """
        Warn when the limits leave part of a model's identified range unreachable.

        ``prefix`` is the model's (``''`` or ``'axis1.'``); ``compensator`` is the core
        serving it (its model and its ``output_min`` / ``output_max``).  The sentence
        stays on /diagnostics (value ``limits``) until the limits or the model fit again.
        """
        shortfall = limits_shortfall(compensator.model, compensator.output_min,
                                     compensator.output_max)
        label = f'axis {prefix[4:-1]}: ' if prefix else ''
        if shortfall is None:
            self._limits_notes.pop(label, None)
            return
        names = 'output.min / output.max'
        if prefix:
            names = f'{prefix}output.min / {prefix}output.max (or {names})'
        note = shortfall.describe(unit=self._input_unit(prefix), names=names)
        self._limits_notes[label] = note
        self.get_logger().warning(f'{label}{note}')

    def _input_unit(self, prefix: str = '') -> str:
        """Return the input unit of the model at ``prefix`` (``'A'``, or ``'V'``)."""
        return input_unit_of(self.get_parameter(prefix + INPUT_QUANTITY_KEY).value)

    # -- hooks of the nodes -------------------------------------------------------------
    def _load(self) -> None:
        """Configure: load and validate the model(s) of the parameters, build the core."""
        raise NotImplementedError

    def _unload(self) -> None:
        """Cleanup: drop what :meth:`_load` built (the base drops the core itself)."""
        raise NotImplementedError

    def _running(self, prefix: str) -> bool:
        """Tell whether a model of this prefix runs."""
        raise NotImplementedError

    def _install_prepared(self, prepared: List[Prepared]) -> None:
        """Swap the prepared updates in (post-set; :func:`mpi_ros.compensation.updates.apply`)."""
        raise NotImplementedError

    def _rejection(self, names: List[str], err: Exception) -> str:
        """Word a refusal (:func:`mpi_ros.compensation.updates.refusal`)."""
        raise NotImplementedError

    def _core_counters(self) -> Dict[str, int]:
        """Return the core's counters (first in :attr:`counters`)."""
        raise NotImplementedError

    def _node_counters(self) -> Dict[str, int]:
        """Return the node's own counters (last in :attr:`counters`)."""
        raise NotImplementedError

    def _status(self, losses: List[str], counters: Dict[str, int],
                before: Dict[str, int]) -> Tuple[int, str]:
        """Return the diagnostics level and message of the period (compensation.status)."""
        raise NotImplementedError

    def _status_values(self) -> Dict[str, Any]:
        """Return the node's own diagnostics values (they may replace common ones)."""
        raise NotImplementedError

    def _status_name(self) -> str:
        """Return the name of the diagnostics status."""
        raise NotImplementedError

    # -- diagnostics --------------------------------------------------------------------
    def _publish_diagnostics(self) -> None:
        self._diagnostics.publish(self.diagnostics())

    def _every_second(self) -> None:
        if self._subscription is not None:
            self._loss.publishers = self._subscription.get_publisher_count()
        self.log_faults()
        self._loss.log(time.monotonic(), self._what)

    def log_faults(self) -> bool:
        """
        Log one warning about the bad inputs since the last one, at most every 5 s.

        Returns
        -------
        bool
            True when a line was logged (there were new non-finite, out-of-range or
            clamped inputs and the last such line is at least 5 s old).

        """
        if self._compensator is None:
            return False
        line = self._fault_log.report(time.monotonic(), self._compensator.counters)
        if line is not None:
            self.get_logger().warning(line)
        return line is not None

    def diagnostics(self) -> DiagnosticArray:
        """
        Build the diagnostics message (and restart the rate window).

        Returns
        -------
        diagnostic_msgs.msg.DiagnosticArray
            One status (see the node's ``_status``; while the lifecycle state is not
            ``active`` its message starts ``lifecycle state <state>: no commands
            published``) with ``hardware_id`` the node's fully qualified name, its counters,
            ``lifecycle_state`` and ``last_rejected_update``, ``rate_hz``,
            ``max_backlog``, ``qos_depth``, ``input_publishers``, ``enabled``,
            ``output_min`` and ``output_max``.

        """
        counters = self.counters
        rate, before = self._window.close(time.monotonic(), self._messages_in, counters)

        status = DiagnosticStatus(name=self._status_name(),
                                  hardware_id=self.get_fully_qualified_name())
        depth = self.get_parameter('qos_depth').value
        losses = self._loss.period(counters, before, depth, self._what)
        state = self.lifecycle_state
        level, status.message = lifecycle_status(
            self._status(losses, counters, before) if self._configured else None, state)
        status.level = bytes([level])
        values = status_values(
            counters, self._status_values(), lifecycle_state=state,
            last_rejected_update=self._rule.last_rejection, rate_hz=round(rate, 3),
            max_backlog=self._loss.last_backlog, qos_depth=depth,
            input_publishers=self._loss.publishers,
            enabled=self.get_parameter('enabled').value,
            output_min=self.get_parameter('output.min').value,
            output_max=self.get_parameter('output.max').value)
        if self._limits_notes and self._compensator is not None:
            values['limits'] = '; '.join(label + note
                                         for label, note in sorted(self._limits_notes.items()))
        status.values = [KeyValue(key=key, value=str(value)) for key, value in values.items()]
        array = DiagnosticArray()
        array.header.stamp = self.get_clock().now().to_msg()
        array.status = [status]
        return array


def _same(current: Parameter, incoming: Parameter) -> bool:
    return bool(current.type_ == incoming.type_ and current.value == incoming.value)
