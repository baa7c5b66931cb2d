# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""ament_pep257 (docstring conventions) over the package, as the ROS 2 template does."""

from pathlib import Path

import pytest

ament_pep257_main = pytest.importorskip('ament_pep257.main')

ROOT = Path(__file__).resolve().parents[1]


@pytest.mark.linter
@pytest.mark.pep257
def test_pep257():
    rc = ament_pep257_main.main(argv=[str(ROOT)])
    assert rc == 0, 'Found code style errors / warnings'
