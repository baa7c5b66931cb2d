# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
One node in its own process (``python -m mpi_ros.app.cli <node> --ros-args ...``), by PID.

The processes of ``mpi-ros demo``, the integration and fault tests and the benchmarks: each
is started with its log in a file and stopped by its PID (SIGINT, then SIGKILL after a
grace period), never by name.  Nothing here imports rclpy; the node in the process does.
"""

import os
from pathlib import Path
import signal
import subprocess
import sys
from typing import Optional

__all__ = ['NodeProcess']


class NodeProcess:
    """
    One node in its own process, stopped by PID (SIGINT, then SIGKILL after a grace period).

    Parameters
    ----------
    node : str
        ``compensator``, ``identifier`` or ``plant-simulator``.
    ros_args : list of str
        Arguments after ``--ros-args``.
    log : Path
        File that receives the process's stdout and stderr.
    env : dict, optional
        Environment (default: this process's).

    """

    def __init__(self, node: str, ros_args: list[str], log: Path,
                 env: Optional[dict[str, str]] = None) -> None:
        self.log_path = Path(log)
        self._log = open(self.log_path, 'w')  # noqa: SIM115 - closed in stop()
        cmd = [sys.executable, '-m', 'mpi_ros.app.cli', node, '--ros-args', *ros_args]
        self.proc = subprocess.Popen(cmd, stdout=self._log, stderr=subprocess.STDOUT,
                                     stdin=subprocess.DEVNULL,
                                     env=dict(os.environ if env is None else env))

    @property
    def pid(self) -> int:
        """Process id."""
        return self.proc.pid

    def running(self) -> bool:
        """Tell whether the process is still alive."""
        return self.proc.poll() is None

    def stop(self, grace: float = 5.0) -> Optional[int]:
        """Stop the process (SIGINT, then SIGKILL); return its exit status."""
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGINT)
            try:
                self.proc.wait(timeout=grace)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait(timeout=grace)
        if not self._log.closed:
            self._log.close()
        return self.proc.returncode

    def kill(self) -> None:
        """Kill the process at once (fault injection)."""
        if self.proc.poll() is None:
            self.proc.kill()
            self.proc.wait(timeout=5.0)
        if not self._log.closed:
            self._log.close()
