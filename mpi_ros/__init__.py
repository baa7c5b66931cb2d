# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
mpi_ros: modified Prandtl-Ishlinskii hysteresis modelling, identification and compensation.

The core (this package without ``mpi_ros.nodes``) never imports rclpy.

>>> from mpi_ros import MPIModel, identify

numba caches the compiled kernels in a per-user directory (``$NUMBA_CACHE_DIR``, else
``$XDG_CACHE_HOME/mpi_ros/numba`` or ``~/.cache/mpi_ros/numba``, one subdirectory per
state of the sources), never in the package: see :mod:`mpi_ros.numba_cache`.
"""

# First: sets numba's cache directory before any @numba.njit(cache=True) is decorated.
from . import numba_cache  # noqa: F401
from .errors import DataError, IdentificationError, ModelError, MPIError, MPIWarning
from .model_fit import IdentificationResult, identify
from .operators.model import MPIModel

__all__ = ['MPIModel', 'identify', 'IdentificationResult', 'MPIError', 'ModelError',
           'IdentificationError', 'DataError', 'MPIWarning']
