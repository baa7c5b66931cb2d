# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Spin a node on rclpy's EventsExecutor and shut down, around two traps of the rclpy wheel.

In the rclpy 7.1.6 wheel (``ros-jazzy-rclpy`` on PyPI), ``EventsExecutor.spin()`` busy-loops
without dispatching subscriptions from other processes and without reacting to SIGINT, while
``spin_once()`` works and keeps up with 10 kHz. :func:`spin` therefore loops over
``spin_once`` until the context shuts down (Ctrl-C, ``rclpy.shutdown``) or ``until`` is done.

On Ctrl-C, rclpy's signal-handler thread shuts the context down while the main thread,
woken by ``KeyboardInterrupt``, runs ``rclpy.try_shutdown()``: that checks ``ok()`` and then
calls ``rcl_shutdown``, which fails with ``RCLError: rcl_shutdown already called`` when the
handler thread got there in between (about 1 run in 10 here). :func:`shutdown` tolerates
exactly that case.

Signals (SIGINT, SIGTERM)
    rclpy's own handlers (``SignalHandlerOptions.ALL``) chain Python's SIGINT handler, so
    a ``KeyboardInterrupt`` is raised wherever the main thread happens to be: inside the
    EventsExecutor's C++ while it builds a message (``RuntimeError: Unable to convert call
    argument``, or ``terminate called after throwing pybind11::error_already_set`` and an
    abort), or in a callback that publishes while their handler thread shuts the context
    down (``publisher's context is invalid``). And they are uninstalled at shutdown, so a
    second signal (Ctrl-C in a terminal reaches the whole process group, then ``ros2
    launch`` sends its own SIGINT) finds Python's default handlers again and ends the
    process with -2 (SIGINT) or -15 (SIGTERM) while it tears DDS down. :func:`run_node_main`
    therefore starts rclpy with ``SignalHandlerOptions.NO`` and handles both signals itself
    with :class:`mpi_ros.stop_signals.StopSignals`: the first one only asks the spin loop
    to stop (it ends within :data:`SPIN_PERIOD_S`); the node is destroyed and the context
    shut down in order on the main thread, and every later signal is ignored, so the
    process exits 0.
"""

import sys
from typing import Any, Callable, List, Optional

import rclpy
from rclpy.context import Context
from rclpy.exceptions import InvalidParameterTypeException, InvalidParameterValueException
from rclpy.executors import Executor, ExternalShutdownException
from rclpy.experimental import EventsExecutor
from rclpy.impl.implementation_singleton import rclpy_implementation as _rclpy
from rclpy.signals import SignalHandlerOptions
from rclpy.task import Future

from ..stop_signals import StopSignals

__all__ = ['events_executor', 'run_node_main', 'shutdown', 'spin']

#: Longest time one spin_once waits for work [s]; bounds the reaction to shutdown.
SPIN_PERIOD_S = 0.1


def events_executor(context: Optional[Context] = None) -> Executor:
    """
    Create an EventsExecutor on ``context`` (the default context if None).

    Parameters
    ----------
    context : rclpy.context.Context, optional
        The context the executor serves.

    Returns
    -------
    rclpy.executors.Executor
        The executor (spin it with :func:`spin`, not its own ``spin()``).

    """
    return EventsExecutor(context=context)


def spin(executor: Executor, context: Context, *, until: Optional[Future] = None,
         stop: Optional[StopSignals] = None) -> None:
    """
    Process callbacks until the context shuts down, ``until`` completes or a stop signal.

    Parameters
    ----------
    executor : rclpy.executors.Executor
        Executor with the node(s) added.
    context : rclpy.context.Context
        Context whose shutdown ends the loop.
    until : rclpy.task.Future, optional
        Stop as soon as this future is done.
    stop : StopSignals, optional
        Stop (within :data:`SPIN_PERIOD_S`) once it has received a signal.

    """
    while (context.ok() and (until is None or not until.done())
           and (stop is None or not stop.requested)):
        executor.spin_once(timeout_sec=SPIN_PERIOD_S)


def shutdown(context: Optional[Context] = None) -> None:
    """
    Shut ``context`` down unless it already is (also when the signal handler races us).

    Parameters
    ----------
    context : rclpy.context.Context, optional
        The context; the default context if None (which rclpy then replaces, so that
        ``rclpy.init`` works again in the same process).

    """
    try:
        rclpy.try_shutdown(context=context)
    except _rclpy.RCLError:
        # The signal-handler thread shut it down between ok() and rcl_shutdown; the
        # second call sees it shut down and only does rclpy's bookkeeping.
        rclpy.try_shutdown(context=context)


def run_node_main(make_node: Callable[[], Any], label: str, args: Optional[List[str]], *,
                  until: Optional[Callable[[Any], Optional[Future]]] = None) -> int:
    """
    Run one node the Jazzy way: init, build, spin, and always destroy and shut down.

    Parameters
    ----------
    make_node : callable
        Builds the node (after ``rclpy.init``).
    label : str
        Node name used in the ``error: <label>: ...`` line.
    args : list of str, optional
        Command line for ``rclpy.init`` (program name first); ``sys.argv`` if None.
    until : callable, optional
        Given the node, returns a future whose completion ends the spin (or None).

    Returns
    -------
    int
        0 on shutdown (SIGINT or SIGTERM, however many, external shutdown, ``until``
        done); 1 when the node cannot be configured (invalid parameters), with one
        ``error:`` line on stderr.

    """
    from ..errors import MPIError, ParameterRejected
    with StopSignals() as stop:
        rclpy.init(args=args, signal_handler_options=SignalHandlerOptions.NO)
        node = None
        try:
            node = make_node()
            executor = events_executor(node.context)
            executor.add_node(node)
            spin(executor, node.context, until=None if until is None else until(node),
                 stop=stop)
        except (KeyboardInterrupt, ExternalShutdownException):
            pass
        except (MPIError, ParameterRejected, InvalidParameterTypeException,
                InvalidParameterValueException) as err:
            print(f'error: {label}: {err}', file=sys.stderr, flush=True)
            return 1
        finally:
            if node is not None:
                node.destroy_node()
            shutdown()
    return 0
