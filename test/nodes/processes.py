# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Run nodes as separate processes in tests (the hook for the integration tests).

>>> with NodeProcess(['compensator', '--ros-args', '-p', 'output.max:=1.8']) as node:
...     node.wait_for_output('no model given yet')    # doctest: +SKIP

A :class:`NodeProcess` starts ``python -m mpi_ros.app.cli <node> ...`` (or any command) with
:func:`ros_env.ros_environment`, collects its merged stdout/stderr in a thread, and on exit
stops it with SIGINT (then SIGTERM, then SIGKILL), so no test leaves a process behind.
"""

import signal
import subprocess
import sys
import threading
import time

from .ros_env import ros_environment

__all__ = ['NodeProcess']


class NodeProcess:
    """
    A node (or any command) running in a child process for the duration of a ``with``.

    Parameters
    ----------
    args : list of str
        ``mpi-ros`` arguments, e.g. ``['compensator', '--ros-args', ...]``; or the
        whole command when ``command`` is true.
    command : bool
        Treat ``args`` as the complete command line.
    env : dict, optional
        Environment; :func:`ros_env.ros_environment` by default.
    cwd : path, optional
        Working directory.

    """

    def __init__(self, args, *, command=False, env=None, cwd=None):
        self.argv = list(args) if command else [sys.executable, '-m', 'mpi_ros.app.cli', *args]
        self.env = ros_environment() if env is None else env
        self.cwd = cwd
        self.lines = []
        self.process = None
        self._reader = None
        self._changed = threading.Condition()

    def __enter__(self):
        """Start the process and the output reader."""
        self.process = subprocess.Popen(
            self.argv, env=self.env, cwd=self.cwd, stdout=subprocess.PIPE,
            stderr=subprocess.STDOUT, text=True, bufsize=1)
        self._reader = threading.Thread(target=self._read, daemon=True)
        self._reader.start()
        return self

    def __exit__(self, *exc_info):
        """Stop the process (SIGINT, then SIGTERM, then SIGKILL)."""
        self.stop()

    @property
    def output(self):
        """Return everything the process printed so far."""
        with self._changed:
            return ''.join(self.lines)

    def wait_for_output(self, marker, timeout=30.0):
        """
        Wait until a printed line contains ``marker``.

        Parameters
        ----------
        marker : str
            Text to wait for.
        timeout : float
            Longest wait [s].

        Returns
        -------
        bool
            True when seen; False on timeout or when the process ended first.

        """
        deadline = time.monotonic() + timeout
        with self._changed:
            while not any(marker in line for line in self.lines):
                remaining = deadline - time.monotonic()
                if remaining <= 0 or (self.process.poll() is not None
                                      and not self._reader.is_alive()):
                    return False
                self._changed.wait(min(remaining, 0.2))
        return True

    def stop(self, timeout=20.0):
        """
        Stop the process and return its exit status.

        Parameters
        ----------
        timeout : float
            Time [s] given to SIGINT and again to SIGTERM before SIGKILL.

        Returns
        -------
        int
            The exit status (negative: killed by that signal).

        """
        if self.process is None:
            return None
        for sig in (signal.SIGINT, signal.SIGTERM):
            if self.process.poll() is not None:
                break
            self.process.send_signal(sig)
            try:
                self.process.wait(timeout=timeout)
            except subprocess.TimeoutExpired:
                continue
        if self.process.poll() is None:
            self.process.kill()
            self.process.wait()
        if self._reader is not None:
            self._reader.join(timeout=5.0)
        return self.process.returncode

    def _read(self):
        for line in self.process.stdout:
            with self._changed:
                self.lines.append(line)
                self._changed.notify_all()
        with self._changed:
            self._changed.notify_all()
