# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
The paper's operators: play, dead zone, hysteresis H, superposition S, Gamma.

The play (2)-(4), the inverse laws (12)-(14), (22)-(25), the model Gamma = S o H and the
turning-point memory.
"""

__all__: list[str] = []
