# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
The identifier on a multi-axis bag: every axis fitted, all models pushed in one request.

The bag holds ``/current_commands`` and ``/displacements`` as Float64MultiArray, one
element per axis, as the multi-axis nodes publish them; the three axes are different
actuators (the built-in one driven around three operating points).  The identifier fits
them in a process pool and pushes all ``axis<k>.model.*`` keys to a multi-axis compensator
in one request; each axis must get exactly the model a single-axis fit of its columns
gives.  A refused axis leaves the compensator untouched.  The same data recorded as chunks
(``layout.dim`` = samples x axes, 10 input and 4 output samples per message) give the same
models.
"""

import threading

from mpi_ros.errors import DataError, IdentificationError
from mpi_ros.nodes.identifier import fit_bag, fit_bag_axes, IdentifierNode
from mpi_ros.nodes.multi_axis import axis_key, MultiAxisCompensatorNode
from mpi_ros.params import read_params_yaml
from mpi_ros.plant.actuator import MagnetostrictiveActuator
from mpi_ros.plant.excitation import identification_excitation
from mpi_ros.recordings import DataOptions
import numpy as np
import pytest
from rclpy.executors import SingleThreadedExecutor
from rclpy.parameter import Parameter

from ..message_bags import ARRAY, chunked, float64_array, write_bag

AXES = 3
ORDER = '6,3'


def _stamps(t):
    return np.round(np.asarray(t) * 1e9).astype(np.int64).tolist()


def _axes_data():
    t, base = identification_excitation(10.0, sample_rate=250.0, seed=1)
    currents = np.column_stack([base, 0.8 * base + 0.3, 1.1 * base - 0.2])
    displacements = np.column_stack([MagnetostrictiveActuator().simulate(t, currents[:, k])
                                     for k in range(AXES)])
    return np.asarray(_stamps(t)), currents, displacements


@pytest.fixture(scope='module')
def axes_bag(tmp_path_factory):
    """Return a 3-axis bag: one Float64MultiArray sample of every axis per message."""
    stamps, currents, displacements = _axes_data()
    commands = [(s, float64_array(row)) for s, row in zip(stamps, currents)]
    measured = [(s + 1, float64_array(row)) for s, row in zip(stamps, displacements)]
    path = tmp_path_factory.mktemp('bags') / 'axes'
    write_bag(path, {'/current_commands': (ARRAY, commands),
                     '/displacements': (ARRAY, measured)})
    return path


@pytest.fixture(scope='module')
def chunked_bag(tmp_path_factory):
    """Return the same data as chunks: 10 samples x 3 axes (input), 4 x 3 (output)."""
    stamps, currents, displacements = _axes_data()
    path = tmp_path_factory.mktemp('bags') / 'chunks'
    write_bag(path, {'/current_commands': (ARRAY, chunked(stamps, currents, 10)),
                     '/displacements': (ARRAY, chunked(stamps + 1, displacements, 4))})
    return path


@pytest.fixture
def compensator(ros_context):
    node = MultiAxisCompensatorNode(context=ros_context, parameter_overrides=[
        Parameter('axes', value=AXES), Parameter('output.min', value=-1.0),
        Parameter('output.max', value=3.0)])
    executor = SingleThreadedExecutor(context=ros_context)
    executor.add_node(node)
    thread = threading.Thread(target=executor.spin, daemon=True)
    thread.start()
    yield node
    executor.shutdown()
    thread.join(timeout=5.0)
    node.destroy_node()


def test_fits_every_axis_and_pushes_all_at_once(ros_context, compensator, axes_bag, tmp_path):
    params_file = tmp_path / 'axes.yaml'
    node = IdentifierNode(context=ros_context, parameter_overrides=[
        Parameter('bag', value=str(axes_bag)), Parameter('order', value=ORDER),
        Parameter('axes', value=AXES), Parameter('workers', value=2),
        Parameter('params_file', value=str(params_file)),
        Parameter('service_timeout', value=10.0)])
    try:
        fits = node.run()
    finally:
        node.destroy_node()
    assert len(fits) == AXES
    assert compensator.compensator is not None                     # every axis configured
    written = read_params_yaml(params_file)
    assert written['axes'] == AXES
    for axis, fit in enumerate(fits):
        alone = fit_bag(str(axes_bag), order=(6, 3), options=DataOptions(
            input_topic='/current_commands', output_topic='/displacements',
            input_index=axis, output_index=axis))
        assert fit.parameters == alone.parameters
        assert compensator.compensator.axes[axis].model.to_params() == fit.parameters
        for key, value in fit.parameters.items():
            assert written[axis_key(axis, key)] == pytest.approx(value, rel=1e-12, abs=0.0)
    assert fits[0].parameters != fits[1].parameters                # different actuators


def test_a_refused_axis_pushes_nothing(ros_context, compensator, tmp_path):
    t, base = identification_excitation(10.0, sample_rate=250.0, seed=2)
    flat = np.column_stack([base, base, np.full_like(base, 1.0)])  # axis 2: constant input
    displacements = np.column_stack([MagnetostrictiveActuator().simulate(t, flat[:, k])
                                     for k in range(AXES)])
    stamps = _stamps(t)
    path = write_bag(tmp_path / 'refused', {
        '/current_commands': (ARRAY, [(s, float64_array(r)) for s, r in zip(stamps, flat)]),
        '/displacements': (ARRAY, [(s + 1, float64_array(r))
                                   for s, r in zip(stamps, displacements)])})
    node = IdentifierNode(context=ros_context, parameter_overrides=[
        Parameter('bag', value=str(path)), Parameter('order', value=ORDER),
        Parameter('axes', value=AXES), Parameter('workers', value=1)])
    try:
        with pytest.raises(IdentificationError, match='axis 2'):
            node.run()
    finally:
        node.destroy_node()
    assert compensator.compensator is None
    assert compensator.counters['rejected_updates'] == 0


def test_chunked_bag_gives_the_models_of_the_per_sample_bag(ros_context, axes_bag, chunked_bag):
    reference = fit_bag_axes(str(axes_bag), AXES, order=(6, 3), workers=1)
    node = IdentifierNode(context=ros_context, parameter_overrides=[
        Parameter('bag', value=str(chunked_bag)), Parameter('order', value=ORDER),
        Parameter('axes', value=AXES), Parameter('workers', value=2),
        Parameter('push', value=False)])
    try:
        fits = node.run()
    finally:
        node.destroy_node()
    assert [fit.parameters for fit in fits] == [fit.parameters for fit in reference]
    assert [fit.result.samples for fit in fits] == [fit.result.samples for fit in reference]


def test_an_axis_count_that_disagrees_with_the_chunks_is_named(chunked_bag):
    with pytest.raises(DataError, match=r'axis 0 \(element or column 0 of /current_commands, '
                                        r'/displacements\): .*it holds chunks of 4 sample\(s\) '
                                        r'x 3 axes \(layout.dim = samples x axes\), but '
                                        r'array_axes is 4; set array_axes to 3'):
        fit_bag_axes(str(chunked_bag), AXES + 1, order=(6, 3), workers=1)
    with pytest.raises(DataError, match=r'^array_axes is 2 but axes is 3; leave array_axes '
                                        r'unset \(it follows axes\) or make them equal$'):
        fit_bag_axes(str(chunked_bag), AXES, options=DataOptions(array_axes=2), workers=1)


def test_chunks_without_layout_dim_are_read_with_the_axis_count(axes_bag, tmp_path):
    """Read K x N values without layout.dim (the nodes accept them) as K samples of N axes."""
    stamps, currents, displacements = _axes_data()
    flat = [(stamp, float64_array(message.data))
            for stamp, message in chunked(stamps, currents, 10)]
    for _, message in flat:
        message.layout.dim = []
    path = write_bag(tmp_path / 'flat', {
        '/current_commands': (ARRAY, flat),
        '/displacements': (ARRAY, chunked(stamps + 1, displacements, 5))})
    reference = fit_bag_axes(str(axes_bag), AXES, order=(6, 3), workers=1)
    fits = fit_bag_axes(str(path), AXES, order=(6, 3), workers=1)
    assert [fit.parameters for fit in fits] == [fit.parameters for fit in reference]
