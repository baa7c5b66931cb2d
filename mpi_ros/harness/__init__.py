# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Drive the nodes from outside: node processes, the lock-step loop driver, the demo's loops.

The ROS side's second package, next to :mod:`mpi_ros.nodes`: nothing here is a node, and no
node imports it.  ``mpi-ros demo`` (:mod:`mpi_ros.app.demo`), the integration and fault
tests and the benchmarks use it.

- :mod:`.processes`: :class:`~.processes.NodeProcess`, one node in its own process,
  started and stopped by PID (no rclpy here);
- :mod:`.driver`: :class:`~.driver.LoopDriver`, the node that publishes commands or desired
  displacements and waits for each answer (lock step);
- :mod:`.demo_runs`: the demo's closed loops over DDS (:func:`~.demo_runs.run_demo`,
  :func:`~.demo_runs.run_effect_demo`).

Importing this package imports none of them (and so not rclpy): the demo's options read the
constants of :mod:`.demo_runs` before anything runs.
"""

__all__: list[str] = []
