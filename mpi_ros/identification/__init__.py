# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Identification of the MPI operator from measured data, section 4.2 of Kuhnen's paper.

The names users call, re-exported: :func:`identify` and the order selection live in
:mod:`.api`, which also explains the design on real records; the parts are :mod:`.qp`
(the design and the QP, (28)-(36)), :mod:`.procedure` (record, segments, start states,
trial fits, dynamics grid) and :mod:`.dynamics` (what moves the output against the input).
"""

from .api import (DEFAULT_ORDERS, IdentificationResult, identify, model_with_dynamics,
                  select_order, select_record_order)
from .procedure import InputDynamics, StartState
from .qp import (ANCHORS, burn_in, fit_generalized_error, fit_model, fit_plain,
                 generalized_error_gram, hysteresis_thresholds, identify_weights,
                 inverse_superposition_thresholds, output_sign, scaled_design, ScaledDesign)

__all__ = [
    'IdentificationResult', 'identify', 'select_order', 'hysteresis_thresholds',
    'inverse_superposition_thresholds', 'fit_generalized_error', 'generalized_error_gram',
    'DEFAULT_ORDERS', 'ScaledDesign', 'scaled_design', 'identify_weights', 'fit_model',
    'output_sign', 'burn_in', 'ANCHORS', 'InputDynamics', 'StartState',
    'model_with_dynamics', 'select_record_order', 'fit_plain',
]
