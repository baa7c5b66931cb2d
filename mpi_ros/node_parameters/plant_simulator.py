# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
The plant simulator node's parameters: the truth, the noise, the excitation, the recording.

``actuator.*`` are the built-in actuator's fields (:class:`mpi_ros.plant.ActuatorConfig`,
the registered effects' plant parameters among them), read when the node declares its
parameters; ``model.*`` are Gamma's for ``truth:=mpi``.  What the node builds from the
values is :mod:`mpi_ros.plant.simulator`.
"""

from dataclasses import replace
from typing import Any, Tuple

from .compensator import AXES, MODEL_PARAMETERS
from .spec import loop_qos_parameters, ParameterSpec
from ..plant.actuator import ActuatorConfig
from ..plant.simulator import NODE_OWNED_FIELDS

__all__ = ['actuator_parameters', 'plant_parameters']


def actuator_parameters() -> Tuple[ParameterSpec, ...]:
    """
    Return the ``actuator.*`` specs: the actuator's fields, the effects' from the registry now.

    Returns
    -------
    tuple of ParameterSpec
        Read-only, with the config's defaults and descriptions (the hysteresis core's, the
        sensor's and every registered effect's plant parameters).

    """
    specs = []
    for field in ActuatorConfig.parameters():
        if field.name in NODE_OWNED_FIELDS:
            continue
        type_ = 'integer' if isinstance(field.default, int) else 'double'
        specs.append(ParameterSpec(
            f'actuator.{field.name}', type_, field.default,
            f'Built-in actuator (truth:=builtin): {field.text}', read_only=True))
    return tuple(specs)


def plant_parameters() -> Tuple[ParameterSpec, ...]:
    """
    Return the plant simulator node's parameters, the ``actuator.*`` ones as registered now.

    Returns
    -------
    tuple of ParameterSpec
        The node's own parameters with the ``actuator.*`` specs after the ``model.*`` ones.

    """
    return (_OWN_PARAMETERS[:_ACTUATOR_AT] + actuator_parameters()
            + _OWN_PARAMETERS[_ACTUATOR_AT:])


def __getattr__(name: str) -> Any:
    """Return ``PARAMETERS``: the node's parameters, from the effect registry as it is now."""
    if name == 'PARAMETERS':
        return plant_parameters()
    msg = f'module {__name__!r} has no attribute {name!r}'
    raise AttributeError(msg)


#: The node's parameters besides the ``actuator.*`` ones (see :func:`plant_parameters`).
_OWN_PARAMETERS = (
    ParameterSpec('truth', 'string', 'builtin',
                  'What the simulated plant is: the built-in magnetostrictive actuator '
                  '(actuator.*) or an MPI model (model.*)',
                  choices=('builtin', 'mpi'), read_only=True),
    *(replace(spec, description=f'truth:=mpi: {spec.description}', read_only=True)
      for spec in MODEL_PARAMETERS),
    ParameterSpec('noise_std', 'double', 0.0,
                  'Standard deviation of additive Gaussian sensor noise, 0 = off', 'm',
                  value_range=(0.0, 1.0), read_only=True),
    ParameterSpec('seed', 'integer', 0, 'Seed of the sensor-noise generator',
                  value_range=(0, 2 ** 62), read_only=True),
    ParameterSpec('excitation.enabled', 'bool', False,
                  'Drive the plant with the identification excitation and publish it on '
                  'current_command', read_only=True),
    ParameterSpec('excitation.duration', 'double', 20.0,
                  'Length of the identification excitation', 's',
                  value_range=(0.01, 86400.0), read_only=True),
    ParameterSpec('excitation.sample_rate', 'double', 1000.0,
                  'Sample rate of the identification excitation', 'Hz',
                  value_range=(1.0, 100000.0), read_only=True),
    ParameterSpec('excitation.bias', 'double', 1.0,
                  'Centre current of the identification excitation', 'A',
                  value_range=(-1.0e3, 1.0e3), read_only=True),
    ParameterSpec('excitation.amplitude', 'double', 0.8,
                  'Largest deviation of the excitation current from its centre', 'A',
                  value_range=(0.0, 1.0e3), read_only=True),
    ParameterSpec('excitation.holds', 'bool', True,
                  'Include constant-current holds (expose creep) in the excitation',
                  read_only=True),
    ParameterSpec('excitation.bursts', 'bool', True,
                  'Include high-frequency bursts (expose rate dependence) in the excitation',
                  read_only=True),
    ParameterSpec('excitation.signal', 'string', 'identification',
                  'Excitation signal: identification (decaying loops, holds, bursts; '
                  'excitation.duration long) or diagnostic (the validation record of '
                  'mpi-ros diagnose: major loops, paired holds, bursts at 5-40 Hz; its '
                  'length follows from excitation.repeats and excitation.hold_duration)',
                  choices=('identification', 'diagnostic'), read_only=True),
    ParameterSpec('excitation.hold_duration', 'double', 2.0,
                  'Length of each constant-current hold of the excitation', 's',
                  value_range=(0.0, 3600.0), read_only=True),
    ParameterSpec('excitation.repeats', 'integer', 2,
                  'excitation.signal:=diagnostic: number of loop-and-hold blocks',
                  value_range=(1, 100), read_only=True),
    ParameterSpec('excitation.exit_when_done', 'bool', True,
                  'Stop the node when the excitation is done (false: go on as a plant)',
                  read_only=True),
    ParameterSpec('record.path', 'string', '',
                  'Record current_command and displacement into a new rosbag2 bag here '
                  '(empty: no recording)', read_only=True),
    ParameterSpec('record.storage', 'string', 'sqlite3', 'rosbag2 storage plugin',
                  choices=('sqlite3', 'mcap'), read_only=True),
    *loop_qos_parameters('current_command and displacement'),
    replace(AXES, description=(
        'Number of simulated actuators: 1 = current_command / displacement (Float64); '
        'N > 1 = N independent plants on current_commands / displacements '
        '(Float64MultiArray, samples x axes)')),
    ParameterSpec('sample_period', 'double', 1.0e-3,
                  'axes > 1: interval between the samples of one chunk (a message with '
                  'several samples per axis)', 's', value_range=(1.0e-7, 10.0),
                  read_only=True),
)
#: Where the ``actuator.*`` specs go in :func:`plant_parameters` (after ``model.*``).
_ACTUATOR_AT = 1 + len(MODEL_PARAMETERS)
