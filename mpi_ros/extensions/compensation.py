# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
The compensator of a parameter set: plain or with an effect.

Every effect with an exact per-step inverse (creep, rate dependence, thermal drift; see
each effect's ``inverse_step``) plugs it into the one :class:`~mpi_ros.compensation.Compensator`;
a dead time is not invertible causally (it needs the future): the compensator inverts its
Gamma only and :func:`compensator_from_params` warns.
"""

from collections.abc import Mapping
from typing import Any
import warnings

from ..compensation import (Compensator, ExtendedCompensator, FeedforwardCompensator,
                            inverse_step_of)
from ..errors import MPIWarning
from ..model import MPIModel

__all__ = ['Compensator', 'ExtendedCompensator', 'compensator_from_params']


def compensator_from_params(mapping: Mapping[str, Any], *, output_min: float,
                            output_max: float, enabled: bool = True,
                            sample_period: float = 1e-3
                            ) -> FeedforwardCompensator | ExtendedCompensator:
    """
    Build the right compensator for a parameter set (plain or extended model).

    Parameters
    ----------
    mapping : Mapping[str, Any]
        Flat parameters: Gamma's ``model.*`` keys plus at most one extension's keys.
    output_min, output_max : float
        Safe current range [A].
    enabled : bool
        False: the best linear map instead of the inverse.
    sample_period : float
        Nominal command interval [s] (extended compensators only).

    Returns
    -------
    FeedforwardCompensator or ExtendedCompensator
        Plain keys: :class:`~mpi_ros.compensation.FeedforwardCompensator`; creep,
        rate-dependence or thermal-drift keys: :class:`ExtendedCompensator`; dead-time
        keys: the plain compensator of Gamma, with an :class:`~mpi_ros.errors.MPIWarning`
        (a dead time cannot be inverted causally).

    Raises
    ------
    ModelError
        Invalid parameters (the message names the key).

    """
    from . import extended_model_from_params
    model = extended_model_from_params(mapping)
    if isinstance(model, MPIModel):
        return FeedforwardCompensator(model, output_min=output_min, output_max=output_max,
                                      enabled=enabled)
    if inverse_step_of(model) is None:
        msg = (f'{model.cause} cannot be inverted causally (it needs the future);'
               ' compensating Gamma only - the output lags the desired displacement')
        if hasattr(model, 'dead_time'):
            msg = (f'model.dead_time = {model.dead_time} s cannot be inverted causally (it'
                   ' needs the future); compensating Gamma only - the output lags the'
                   ' desired displacement by the dead time')
        warnings.warn(msg, MPIWarning, stacklevel=2)
        return FeedforwardCompensator(model.model, output_min=output_min,
                                      output_max=output_max, enabled=enabled)
    return ExtendedCompensator(model, output_min=output_min, output_max=output_max,
                               enabled=enabled, sample_period=sample_period)
