# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Identifier node: fit an MPI model (28)-(36) from a rosbag2 bag and push it atomically.

One run: read the bag (sqlite3 or mcap; a ``.csv`` file works too) with
:func:`mpi_ros.pipeline.fit_recording` (the CLI's pipeline), pairing ``input_topic``
(current [A]) with ``output_topic`` (displacement [m]); the data parameters
(``input_joint``, ``input_field``, ``input_index``, ``output_scale``, ...) are the data
options of ``mpi-ros identify`` (:data:`mpi_ros.recordings.DATA_OPTIONS`). Fit with
:func:`mpi_ros.identify` (``order``
``auto``, ``N,L`` or ``N L``, parsed by :func:`mpi_ros.order.parse_order`); report the
fit errors (37); optionally write the parameter YAML (``params_file``); then send every
key ``mpi-ros identify`` writes (:func:`mpi_ros.pipeline.identified_parameters`: Gamma's
four arrays, the operating point ``model.input_offset``, ``model.output_offset``,
``model.output_sign``, the dynamics the fit found, ``model.dead_time``,
``model.rate_dependence.*`` or ``model.resonance.*``, the record's start
``record_start.*``, and ``output.min`` / ``output.max``,
the input range of the identification) in **one** ``set_parameters_atomically`` request
to ``target_node``. The target either applies the
whole model or rejects it, so nothing is ever half-applied (a plain model switches the
target's extension off); the wait for the service and for its answer is bounded by
``service_timeout``.  An answer lost on the way back (rmw under load) is not a failure
when the target's values, read back, are the pushed ones.

Several actuators (``axes`` > 1)
    The bag holds ``std_msgs/msg/Float64MultiArray`` topics with one element per axis
    (``/current_commands`` and ``/displacements`` when the topics are left at their
    single-axis defaults), as the multi-axis compensator and plant simulator publish
    them: one sample of every axis per message, or a chunk of K samples x N axes
    (``layout.dim`` = samples x axes, or K x N values without ``dim``); the K samples of
    a message end at its log time and are spaced by the time since the previous message
    / K, or ``sample_period``; input and output chunk sizes may differ, see
    :func:`mpi_ros.recordings.read_bag_signals`).
    Axis k is fitted from element (column) k of both topics
    (``input_index`` / ``output_index`` are set per axis), the axes in parallel in a
    process pool (``workers``, 0 = one per CPU, at most one per axis), and all models
    go to the multi-axis compensator in **one** ``set_parameters_atomically`` request
    with the keys ``axis<k>.model.*``: every axis changes, or none.  If any axis is
    refused, nothing is written or pushed.

With ``diagnose:=true`` the node also runs :func:`mpi_ros.diagnosis.diagnose` on the
record (the first 60 % trains, the rest validates) and, when the diagnosis names an effect
with a clear gain (not weak, not tied), delivers that extended model instead
(:func:`mpi_ros.pipeline.diagnosed_parameters`); it logs what the diagnosis found either way.

When :func:`mpi_ros.identify` refuses the data (``IdentificationError``: output not
monotone in the input, a fit no better than a straight line, too little excitation),
the node logs the reason, writes no file and pushes nothing.

The node exits with status 0 when the model was fitted (and, if ``push`` is true,
accepted by the target), and with status 1 and one ``error: ...`` line on stderr for
any failure: unreadable bag, refused or failed fit, target missing, push rejected or
unanswered (and not confirmed by its values read back).
"""

import sys
import time
from typing import Any, List, Mapping, Optional

import numpy as np
from rcl_interfaces.msg import SetParametersResult
from rcl_interfaces.srv import GetParameters, SetParametersAtomically
import rclpy
from rclpy.exceptions import InvalidParameterTypeException, InvalidParameterValueException
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node
from rclpy.parameter import Parameter, parameter_value_to_python
from rclpy.signals import SignalHandlerOptions
from rclpy.task import Future

from .parameters import answer_request, check_parameters, declare_parameters, \
    harden_parameter_services
from .spinning import shutdown
from ..errors import MPIError, ParameterPushError, ParameterRejected
from ..node_parameters import specs_by_name, typed_value
from ..node_parameters.identifier import check_identifier_value, DATA_PARAMETERS, PARAMETERS, \
    parse_order
from ..pipeline import BagFit, fit_bag, fit_bag_axes, identify_bag
from ..stop_signals import StopSignals

__all__ = [
    'IdentifierNode', 'BagFit', 'ParameterPushError', 'PARAMETERS', 'DATA_PARAMETERS',
    'fit_bag', 'fit_bag_axes', 'parse_order', 'push_model_parameters', 'main',
]

_SPECS = specs_by_name(PARAMETERS)


class IdentifierNode(Node):
    """
    Fit a model from a bag and push it to the target node; see the module docstring.

    Parameters
    ----------
    node_name : str
        Node name; ``identifier`` unless remapped.
    **kwargs
        Passed on to :class:`rclpy.node.Node`.

    """

    def __init__(self, node_name: str = 'identifier', **kwargs: Any) -> None:
        super().__init__(node_name, **kwargs)
        self.add_on_set_parameters_callback(self._validate_parameters)
        declare_parameters(self, PARAMETERS)
        harden_parameter_services(self, specs=_SPECS)

    def _validate_parameters(self, parameters: List[Parameter]) -> SetParametersResult:
        def check() -> None:
            check_parameters(_SPECS, parameters)
            for parameter in parameters:
                check_identifier_value(parameter.name, parameter.value)
        return answer_request(check)

    def run(self) -> 'BagFit | List[BagFit]':
        """
        Fit, report, write the YAML if asked, and push if asked.

        Returns
        -------
        BagFit
            The fit that was pushed (or only computed, with ``push:=false``).

        Raises
        ------
        mpi_ros.errors.MPIError
            ``DataError`` (bag), ``IdentificationError`` (fit), ``ParameterPushError``.

        """
        values = {name: self.get_parameter(name).value for name in _SPECS}
        logger = self.get_logger()
        fitted, parameters = identify_bag(values, info=logger.info, error=logger.error,
                                          warn=logger.warning)
        if values['push']:
            target = values['target_node']
            push_model_parameters(self, target, parameters, timeout=values['service_timeout'])
            axes = values['axes']
            logger.info(f'{target} accepted the models of all {axes} axes' if axes > 1
                        else f'{target} accepted the model')
        return fitted


def push_model_parameters(node: Node, target_node: str, parameters: Mapping[str, Any], *,
                          timeout: float) -> None:
    """
    Send all parameters to ``target_node`` in one ``set_parameters_atomically`` request.

    When the answer does not come within ``timeout`` (under load rmw can fail to send a
    service response: "failed to send response (timeout)", after the target applied the
    request), the target's values are read back with ``get_parameters`` (its service and
    its answer each waited for at most ``timeout``): if every pushed key holds the pushed
    value, the target runs the new model and the push succeeds, with a warning on
    ``node``'s log.

    Parameters
    ----------
    node : rclpy.node.Node
        Node that owns the client (it is spun on a private executor while waiting).
    target_node : str
        Fully qualified target name, e.g. ``/compensator``.
    parameters : Mapping[str, sequence of float or float or int]
        The ``model.*`` keys (as from ``MPIModel.to_params()``, or an extended model's
        ``to_params()``): arrays are sent as double arrays, integers
        (``model.output_sign``) as integers, other scalars as doubles.
    timeout : float
        Longest wait [s] for the service to appear, and again for the answer.

    Raises
    ------
    ParameterPushError
        Target missing, request rejected (with the target's reason), or unanswered and
        not confirmed by reading the target's values back.

    """
    service = f'{target_node.rstrip("/")}/set_parameters_atomically'
    typed = [_typed(name, values) for name, values in parameters.items()]
    client = node.create_client(SetParametersAtomically, service)
    try:
        if not client.wait_for_service(timeout_sec=timeout):
            msg = (f'no parameter service {service} within {timeout:g} s; is the node '
                   f'{target_node} running with the same ROS_DOMAIN_ID? Nothing was pushed')
            raise ParameterPushError(msg)
        request = SetParametersAtomically.Request()
        request.parameters = [p.to_parameter_msg() for p in typed]
        response = _answer(node, client.call_async(request), timeout)
    finally:
        node.destroy_client(client)
    if response is None:
        held = _read_back(node, target_node, typed, timeout)
        if held == 'applied':
            node.get_logger().warning(
                f'{service} did not answer within {timeout:g} s, but every pushed key reads '
                f'back from {target_node} with the pushed value: the new model is applied')
            return
        msg = (f'{service} did not answer within {timeout:g} s, and {held}; the target '
               'applies either the whole new model or none of it: check model_version on '
               '/diagnostics')
        raise ParameterPushError(msg)
    if not response.result.successful:
        msg = (f'{target_node} rejected the model (its old model keeps running): '
               f'{response.result.reason}')
        raise ParameterPushError(msg)


def _answer(node: Node, future: Future, timeout: float) -> Any:
    """Spin ``node`` on a private executor until ``future`` is done; its result or None."""
    executor = SingleThreadedExecutor(context=node.context)
    executor.add_node(node)
    deadline = time.monotonic() + timeout
    try:
        while not future.done() and time.monotonic() < deadline:
            executor.spin_once(timeout_sec=min(0.1, max(deadline - time.monotonic(), 0.0)))
    finally:
        executor.remove_node(node)
        executor.shutdown()
    if not future.done():
        future.cancel()
        return None
    return future.result()


def _read_back(node: Node, target_node: str, typed: List[Parameter], timeout: float) -> str:
    """
    Return ``'applied'`` when ``target_node`` holds every pushed value, else what was read.

    The values are compared exactly: doubles cross DDS unchanged.
    """
    service = f'{target_node.rstrip("/")}/get_parameters'
    client = node.create_client(GetParameters, service)
    try:
        if not client.wait_for_service(timeout_sec=timeout):
            return f'{service} did not appear within {timeout:g} s to read the values back'
        request = GetParameters.Request()
        request.names = [p.name for p in typed]
        response = _answer(node, client.call_async(request), timeout)
    finally:
        node.destroy_client(client)
    if response is None or len(response.values) != len(typed):
        return f'{service} did not answer within {timeout:g} s either'
    differ = [p.name for p, value in zip(typed, response.values)
              if not _same_value(p.value, parameter_value_to_python(value))]
    if differ:
        return (f'{len(differ)} of the {len(typed)} pushed keys read back with other values'
                f' ({", ".join(differ[:3])}{", ..." if len(differ) > 3 else ""}): not'
                ' applied when read')
    return 'applied'


def _same_value(sent: Any, held: Any) -> bool:
    """Whether a pushed value and a read-back value are equal (arrays element by element)."""
    if held is None:
        return False
    try:
        return bool(np.array_equal(np.asarray(sent, dtype=np.float64),
                                   np.asarray(held, dtype=np.float64)))
    except (TypeError, ValueError):
        return False


def main(args: Optional[List[str]] = None) -> int:
    """
    Run the identifier once (``ros2 run mpi_ros identifier --ros-args -p bag:=PATH``).

    ``args`` is the command line for ``rclpy.init`` (program name first; ``sys.argv`` if
    None).  Returns the exit status: 0 when the model was fitted and (if asked) accepted,
    and on a stop by SIGINT or SIGTERM (however many); 1 on any failure.

    """
    with StopSignals(interrupt=True) as stop:
        node = None
        status = 0
        try:
            rclpy.init(args=args, signal_handler_options=SignalHandlerOptions.NO)
            node = IdentifierNode()
            node.run()
        except KeyboardInterrupt:
            pass
        except (MPIError, ParameterRejected, InvalidParameterTypeException,
                InvalidParameterValueException) as err:
            if not stop.requested:
                status = 1
                print(f'error: identifier: {err}', file=sys.stderr, flush=True)
        except Exception:  # noqa: B902 - see below
            # A stop signal raises KeyboardInterrupt wherever the main thread is; inside
            # rclpy's C++ (taking the service answer) it comes out as another exception.
            if not stop.requested:
                raise
        finally:
            stop.interrupt = False      # a signal from here on must not break the cleanup
            if node is not None:
                node.destroy_node()
            shutdown()
        if stop.requested:
            print(f'identifier: stopped by {stop.name}; nothing was pushed unless the target '
                  'said so (check model_version on its /diagnostics)', file=sys.stderr,
                  flush=True)
    return status


def _typed(name: str, value: Any) -> Parameter:
    """Return an integer, double (scalar) or double-array parameter (core: typed_value)."""
    kind, plain = typed_value(name, value)
    return Parameter(name, Parameter.Type[kind.upper()], plain)
