# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Physically motivated extensions of the MPI model, one module per cause.

=====================  ==========================================  ===========================
cause                  model                                       extra parameter keys
=====================  ==========================================  ===========================
``creep``              ``y0 + sign S[H[u] + sum_j w_Cj C_j[u]]``   ``model.creep.*``
``rate_dependence``    ``Gamma[L_tau_e[x]]``                       ``model.rate_dependence.*``
``thermal_drift``      ``y0 + sign S[H[u] + w_T L_tau_T[x^2]]``    ``model.thermal_drift.*``
``dead_time``          ``Gamma[x](t - L)``                         ``model.dead_time``
=====================  ==========================================  ===========================

``u = x - x0``; Gamma carries the operating point (``model.input_offset`` ``x0``,
``model.output_offset`` ``y0``, ``model.output_sign``), and every extended model keeps it
in ``simulate`` and in its parameter form.  The fits use
:func:`mpi_ros.identification.identify`'s design (operating point, detected sign, constant
term, burn-in), so an extension is fitted on the same samples as the plain model.

Every model has ``simulate(time, current)``, ``to_params()``, ``from_params(mapping)`` and a
``cause`` name; :func:`extended_model_from_params` picks the class from the keys present.
:class:`ExtendedCompensator` inverts creep, rate dependence and thermal drift step by step;
:func:`compensator_from_params` builds the right compensator from a parameter set.
"""

from collections.abc import Mapping
from typing import Any

from .compensation import compensator_from_params, ExtendedCompensator
from .creep import CREEP_TIME_CONSTANTS, creep_time_constants, CREEP_WEIGHTS, CreepModel, \
    fit_creep
from .dead_time import DEAD_TIME, DeadTimeModel, fit_dead_time
from .rate_dependence import fit_rate_dependence, RATE_TIME_CONSTANT, RateDependentModel
from .thermal_drift import fit_thermal_drift, THERMAL_TIME_CONSTANT, THERMAL_WEIGHT, \
    ThermalDriftModel
from ..errors import ModelError
from ..model import MPIModel

__all__ = ['CreepModel', 'RateDependentModel', 'ThermalDriftModel', 'DeadTimeModel',
           'ExtendedModel', 'fit_creep', 'fit_rate_dependence',
           'fit_thermal_drift', 'fit_dead_time', 'creep_time_constants',
           'extended_model_from_params', 'EXTENSION_KEYS', 'ExtendedCompensator',
           'compensator_from_params']

ExtendedModel = CreepModel | RateDependentModel | ThermalDriftModel | DeadTimeModel

#: Parameter keys that mark each extension (used by :func:`extended_model_from_params`).
EXTENSION_KEYS: dict[str, tuple[str, ...]] = {
    'creep': (CREEP_TIME_CONSTANTS, CREEP_WEIGHTS),
    'rate_dependence': (RATE_TIME_CONSTANT,),
    'thermal_drift': (THERMAL_TIME_CONSTANT, THERMAL_WEIGHT),
    'dead_time': (DEAD_TIME,),
}

_CLASSES: dict[str, Any] = {'creep': CreepModel, 'rate_dependence': RateDependentModel,
                            'thermal_drift': ThermalDriftModel, 'dead_time': DeadTimeModel}


def extended_model_from_params(mapping: Mapping[str, Any]) -> 'ExtendedModel | MPIModel':
    """
    Build the model a parameter set describes: Gamma alone or Gamma with one extension.

    Parameters
    ----------
    mapping : Mapping[str, Any]
        Flat parameters (Gamma's ``model.*`` keys plus at most one extension's keys).

    Returns
    -------
    MPIModel or one of the extended models
        Validated.

    Raises
    ------
    ModelError
        When keys of more than one extension are present, or a value is invalid.

    """
    present = [cause for cause, keys in EXTENSION_KEYS.items()
               if any(k in mapping for k in keys)]
    if len(present) > 1:
        msg = (f'parameters hold keys of several model extensions ({", ".join(present)});'
               ' a model has at most one extension, keep the keys of one')
        raise ModelError(msg)
    if not present:
        return MPIModel.from_params(mapping)
    return _CLASSES[present[0]].from_params(mapping)  # type: ignore[no-any-return]
