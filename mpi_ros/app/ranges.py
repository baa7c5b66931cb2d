# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
The range a model was identified on, and the samples of a signal outside a range.

``mpi-ros simulate`` and ``mpi-ros compensate`` warn when they are asked for values outside
the range the model knows (the model extrapolates there), and ``compensate`` clamps its
commands as the compensator node does.

Where the range comes from:

- **The parameter file's header** (:func:`recorded_range`): ``mpi-ros identify`` writes the
  record's current and displacement ranges into the YAML's header comment (a ROS parameter
  file holds only node parameters; the comment is what ROS ignores), as
  ``# identified on current 0 to 1.8 A, displacement 6.3e-06 to 4.36e-05 m``.  Exact.
- **The model itself**, when the file has no such line (written by an older ``identify``,
  by ``diagnose --params-out``, or by hand): :func:`identified_range`, below; exact where it
  holds ``model.identified_input_range`` (``identify`` and ``diagnose`` write it).

What a model knows of its identification record (:func:`identified_range`):

- **Displacement.** :func:`mpi_ros.model_fit.identify` places the thresholds of the
  inverse superposition operator S' over the record's output range, (29)-(31): the largest
  of ``l`` positive thresholds is ``(l - 1/2)/l`` of the output's extent above the operating
  point ``y0`` (and the same below), so the output range follows from them exactly.
- **Current.** The plays' thresholds give the input's extent, but the operating point
  ``x0`` is shifted by the QP's constant term, so not where it lies.  The current range is
  therefore taken as the currents at which the model's major loop reaches the two ends of
  its displacement range: after a descent to ``a`` every play is at ``a - x0 + r_i``, after
  an ascent to ``b`` at ``b - x0 - r_i``, so (with ``W = sum w_i`` and S' the inverse of S)
  ``a = x0 + (S'[v_lo] - sum w_i r_i) / W`` and ``b = x0 + (S'[v_hi] + sum w_i r_i) / W``.
  Any history inside ``[a, b]`` reaches the displacement range's ends within ``[a, b]``, so
  clamping commands to it never clips a desired value inside the displacement range.  On
  records of the built-in actuator this is the recorded current range to about 1 % of its
  span at orders (8, 4) and up; an output that overshoots (ringing after steps) widens it,
  since the displacement range includes the overshoot (up to 90 % of the span above the
  recorded current on synthetic records with ringing): the header's range is preferred.
- A model whose S' thresholds are not spaced as (29)-(31) space them (the ``k`` thresholds
  of a branch at 1, 3, 5, ... times the first: a model written by hand, or ``l = 0``) does
  not tell its range: None.
