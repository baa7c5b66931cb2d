# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Packaging: package.xml, setup.py/setup.cfg, config and launch files, and a real colcon build.

The colcon test builds the repository into a temporary directory with colcon-core,
colcon-ros and colcon-python-setup-py (as on a ROS machine, but without a ROS install:
``AMENT_PREFIX_PATH`` and ``ROS_DISTRO`` unset) and starts an installed executable.
"""

import configparser
import os
from pathlib import Path
import re
import shutil
import subprocess
import sys

from catkin_pkg.package import parse_package
import pytest
import yaml

ROOT = Path(__file__).resolve().parents[1]

NODE_EXECUTABLES = ('compensator', 'identifier', 'plant_simulator')


def test_package_xml_declares_the_dependencies():
    package = parse_package(str(ROOT / 'package.xml'))
    assert package.package_format == 3
    assert package.name == 'mpi_ros'
    assert package.get_build_type() == 'ament_python'
    assert [m.email for m in package.maintainers] == ['mpi-ros-dev@users.noreply.github.com']
    assert package.licenses == ['Apache-2.0']
    exec_depends = {d.name for d in package.exec_depends}
    assert {'rclpy', 'std_msgs', 'rcl_interfaces', 'diagnostic_msgs',
            'python3-numpy', 'python3-scipy', 'ament_index_python', 'launch',
            'launch_ros'} <= exec_depends
    assert {d.name for d in package.test_depends} == {
        'ament_flake8', 'ament_pep257', 'python3-pytest'}


def test_versions_agree():
    package = parse_package(str(ROOT / 'package.xml'))
    setup_py = (ROOT / 'setup.py').read_text(encoding='utf-8')
    assert f"version='{package.version}'" in setup_py


def test_setup_cfg_installs_scripts_where_ros2_run_looks():
    config = configparser.ConfigParser()
    config.read(ROOT / 'setup.cfg')
    assert config['develop']['script_dir'] == '$base/lib/mpi_ros'
    assert config['install']['install_scripts'] == '$base/lib/mpi_ros'
    assert (ROOT / 'resource' / 'mpi_ros').is_file()


def _install_requires(env_updates):
    """Run setup.py with a stub setup() and return its install_requires."""
    code = (
        'import runpy, setuptools\n'
        'captured = {}\n'
        'setuptools.setup = lambda **kw: captured.update(kw)\n'
        "runpy.run_path('setup.py', run_name='__main__')\n"
        "print('\\n'.join(captured['install_requires']))\n"
    )
    env = {k: v for k, v in os.environ.items()
           if k not in ('AMENT_PREFIX_PATH', 'ROS_DISTRO', 'MPI_ROS_SKIP_ROS_WHEELS')}
    env.update(env_updates)
    out = subprocess.run([sys.executable, '-c', code], cwd=ROOT, env=env, check=True,
                         capture_output=True, text=True, timeout=60)
    return out.stdout.split()


def test_pip_install_pulls_ros_wheels_only_without_a_ros_install():
    plain = _install_requires({})
    assert 'ros-jazzy-rclpy[fastrtps]' in plain
    assert 'ros-jazzy-common-interfaces' in plain
    for name in ('numpy', 'numba', 'osqp', 'scipy', 'rosbags', 'matplotlib', 'pyyaml'):
        assert any(re.match(rf'{name}\b', requirement) for requirement in plain), name
    for env in ({'AMENT_PREFIX_PATH': '/opt/ros/jazzy'}, {'ROS_DISTRO': 'jazzy'},
                {'MPI_ROS_SKIP_ROS_WHEELS': '1'}):
        on_ros = _install_requires(env)
        assert not [r for r in on_ros if r.startswith('ros-jazzy-')], env
        assert len(on_ros) == len(plain) - 2


@pytest.mark.parametrize('node', NODE_EXECUTABLES)
def test_config_file_is_keyed_by_the_node_and_names_its_parameters(node):
    from mpi_ros.params import flatten_parameters
    module = __import__(f'mpi_ros.nodes.{node}', fromlist=['PARAMETERS'])
    specs = {spec.name: spec for spec in module.PARAMETERS}
    document = yaml.safe_load((ROOT / 'config' / f'{node}.yaml').read_text(encoding='utf-8'))
    # /**/<node>: the file applies in any namespace (ros2 launch ... namespace:=rig_a).
    assert list(document) == [f'/**/{node}']
    parameters = flatten_parameters(document[f'/**/{node}']['ros__parameters'])
    assert parameters
    for name, value in parameters.items():
        assert name in specs, f'{node}.yaml sets undeclared parameter {name}'
        expected = specs[name].type_.upper()
        found = {bool: 'BOOL', int: 'INTEGER', float: 'DOUBLE', str: 'STRING'}[type(value)]
        assert found == expected, f'{node}.yaml: {name} is {found}, the node wants {expected}'


def test_launch_file_compiles():
    path = ROOT / 'launch' / 'mpi_loop.launch.py'
    code = compile(path.read_text(encoding='utf-8'), str(path), 'exec')
    assert 'generate_launch_description' in code.co_names


def test_launcher_rejects_unknown_nodes_without_importing_rclpy():
    code = (
        'import sys\n'
        'from mpi_ros.nodes.launcher import run_node\n'
        "assert run_node('nope', []) == 2\n"
        "assert 'rclpy' not in sys.modules\n"
    )
    subprocess.run([sys.executable, '-c', code], cwd=ROOT, check=True, timeout=60,
                   capture_output=True)


@pytest.mark.slow
def test_colcon_build_installs_the_node_executables(tmp_path):
    """Build with colcon (no ROS install): the executables land where ros2 run looks."""
    colcon = shutil.which('colcon') or str(Path(sys.executable).with_name('colcon'))
    if not Path(colcon).exists():
        pytest.skip('colcon is not installed')
    env = {k: v for k, v in os.environ.items()
           if k not in ('AMENT_PREFIX_PATH', 'ROS_DISTRO', 'COLCON_PREFIX_PATH')}
    env['PATH'] = f'{Path(sys.executable).parent}{os.pathsep}{env.get("PATH", "")}'
    command = [colcon, '--log-base', str(tmp_path / 'log'), 'build',
               '--base-paths', str(ROOT),
               '--build-base', str(tmp_path / 'build'),
               '--install-base', str(tmp_path / 'install'),
               '--event-handlers', 'console_direct-']
    result = subprocess.run(command, cwd=tmp_path, env=env, capture_output=True, text=True,
                            timeout=600)
    assert result.returncode == 0, result.stdout + result.stderr
    prefix = tmp_path / 'install' / 'mpi_ros'
    lib = prefix / 'lib' / 'mpi_ros'
    for executable in NODE_EXECUTABLES + ('mpi-ros',):
        assert os.access(lib / executable, os.X_OK), executable
    share = prefix / 'share'
    assert (share / 'ament_index' / 'resource_index' / 'packages' / 'mpi_ros').is_file()
    assert (share / 'mpi_ros' / 'package.xml').is_file()
    assert (share / 'mpi_ros' / 'launch' / 'mpi_loop.launch.py').is_file()
    for node in NODE_EXECUTABLES:
        assert (share / 'mpi_ros' / 'config' / f'{node}.yaml').is_file()

    # The installed compensator starts (as `ros2 run mpi_ros compensator` would) and stops
    # cleanly on SIGINT.
    from test.nodes.processes import NodeProcess
    from test.nodes.ros_env import ros_environment
    site = next((prefix / 'lib').glob('python3*/site-packages'))
    run_env = ros_environment()
    run_env['PYTHONPATH'] = os.pathsep.join(filter(None, [str(site),
                                                          run_env.get('PYTHONPATH')]))
    command = [str(lib / 'compensator'), '--ros-args', '-r', '__node:=colcon_smoke',
               '--params-file', str(share / 'mpi_ros' / 'config' / 'compensator.yaml')]
    with NodeProcess(command, command=True, env=run_env, cwd=tmp_path) as node:
        started = node.wait_for_output('no model given yet', timeout=60.0)
        status = node.stop()
    assert started, node.output
    assert status == 0, node.output
