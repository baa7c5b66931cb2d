# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""ament_flake8 over the package, as the ROS 2 ament_python template does."""

from pathlib import Path

import pytest

ament_flake8_main = pytest.importorskip('ament_flake8.main')

ROOT = Path(__file__).resolve().parents[1]


@pytest.mark.flake8
@pytest.mark.linter
def test_flake8():
    rc, errors = ament_flake8_main.main_with_errors(argv=[str(ROOT)])
    assert rc == 0, 'Found %d code style errors / warnings:\n' % len(errors) + \
        '\n'.join(errors)
