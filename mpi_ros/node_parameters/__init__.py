# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
The nodes' parameters as plain data (ROS-free): one home for every node's specs.

Each node describes its parameters once, as :class:`ParameterSpec` tuples; the ROS side
(:mod:`mpi_ros.nodes.parameters`) turns them into rclpy descriptors and declares them,
the command line reads them (``mpi-ros config``), the tests check them. Modules:

- :mod:`.spec`: :class:`ParameterSpec` and the checks of an incoming value
  (:func:`check_value`, :func:`normalized`, ...), shared by every node;
- :mod:`.compensator`: the single- and multi-axis compensator nodes (Gamma, the
  operating point, the registered effects' keys, limits, switches, adaptation) and the
  multi-axis keys (:class:`~.compensator.AxisKeys`, :func:`~.compensator.merge_axes`);
- :mod:`.identifier`: the identifier node (bag, data options, order, push);
- :mod:`.plant_simulator`: the plant simulator node (truth, noise, excitation, record).

A multi-axis node's key is :func:`axis_key` (``axis<k>.`` + the single-axis key); the
output limits' keys are :data:`LIMIT_KEYS`. Both are the compensator's update rule's
(:mod:`mpi_ros.compensation.updates`), given here so that no node or pipeline reaches
into the compensator for a parameter name.
"""

from .spec import ARRAY_KINDS, check_value, check_values, is_null, loop_qos_parameters, \
    normalized, NULL_STRINGS, ParameterSpec, plain_value, RCLPY_PARAMETERS, RELIABILITIES, \
    request_steps, specs_by_name, typed_value
from ..compensation.updates import axis_key, LIMIT_KEYS

__all__ = [
    'ARRAY_KINDS', 'LIMIT_KEYS', 'NULL_STRINGS', 'RCLPY_PARAMETERS', 'RELIABILITIES',
    'ParameterSpec', 'axis_key', 'check_value', 'check_values', 'is_null',
    'loop_qos_parameters', 'normalized', 'plain_value', 'request_steps', 'specs_by_name',
    'typed_value',
]
