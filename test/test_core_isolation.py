# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""The math core never imports rclpy or message packages."""

from pathlib import Path
import subprocess
import sys

CORE_MODULES = ['mpi_ros', 'mpi_ros.identification', 'mpi_ros.compensation', 'mpi_ros.params',
                'mpi_ros.metrics', 'mpi_ros.memory', 'mpi_ros.inverse', 'mpi_ros.array_layout']


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
