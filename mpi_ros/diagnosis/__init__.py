# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Diagnosis of measured data: what the MPI simulation misses, the cause, the extended model.

Verdicts (``DiagnosisReport.cause``): the name of a registered effect
(:data:`mpi_ros.extensions.EFFECTS`), two of them joined by ``+``, ``none``, and
``outside_invertible_class`` (data no invertible MPI model can describe, e.g. butterfly
loops; nothing is fitted).  The noise floor of a record is
:func:`mpi_ros.identification.dynamics.noise_std`.
"""

from .diagnose import CAUSES, diagnose, DiagnosisReport
from .invertibility import check_invertible_class, InvertibilityCheck, \
    OUTSIDE_INVERTIBLE_CLASS
from .report import write_report

__all__ = ['diagnose', 'DiagnosisReport', 'CAUSES', 'write_report',
           'check_invertible_class', 'InvertibilityCheck', 'OUTSIDE_INVERTIBLE_CLASS']
