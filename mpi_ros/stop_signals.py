# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Turn the first SIGINT or SIGTERM into a stop request and ignore every later one.

The nodes' mains (:func:`mpi_ros.nodes.spinning.run_node_main`, the identifier's) start
rclpy without its signal handlers and handle both signals with :class:`StopSignals`: the
first one asks the spin loop to stop (or interrupts a fit), later ones are ignored, so a
node always shuts down in order and exits 0 (the reasons are in
:mod:`mpi_ros.nodes.spinning`).  Plain Python signals: no ROS here.
"""

import signal
import threading
from types import FrameType
from typing import Any, Dict, Optional

__all__ = ['STOP_SIGNALS', 'StopSignals']

#: The signals that stop a run (a node, or the workers of
#: :func:`mpi_ros.pipeline.fit_bag_axes`).
STOP_SIGNALS = (signal.SIGINT, signal.SIGTERM)


class StopSignals:
    """
    Turn the first SIGINT or SIGTERM into a stop request and ignore every later one.

    Use it as a context manager around ``rclpy.init(..., signal_handler_options=
    SignalHandlerOptions.NO)`` and the spin loop. In the main thread it installs Python
    handlers for :data:`STOP_SIGNALS` (elsewhere it does nothing: only the main thread
    receives signals in Python). The first signal sets :attr:`received`; with
    ``interrupt=True`` it also raises ``KeyboardInterrupt`` (for work that no spin loop
    polls, such as a fit). Later signals do nothing. On leaving, the previous handlers come
    back if no signal arrived; after one, both signals are set to ``SIG_IGN``, so that a
    late signal cannot kill the process while it exits (Python restores the default
    handlers in place of Python functions, but keeps ``SIG_IGN``, when it finalises).

    Parameters
    ----------
    interrupt : bool
        Raise ``KeyboardInterrupt`` in the main thread on the first signal.

    Examples
    --------
    >>> with StopSignals() as stop:
    ...     stop.requested
    False

    """

    def __init__(self, *, interrupt: bool = False) -> None:
        self.received: Optional[int] = None
        #: Raise KeyboardInterrupt on the first signal (set False before cleaning up).
        self.interrupt = interrupt
        self._previous: Dict[int, Any] = {}

    @property
    def requested(self) -> bool:
        """Tell whether a stop signal arrived."""
        return self.received is not None

    @property
    def name(self) -> str:
        """Name the signal that arrived (``SIGINT``, ``SIGTERM``), or ``''``."""
        return '' if self.received is None else signal.Signals(self.received).name

    def __enter__(self) -> 'StopSignals':
        """Install the handlers (main thread only)."""
        if threading.current_thread() is threading.main_thread():
            for signum in STOP_SIGNALS:
                self._previous[signum] = signal.signal(signum, self._handle)
        return self

    def __exit__(self, *exc_info: Any) -> None:
        """Restore the previous handlers, or ignore both signals if one arrived."""
        previous, self._previous = self._previous, {}
        for signum, handler in previous.items():
            # signal.signal first runs the handlers of signals already caught, so none is
            # left pending (Python would report it as 'ignored due to race condition').
            signal.signal(signum, signal.SIG_IGN if self.received is not None else handler)

    def _handle(self, signum: int, frame: Optional[FrameType]) -> None:
        # No signal.signal here: inside a handler it would not run a signal caught at the
        # same time, which would then be reported as 'ignored due to race condition'.
        if self.received is not None:
            return
        self.received = signum
        if self.interrupt:
            raise KeyboardInterrupt
