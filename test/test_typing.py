# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
``mypy --strict`` over the package, with the repository's configuration (setup.cfg ``[mypy]``).

The configuration turns on ``strict`` and names the third-party packages that ship no types
(osqp, the ROS message packages); scipy and PyYAML are typed through scipy-stubs and
types-PyYAML from the ``test`` extras.  The test skips when mypy is not installed.

``mpi_ros/nodes`` is left out for now: its modules still have strict-mode errors, which the
node restructuring of issue 10 fixes.  Once they are fixed, add it: delete
``NOT_YET_CHECKED`` below so that the whole package is checked (its modules are analysed
already, as imports of the rest, but their errors are silenced by ``--follow-imports=silent``).
"""

from pathlib import Path
import re
import subprocess
import sys

import pytest

pytest.importorskip('mypy', reason='mypy is not installed (pip install -e .[test])')

ROOT = Path(__file__).resolve().parents[1]

#: Left out of the check until their errors are fixed (see the module docstring).
NOT_YET_CHECKED = ['--exclude', '^mpi_ros/nodes/', '--follow-imports=silent']


@pytest.mark.linter
def test_mypy_strict():
    command = [sys.executable, '-m', 'mypy', '--config-file', str(ROOT / 'setup.cfg'),
               '--strict', *NOT_YET_CHECKED, 'mpi_ros']
    done = subprocess.run(command, cwd=ROOT, capture_output=True, text=True, timeout=900)
    output = done.stdout + done.stderr
    errors = [line for line in output.splitlines() if re.match(r'^\S+:\d+: error:', line)]
    assert done.returncode == 0 and not errors, (
        f'mypy --strict found {len(errors)} error(s) (exit status {done.returncode}):\n'
        + output)
    assert 'Success: no issues found' in done.stdout, output
