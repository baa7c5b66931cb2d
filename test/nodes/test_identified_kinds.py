# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Issue 27: the compensators accept every kind of model ``identify`` writes, as it writes it.

Synthetic rig records of the four kinds the identification delivers (Gamma alone, an input
lag, a dead time, an output mode) are identified; ``identified_parameters`` (what the YAML
holds and the identifier pushes: the model, ``model.input_quantity`` and the limits) goes in
one ``set_parameters_atomically`` request to a single-axis node and, renamed, to one axis of a
two-axis node.  Each is accepted and runs that model.
"""

from mpi_ros.compensation import kind_of
from mpi_ros.compensation.updates import axis_key
from mpi_ros.extensions import extended_model_from_params
from mpi_ros.nodes.compensator import CompensatorNode
from mpi_ros.nodes.multi_axis import MultiAxisCompensatorNode
from mpi_ros.pipeline import fit_recording, identified_parameters
from mpi_ros.plant.synthetic import synthetic_record
from mpi_ros.recordings import Recording
import pytest

from .test_output_limits import typed

KINDS = {'virgin': 'none', 'lag 3 ms at 1 kHz': 'rate_dependence',
         'dead time 10 samples at 10 kHz': 'dead_time (predicted)',
         'ringing 1000 Hz': 'resonance (not compensated)'}


@pytest.fixture(scope='module')
def identified():
    """Return identify's parameters of one record per kind."""
    out = {}
    for kind in KINDS:
        record = synthetic_record(kind, 0)
        fit = fit_recording(Recording(record.time, record.current, record.displacement),
                            order=(6, 3))
        out[kind] = identified_parameters(fit.result, fit.recording)
    return out


@pytest.mark.parametrize('kind', sorted(KINDS))
def test_every_identified_kind_is_accepted_on_one_axis_and_on_an_axis(ros_context, identified,
                                                                      kind):
    parameters = identified[kind]
    model = extended_model_from_params(parameters)
    assert kind_of(model) == KINDS[kind]
    single = CompensatorNode(context=ros_context)
    multi = MultiAxisCompensatorNode(context=ros_context,
                                     parameter_overrides=typed({'axes': 2}))
    try:
        result = single.set_parameters_atomically(typed(parameters))
        assert result.successful, result.reason
        assert single.compensator.model.to_params() == model.to_params()
        assert single.compensator.kind == KINDS[kind]
        assert (single.compensator.output_min, single.compensator.output_max) == (
            parameters['output.min'], parameters['output.max'])
        result = multi.set_parameters_atomically(typed(
            {axis_key(1, key): value for key, value in parameters.items()}))
        assert result.successful, result.reason
        assert multi.get_parameter('axis1.model.input_quantity').value == 'current'
        assert multi.get_parameter('axis1.output.min').value == parameters['output.min']
        assert multi.compensator is None                  # axis 0 has no model yet
        result = multi.set_parameters_atomically(typed(
            {axis_key(0, key): value for key, value in identified['virgin'].items()}))
        assert result.successful, result.reason
        assert multi.compensator.axes[1].model.to_params() == model.to_params()
        assert multi.compensator.axes[1].kind == KINDS[kind]
    finally:
        single.destroy_node()
        multi.destroy_node()