"""

from dataclasses import dataclass
import os
from pathlib import Path
import re

import numpy as np
import numpy.typing as npt

from ..compensation.limits import identified_range, IdentifiedRange
from ..units import input_unit_of

__all__ = ['IdentifiedRange', 'Outside', 'identified_range', 'outside', 'range_header',
           'recorded_range']

#: The header line :func:`range_header` writes and :func:`recorded_range` reads.
_NUMBER = r'([-+0-9.eE]+|nan|inf)'
_HEADER = re.compile(rf'^#\s*identified on (?:current|voltage) {_NUMBER} to {_NUMBER} [AV], '
                     rf'displacement {_NUMBER} to {_NUMBER} m\s*$')


@dataclass(frozen=True)
class Outside:
    """
    The samples of a signal outside a range.

    Attributes
    ----------
    count : int
        Finite samples below or above the range.
    total : int
        All samples.
    below, above : float
        Largest distance below the lower end and above the upper end (0 if none).
    low, high : float
        The range.

    """

    count: int
    total: int
    below: float
    above: float
    low: float
    high: float

    def describe(self, what: str, where: str, unit: str, scale: float = 1.0) -> str:
        """
        Say how many samples lie outside the range and by how much.

        Parameters
        ----------
        what : str
            The samples, plural (``'desired displacements'``).
        where : str
            The range in words, written right after it (``', the input range the model was
            identified on'``).
        unit : str
            Unit of the numbers after multiplying by ``scale`` (``'A'``, ``'µm'``).
        scale : float
            Factor from the signal's unit to ``unit``.

        Returns
        -------
        str
            E.g. ``'120 of 5000 currents (2.4 %) lie outside 0.19 to 3.5 A, the input range
            the model was identified on: below it by up to 0.2 A, above it by up to
            1.06 A'``.

        """
        share = 100.0 * self.count / self.total if self.total else 0.0
        sides = []
        if self.below > 0.0:
            sides.append(f'below it by up to {self.below * scale:.3g} {unit}')
        if self.above > 0.0:
            sides.append(f'above it by up to {self.above * scale:.3g} {unit}')
        return (f'{self.count} of {self.total} {what} ({share:.3g} %) lie outside '
                f'{self.low * scale:.4g} to {self.high * scale:.4g} {unit}{where}: '
                f'{", ".join(sides)}')


def range_header(current: npt.ArrayLike, displacement: npt.ArrayLike,
                 quantity: str = 'current') -> str:
    """
    Return the header line (without ``#``) that records a record's ranges in a YAML.

    Parameters
    ----------
    current : array_like of float, shape (N,)
        The record's current [A].
    displacement : array_like of float, shape (N,)
        The record's displacement [m].
    quantity : {'current', 'voltage'}
        The input quantity (:mod:`mpi_ros.units`): the input is in A or V.

    Returns
    -------
    str
        ``identified on current LO to HI A, displacement LO to HI m`` (``voltage ... V``
        for a voltage; the shortest digits that read back as the same floats).

    """
    x = np.asarray(current, dtype=np.float64)
    y = np.asarray(displacement, dtype=np.float64)
    ends = [float(np.min(x)), float(np.max(x)), float(np.min(y)), float(np.max(y))]
    unit = input_unit_of(quantity)
    return (f'identified on {quantity} {ends[0]!r} to {ends[1]!r} {unit}, displacement '
            f'{ends[2]!r} to {ends[3]!r} m')


def recorded_range(path: 'str | os.PathLike[str]') -> IdentifiedRange | None:
    """
    Return the ranges ``identify`` recorded in a parameter file's header, or None.

    Parameters
    ----------
    path : str or PathLike
        The parameter YAML.

    Returns
    -------
    IdentifiedRange or None
        The ranges of the line :func:`range_header` wrote among the file's leading comment
        lines; None when there is none (or it does not give two proper ranges).

    """
    try:
        with Path(path).open(encoding='utf-8') as f:
            for line in f:
                if not line.startswith('#'):
                    break
                match = _HEADER.match(line.strip())
                if match:
                    lo_x, hi_x, lo_y, hi_y = (float(v) for v in match.groups())
                    if all(np.isfinite([lo_x, hi_x, lo_y, hi_y])) and lo_x < hi_x and \
                            lo_y < hi_y:
                        return IdentifiedRange((lo_x, hi_x), (lo_y, hi_y))
                    return None
    except (OSError, UnicodeDecodeError):
        return None
    return None


def outside(values: npt.ArrayLike, low: float, high: float) -> Outside:
    """
    Count the samples outside ``[low, high]`` and how far they go.

    Parameters
    ----------
    values : array_like of float, shape (N,)
        The signal (non-finite samples are not counted).
    low, high : float
        The range.

    Returns
    -------
    Outside
        The count and the largest distances below and above.

    """
    x = np.asarray(values, dtype=np.float64).reshape(-1)
    finite = x[np.isfinite(x)]
    under = low - finite[finite < low]
    over = finite[finite > high] - high
    return Outside(int(under.size + over.size), int(x.size),
                   float(np.max(under)) if under.size else 0.0,
                   float(np.max(over)) if over.size else 0.0, float(low), float(high))
