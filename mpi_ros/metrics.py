# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Error measures: nonlinearity error (37), control error (38), relative RMS error.

All return fractions (0.026 means 2.6 %).

(37) and (38) as printed divide by ``max|s|``: meaningful when the displacement is
measured from the actuator's rest, as in the paper.  A rig's sensor has an arbitrary
zero (an interferometer reading -123...-74 units), which makes them arbitrary too.
:func:`range_error` and :func:`rms_range_error` divide by the measured output's range
instead: they do not depend on the sensor's zero or sign, and equal (37) when the
output starts at 0.  The identification, the order selection and the refusal checks
use them.
"""

import numpy as np
import numpy.typing as npt

from .errors import DataError

__all__ = ['nonlinearity_error', 'control_error', 'relative_rms_error', 'range_error',
           'rms_range_error']


def _pair(a: npt.ArrayLike, b: npt.ArrayLike, names: tuple[str, str]) -> tuple[
        npt.NDArray[np.float64], npt.NDArray[np.float64]]:
    x = np.asarray(a, dtype=np.float64).reshape(-1)
    y = np.asarray(b, dtype=np.float64).reshape(-1)
    if x.shape != y.shape:
        msg = f'{names[0]} and {names[1]} must have the same length; found {x.size} and {y.size}'
        raise DataError(msg)
    if x.size == 0:
        msg = f'{names[0]} and {names[1]} must not be empty'
        raise DataError(msg)
    return x, y


def nonlinearity_error(model_output: npt.ArrayLike, measured: npt.ArrayLike) -> float:
    """
    Nonlinearity error (37): ``max|Gamma[x] - s| / max|Gamma[x]|``.

    Parameters
    ----------
    model_output : array_like of float, shape (N,)
        Simulated output ``Gamma[x]`` [m].
    measured : array_like of float, shape (N,)
        Measured output ``s`` [m].

    Returns
    -------
    float
        (37) as a fraction (0.05 is 5 %).

    Examples
    --------
    >>> round(nonlinearity_error([1.0, 2.0], [1.1, 2.0]), 12)
    0.05

    """
    g, s = _pair(model_output, measured, ('model_output', 'measured'))
    return float(np.max(np.abs(g - s)) / np.max(np.abs(g)))


def control_error(desired: npt.ArrayLike, measured: npt.ArrayLike) -> float:
    """
    Control error (38): ``max|s_c - s| / max|s_c|``.

    Parameters
    ----------
    desired : array_like of float, shape (N,)
        Desired displacement ``s_c`` [m].
    measured : array_like of float, shape (N,)
        Measured displacement ``s`` [m].

    Returns
    -------
    float
        (38) as a fraction.

    """
    c, s = _pair(desired, measured, ('desired', 'measured'))
    return float(np.max(np.abs(c - s)) / np.max(np.abs(c)))


def relative_rms_error(model_output: npt.ArrayLike, measured: npt.ArrayLike) -> float:
    """
    Relative RMS error: ``rms(Gamma[x] - s) / rms(s)``.

    Parameters
    ----------
    model_output, measured : array_like of float, shape (N,)
        Simulated and measured output [m]; `measured` not all 0.

    Returns
    -------
    float
        A fraction of the RMS of `measured`.

    """
    g, s = _pair(model_output, measured, ('model_output', 'measured'))
    return float(np.sqrt(np.mean((g - s) ** 2)) / np.sqrt(np.mean(s ** 2)))


def _output_range(measured: npt.NDArray[np.float64]) -> float:
    span = float(np.max(measured) - np.min(measured))
    if not span > 0.0:
        msg = 'measured is constant: an error relative to its range is undefined'
        raise DataError(msg)
    return span


def range_error(model_output: npt.ArrayLike, measured: npt.ArrayLike) -> float:
    """
    Largest error over the measured output's range: ``max|Gamma[x] - s| / (max s - min s)``.

    (37) with the range in place of ``max|Gamma[x]|``: equal to it when the output starts
    at 0, and independent of the sensor's zero and sign.

    Parameters
    ----------
    model_output, measured : array_like of float, shape (N,)
        Simulated and measured output [m].

    Returns
    -------
    float
        A fraction of the measured range.

    Examples
    --------
    >>> round(range_error([1.0, 2.0], [1.1, 2.0]), 12)
    0.111111111111

    """
    g, s = _pair(model_output, measured, ('model_output', 'measured'))
    return float(np.max(np.abs(g - s)) / _output_range(s))


def rms_range_error(model_output: npt.ArrayLike, measured: npt.ArrayLike) -> float:
    """
    RMS error over the measured output's range: ``rms(Gamma[x] - s) / (max s - min s)``.

    Parameters
    ----------
    model_output, measured : array_like of float, shape (N,)
        Simulated and measured output [m]; `measured` not constant.

    Returns
    -------
    float
        A fraction of the measured range, independent of the sensor's zero and sign.

    """
    g, s = _pair(model_output, measured, ('model_output', 'measured'))
    return float(np.sqrt(np.mean((g - s) ** 2)) / _output_range(s))
