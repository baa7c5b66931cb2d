# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Random, extreme and wrong-typed pushes into every model key of a live compensator node.

The node runs in-process on a private context; each push goes through the functions the
parameter services call (``set_parameters_atomically``, the grouped ``set_parameters``).
No exception may escape, a push is applied whole or refused whole (with a reason), and
after every push the node's commands are finite and inside its limits.
"""

import math

from hypothesis import given, HealthCheck, seed, settings, strategies as st
from mpi_ros.node_parameters import specs_by_name
from mpi_ros.node_parameters.compensator import compensator_parameters
from mpi_ros.nodes.compensator import CompensatorNode
import numpy as np
from rclpy.parameter import Parameter

from .test_compensator_node import MODEL_A_OP, OUTPUT_MAX, OUTPUT_MIN
from ..hostile_values import pushes

SPECS = specs_by_name(compensator_parameters())
#: Fixed before the first run.
SEED = 2511
EXAMPLES = 80


def _snapshot(node):
    """Return every model key's value as text (NaN compares equal to itself)."""
    return {name: repr(node.get_parameter(name).value) for name in SPECS
            if name.startswith('model.')}


def test_no_push_ends_the_node_or_makes_a_bad_command(ros_context):
    overrides = [Parameter(name, value=value) for name, value in MODEL_A_OP.items()]
    overrides += [Parameter('output.min', value=OUTPUT_MIN),
                  Parameter('output.max', value=OUTPUT_MAX)]
    node = CompensatorNode(context=ros_context, parameter_overrides=overrides)
    tally = {'accepted': 0, 'refused': 0, 'commands': 0}
    rng = np.random.default_rng(SEED)

    @seed(SEED)
    @settings(max_examples=EXAMPLES, deadline=None, suppress_health_check=list(HealthCheck),
              database=None)
    @given(pushes(SPECS, base=MODEL_A_OP), st.booleans())
    def push(request, atomic):
        parameters = [Parameter(name, value=value) for name, value in request.items()]
        before = _snapshot(node)
        if atomic:
            results = [node.set_parameters_atomically(parameters)]
        else:
            results = node.set_parameters(parameters)
        # A null for a key that is unset is answered alone ("it stays unset"); the keys
        # that are set are applied whole or refused whole.
        accepted = {result.successful for result in results
                    if not result.reason.endswith('stays unset')} or {True}
        assert len(accepted) == 1, results
        if accepted == {True}:
            tally['accepted'] += 1
        else:
            tally['refused'] += 1
            assert all(result.reason for result in results)
            assert _snapshot(node) == before, request
        low, high = node.compensator.displacement_range
        desired = list(rng.uniform(low, high, 30)) + [math.nan, math.inf, -1e308, 1e308]
        commands = np.array([node.command(value) for value in desired])
        tally['commands'] += commands.size
        assert np.all(np.isfinite(commands)), request
        assert np.all((commands >= OUTPUT_MIN) & (commands <= OUTPUT_MAX)), request
        assert node.compensator.counters['nonfinite_command'] == 0, request

    try:
        push()
    finally:
        node.destroy_node()
    assert tally['accepted'] + tally['refused'] == EXAMPLES
    assert tally['refused'] > 0
    print(f'live node: {tally}')
