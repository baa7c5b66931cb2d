# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Exception and warning types of mpi_ros.

One catch-all (:class:`MPIError`); each concrete error also derives from the
built-in type users expect (``ValueError`` for bad data or parameters,
``RuntimeError`` for a failed identification).
"""

__all__ = ['MPIError', 'ModelError', 'IdentificationError', 'DataError', 'ParameterRejected',
           'ParameterPushError', 'MPIWarning']


class MPIError(Exception):
    """Base class of every error raised by mpi_ros."""


class ModelError(MPIError, ValueError):
    """A parameter set does not describe a valid (invertible) MPI model."""


class IdentificationError(MPIError, RuntimeError):
    """Identification failed: solver status, too little excitation, bad order."""


class DataError(MPIError, ValueError):
    """Recorded data (bag, CSV, arrays) is missing, malformed or unusable."""


class ParameterRejected(MPIError, ValueError):
    """A node parameter value failed validation; the message names the parameter."""


class ParameterPushError(MPIError, RuntimeError):
    """A model could not be pushed to a node: target missing, request rejected or unanswered."""


class MPIWarning(UserWarning):
    """A condition the user should know about that does not stop the computation."""
