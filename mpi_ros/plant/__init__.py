# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
The plant simulation: the actuator with its effects, and its excitation signals.

The actuator is a non-MPI magnetostrictive plant; the plant simulator node runs it.
"""

__all__: list[str] = []
