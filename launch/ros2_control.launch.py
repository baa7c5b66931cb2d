# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Feed a ros2_control forward_command_controller with the multi-axis compensator's currents.

    ros2 launch mpi_ros ros2_control.launch.py joints:=wrist,elbow,shoulder
    ros2 launch mpi_ros ros2_control.launch.py joints:=a,b controller:=arm model_params:=m.yaml

The compensator starts with ``axes`` = the number of ``joints``, ``output_layout: flat`` and
its ``current_commands`` remapped to ``/<controller>/commands``: every message holds one
current [A] per joint, in the order of ``joints``, with an empty ``layout`` - exactly what
``forward_command_controller/ForwardCommandController`` takes on ``~/commands`` (it drops a
message of any other size).  Give the controller the same ``joints`` in the same order and
the command interface the hardware exposes for the current (e.g. ``effort``)::

    controller_manager:
      ros__parameters:
        current_controller:
          type: forward_command_controller/ForwardCommandController
    current_controller:
      ros__parameters:
        joints: [wrist, elbow, shoulder]
        interface_name: effort

The controller subscribes with the system-default QoS (with Fast DDS a best-effort reader
that keeps the newest message; either ``qos_reliability`` of the compensator reaches it):
send one sample per message (of a chunk's messages, the controller keeps the newest).

Launch arguments
    ``joints``: joint names, comma- or space-separated, in the controller's order (required).
    ``controller``: name of the forward_command_controller (default ``current_controller``).
    ``input_message``: ``joint_state`` (default: ``sensor_msgs/JointState`` on
    ``desired_joint_states``, each joint's position [m] by name) or ``array``
    (``Float64MultiArray`` on ``desired_displacements``, one column per joint in order).
    ``compensator_params``: parameter YAML (default: the package's
    ``config/compensator.yaml``, keyed ``/**/compensator``).
    ``model_params``: the models, ``axis<k>.model.*`` (k in the order of ``joints``), e.g.
    from ``mpi-ros identify`` / the identifier with ``axes``; empty: the compensator starts
    without models and publishes nothing until they are pushed.
    ``autostart``: configure and activate at start-up (default ``true``; ``false`` leaves the
    managed node unconfigured for a lifecycle manager).
"""

import os
import re

from ament_index_python.packages import get_package_share_directory
from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument, OpaqueFunction
from launch.substitutions import LaunchConfiguration
from launch_ros.actions import Node


def generate_launch_description():
    """Describe the compensator wired to a forward_command_controller."""
    config = os.path.join(get_package_share_directory('mpi_ros'), 'config')
    arguments = [
        DeclareLaunchArgument(
            'joints', default_value='',
            description='Joint names, comma- or space-separated, in the order of the '
                        "controller's joints parameter (required)"),
        DeclareLaunchArgument(
            'controller', default_value='current_controller',
            description='Name of the forward_command_controller: the currents go to '
                        '/<controller>/commands'),
        DeclareLaunchArgument(
            'input_message', default_value='joint_state',
            description='joint_state (sensor_msgs/JointState on desired_joint_states) or '
                        'array (Float64MultiArray on desired_displacements)'),
        DeclareLaunchArgument(
            'compensator_params', default_value=os.path.join(config, 'compensator.yaml'),
            description='Parameter YAML of the compensator (keyed /**/compensator)'),
        DeclareLaunchArgument(
            'model_params', default_value='',
            description='The axis<k>.model.* keys, k in the order of joints (empty: none)'),
        DeclareLaunchArgument(
            'autostart', default_value='true',
            description='Configure and activate at start-up (false: wait unconfigured)'),
    ]
    return LaunchDescription([*arguments, OpaqueFunction(function=_nodes)])


def _nodes(context, *args, **kwargs):
    """Return the compensator for the performed launch arguments."""
    def value(name):
        return LaunchConfiguration(name).perform(context).strip()

    joints = [name for name in re.split(r'[,\s]+', value('joints')) if name]
    if not joints:
        msg = 'joints:=a,b,c is required: the joint names, in the order of the controller'
        raise ValueError(msg)
    controller = value('controller').strip('/')
    autostart = value('autostart').lower()
    if autostart not in ('true', '1', 'false', '0'):
        msg = f'autostart must be true or false; found {value("autostart")!r}'
        raise ValueError(msg)
    parameters = [value('compensator_params')]
    if value('model_params'):
        parameters.append(value('model_params'))
    parameters.append({
        'axes': len(joints),
        'joints': joints,
        'output_layout': 'flat',
        'input_message': value('input_message'),
        'autostart': autostart in ('true', '1'),
    })
    return [Node(package='mpi_ros', executable='compensator', name='compensator',
                 parameters=parameters,
                 remappings=[('current_commands', f'/{controller}/commands')],
                 output='screen')]
