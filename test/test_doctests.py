# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""The examples in the core's docstrings run (numpydoc ``Examples`` sections)."""

import doctest
import importlib

import pytest

MODULES = ['mpi_ros.operators.play', 'mpi_ros.operators.deadzone', 'mpi_ros.operators.model',
           'mpi_ros.identification', 'mpi_ros.identification.folds', 'mpi_ros.model_fit',
           'mpi_ros.metrics', 'mpi_ros.recordings.recording', 'mpi_ros.recordings.bag_writer',
           'mpi_ros.recordings.csv_files', 'mpi_ros.recordings.options', 'mpi_ros.order',
           'mpi_ros.plant.actuator', 'mpi_ros.plant.excitation', 'mpi_ros.array_layout',
           'mpi_ros.compensation.loss', 'mpi_ros.compensation.message_time',
           'mpi_ros.compensation.multi_axis',
           'mpi_ros.node_parameters.spec', 'mpi_ros.node_parameters.compensator',
           'mpi_ros.compensation.screening',
           'mpi_ros.compensation.status', 'mpi_ros.compensation.updates',
           'mpi_ros.plant.simulator', 'mpi_ros.stop_signals']


@pytest.mark.parametrize('name', MODULES)
def test_docstring_examples(name):
    result = doctest.testmod(importlib.import_module(name), optionflags=doctest.ELLIPSIS)
    assert result.failed == 0
