# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
``mypy --strict`` over the package, with the repository's configuration (setup.cfg ``[mypy]``).

The configuration turns on ``strict`` and names the third-party packages that ship no types
(osqp, the ROS message packages); scipy and PyYAML are typed through scipy-stubs and
types-PyYAML from the ``test`` extras.  The test skips when mypy is not installed.

The whole package is checked, ``mpi_ros/nodes`` included (there rclpy's unannotated Node
methods may be called: ``disallow_untyped_calls = False`` for ``mpi_ros.nodes.*`` only).
"""

from pathlib import Path
import re
import subprocess
import sys

import pytest

pytest.importorskip('mypy', reason='mypy is not installed (pip install -e .[test])')

ROOT = Path(__file__).resolve().parents[1]


@pytest.mark.linter
def test_mypy_strict():
    command = [sys.executable, '-m', 'mypy', '--config-file', str(ROOT / 'setup.cfg'),
               '--strict', 'mpi_ros']
    done = subprocess.run(command, cwd=ROOT, capture_output=True, text=True, timeout=900)
    output = done.stdout + done.stderr
    errors = [line for line in output.splitlines() if re.match(r'^\S+:\d+: error:', line)]
    assert done.returncode == 0 and not errors, (
        f'mypy --strict found {len(errors)} error(s) (exit status {done.returncode}):\n'
        + output)
    assert 'Success: no issues found' in done.stdout, output
