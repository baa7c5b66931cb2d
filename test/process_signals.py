# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Node processes started as ``ros2 run`` / ``ros2 launch`` start them, and stopped by signals.

A :class:`ProcessGroup` starts each node in one process group of its own (the terminal's
view of ``ros2 launch``: Ctrl-C sends SIGINT to the whole group), with its output in a log
file. :meth:`ProcessGroup.interrupt_like_launch` does what Ctrl-C on ``ros2 launch`` does:
SIGINT to the group, then, 50 ms later, launch's own SIGINT to every node. Everything is
stopped by PID at the end (SIGKILL after a bounded wait), so no test leaves a process.
"""

import os
from pathlib import Path
import signal
import subprocess
import sys
import time

__all__ = ['BAD_OUTPUT', 'ProcessGroup', 'bad_output', 'node_command']

#: What must never appear in a node's output on shutdown (case-insensitive).
BAD_OUTPUT = ('traceback', 'fatal', 'terminate called', 'error_already_set',
              'context is invalid', 'failed to publish log message')

_CLI_NAMES = {'plant_simulator': 'plant-simulator'}


def node_command(executable):
    """
    Return the command that starts a node as ``ros2 run mpi_ros <executable>`` does.

    Parameters
    ----------
    executable : str
        ``compensator``, ``identifier`` or ``plant_simulator``.

    Returns
    -------
    list of str
        The console script beside this Python (``pip install``), else
        ``python -m mpi_ros.app.cli <node>`` (the same ``main``).

    """
    script = Path(sys.executable).with_name(executable)
    if script.is_file() and os.access(script, os.X_OK):
        return [str(script)]
    return [sys.executable, '-m', 'mpi_ros.app.cli', _CLI_NAMES.get(executable, executable)]


def bad_output(text):
    """Return the lines of ``text`` that contain anything of :data:`BAD_OUTPUT`."""
    return [line for line in text.splitlines()
            if any(bad in line.lower() for bad in BAD_OUTPUT)]


class ProcessGroup:
    """
    Node processes in one process group, each logging to ``<directory>/<label>.log``.

    Parameters
    ----------
    directory : Path
        Where the log files go.
    env : dict, optional
        Environment of the processes (default: this process's).

    """

    def __init__(self, directory, env=None):
        self.directory = Path(directory)
        self.env = dict(os.environ if env is None else env)
        self.processes = {}
        self._logs = {}
        self.pgid = None

    def start(self, label, command):
        """Start ``command`` in the group; return its Popen."""
        log = open(self.directory / f'{label}.log', 'w')  # noqa: SIM115 - closed in close()
        process = subprocess.Popen(
            command, stdout=log, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL,
            env=self.env, process_group=0 if self.pgid is None else self.pgid)
        if self.pgid is None:
            self.pgid = process.pid
        self.processes[label] = process
        self._logs[label] = log
        return process

    def output(self, label):
        """Return what the process has printed so far."""
        return (self.directory / f'{label}.log').read_text(errors='replace')

    def wait_for_output(self, label, marker, timeout=60.0):
        """Wait until the output of ``label`` contains ``marker``; False on timeout or exit."""
        deadline = time.monotonic() + timeout
        while marker not in self.output(label):
            if time.monotonic() > deadline or self.processes[label].poll() is not None:
                return marker in self.output(label)
            time.sleep(0.05)
        return True

    def signal(self, label, signum):
        """Send ``signum`` to one process if it still runs."""
        process = self.processes[label]
        if process.poll() is None:
            process.send_signal(signum)

    def interrupt_like_launch(self, gap=0.05):
        """Ctrl-C on ``ros2 launch``: SIGINT to the group, then to each process."""
        alive = [p for p in self.processes.values() if p.poll() is None]
        if alive:
            os.killpg(self.pgid, signal.SIGINT)
        time.sleep(gap)
        for process in alive:
            if process.poll() is None:
                process.send_signal(signal.SIGINT)

    def wait(self, label, timeout=30.0):
        """Wait (bounded) for one process to end; return its exit status, None on timeout."""
        try:
            return self.processes[label].wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            return None

    def wait_all(self, timeout=30.0):
        """Wait (bounded) for every process to end; return ``{label: exit status}``."""
        deadline = time.monotonic() + timeout
        statuses = {}
        for label, process in self.processes.items():
            try:
                statuses[label] = process.wait(timeout=max(deadline - time.monotonic(), 0.1))
            except subprocess.TimeoutExpired:
                statuses[label] = None
        return statuses

    def close(self):
        """Kill whatever still runs (by PID) and close the logs."""
        for process in self.processes.values():
            if process.poll() is None:
                process.kill()
                process.wait(timeout=10.0)
        for log in self._logs.values():
            if not log.closed:
                log.close()
