# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
The progress line of the commands: :class:`mpi_ros.progress.Progress`, under its old name.

It lives in :mod:`mpi_ros.progress` (no layer of its own: the application, the diagnosis'
command and the demo's closed loops on the ROS side use it); this name keeps working.
"""

from ..progress import Progress, ProgressCallback

__all__ = ['Progress', 'ProgressCallback']
