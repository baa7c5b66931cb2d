# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Start the compensation loop: plant_simulator and compensator (ROS installs with launch_ros).

    ros2 launch mpi_ros mpi_loop.launch.py model_params:=/path/to/params.yaml

``model_params`` is the YAML written by ``mpi-ros identify`` (keyed by ``compensator``);
leave it empty to start the compensator unconfigured and push a model later with the
identifier node. ``plant:=false`` starts only the compensator (for a real actuator).
"""

import os

from ament_index_python.packages import get_package_share_directory
from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument, OpaqueFunction
from launch.conditions import IfCondition
from launch.substitutions import LaunchConfiguration
from launch_ros.actions import Node


def _compensator(context, *args, **kwargs):
    share = get_package_share_directory('mpi_ros')
    parameters = [os.path.join(share, 'config', 'compensator.yaml')]
    model_params = LaunchConfiguration('model_params').perform(context)
    if model_params:
        parameters.append(model_params)
    return [Node(package='mpi_ros', executable='compensator', name='compensator',
                 parameters=parameters, output='screen')]


def generate_launch_description():
    """Describe the loop: optional plant simulator plus compensator."""
    share = get_package_share_directory('mpi_ros')
    return LaunchDescription([
        DeclareLaunchArgument(
            'model_params', default_value='',
            description='Parameter YAML with the model (from mpi-ros identify); empty: none'),
        DeclareLaunchArgument(
            'plant', default_value='true',
            description='Start the plant simulator (false for a real actuator)'),
        Node(package='mpi_ros', executable='plant_simulator', name='plant_simulator',
             parameters=[os.path.join(share, 'config', 'plant_simulator.yaml')],
             output='screen', condition=IfCondition(LaunchConfiguration('plant'))),
        OpaqueFunction(function=_compensator),
    ])
