# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""Read-only float vectors: the parameter arrays of the operators."""

import numpy as np
import numpy.typing as npt

from ..errors import ModelError

__all__ = ['frozen_vector']


def frozen_vector(values: npt.ArrayLike, name: str) -> npt.NDArray[np.float64]:
    """
    Return ``values`` as a read-only 1-D float64 array, or raise ModelError.

    Parameters
    ----------
    values : array_like of float
        The values.
    name : str
        Parameter name used in the error message.

    Returns
    -------
    ndarray of float, shape (m,)
        A read-only copy.

    """
    try:
        arr = np.array(values, dtype=np.float64)
    except (TypeError, ValueError) as err:
        msg = f'{name} must be a list of numbers; found {values!r}'
        raise ModelError(msg) from err
    if arr.ndim != 1:
        msg = f'{name} must be a flat list of numbers; found shape {arr.shape}'
        raise ModelError(msg)
    if arr.size == 0:
        msg = f'{name} must not be empty'
        raise ModelError(msg)
    bad = np.flatnonzero(~np.isfinite(arr))
    if bad.size:
        msg = (f'{name} must be finite; found {arr[bad[0]]} at index {bad[0]}'
               f' ({bad.size} non-finite value(s))')
        raise ModelError(msg)
    arr.flags.writeable = False
    return arr
