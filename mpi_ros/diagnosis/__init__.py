# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Diagnosis of measured data: what the MPI simulation misses, the cause, the extended model.

Verdicts (``DiagnosisReport.cause``): ``creep``, ``rate_dependence``, ``thermal_drift``,
``dead_time``, ``none`` and ``outside_invertible_class`` (data no invertible MPI model can
describe, e.g. butterfly loops; nothing is fitted).
"""

from .diagnose import CAUSES, diagnose, DiagnosisReport, noise_floor
from .invertibility import check_invertible_class, InvertibilityCheck, \
    OUTSIDE_INVERTIBLE_CLASS
from .report import write_report

__all__ = ['diagnose', 'DiagnosisReport', 'CAUSES', 'noise_floor', 'write_report',
           'check_invertible_class', 'InvertibilityCheck', 'OUTSIDE_INVERTIBLE_CLASS']
