# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""``mpi-ros demo``: which ROS_DOMAIN_ID it uses (the run itself: test/integration)."""

from mpi_ros.app.demo import demo_domain_id
from mpi_ros.errors import MPIError
import pytest


def test_an_exported_domain_is_used(monkeypatch):
    monkeypatch.setenv('ROS_DOMAIN_ID', '17')
    assert demo_domain_id() == 17


def test_the_option_wins_over_the_exported_domain(monkeypatch):
    monkeypatch.setenv('ROS_DOMAIN_ID', '17')
    assert demo_domain_id(42) == 42


@pytest.mark.parametrize('exported', [None, '', '  '])
def test_without_one_it_picks_its_own(monkeypatch, exported):
    if exported is None:
        monkeypatch.delenv('ROS_DOMAIN_ID', raising=False)
    else:
        monkeypatch.setenv('ROS_DOMAIN_ID', exported)
    assert all(101 <= demo_domain_id() <= 199 for _ in range(20))


@pytest.mark.parametrize('exported, given, match', [
    ('abc', None, "the exported ROS_DOMAIN_ID must be an integer from 0 to 232; found 'abc'"),
    ('300', None, "the exported ROS_DOMAIN_ID must be an integer from 0 to 232; found '300'"),
    ('5', 233, "--domain-id must be an integer from 0 to 232; found '233'"),
    ('5', -1, "--domain-id must be an integer from 0 to 232; found '-1'"),
])
def test_an_invalid_domain_is_refused(monkeypatch, exported, given, match):
    monkeypatch.setenv('ROS_DOMAIN_ID', exported)
    with pytest.raises(MPIError, match=match):
        demo_domain_id(given)
