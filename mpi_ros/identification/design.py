# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
The design of the identification.

Operating point, scaling, thresholds (28)-(31), the detected sign and the burn-in.
"""

from dataclasses import dataclass
import math

import numpy as np
import numpy.typing as npt

from ..errors import DataError
from ..operators.hysteresis import PIHysteresisOperator
from ..operators.inverse import invert_superposition
from ..operators.model import MPIModel
from ..operators.superposition import PISuperpositionOperator

__all__ = ['ANCHORS', 'ScaledDesign', 'burn_in', 'hysteresis_thresholds',
           'inverse_superposition_thresholds', 'output_sign', 'scaled_design']


FloatArray = npt.NDArray[np.float64]

#: Orders tried by the automatic order selection: l = n/2 as in the paper's table.
DEFAULT_ORDERS: tuple[tuple[int, int], ...] = tuple((2 * k, k) for k in range(11))

#: A branch of S' whose extent is below this fraction of the output range gets no thresholds.
_BRANCH_FRACTION = 0.01

#: Where the thresholds are anchored: the data's operating point (default) or the origin.
ANCHORS = ('operating_point', 'origin')

#: Below this |correlation| between input and output the output is not monotone in the
#: input (e.g. a ferroelectric butterfly loop, a wrong column): refused.
_MIN_CORRELATION = 0.3

#: Largest excursion of the output against the input's direction within one monotone
#: sweep of the input (beyond 4 noise standard deviations), as a fraction of the output
#: range.  Hysteresis loops (also with creep, dead time, rate dependence) stay below 0.1;
#: butterfly loops (ferroelectric switching) reach 0.2-0.9.
_MAX_COUNTER_MOVE = 0.15

#: A turning point of the input: it retreats by this fraction of its range.
_TURN_FRACTION = 0.05

#: A play whose standard deviation after the burn-in is below this fraction of the first
#: play's is idle: its weight is fixed at 0.
_IDLE_PLAY = 0.05

#: The burn-in lasts until the input covered this fraction of its range (2 = full range).
_FULL_SWEEP = 2.0 * 0.99

#: After the burn-in the input must rise and fall over this fraction of its range.
_MIN_LOOP_SWEEP = 0.25

#: At least this fraction of the record must remain after the burn-in.
_MIN_DETERMINED_FRACTION = 0.2


def hysteresis_thresholds(current_abs_max: float, n: int) -> FloatArray:
    """
    Play thresholds (28): ``r_Hi = i/(n+1) ||x||_inf``, ``i = 0..n``.

    Parameters
    ----------
    current_abs_max : float
        ``||x||_inf`` of the input [A].
    n : int
        Order of H.

    Returns
    -------
    ndarray of float, shape (n+1,)
        Thresholds [A].

    """
    return np.arange(n + 1, dtype=np.float64) / (n + 1) * current_abs_max


def inverse_superposition_thresholds(output_max: float, output_min: float, l: int  # noqa: E741
                                     ) -> FloatArray:
    """
    Thresholds of the inverse superposition operator S', (29)-(31).

    A branch whose side of 0 the output does not reach (``output_max <= 0`` or
    ``output_min >= 0``) gets no thresholds.

    Parameters
    ----------
    output_max, output_min : float
        ``max y`` and ``min y`` of the output [m].
    l : int
        Order of S.

    Returns
    -------
    ndarray of float, shape (<= 2l+1,)
        Ascending thresholds [m] containing exactly one 0.

    """
    i = np.arange(1, l + 1, dtype=np.float64)
    positive = (i - 0.5) / l * output_max if output_max > 0.0 and l > 0 else np.empty(0)  # (30)
    # (31) as printed, ((i + 1/2)/l) min y for i = -l..-1, is positive for min y < 0; the
    # evident intent, the mirror image of (30), is (|i| - 1/2)/l min y, which is used here.
    negative = (i - 0.5) / l * output_min if output_min < 0.0 and l > 0 else np.empty(0)
    return np.concatenate([np.sort(negative),
                           [0.0], positive])                                              # (29)


@dataclass(frozen=True)
class ScaledDesign:
    """
    Operating point, scaling and thresholds of the QP (34)-(36) for one record and order.

    The QP sees the scaled input ``u = (x - input_offset) / x_scale`` and the scaled
    output ``v = sign * (y - output_offset) / y_scale`` (see :func:`scaled_design`).

    Attributes
    ----------
    x_scale : float
        Input scale [A].
    y_scale : float
        Output scale [m].
    hysteresis_thresholds : ndarray of float, shape (n+1,)
        ``r_H`` (28) in scaled units.
    inverse_superposition_thresholds : ndarray of float, shape (m,)
        ``r'_S`` (29)-(31) in scaled units.
    center : int
        Index of the zero threshold in ``inverse_superposition_thresholds``.
    input_offset : float
        ``x0`` [A] the input is centred on (0 for ``anchor='origin'``).
    output_offset : float
        ``y0`` [m] the output is centred on (0 for ``anchor='origin'``).
    sign : int
        +1, or -1 when the output falls as the input rises.
    burn_in : int
        Samples at the start left out of the generalised error (states not determined).
    constant : bool
        True when the generalised error has the constant term (``anchor='operating_point'``).
    input_rest : float or None
        The input [A] at which the returned model's plays start at rest (its initial
        states): the lowest input of the record, where an actuator rests when it is off;
        None: ``z_H0 = 0`` (32).

    """

    x_scale: float
    y_scale: float
    hysteresis_thresholds: FloatArray
    inverse_superposition_thresholds: FloatArray
    center: int
    input_offset: float = 0.0
    output_offset: float = 0.0
    sign: int = 1
    burn_in: int = 0
    constant: bool = False
    input_rest: float | None = None

    def scaled_input(self, x: FloatArray) -> FloatArray:
        """Return ``(x - x0) / x_scale``, the input the QP sees."""
        return (np.asarray(x, dtype=np.float64) - self.input_offset) / self.x_scale

    def scaled_output(self, y: FloatArray) -> FloatArray:
        """Return ``sign * (y - y0) / y_scale``, the output the QP sees."""
        return self.sign * (np.asarray(y, dtype=np.float64) - self.output_offset) / self.y_scale

    def model(self, w_h: FloatArray, w_s_inv: FloatArray, constant: float = 0.0, *,
              shift_weight: float = 0.0,
              initial_states: FloatArray | None = None) -> MPIModel:
        """
        Return the forward MPI model in SI units for QP weights found on the scaled data.

        Parameters
        ----------
        w_h : ndarray of float, shape (n+1,)
            Weights of H (dimensionless, unchanged by the scaling).
        w_s_inv : ndarray of float, shape (m,)
            Weights of S' in scaled units.
        constant : float
            The constant term ``c`` of the generalised error (scaled units); it becomes
            the input offset ``x0 - c x_scale / (sum w_H + shift_weight)``.
        shift_weight : float
            Sum of the weights of extra regressors that shift with the input like the
            plays (e.g. creep lags); 0 for none.
        initial_states : ndarray of float, shape (n+1,), optional
            The plays' states at the first sample, in the scaled input the QP saw (the
            record's start state); by default at rest at the lowest input (``input_rest``)
            or ``z_H0 = 0`` (32).

        Returns
        -------
        MPIModel
            Gamma with S from S' by (22)-(25), ``z_H0 = 0`` (32) and the operating point.

        """
        r_h = self.hysteresis_thresholds
        # Back to SI: H maps A -> A (w_H dimensionless); S' maps m -> A.
        hysteresis = PIHysteresisOperator(r_h * self.x_scale, w_h, np.zeros(r_h.size))
        s_inv = PISuperpositionOperator(self.inverse_superposition_thresholds * self.y_scale,
                                        w_s_inv * (self.x_scale / self.y_scale))
        # H[u] + c = H[u + c / W] once the states are set by the data (wiping-out).
        x0 = self.input_offset - constant * self.x_scale / (float(np.sum(w_h)) + shift_weight)
        if initial_states is not None:
            # The QP's plays ran on (x - x0_design) / x_scale; the model's run on x - x0:
            # the same trajectory scaled and shifted by the constant's input shift.
            states = (np.asarray(initial_states, dtype=np.float64) * self.x_scale
                      + (self.input_offset - x0))
            hysteresis = PIHysteresisOperator(hysteresis.thresholds, w_h, states)
        elif self.input_rest is not None:
            # Every play at rest at the lowest input: the actuator's state when it has been
            # off (the paper's z_H0 = 0 at x = 0 for data that start there).
            hysteresis = PIHysteresisOperator(hysteresis.thresholds, w_h,
                                              np.full(r_h.size, self.input_rest - x0))
        return MPIModel(hysteresis, invert_superposition(s_inv),                # (22)-(25)
                        input_offset=x0, output_offset=self.output_offset,
                        output_sign=self.sign)


def output_sign(current: npt.ArrayLike, displacement: npt.ArrayLike) -> tuple[int, float]:
    """
    Detect whether the output rises or falls with the input, and how monotone it is.

    Parameters
    ----------
    current : array_like of float, shape (N,)
        Input [A].
    displacement : array_like of float, shape (N,)
        Output [m].

    Returns
    -------
    sign : int
        +1 when the straight-line fit rises, -1 when it falls.
    correlation : float
        Pearson correlation of input and output (|correlation| near 1: monotone with
        narrow loops; near 0: not monotone, e.g. a butterfly loop).

    """
    x = np.asarray(current, dtype=np.float64)
    y = np.asarray(displacement, dtype=np.float64)
    xc, yc = x - np.mean(x), y - np.mean(y)
    # Sums of products, not np.dot: BLAS threads stall on a loaded machine (5 ms a dot).
    denominator = math.sqrt(float(np.sum(xc * xc)) * float(np.sum(yc * yc)))
    correlation = float(np.sum(xc * yc)) / denominator if denominator > 0.0 else 0.0
    return (1 if correlation >= 0.0 else -1), correlation


def burn_in(x: npt.ArrayLike, sweep: float, *, to_turning_point: bool = False) -> int:
    """
    Return the first sample after which the input has covered a range of ``sweep``.

    By the wiping-out property a play with threshold ``r`` no longer depends on its
    initial state once the input has covered a range of ``2 r``.

    Parameters
    ----------
    x : array_like of float, shape (N,)
        Input.
    sweep : float
        Range to cover (``2 r``), unit of the input.
    to_turning_point : bool
        Go on to the input's next turning point (where it has retreated by 1 % of its
        range from its running extreme): the extreme itself, not a sample just below it.

    Returns
    -------
    int
        Index of the first sample whose play outputs are determined; ``N`` when never.

    """
    arr = np.asarray(x, dtype=np.float64)
    if sweep <= 0.0 or arr.size == 0:
        return 0
    covered = np.maximum.accumulate(arr) - np.minimum.accumulate(arr)
    hits = np.flatnonzero(covered >= sweep * (1.0 - 1e-12))
    if not hits.size:
        return int(arr.size)
    start = int(hits[0])
    if not to_turning_point:
        return start
    rising = arr[start] - np.min(arr[:start + 1]) >= np.max(arr[:start + 1]) - arr[start]
    tail = arr[start:] if rising else -arr[start:]
    peak = np.maximum.accumulate(tail)
    retreat = np.flatnonzero(peak - tail >= 0.01 * float(np.ptp(arr)))
    end = int(retreat[0]) if retreat.size else tail.size
    return start + int(np.argmax(tail[:end])) if end > 0 else start


def scaled_design(x: FloatArray, y: FloatArray, n: int, l: int, *,  # noqa: E741
                  anchor: str = 'operating_point') -> ScaledDesign:
    """
    Return the operating point, scaling and thresholds (28)-(31) :func:`identify` uses.

    Parameters
    ----------
    x : ndarray of float, shape (N,)
        Input [A].
    y : ndarray of float, shape (N,)
        Output [m].
    n, l : int
        Model orders.
    anchor : {'operating_point', 'origin'}
        ``'operating_point'``: input and output centred on the middle of their ranges,
        the output's sign detected, a constant term, and a burn-in until the largest play
        is determined.  ``'origin'``: the paper's design as printed (scales
        ``||x||_inf``, ``||y||_inf``, plays from 0 at x = 0, no constant, no burn-in).

    Returns
    -------
    ScaledDesign
        Scales, scaled thresholds, the index of S' zero threshold, the operating point.

    """
    if anchor not in ANCHORS:
        msg = f"anchor must be one of {', '.join(ANCHORS)}; found {anchor!r}"
        raise DataError(msg)
    r_h = hysteresis_thresholds(1.0, n)                                          # (28)
    if anchor == 'origin':
        x_scale = float(np.max(np.abs(x)))
        y_scale = float(np.max(np.abs(y)))
        ys = y / y_scale
        y_max, y_min = float(np.max(ys)), float(np.min(ys))
        span = y_max - y_min
        r_s_inv = inverse_superposition_thresholds(
            y_max if y_max > _BRANCH_FRACTION * span else 0.0,
            y_min if y_min < -_BRANCH_FRACTION * span else 0.0, l)             # (29)-(31)
        c = int(np.flatnonzero(r_s_inv == 0.0)[0])
        return ScaledDesign(x_scale, y_scale, r_h, r_s_inv, c)
    x_lo, x_hi = float(np.min(x)), float(np.max(x))
    y_lo, y_hi = float(np.min(y)), float(np.max(y))
    x_scale = 0.5 * (x_hi - x_lo)
    y_scale = 0.5 * (y_hi - y_lo)
    sign, _ = output_sign(x, y)
    r_s_inv = inverse_superposition_thresholds(1.0, -1.0, l)                    # (29)-(31)
    c = int(np.flatnonzero(r_s_inv == 0.0)[0])
    # Plays are determined once the input covered 2 r_Hn; the actuator itself (any
    # hysteresis with the wiping-out property) only once it visited both extremes of the
    # record: its initial loading curve is not the loops' (1 % tolerance for a noisy input).
    start = burn_in(x, max(2.0 * float(r_h[-1]), _FULL_SWEEP) * x_scale,
                    to_turning_point=True)
    return ScaledDesign(x_scale, y_scale, r_h, r_s_inv, c,
                        input_offset=0.5 * (x_lo + x_hi), output_offset=0.5 * (y_lo + y_hi),
                        sign=sign, burn_in=start, constant=True, input_rest=x_lo)
