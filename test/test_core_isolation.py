# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""The math core never imports rclpy or message packages."""

from pathlib import Path
import subprocess
import sys

CORE_MODULES = ['mpi_ros', 'mpi_ros.identification', 'mpi_ros.compensation', 'mpi_ros.params',
                'mpi_ros.metrics', 'mpi_ros.operators.memory', 'mpi_ros.operators.inverse',
                'mpi_ros.array_layout']


def test_core_does_not_import_ros():
    code = ('import sys\n'
            + ''.join(f'import {m}\n' for m in CORE_MODULES)
            + "bad = [m for m in sys.modules if m.split('.')[0] in "
              "('rclpy', 'std_msgs', 'rcl_interfaces', 'diagnostic_msgs')]\n"
              'print(bad)\n'
              'sys.exit(1 if bad else 0)\n')
    root = Path(__file__).resolve().parents[1]
    done = subprocess.run([sys.executable, '-c', code], cwd=root, capture_output=True,
                          text=True, timeout=120)
    assert done.returncode == 0, done.stdout + done.stderr


#: Top-level packages that belong to ROS (rclpy and the generated message packages).
ROS_PACKAGES = ('rclpy', 'rcl_interfaces', 'std_msgs', 'sensor_msgs', 'diagnostic_msgs',
                'lifecycle_msgs', 'builtin_interfaces', 'rosidl_runtime_py', 'rosidl_parser',
                'rosgraph_msgs', 'launch', 'launch_ros', 'ament_index_python', 'rosbag2_py')


#: The ROS side of the package: the only folders whose modules may import ROS.
ROS_SIDE = {'nodes', 'harness'}


def _imported_packages(path):
    import ast
    tree = ast.parse(path.read_text(), filename=str(path))
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for alias in node.names:
                yield node.lineno, alias.name.split('.')[0]
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            yield node.lineno, node.module.split('.')[0]


def test_no_module_outside_the_ros_side_imports_ros():
    # Every module of the package (found on disk, not a hand-kept list) outside the ROS
    # side (mpi_ros/nodes/, mpi_ros/harness/), at any depth and in any function (lazy
    # imports too).
    package = Path(__file__).resolve().parents[1] / 'mpi_ros'
    core = [p for p in package.rglob('*.py')
            if not ROS_SIDE & set(p.relative_to(package).parts)]
    assert len(core) > 40, core
    found = [f'{p.relative_to(package.parent)}:{line} imports {name}'
             for p in core for line, name in _imported_packages(p) if name in ROS_PACKAGES]
    assert not found, '\n'.join(found)


def _absolute_imports(path, package):
    """Yield (line, module) for each import of ``path``, relative ones made absolute."""
    import ast
    here = ('mpi_ros',) + path.relative_to(package).parts[:-1]
    for node in ast.walk(ast.parse(path.read_text(), filename=str(path))):
        if isinstance(node, ast.ImportFrom):
            base = here[:len(here) - node.level + 1] if node.level else ()
            module = '.'.join(base + ((node.module,) if node.module else ()))
            yield node.lineno, module
            for alias in node.names:        # from .. import app: the module mpi_ros.app
                yield node.lineno, f'{module}.{alias.name}'
        elif isinstance(node, ast.Import):
            for alias in node.names:
                yield node.lineno, alias.name


def test_the_ros_side_imports_nothing_from_the_application():
    # Layers: the application (mpi_ros/app/) sits on the ROS side, never below it.
    package = Path(__file__).resolve().parents[1] / 'mpi_ros'
    ros_side = [p for p in package.rglob('*.py') if ROS_SIDE & set(p.relative_to(package).parts)]
    assert len(ros_side) > 10, ros_side
    found = [f'{p.relative_to(package.parent)}:{line} imports {name}'
             for p in ros_side for line, name in _absolute_imports(p, package)
             if name == 'mpi_ros.app' or name.startswith('mpi_ros.app.')]
    assert not found, '\n'.join(found)
