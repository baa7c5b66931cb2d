# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Identification of the MPI operator from measured data, section 4.2 of Kuhnen's paper.

The parts, below the effects (this package imports nothing from :mod:`mpi_ros.extensions`):
:mod:`.qp` (the design and the QP, (28)-(36)), :mod:`.record` (a record's segments, analysis
and refusals), :mod:`.start_states` (how a record starts), :mod:`.fitter` (Gamma fitted on a
record: start states, weights, cross-validation), :mod:`.folds` (held-out blocks),
:mod:`.dynamics_grid` (dead time and lag on held-out blocks), :mod:`.order_selection` (the
order) and :mod:`.dynamics` (what moves the output against the input).
:func:`mpi_ros.identify` (in :mod:`mpi_ros.model_fit`, above the effects) ties them together
with the effects it models.
"""

from .dynamics import InputDynamics
from .order_selection import select_order, select_record_order
from .qp import (ANCHORS, burn_in, DEFAULT_ORDERS, fit_generalized_error, fit_model,
                 fit_plain, generalized_error_gram, hysteresis_thresholds, identify_weights,
                 inverse_superposition_thresholds, output_sign, scaled_design, ScaledDesign)
from .start_states import StartState

__all__ = [
    'select_order', 'hysteresis_thresholds',
    'inverse_superposition_thresholds', 'fit_generalized_error', 'generalized_error_gram',
    'DEFAULT_ORDERS', 'ScaledDesign', 'scaled_design', 'identify_weights', 'fit_model',
    'output_sign', 'burn_in', 'ANCHORS', 'InputDynamics', 'StartState',
    'select_record_order', 'fit_plain',
]
