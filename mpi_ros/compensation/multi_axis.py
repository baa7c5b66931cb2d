# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Several actuators served together.

One :class:`~mpi_ros.compensation.Compensator` per axis; blocks of samples x axes in and out.
"""

from collections.abc import Sequence
from typing import Any

import numpy as np
import numpy.typing as npt

from .compensator import Compensator
from ..errors import DataError, ModelError

__all__ = ['MultiAxisCompensator']

FloatArray = npt.NDArray[np.float64]


class MultiAxisCompensator:
    """
    Several actuators, each with its own model and :class:`Compensator`, served together.

    A block of desired displacements, ``samples x axes`` (one row per sample, one column
    per axis, as in a ``Float64MultiArray`` chunk), gives a block of commands of the same
    shape; each column is exactly what that axis's single-axis compensator gives.

    Parameters
    ----------
    models : sequence of MPIModel or extended models
        One forward model per axis.
    output_min, output_max : float or sequence of float
        Safe current range [A], one for all axes or one per axis.
    enabled : bool
        False: the best linear maps instead of the inverses.
    sample_period : float
        Nominal command interval [s] (effects with lags only).

    """

    def __init__(self, models: Sequence[Any], *, output_min: float | Sequence[float],
                 output_max: float | Sequence[float], enabled: bool = True,
                 sample_period: float = 1e-3) -> None:
        if len(models) == 0:
            msg = 'a multi-axis compensator needs at least one axis model'
            raise ModelError(msg)
        count = len(models)
        lows = _per_axis(output_min, count, 'output.min')
        highs = _per_axis(output_max, count, 'output.max')
        self.axes = [Compensator(model, output_min=lo, output_max=hi, enabled=enabled,
                                 sample_period=sample_period)
                     for model, lo, hi in zip(models, lows, highs)]

    def __len__(self) -> int:
        """Return the number of axes."""
        return len(self.axes)

    def command(self, desired: npt.ArrayLike) -> FloatArray:
        """
        Return the commands for a block of desired displacements.

        Parameters
        ----------
        desired : array_like of float, shape (K, N) or (N,)
            Desired displacements [m]: K samples of N axes (one sample: shape (N,)).

        Returns
        -------
        ndarray of float, same shape as ``desired``
            Current commands [A].

        Raises
        ------
        DataError
            When the block does not have one column per axis.

        """
        block = np.asarray(desired, dtype=np.float64)
        single = block.ndim == 1
        rows = block.reshape(1, -1) if single else block
        if rows.ndim != 2 or rows.shape[1] != len(self.axes):
            msg = (f'desired displacements must be samples x axes with {len(self.axes)}'
                   f' axes; found shape {tuple(block.shape)}')
            raise DataError(msg)
        out = np.empty_like(rows)
        for axis, compensator in enumerate(self.axes):
            out[:, axis] = compensator.command_batch(rows[:, axis])
        return out[0] if single else out


def _per_axis(value: float | Sequence[float], count: int, name: str) -> list[float]:
    if isinstance(value, (int, float)):
        values = [float(value)] * count
    else:
        values = [float(v) for v in value]
    if len(values) != count:
        msg = f'{name} must be one value or one per axis ({count}); found {len(values)}'
        raise ModelError(msg)
    return values
