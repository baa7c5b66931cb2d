# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
launch/ros2_control.launch.py, and the compensator process it describes.

The launch file is loaded with the stand-ins of ``test/integration/test_launch.py`` (launch
and launch_ros are not dependencies of the package); the node it asks for is started as a
subprocess with the command line launch_ros would give it (``-r __node:=``, every parameter
file, the dictionary written to a file keyed by the node's name, ``-r from:=to`` for each
remapping).  A client subscribes ``/<controller>/commands`` as forward_command_controller
does and checks the contract: one value per joint in the ``joints`` order, no layout.
Also the ``autostart`` argument of ``launch/mpi_loop.launch.py``.
"""

import importlib.util
from pathlib import Path
import sys
import time
import types

from mpi_ros.compensation import Compensator
import numpy as np
import pytest
import rclpy
from rclpy.executors import SingleThreadedExecutor
from rclpy.qos import qos_profile_system_default
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray
import yaml

from .processes import NodeProcess
from .test_ros2_control_output import joint_models
from ..integration.test_launch import (_DeclareLaunchArgument, _described, _OpaqueFunction,
                                       _stub_modules)
from ..process_signals import node_command

ROOT = Path(__file__).resolve().parents[2]
LAUNCH_FILE = ROOT / 'launch' / 'ros2_control.launch.py'


def describe(monkeypatch, **arguments):
    """Return (declared defaults, the Node actions) of ros2_control.launch.py."""
    import ament_index_python.packages as packages
    monkeypatch.setattr(packages, 'get_package_share_directory', lambda name: str(ROOT))
    for name, module in _stub_modules().items():
        monkeypatch.setitem(sys.modules, name, module)
    spec = importlib.util.spec_from_file_location('ros2_control_launch', LAUNCH_FILE)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    entities = module.generate_launch_description()
    declared = {e.name: e.kwargs['default_value'] for e in entities
                if isinstance(e, _DeclareLaunchArgument)}
    assert not set(arguments) - set(declared)
    context = types.SimpleNamespace(launch_configurations={**declared, **arguments})
    nodes = [node for entity in entities if isinstance(entity, _OpaqueFunction)
             for node in entity.execute(context)]
    return declared, nodes


def command_line(node, directory):
    """Return the command launch_ros builds for one Node action."""
    spec = node.kwargs
    command = node_command(spec['executable']) + ['--ros-args', '-r',
                                                  f'__node:={spec["name"]}']
    for index, parameters in enumerate(spec['parameters']):
        if isinstance(parameters, dict):
            path = directory / f'launch_params_{index}.yaml'
            path.write_text(yaml.safe_dump(
                {f'/{spec["name"]}': {'ros__parameters': parameters}}))
            parameters = str(path)
        command += ['--params-file', parameters]
    for source, target in spec.get('remappings', []):
        command += ['-r', f'{source}:={target}']
    return command


def test_the_description(monkeypatch):
    declared, nodes = describe(monkeypatch, joints='wrist, elbow,shoulder',
                               controller='arm_currents')
    assert declared['controller'] == 'current_controller'
    assert declared['input_message'] == 'joint_state'
    assert declared['compensator_params'] == str(ROOT / 'config' / 'compensator.yaml')
    (node,) = nodes
    spec = node.kwargs
    assert spec['executable'] == 'compensator' and spec['name'] == 'compensator'
    assert spec['remappings'] == [('current_commands', '/arm_currents/commands')]
    assert spec['parameters'][0] == declared['compensator_params']
    assert spec['parameters'][-1] == {
        'axes': 3, 'joints': ['wrist', 'elbow', 'shoulder'], 'output_layout': 'flat',
        'input_message': 'joint_state', 'autostart': True}
    with pytest.raises(ValueError, match='joints:=a,b,c is required'):
        describe(monkeypatch)
    _, (managed,) = describe(monkeypatch, joints='a', autostart='false')
    assert managed.kwargs['parameters'][-1]['autostart'] is False


def test_mpi_loop_autostart_argument(monkeypatch):
    declared, nodes = _described(monkeypatch)
    assert declared['autostart'] == 'true'
    compensator = next(n for n in nodes if n.kwargs['name'] == 'compensator')
    assert compensator.kwargs['parameters'] == [declared['compensator_params']]
    _, nodes = _described(monkeypatch, autostart='false')
    compensator = next(n for n in nodes if n.kwargs['name'] == 'compensator')
    assert compensator.kwargs['parameters'][-1] == {'autostart': False}
    with pytest.raises(ValueError, match='autostart must be true or false'):
        _described(monkeypatch, autostart='maybe')


def _nested(flat):
    """Turn {'axis0.model.x': v} into the nested YAML a parameter file holds."""
    tree = {}
    for key, value in flat.items():
        *parents, leaf = key.split('.')
        branch = tree
        for name in parents:
            branch = branch.setdefault(name, {})
        branch[leaf] = value
    return tree


@pytest.mark.slow
def test_the_launched_compensator_feeds_the_controller_topic(monkeypatch, tmp_path,
                                                             ros_context):
    joints = ['elbow', 'wrist']
    models = joint_models(12, count=2)
    flat = {}
    for axis, model in enumerate(models):
        for key, value in model.to_params().items():
            flat[f'axis{axis}.{key}'] = (int(value) if key.endswith('output_sign') else
                                         [float(v) for v in value]
                                         if isinstance(value, (list, tuple, np.ndarray))
                                         else float(value))
    model_file = tmp_path / 'models.yaml'
    model_file.write_text(yaml.safe_dump(
        {'/**/compensator': {'ros__parameters': _nested(flat)}}))
    _, (node,) = describe(monkeypatch, joints=','.join(joints), controller='arm_currents',
                          model_params=str(model_file))
    command = command_line(node, tmp_path)

    client = rclpy.create_node('controller_stand_in', context=ros_context)
    executor = SingleThreadedExecutor(context=ros_context)
    executor.add_node(client)
    received = []
    client.create_subscription(Float64MultiArray, '/arm_currents/commands', received.append,
                               qos_profile_system_default)
    publisher = client.create_publisher(JointState, 'desired_joint_states', 10)
    desired = {'wrist': models[1].simulate(np.array([1.1]))[0],
               'elbow': models[0].simulate(np.array([0.7]))[0]}
    try:
        with NodeProcess(command, command=True) as process:
            deadline = time.monotonic() + 90.0
            while not received and time.monotonic() < deadline:
                if publisher.get_subscription_count() > 0:
                    publisher.publish(JointState(name=['gripper', 'wrist', 'elbow'],
                                                 position=[0.0, desired['wrist'],
                                                           desired['elbow']]))
                executor.spin_once(timeout_sec=0.2)
            assert received, process.output
            status = process.stop()
    finally:
        executor.shutdown()
        client.destroy_node()
    assert status == 0, process.output
    msg = received[0]
    assert len(msg.data) == len(joints)
    assert list(msg.layout.dim) == [] and msg.layout.data_offset == 0
    expected = [Compensator(model, output_min=0.2, output_max=1.8).command(desired[joint])
                for joint, model in zip(joints, models)]
    np.testing.assert_allclose(msg.data, expected, rtol=0, atol=1e-12)
