# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Issue 27: output limits that fit the model.

A voltage-driven actuator identified on -90 to 90 V, its model pushed into a compensator
with the default limits (0 to 2): the push is accepted, with a WARN that says how much of
the displacement range is unreachable, and /diagnostics says so too.  The file ``identify``
writes, pushed as it is, carries its identified range as ``output.min`` / ``output.max``:
no warning, and the commands stay inside that range.
"""

from mpi_ros.compensation.limits import limits_shortfall
from mpi_ros.node_parameters.compensator import LIMIT_PARAMETERS
from mpi_ros.nodes.compensator import CompensatorNode
from mpi_ros.nodes.multi_axis import MultiAxisCompensatorNode
from mpi_ros.pipeline import fit_recording, identified_parameters
from mpi_ros.plant.actuator import MagnetostrictiveActuator
from mpi_ros.plant.excitation import identification_excitation
from mpi_ros.recordings import Recording
from mpi_ros.units import resolve_units
import numpy as np
import pytest

from .test_compensator_extensions import typed as typed_numbers

VOLTS_PER_AMPERE = 112.5             # 0.2..1.8 A of the built-in actuator -> -90..90 V


def typed(mapping):
    """Return rclpy Parameters: strings as strings, the rest as typed_numbers does."""
    from rclpy.parameter import Parameter
    text = {name: value for name, value in mapping.items() if isinstance(value, str)}
    numbers = {name: value for name, value in mapping.items() if name not in text}
    strings = [Parameter(name, Parameter.Type.STRING, value) for name, value in text.items()]
    return typed_numbers(numbers) + strings


@pytest.fixture(scope='module')
def piezo():
    """Return a model identified on -90..90 V, identify's parameters and the record."""
    t, current = identification_excitation(8.0, sample_rate=500.0, seed=3)
    displacement = MagnetostrictiveActuator().simulate(t, current)
    volts = VOLTS_PER_AMPERE * (current - 1.0)
    recording = Recording(t, volts, displacement, units=resolve_units(input_unit='V'))
    fit = fit_recording(recording, order=(6, 3), dynamics='off')
    return fit.result.model, identified_parameters(fit.result, fit.recording), fit.recording


def _desired(recording):
    low, high = np.min(recording.displacement), np.max(recording.displacement)
    return low + np.array([0.1, 0.5, 0.9]) * (high - low)


def _diagnostics(node):
    status = node.diagnostics().status[0]
    return {v.key: v.value for v in status.values}


def test_a_model_outside_the_default_limits_is_pushed_with_a_warning(ros_context, piezo,
                                                                     capfd):
    model, parameters, recording = piezo
    defaults = tuple(spec.default for spec in LIMIT_PARAMETERS)
    assert defaults == (0.0, 2.0)
    node = CompensatorNode(context=ros_context)
    try:
        capfd.readouterr()
        gamma_only = {key: value for key, value in parameters.items()
                      if not key.startswith('output.')}
        assert all(r.successful for r in [node.set_parameters_atomically(typed(gamma_only))])
        err = capfd.readouterr().err
        shortfall = limits_shortfall(model, *defaults)
        assert shortfall is not None and 0.4 < shortfall.unreachable < 1.0
        assert f'{100 * shortfall.unreachable:.3g} % of its displacement range' in err
        assert 'WARN' in err and 'is unreachable' in err
        assert 'V, not inside output.min / output.max 0 to 2 V' in err     # a voltage model
        values = _diagnostics(node)
        assert 'is unreachable' in values['limits']
        commands = [node.command(float(d)) for d in _desired(recording)]
        assert min(commands) >= 0.0 and max(commands) <= 2.0         # clamped to 0..2
        clamped = node.counters['clamped']
        assert clamped > 0

        # identify's file as it is: its limits are the identified range; no warning.
        result = node.set_parameters_atomically(typed(parameters))
        assert result.successful, result.reason
        assert 'is unreachable' not in capfd.readouterr().err
        values = _diagnostics(node)
        assert 'limits' not in values
        commands = np.array([node.command(float(d)) for d in _desired(recording)])
        low, high = parameters['output.min'], parameters['output.max']
        assert (low, high) == (np.min(recording.current), np.max(recording.current))
        assert np.all((commands >= low) & (commands <= high))
        assert commands.min() < 0.0 < commands.max()     # the whole range is used again
        assert node.counters['clamped'] == clamped
    finally:
        node.destroy_node()


def test_the_multi_axis_node_warns_per_axis(ros_context, piezo, capfd):
    model, parameters, _ = piezo
    gamma_only = {f'axis{k}.{key}': value for k in range(2)
                  for key, value in parameters.items() if not key.startswith('output.')}
    node = MultiAxisCompensatorNode(context=ros_context, parameter_overrides=typed(
        {'axes': 2}) + typed({'axis1.output.min': parameters['output.min'],
                              'axis1.output.max': parameters['output.max']}))
    try:
        capfd.readouterr()
        assert node.set_parameters_atomically(typed(gamma_only)).successful
        err = capfd.readouterr().err
        assert 'axis 0: the model was identified on inputs' in err
        assert 'axis 1: the model' not in err
        values = _diagnostics(node)
        assert values['limits'].startswith('axis 0: ')
    finally:
        node.destroy_node()


def test_a_model_outside_the_limits_is_warned_about_at_configure(ros_context, piezo, capfd):
    _, parameters, _ = piezo
    gamma_only = {key: value for key, value in parameters.items()
                  if not key.startswith('output.')}
    capfd.readouterr()
    node = CompensatorNode(context=ros_context, parameter_overrides=typed(gamma_only))
    try:
        assert node.lifecycle_state == 'active'                    # autostart: configured
        err = capfd.readouterr().err
        assert 'is unreachable' in err and 'configure done' in err
        assert err.index('is unreachable') < err.index('configure done')
        assert 'is unreachable' in _diagnostics(node)['limits']
    finally:
        node.destroy_node()
