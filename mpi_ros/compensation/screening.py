# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
What the compensator does around the inverse.

Screening of the desired values, the model's operating range over the safe current range,
the best linear map (the uncompensated baseline), and the counters of bad inputs.
"""

from collections.abc import Mapping
from dataclasses import dataclass
import math

import numpy as np
import numpy.typing as npt

from ..operators.model import MPIModel

__all__ = ['screen_desired', 'LinearMap', 'operating_range', 'best_linear_map', 'FAULT_KEYS',
           'FAULT_LOG_PERIOD_S', 'FaultLog', 'new_faults', 'describe_faults']

FloatArray = npt.NDArray[np.float64]

#: Desired values beyond this many operating ranges outside it are saturated there (the
#: clamped command is the same, and the inverse's arithmetic stays finite).  The compiled
#: block loop (:func:`~mpi_ros.compensation.kernels.compensate_axes`) uses it too.
SATURATION_RANGES = 10.0
#: Counters of bad inputs (a node's diagnostics period with any of them is WARN).
FAULT_KEYS = ('nonfinite_input', 'out_of_range', 'clamped', 'nonfinite_command')
_FAULT_WORDS = {'nonfinite_input': 'non-finite', 'out_of_range': 'out-of-range',
                'clamped': 'clamped', 'nonfinite_command': 'held (non-finite inverse)'}
#: At most one warning about bad inputs per this period [s] (:class:`FaultLog`).
FAULT_LOG_PERIOD_S = 5.0


def screen_desired(desired: object, counters: dict[str, int],
                   displacement_range: tuple[float, float]) -> float | None:
    """
    Screen one desired displacement before inversion; count what is wrong with it.

    Parameters
    ----------
    desired : object
        The incoming value (anything: NaN, Inf, text, None are possible).
    counters : dict[str, int]
        ``messages``, ``nonfinite_input`` and ``out_of_range`` are incremented here.
    displacement_range : (float, float)
        The model's operating range [m].

    Returns
    -------
    float or None
        The value to invert, or None when it is not a finite number (hold the last
        command).  Values far outside the range are saturated: Gamma^-1 is increasing,
        so the clamped command is the same, and the arithmetic stays finite (1e308
        would otherwise give inf - inf = NaN inside the inverse).

    """
    counters['messages'] += 1
    try:
        s_c = float(desired)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        s_c = math.nan
    if not math.isfinite(s_c):
        counters['nonfinite_input'] += 1
        return None
    lo, hi = displacement_range
    if s_c < lo or s_c > hi:
        counters['out_of_range'] += 1
        margin = SATURATION_RANGES * (hi - lo)
        s_c = min(max(s_c, lo - margin), hi + margin)
    return s_c


@dataclass(frozen=True)
class LinearMap:
    """
    Affine map ``current = gain * displacement + offset`` (the uncompensated baseline).

    Attributes
    ----------
    gain : float
        [A/m].
    offset : float
        [A].

    """

    gain: float
    offset: float

    def __call__(self, displacement: float) -> float:
        """Return the current [A] for a displacement [m]."""
        return self.gain * displacement + self.offset


def _major_loop(current_min: float, current_max: float,
                points: int = 401) -> tuple[FloatArray, slice]:
    # Up and down once to set the plays (whatever the model's initial states: a model
    # identified on a record that starts mid-history has none it can vouch for), then the
    # major loop proper: up, down, up.  Returns the currents and the part to use.
    up = np.linspace(current_min, current_max, points)
    return np.concatenate([up, up[::-1], up, up[::-1], up]), slice(2 * points, None)


def operating_range(model: MPIModel, current_min: float,
                    current_max: float) -> tuple[float, float]:
    """
    Return the displacement range the model reaches for currents in the given range.

    Parameters
    ----------
    model : MPIModel
        Forward model.
    current_min, current_max : float
        Current range [A].

    Returns
    -------
    (float, float)
        Lowest and highest displacement [m] on the major loop.

    """
    x, keep = _major_loop(current_min, current_max)
    s = model.simulate(x)[keep]
    return float(np.min(s)), float(np.max(s))


def best_linear_map(model: MPIModel, current_min: float, current_max: float) -> LinearMap:
    """
    Best affine inverse of the model over its major loop (least squares), the baseline.

    Parameters
    ----------
    model : MPIModel
        Forward model.
    current_min, current_max : float
        Current range of the major loop [A].

    Returns
    -------
    LinearMap
        ``current ~ gain * displacement + offset``.

    """
    x, keep = _major_loop(current_min, current_max)
    gain, offset = np.polyfit(model.simulate(x)[keep], x[keep], 1)
    return LinearMap(float(gain), float(offset))


def new_faults(counters: Mapping[str, int], before: Mapping[str, int]) -> dict[str, int]:
    """
    Return how many inputs of each fault kind came since ``before``.

    Parameters
    ----------
    counters, before : mapping of str to int
        Counters now and at the start of the period (missing keys count 0).

    Returns
    -------
    dict of str to int
        One count per :data:`FAULT_KEYS` entry, never negative.

    """
    return {key: max(counters.get(key, 0) - before.get(key, 0), 0) for key in FAULT_KEYS}


def describe_faults(faults: Mapping[str, int]) -> str:
    """
    Describe fault counts in words.

    Parameters
    ----------
    faults : mapping of str to int
        Counts by :data:`FAULT_KEYS` entry.

    Returns
    -------
    str
        e.g. ``3 non-finite, 2 clamped inputs``.

    Examples
    --------
    >>> describe_faults({'nonfinite_input': 3, 'out_of_range': 0, 'clamped': 2})
    '3 non-finite, 2 clamped inputs'

    """
    parts = [f'{faults[key]} {_FAULT_WORDS[key]}' for key in FAULT_KEYS if faults.get(key)]
    return f'{", ".join(parts) or "no bad"} inputs'


class FaultLog:
    """
    The throttle of a node's warnings about bad inputs: at most one per period.

    Parameters
    ----------
    period : float
        Shortest time between two warnings [s].

    Examples
    --------
    >>> log = FaultLog()
    >>> log.report(100.0, {'nonfinite_input': 2})[:12]
    '2 non-finite'
    >>> log.report(101.0, {'nonfinite_input': 5}) is None       # within 5 s
    True
    >>> log.report(105.0, {'nonfinite_input': 5})[:12]           # the 3 since the last one
    '3 non-finite'

    """

    def __init__(self, period: float = FAULT_LOG_PERIOD_S) -> None:
        self.period = period
        self._last: tuple[float, dict[str, int]] = (-math.inf, {})

    def report(self, now: float, counters: Mapping[str, int]) -> str | None:
        """
        Return the warning about the bad inputs since the last one, if one is due.

        Parameters
        ----------
        now : float
            Steady time [s].
        counters : mapping of str to int
            The core's counters now (:data:`FAULT_KEYS`; missing keys count 0).

        Returns
        -------
        str or None
            The warning (what came, and what the compensator did with it); None when the
            last one is younger than ``period`` or no bad input came since.

        """
        last_time, last_counters = self._last
        if now - last_time < self.period:
            return None
        faults = new_faults(counters, last_counters)
        if not any(faults.values()):
            return None
        self._last = (now, {key: counters.get(key, 0) for key in FAULT_KEYS})
        return (f'{describe_faults(faults)} since the last report (non-finite: last command '
                'held; out of range: beyond the displacement range of the model; clamped: '
                'command limited to [output.min, output.max])')
