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

Start-up arguments
    rcl parses the ``--ros-args`` inside ``rclpy.init`` and fails with an ``RCLError``
    traceback (after its own log line) on a ``--params-file`` it cannot read or parse.
    :func:`run_node_main` therefore checks every ``--params-file`` first
    (:func:`params_file_problem`: the file exists and is readable, is YAML without aliases
    nested at most :data:`PARAMS_DEPTH` deep, and maps node names to
    ``ros__parameters`` mappings) and turns any remaining ``RCLError`` of ``rclpy.init``
    into one ``error:`` line and exit status 1.
"""

import os
import sys
from typing import Any, Callable, Iterator, List, Optional, Sequence

import rclpy
from rclpy.context import Context
from rclpy.exceptions import InvalidParameterTypeException, InvalidParameterValueException
from rclpy.executors import Executor, ExternalShutdownException
from rclpy.experimental import EventsExecutor
from rclpy.impl.implementation_singleton import rclpy_implementation as _rclpy
from rclpy.signals import SignalHandlerOptions
from rclpy.task import Future

from ..stop_signals import StopSignals

__all__ = ['PARAMS_DEPTH', 'events_executor', 'params_file_problem', 'params_files',
           'run_node_main', 'shutdown', 'spin']

#: Longest time one spin_once waits for work [s]; bounds the reaction to shutdown.
SPIN_PERIOD_S = 0.1
#: Deepest nesting of mappings and sequences a node's ``--params-file`` may have.
PARAMS_DEPTH = 64
#: Largest ``--params-file`` a node reads [bytes].
PARAMS_SIZE = 64 * 1024 * 1024


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


def params_files(args: Sequence[str]) -> Iterator[str]:
    """
    Yield the paths given to ``--params-file`` inside the ``--ros-args`` sections.

    Parameters
    ----------
    args : sequence of str
        A node's command line (program name first).

    Yields
    ------
    str
        Each path, in order.

    Examples
    --------
    >>> list(params_files(['n', '--ros-args', '--params-file', 'a.yaml', '--', 'x']))
    ['a.yaml']

    """
    inside = False
    items = list(args)
    for i, arg in enumerate(items):
        if arg == '--ros-args':
            inside = True
        elif arg == '--':
            inside = False
        elif inside and arg == '--params-file' and i + 1 < len(items):
            yield items[i + 1]


def params_file_problem(path: str) -> Optional[str]:
    """
    Say what makes a ``--params-file`` unusable for a node, before rcl reads it.

    Parameters
    ----------
    path : str
        The file.

    Returns
    -------
    str or None
        One line naming the file and the problem (missing, unreadable, too large, not
        YAML, aliases, nested deeper than :data:`PARAMS_DEPTH`, not a mapping of node
        names to ``ros__parameters`` mappings); None when rcl may read it.

    """
    import yaml
    try:
        size = os.path.getsize(path)
        if size > PARAMS_SIZE:
            return f'{path}: {size} bytes; a params file is at most {PARAMS_SIZE} bytes'
        with open(path, 'rb') as stream:
            text = stream.read()
    except OSError as err:
        return f'{path}: cannot read it: {err.strerror or err}'
    try:
        depth = 0
        for event in yaml.parse(text, Loader=yaml.SafeLoader):
            if isinstance(event, yaml.AliasEvent):
                return f'{path}: YAML aliases (*name) are not allowed in a params file'
            if isinstance(event, (yaml.MappingStartEvent, yaml.SequenceStartEvent)):
                depth += 1
                if depth > PARAMS_DEPTH:
                    return f'{path}: nested deeper than {PARAMS_DEPTH} levels'
            elif isinstance(event, (yaml.MappingEndEvent, yaml.SequenceEndEvent)):
                depth -= 1
        content = yaml.safe_load(text)
    except (yaml.YAMLError, ValueError) as err:
        where = getattr(err, 'problem_mark', None)
        line = f' (line {where.line + 1})' if where is not None else ''
        problem = getattr(err, 'problem', None) or str(err).splitlines()[0]
        return f'{path}: not valid YAML{line}: {problem}'
    return _params_structure(path, content)


def _params_structure(path: str, content: Any) -> Optional[str]:
    """Check ``{node: {ros__parameters: {...}}}`` (namespaces may nest node names)."""
    expected = 'a mapping of node names to {ros__parameters: {name: value}}'
    if not isinstance(content, dict) or not content:
        return f'{path}: expected {expected}; found {type(content).__name__}'
    pending = [(str(key), value) for key, value in content.items()]
    found = False
    while pending:
        name, value = pending.pop()
        if not isinstance(value, dict):
            return (f'{path}: {name} must be a mapping ({expected}); found '
                    f'{type(value).__name__}')
        for key, inner in value.items():
            if key == 'ros__parameters':
                if not isinstance(inner, dict):
                    return (f'{path}: {name}.ros__parameters must be a mapping of parameter '
                            f'names to values; found {type(inner).__name__}')
                problem = _mixed_sequence(inner)
                if problem is not None:
                    return f'{path}: {name}.ros__parameters.{problem}'
                found = True
            else:
                pending.append((f'{name}.{key}', inner))
    return None if found else f'{path}: no ros__parameters section ({expected})'


def _mixed_sequence(parameters: dict) -> Optional[str]:  # type: ignore[type-arg]
    """Name a list value whose items are not all of one scalar type (rcl refuses it)."""
    pending = list(parameters.items())
    while pending:
        name, value = pending.pop()
        if isinstance(value, dict):
            pending.extend((f'{name}.{key}', inner) for key, inner in value.items())
        elif isinstance(value, list):
            kinds = {type(item).__name__ for item in value}
            if len(kinds) > 1 or kinds - {'bool', 'int', 'float', 'str'}:
                return (f'{name}: a list must hold items of one type (bool, integer, double '
                        f'or string); found {", ".join(sorted(kinds))}')
    return None


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
        done); 1 when a ``--params-file`` or another ROS argument is unusable, or the
        node cannot be configured (invalid parameters), with one ``error:`` line on
        stderr.

    """
    from ..errors import MPIError, ParameterRejected
    for path in params_files(sys.argv if args is None else args):
        problem = params_file_problem(path)
        if problem is not None:
            print(f'error: {label}: --params-file {problem}', file=sys.stderr, flush=True)
            return 1
    with StopSignals() as stop:
        try:
            rclpy.init(args=args, signal_handler_options=SignalHandlerOptions.NO)
        except _rclpy.RCLError as err:
            first = str(err).splitlines()[0] if str(err) else type(err).__name__
            print(f'error: {label}: the ROS arguments were refused: {first}',
                  file=sys.stderr, flush=True)
            return 1
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
