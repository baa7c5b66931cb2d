# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Inverse feed-forward compensation (Fig. 10 of Kuhnen's paper), the compensator node's core.

Per desired displacement ``s_c`` the compensator outputs the current
``Gamma^-1[s_c]`` (27), clamped to the actuator's safe range.  Its only state
is the play state ``z_H`` of the *forward* model driven by the current that
was actually commanded; the inverse play state follows from it by the
initial-state law (14) at every step.  Hence

- clamping never leaves the inverse out of step with the actuator;
- a newly pushed model starts from the operating point: the stored turning
  points of the commanded current are replayed through the new H and (14)
  gives the new inverse state (bumpless swap);
- non-finite input never reaches the output: the last command is held and
  the case is counted.

One class, :class:`Compensator`, serves every model: a plain MPI model (one compiled
step) or an extended model whose effect plugs in its exact per-step inverse
(:class:`InverseStep`, e.g. :class:`mpi_ros.extensions.creep.CreepInverse`).  It owns the
limits, the screening, the counters, the turning-point memory and the bumpless handover
between models of any kind (:meth:`Compensator.install`); a node only translates
messages and parameters; the rule by which a node's parameters update the model is in
:mod:`mpi_ros.compensation.updates`.
"""

from .compensator import Compensator, gamma_of, inverse_step_of, InverseStep, kind_of
from .multi_axis import MultiAxisCompensator
from .screening import best_linear_map, LinearMap, operating_range, screen_desired

__all__ = ['Compensator', 'InverseStep', 'MultiAxisCompensator', 'gamma_of', 'inverse_step_of',
           'kind_of', 'LinearMap', 'best_linear_map', 'operating_range', 'screen_desired']
