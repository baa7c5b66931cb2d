# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Run a node from the ``mpi-ros`` command exactly as ``ros2 run mpi_ros <node>`` would.

``mpi-ros compensator --ros-args -p output.max:=1.8`` calls
``run_node('compensator', ['--ros-args', '-p', 'output.max:=1.8'])``, which hands
``['compensator', '--ros-args', ...]`` to the node's ``main`` and so to
``rclpy.init(args=...)``: rcl skips the program name, parses everything between
``--ros-args`` and ``--`` (remappings, ``-p``, ``--params-file``, ``-r __node:=``,
``--log-level``) and leaves other arguments alone, just as for the console script
that ``ros2 run`` starts. The node module is imported only here, so ``mpi-ros
identify`` and the other offline subcommands never load rclpy.
"""

import importlib
import sys
from typing import Dict, List, Sequence, Tuple

__all__ = ['NODES', 'node_names', 'run_node']

#: CLI name -> (module in mpi_ros.nodes, executable name, one-line summary).
NODES: Dict[str, Tuple[str, str, str]] = {
    'compensator': (
        'compensator', 'compensator',
        'feedforward compensator: desired_displacement [m] -> current_command [A]'),
    'identifier': (
        'identifier', 'identifier',
        'fit a model from a bag and push it to the compensator atomically'),
    'plant-simulator': (
        'plant_simulator', 'plant_simulator',
        'simulated actuator: current_command [A] -> displacement [m]'),
}

_ALIASES = {'plant_simulator': 'plant-simulator'}


def node_names() -> List[str]:
    """
    List the node subcommands of ``mpi-ros``.

    Returns
    -------
    list of str
        ``['compensator', 'identifier', 'plant-simulator']``.

    """
    return list(NODES)


def run_node(name: str, argv: Sequence[str]) -> int:
    """
    Run one node in this process until it shuts down.

    Parameters
    ----------
    name : str
        ``compensator``, ``identifier`` or ``plant-simulator`` (``plant_simulator``
        is accepted too).
    argv : sequence of str
        Arguments after the subcommand, e.g. ``['--ros-args', '-p', 'enabled:=false']``.

    Returns
    -------
    int
        The node's exit status (0 on a clean shutdown, 2 for an unknown name).

    """
    key = _ALIASES.get(name, name)
    if key not in NODES:
        print(f'error: unknown node {name!r}; expected one of: {", ".join(NODES)}',
              file=sys.stderr)
        return 2
    module_name, executable, _ = NODES[key]
    module = importlib.import_module(f'.{module_name}', __package__)
    status = module.main(args=[executable, *argv])
    return int(status or 0)
