# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
mpi_ros: modified Prandtl-Ishlinskii hysteresis modelling, identification and compensation.

The core (this package without ``mpi_ros.nodes``) never imports rclpy.

>>> from mpi_ros import MPIModel, identify
"""

from .errors import DataError, IdentificationError, ModelError, MPIError, MPIWarning
from .identification import IdentificationResult, identify
from .model import MPIModel

__all__ = ['MPIModel', 'identify', 'IdentificationResult', 'MPIError', 'ModelError',
           'IdentificationError', 'DataError', 'MPIWarning']
