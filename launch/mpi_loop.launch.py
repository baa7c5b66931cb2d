# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Start the compensation loop: compensator, plant simulator and, given a bag, the identifier.

    ros2 launch mpi_ros mpi_loop.launch.py
    ros2 launch mpi_ros mpi_loop.launch.py namespace:=rig_a bag:=/path/to/excitation_bag
    ros2 launch mpi_ros mpi_loop.launch.py model_params:=params.yaml plant:=false

Launch arguments
    ``namespace``: namespace of every node and topic (default: none).
    ``compensator_params``, ``plant_simulator_params``, ``identifier_params``: parameter
    YAML of each node (default: the package's ``config/<node>.yaml``).
    ``model_params``: a further YAML for the compensator, e.g. the model written by
    ``mpi-ros identify`` (default: none, the compensator starts unconfigured).
    ``plant``: start the plant simulator (default ``true``; ``false`` for a real actuator).
    ``autostart``: the compensator, a managed (lifecycle) node, configures and activates
    itself at start-up (default ``true``); ``false`` leaves it unconfigured for a lifecycle
    manager or ``ros2 lifecycle set /compensator configure`` (then ``activate``).
    ``bag``: when given, the identifier fits a model from this bag and pushes it into the
    compensator of this launch (``target_node`` is set to it), then exits.

A parameter file applies to a node whose key matches its fully qualified name: the
package's config files are keyed ``/**/<node>`` and so apply in any namespace. A file
keyed ``compensator`` (as ``mpi-ros identify`` writes it) means ``/compensator`` and
applies only without a namespace; under one, key it ``/**/compensator`` or push the
model with ``bag:=``.

Ctrl-C stops every node cleanly (exit 0), also when the terminal's SIGINT and the one
launch sends next reach a node together.
"""

import os

from ament_index_python.packages import get_package_share_directory
from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument, OpaqueFunction
from launch.conditions import IfCondition
from launch.substitutions import LaunchConfiguration
from launch_ros.actions import Node

#: Nodes with a parameter-file launch argument ``<node>_params``.
NODES = ('compensator', 'plant_simulator', 'identifier')


def generate_launch_description():
    """Describe the loop: its launch arguments, then the nodes (built once they are known)."""
    config = os.path.join(get_package_share_directory('mpi_ros'), 'config')
    arguments = [
        DeclareLaunchArgument(
            'namespace', default_value='',
            description='Namespace of every node and topic (empty: none)'),
        *(DeclareLaunchArgument(
            f'{node}_params', default_value=os.path.join(config, f'{node}.yaml'),
            description=f'Parameter YAML of the {node} node (keyed /**/{node})')
          for node in NODES),
        DeclareLaunchArgument(
            'model_params', default_value='',
            description='Further compensator YAML, e.g. the model from mpi-ros identify '
                        '(empty: none, the compensator starts unconfigured)'),
        DeclareLaunchArgument(
            'plant', default_value='true',
            description='Start the plant simulator (false for a real actuator)'),
        DeclareLaunchArgument(
            'autostart', default_value='true',
            description='The compensator configures and activates itself at start-up (false: '
                        'it waits unconfigured for the lifecycle transitions)'),
        DeclareLaunchArgument(
            'bag', default_value='',
            description='rosbag2 bag to identify from; the identifier pushes the model into '
                        'this compensator and exits (empty: no identifier)'),
    ]
    return LaunchDescription([*arguments, OpaqueFunction(function=_nodes)])


def _nodes(context, *args, **kwargs):
    """Return the Node actions for the performed launch arguments."""
    def value(name):
        return LaunchConfiguration(name).perform(context).strip()

    namespace = _namespace(context.launch_configurations.get('ros_namespace'),
                           value('namespace'))
    compensator_params = [value('compensator_params')]
    if value('model_params'):
        compensator_params.append(value('model_params'))
    if value('autostart').lower() not in ('true', '1'):
        if value('autostart').lower() not in ('false', '0'):
            msg = f"autostart must be true or false; found {value('autostart')!r}"
            raise ValueError(msg)
        compensator_params.append({'autostart': False})
    nodes = [Node(package='mpi_ros', executable='compensator', name='compensator',
                  namespace=namespace, parameters=compensator_params, output='screen')]
    nodes.append(Node(package='mpi_ros', executable='plant_simulator', name='plant_simulator',
                      namespace=namespace, parameters=[value('plant_simulator_params')],
                      output='screen', condition=IfCondition(LaunchConfiguration('plant'))))
    if value('bag'):
        target = f'{namespace or ""}/compensator'
        nodes.append(Node(package='mpi_ros', executable='identifier', name='identifier',
                          namespace=namespace,
                          parameters=[value('identifier_params'),
                                      {'bag': value('bag'), 'target_node': target}],
                          output='screen'))
    return nodes


def _namespace(base, namespace):
    """
    Return the absolute namespace of the nodes ('/a/b'), or None for the root.

    A relative ``namespace`` goes below the one pushed by an including launch file
    (``PushRosNamespace``, launch configuration ``ros_namespace``), as launch_ros does.
    """
    parts = [] if namespace.startswith('/') else [base or '']
    parts.append(namespace)
    joined = '/'.join(part.strip('/') for part in parts if part.strip('/'))
    return f'/{joined}' if joined else None
