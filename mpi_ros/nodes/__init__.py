# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
ROS 2 nodes of mpi_ros: the only part of the package that imports rclpy.

One node per module: :mod:`.compensator`, :mod:`.identifier`,
:mod:`.plant_simulator`; :mod:`.launcher` runs them from the ``mpi-ros`` command.
Importing this package imports no node (and so not rclpy).
"""

__all__ = []
