# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
launch/mpi_loop.launch.py: its description, and the process layout it starts.

``launch`` and ``launch_ros`` are not dependencies of the package (they come with a ROS
install). Where they are importable, the launch file is loaded with them and its
description checked. Everywhere, it is also loaded with small stand-ins for the few launch
classes it uses, which record what it asks for; the nodes are then started as
subprocesses with exactly the command lines launch_ros would give them (``-r __node:=``,
``-r __ns:=``, ``--params-file`` in order, dictionaries written to a file keyed by the
node's fully qualified name), in one process group, and stopped as Ctrl-C on ``ros2
launch`` stops them: SIGINT to the group, then launch's own SIGINT 50 ms later.
"""

import contextlib
import importlib.util
from pathlib import Path
import sys
import threading
import time
import types

from mpi_ros.harness.driver import LoopDriver
from mpi_ros.plant.actuator import MagnetostrictiveActuator
from mpi_ros.plant.excitation import identification_excitation
from mpi_ros.recordings import write_bag_signals
import pytest
from rcl_interfaces.msg import ParameterType
from rcl_interfaces.srv import GetParameters
import rclpy
from std_msgs.msg import Float64
import yaml

from ..process_signals import bad_output, node_command, ProcessGroup

ROOT = Path(__file__).resolve().parents[2]
LAUNCH_FILE = ROOT / 'launch' / 'mpi_loop.launch.py'
NODES = ('compensator', 'plant_simulator', 'identifier')


# -- stand-ins for launch / launch_ros ---------------------------------------------------
class _Recorded:
    """Records the arguments it was built with."""

    def __init__(self, *args, **kwargs):
        self.args = args
        self.kwargs = kwargs


class _LaunchConfiguration:
    """launch.substitutions.LaunchConfiguration: the value of a launch argument."""

    def __init__(self, name):
        self.name = name

    def perform(self, context):
        return context.launch_configurations[self.name]


class _IfCondition:
    """launch.conditions.IfCondition: true, 1, false or 0 (else an error)."""

    def __init__(self, predicate):
        self.predicate = predicate

    def evaluate(self, context):
        text = self.predicate.perform(context).strip().lower()
        if text not in ('true', '1', 'false', '0'):
            raise ValueError(f'invalid condition {text!r}')
        return text in ('true', '1')


class _DeclareLaunchArgument(_Recorded):
    """launch.actions.DeclareLaunchArgument."""

    @property
    def name(self):
        return self.args[0]


class _OpaqueFunction(_Recorded):
    """launch.actions.OpaqueFunction: its function returns the actions."""

    def execute(self, context):
        return self.kwargs['function'](context)


def _stub_modules():
    launch = types.ModuleType('launch')
    launch.LaunchDescription = lambda entities: list(entities)
    actions = types.ModuleType('launch.actions')
    actions.DeclareLaunchArgument = _DeclareLaunchArgument
    actions.OpaqueFunction = _OpaqueFunction
    conditions = types.ModuleType('launch.conditions')
    conditions.IfCondition = _IfCondition
    substitutions = types.ModuleType('launch.substitutions')
    substitutions.LaunchConfiguration = _LaunchConfiguration
    launch_ros = types.ModuleType('launch_ros')
    ros_actions = types.ModuleType('launch_ros.actions')
    ros_actions.Node = _Recorded
    return {'launch': launch, 'launch.actions': actions, 'launch.conditions': conditions,
            'launch.substitutions': substitutions, 'launch_ros': launch_ros,
            'launch_ros.actions': ros_actions}


def _load_launch_file(monkeypatch, *, stubs):
    """Import the launch file (share directory: this checkout); with stand-ins if asked."""
    import ament_index_python.packages as packages
    monkeypatch.setattr(packages, 'get_package_share_directory', lambda name: str(ROOT))
    if stubs:
        for name, module in _stub_modules().items():
            monkeypatch.setitem(sys.modules, name, module)
    spec = importlib.util.spec_from_file_location('mpi_loop_launch', LAUNCH_FILE)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _described(monkeypatch, **arguments):
    """Return (declared defaults, recorded Node actions started) for these arguments."""
    module = _load_launch_file(monkeypatch, stubs=True)
    entities = module.generate_launch_description()
    declared = {e.name: e.kwargs['default_value'] for e in entities
                if isinstance(e, _DeclareLaunchArgument)}
    unknown = set(arguments) - set(declared)
    assert not unknown, f'not launch arguments: {unknown}'
    context = types.SimpleNamespace(launch_configurations={**declared, **arguments})
    nodes = []
    for entity in entities:
        if isinstance(entity, _OpaqueFunction):
            for node in entity.execute(context):
                condition = node.kwargs.get('condition')
                if condition is None or condition.evaluate(context):
                    nodes.append(node)
    return declared, nodes


def _command_lines(nodes, directory):
    """Return {name: command} as launch_ros builds them for ``ros2 launch``."""
    commands = {}
    for node in nodes:
        spec = node.kwargs
        name, namespace = spec['name'], spec.get('namespace')
        fqn = f'{namespace or ""}/{name}'
        command = node_command(spec['executable']) + ['--ros-args', '-r', f'__node:={name}']
        if namespace:
            command += ['-r', f'__ns:={namespace}']
        for index, parameters in enumerate(spec.get('parameters', [])):
            if isinstance(parameters, dict):
                path = directory / f'launch_params_{name}_{index}.yaml'
                path.write_text(yaml.safe_dump({fqn: {'ros__parameters': parameters}}))
                parameters = str(path)
            command += ['--params-file', parameters]
        commands[name] = command
    return commands


# -- the description -------------------------------------------------------------------
def test_arguments_default_to_the_package_config(monkeypatch):
    declared, nodes = _described(monkeypatch)
    assert declared['namespace'] == ''
    assert declared['bag'] == ''
    for node in NODES:
        assert declared[f'{node}_params'] == str(ROOT / 'config' / f'{node}.yaml')
    started = {node.kwargs['name']: node.kwargs for node in nodes}
    assert set(started) == {'compensator', 'plant_simulator'}       # no bag: no identifier
    assert started['compensator']['parameters'] == [declared['compensator_params']]
    assert started['plant_simulator']['parameters'] == [declared['plant_simulator_params']]
    for spec in started.values():
        assert spec['package'] == 'mpi_ros'
        assert spec['executable'] == spec['name']
        assert spec['namespace'] is None


def test_namespace_params_files_and_bag(monkeypatch, tmp_path):
    files = {node: str(tmp_path / f'{node}.yaml') for node in NODES}
    _, nodes = _described(
        monkeypatch, namespace='rig_a', bag=str(tmp_path / 'bag'),
        model_params=str(tmp_path / 'model.yaml'),
        **{f'{node}_params': path for node, path in files.items()})
    started = {node.kwargs['name']: node.kwargs for node in nodes}
    assert set(started) == set(NODES)
    assert {spec['namespace'] for spec in started.values()} == {'/rig_a'}
    assert started['compensator']['parameters'] == [files['compensator'],
                                                    str(tmp_path / 'model.yaml')]
    assert started['plant_simulator']['parameters'] == [files['plant_simulator']]
    assert started['identifier']['parameters'] == [
        files['identifier'],
        {'bag': str(tmp_path / 'bag'), 'target_node': '/rig_a/compensator'}]


@pytest.mark.parametrize('namespace, expected', [
    ('', None), ('/', None), ('rig_a', '/rig_a'), ('/rig_a/', '/rig_a'), ('a/b', '/a/b')])
def test_namespace_forms(monkeypatch, namespace, expected):
    _, nodes = _described(monkeypatch, namespace=namespace, bag='x')
    assert {node.kwargs['namespace'] for node in nodes} == {expected}
    identifier = next(node for node in nodes if node.kwargs['name'] == 'identifier')
    assert identifier.kwargs['parameters'][1]['target_node'] == f'{expected or ""}/compensator'


def test_plant_false_starts_only_the_compensator(monkeypatch):
    _, nodes = _described(monkeypatch, plant='false')
    assert [node.kwargs['name'] for node in nodes] == ['compensator']


def test_the_launch_file_is_installed_with_the_package():
    setup_py = (ROOT / 'setup.py').read_text(encoding='utf-8')
    assert "('share/' + package_name + '/launch', sorted(glob('launch/*.py')))" in setup_py


def test_with_launch_installed(monkeypatch, tmp_path):
    """With the real launch and launch_ros (a ROS install): the same description."""
    # launch.actions, not launch: this checkout's launch/ folder imports as a namespace
    # package named launch.
    pytest.importorskip('launch.actions')
    pytest.importorskip('launch_ros.actions')
    from launch import LaunchContext
    from launch.actions import DeclareLaunchArgument, OpaqueFunction
    from launch_ros.actions import Node
    module = _load_launch_file(monkeypatch, stubs=False)
    description = module.generate_launch_description()
    arguments = {a.name: a for a in description.entities if isinstance(a, DeclareLaunchArgument)}
    assert {'namespace', 'bag', 'model_params', 'plant',
            *(f'{node}_params' for node in NODES)} <= set(arguments)
    context = LaunchContext()
    for name, argument in arguments.items():
        context.launch_configurations[name] = ''.join(
            s.perform(context) for s in argument.default_value)
    context.launch_configurations.update(namespace='rig_a', bag=str(tmp_path / 'bag'))
    opaque = [e for e in description.entities if isinstance(e, OpaqueFunction)]
    nodes = [node for function in opaque for node in function.execute(context) or []]
    assert all(isinstance(node, Node) for node in nodes)
    for node in nodes:
        node._perform_substitutions(context)      # what Node.execute does first
    assert sorted(node.node_name for node in nodes) == [
        '/rig_a/compensator', '/rig_a/identifier', '/rig_a/plant_simulator']
    assert {node.expanded_node_namespace for node in nodes} == {'/rig_a'}


# -- the processes ---------------------------------------------------------------------
def _get_parameters(driver, node, names, timeout=30.0):
    client = driver.create_client(GetParameters, f'{node}/get_parameters')
    try:
        assert client.wait_for_service(timeout_sec=timeout), f'no {node}/get_parameters'
        future = client.call_async(GetParameters.Request(names=list(names)))
        driver.executor_.spin_until_future_complete(future, timeout_sec=timeout)
        assert future.done(), f'{node}/get_parameters did not answer'
        values = future.result().values
    finally:
        driver.destroy_client(client)
    assert all(v.type == ParameterType.PARAMETER_DOUBLE for v in values)
    return [v.double_value for v in values]


@contextlib.contextmanager
def _flooding(publisher, value):
    stop = threading.Event()

    def run():
        while not stop.is_set():
            for _ in range(10):
                publisher.publish(Float64(data=value))
            time.sleep(0.001)

    thread = threading.Thread(target=run, daemon=True)
    thread.start()
    try:
        yield
    finally:
        stop.set()
        thread.join(timeout=10.0)


@pytest.mark.slow
def test_launched_loop_runs_in_its_namespace_and_stops_on_ctrl_c(
        ros_env, monkeypatch, tmp_path):
    t, current = identification_excitation(12.0, sample_rate=250.0, seed=1)
    bag = tmp_path / 'bag'
    write_bag_signals(bag, t, current, MagnetostrictiveActuator().simulate(t, current))
    identifier_params = tmp_path / 'identifier.yaml'
    identifier_params.write_text(yaml.safe_dump(
        {'/**/identifier': {'ros__parameters': {'order': '6,3', 'service_timeout': 60.0}}}))
    _, nodes = _described(monkeypatch, namespace='launch_test', bag=str(bag),
                          identifier_params=str(identifier_params))
    commands = _command_lines(nodes, tmp_path)
    group = ProcessGroup(tmp_path)
    context = rclpy.Context()
    rclpy.init(context=context)
    driver = LoopDriver('launch_test_driver', namespace='/launch_test', context=context)
    try:
        for name in ('compensator', 'plant_simulator', 'identifier'):
            group.start(name, commands[name])
            if name == 'compensator':
                # It got config/compensator.yaml (keyed /**/compensator) in the namespace:
                # its output limits are the file's, not the defaults (0 and 2 A).
                assert _get_parameters(driver, '/launch_test/compensator',
                                       ['output.min', 'output.max']) == [0.2, 1.8]
        # The identifier fits, pushes into /launch_test/compensator and exits 0.
        assert group.wait('identifier', timeout=120.0) == 0, group.output('identifier')
        assert '/launch_test/compensator accepted the model' in group.output('identifier')
        # It pushed what identify writes, the limits included: the identified input range.
        assert _get_parameters(driver, '/launch_test/compensator',
                               ['output.min', 'output.max']) == pytest.approx(
                                   [float(current.min()), float(current.max())], rel=1e-12)
        # The loop answers under the namespace: desired -> compensator -> plant.
        displacement = driver.handshake(driver.desired_pub, 2.0e-5)
        assert 0.0 < displacement < 1.0e-4
        with _flooding(driver.desired_pub, 2.0e-5):
            driver.spin_for(1.0)
            group.interrupt_like_launch()
            statuses = group.wait_all(timeout=30.0)
    finally:
        group.close()
        driver.destroy_node()
        rclpy.try_shutdown(context=context)
    for name in ('compensator', 'plant_simulator'):
        output = group.output(name)
        assert statuses[name] == 0, output
        assert bad_output(output) == [], output
    assert statuses['identifier'] == 0
