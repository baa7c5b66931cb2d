# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
The application layer: the mpi-ros command line, the demo and its report.

Progress lines and range checks for offline use live here too.
"""

__all__: list[str] = []
