# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
What the identification refuses, and how a fit is judged.

Monotonicity, excitation, start-state coverage, butterfly loops; the fit against the
straight line on the same samples.
"""

import math

import numba
import numpy as np
import numpy.typing as npt

from .design import (_FULL_SWEEP, _MAX_COUNTER_MOVE, _MIN_CORRELATION, _MIN_DETERMINED_FRACTION,
                     _MIN_LOOP_SWEEP, _TURN_FRACTION, burn_in, FloatArray, output_sign)
from ..errors import DataError, IdentificationError

__all__ = []


def _check_signals(current: npt.ArrayLike, displacement: npt.ArrayLike) -> tuple[
        FloatArray, FloatArray]:
    x = np.asarray(current, dtype=np.float64).reshape(-1)
    y = np.asarray(displacement, dtype=np.float64).reshape(-1)
    if x.size != y.size:
        msg = (f'current and displacement must have the same length; found {x.size} and'
               f' {y.size} samples')
        raise DataError(msg)
    for name, arr in (('current', x), ('displacement', y)):
        bad = np.flatnonzero(~np.isfinite(arr))
        if bad.size:
            msg = (f'{name} contains {bad.size} non-finite value(s), the first at sample'
                   f' {bad[0]}; remove or interpolate them before identifying')
            raise DataError(msg)
    return x, y


def _check_monotone(x: FloatArray, y: FloatArray) -> None:
    if np.ptp(x) <= 1e-9 * np.max(np.abs(x)) or not np.ptp(y) > 0.0:
        return                                   # _check_excitation says what is wrong
    sign, correlation = output_sign(x, y)
    if abs(correlation) < _MIN_CORRELATION:
        msg = (f'the output is not monotone in the input (correlation {correlation:.2f}):'
               ' the MPI model needs a displacement that rises (or falls) with the input'
               ' around hysteresis loops; check the input and output columns/topics, or,'
               ' for a butterfly loop (ferroelectric switching), lower the amplitude below'
               ' the coercive field')
        raise IdentificationError(msg)
    # The whole record, burn-in included: a butterfly whose determined part happens to be
    # monotone must not pass.  Noise (robust estimate from second differences) is allowed.
    span = float(np.ptp(y))
    move, first, last = _counter_move(x, sign * y, _TURN_FRACTION * float(np.ptp(x)))
    excess = (move - 4.0 * _noise_std(y)) / span
    if excess > _MAX_COUNTER_MOVE:
        msg = (f'the output is not monotone in the input: within one sweep of the input'
               f' (samples {first} to {last}) it moves against the input by'
               f' {100 * move / span:.3g} % of its range (a hysteresis loop: at most'
               f' {100 * _MAX_COUNTER_MOVE:.3g} % beyond the noise);'
               ' this is a butterfly loop (ferroelectric switching: lower the amplitude below'
               ' the coercive field) or a record dominated by drift or switching transients;'
               ' the MPI model cannot represent it')
        raise IdentificationError(msg)


def _noise_std(y: FloatArray) -> float:
    # Robust noise estimate: MAD of the second differences (std of white noise * sqrt 6).
    if y.size < 3:
        return 0.0
    d2 = np.diff(y, 2)
    return 1.4826 * float(np.median(np.abs(d2 - np.median(d2)))) / math.sqrt(6.0)


@numba.njit(cache=True, nogil=True)
def _counter_move(x: FloatArray, v: FloatArray,
                  tolerance: float) -> tuple[float, int, int]:  # pragma: no cover - compiled
    # Largest fall of v from its running maximum within one monotone sweep of x (v is the
    # output times its sign, so it should rise with x); the sweep's direction flips v.
    # A turning point is the extreme of x before x retreats from it by `tolerance`.
    n = x.shape[0]
    turns = np.empty(n + 1, dtype=np.int64)
    count = 1
    turns[0] = 0
    direction = 0
    extreme = 0
    for k in range(1, n):
        if direction == 0:
            if abs(x[k] - x[0]) > tolerance:
                direction = 1 if x[k] > x[0] else -1
                extreme = k
            continue
        if direction * (x[k] - x[extreme]) > 0.0:
            extreme = k
        elif direction * (x[extreme] - x[k]) > tolerance:
            turns[count] = extreme
            count += 1
            direction = -direction
            extreme = k
    turns[count] = n - 1
    count += 1
    worst = 0.0
    first = 0
    last = 0
    for b in range(count - 1):
        a, e = turns[b], turns[b + 1]
        s = 1.0 if x[e] >= x[a] else -1.0
        peak = s * v[a]
        for k in range(a, e + 1):
            value = s * v[k]
            if value > peak:
                peak = value
            elif peak - value > worst:
                worst = peak - value
                first = a
                last = e
    return worst, first, last


def _check_excitation(x: FloatArray, y: FloatArray, n: int, l: int, *,  # noqa: E741
                      anchor: str = 'operating_point') -> None:
    needed = 2 * (n + 1 + 2 * l + 1)
    if x.size < needed:
        msg = (f'too few samples to identify order n={n}, l={l}: found {x.size}, need at'
               f' least {needed}; record longer or lower the order')
        raise IdentificationError(msg)
    if not np.max(np.abs(x)) > 0.0:
        msg = 'the current is zero everywhere: nothing to identify; record an excitation'
        raise IdentificationError(msg)
    if not np.max(np.abs(y)) > 0.0:
        msg = 'the displacement is zero everywhere: check the output topic or column'
        raise IdentificationError(msg)
    if np.ptp(x) <= 1e-9 * np.max(np.abs(x)):
        msg = ('the current is constant: a hysteresis model needs an excitation that moves'
               ' the input up and down over the operating range')
        raise IdentificationError(msg)
    if not np.ptp(y) > 0.0:
        msg = ('the displacement is constant: check the output topic or column and that the'
               ' actuator moved')
        raise IdentificationError(msg)
    if n > 0:
        # A play with threshold r only leaves its initial loading curve after an input
        # reversal larger than 2 r: without one, H degenerates to a static map and the
        # weights are not identifiable.
        scale = float(np.max(np.abs(x))) if anchor == 'origin' else 0.5 * float(np.ptp(x))
        r_1 = scale / (n + 1)                                                     # (28)
        largest = _largest_reversal(x)
        if largest <= 2.0 * r_1:
            found = 'never reverses' if largest == 0.0 else (
                f'reverses by at most {largest:.4g}')
            msg = (f'too little excitation to identify order n={n}: the current {found}, but'
                   f' the smallest play threshold r_H1 = {r_1:.4g} needs reversals larger than'
                   f' {2 * r_1:.4g}; record an excitation with larger up-and-down sweeps'
                   ' (minor loops), or lower n')
            raise IdentificationError(msg)
    if anchor == 'operating_point':
        start = burn_in(x, max(2.0 * n / (n + 1), _FULL_SWEEP) * 0.5 * float(np.ptp(x)),
                        to_turning_point=True)
        if start > x.size * (1.0 - _MIN_DETERMINED_FRACTION):
            msg = (f'the input covers its full range only at sample {start} of {x.size}:'
                   ' before that the states of the plays and of the actuator are unknown'
                   ' (the record starts mid-history or on an initial loading curve),'
                   ' leaving too little data to fit; record more cycles over the full'
                   ' range')
            raise IdentificationError(msg)
        rise, fall = _largest_sweeps(x[start:])
        span = float(np.ptp(x))
        if min(rise, fall) < _MIN_LOOP_SWEEP * span:
            msg = (f'after the burn-in (samples {start} to {x.size}, where the states of the'
                   ' plays and of the actuator are known) the input sweeps at most'
                   f' {100 * rise / span:.3g} % of its range upwards and'
                   f' {100 * fall / span:.3g} % downwards: the loops (both branches) are not'
                   ' determined and a model fitted there is arbitrary elsewhere; record'
                   ' at least two full cycles over the range (a single cycle from an'
                   ' unknown state is not enough), or, if the record is one period of an'
                   ' excitation the actuator had been following, say so: periodic=True'
                   ' (mpi-ros identify --periodic)')
            raise IdentificationError(msg)


def _largest_sweeps(x: FloatArray) -> tuple[float, float]:
    # Largest monotone rise and fall between successive turning points of x.
    step = np.diff(x)
    step = step[step != 0.0]
    if step.size == 0:
        return 0.0, 0.0
    turns = np.flatnonzero(np.sign(step[1:]) != np.sign(step[:-1])) + 1
    ends = np.concatenate([[0], turns, [step.size]])
    levels = np.concatenate([[0.0], np.cumsum(step)])[ends]
    moves = np.diff(levels)
    return float(max(np.max(moves), 0.0)), float(max(-np.min(moves), 0.0))


def _largest_reversal(x: FloatArray) -> float:
    # Largest monotone excursion that follows a change of direction (turning point).
    step = np.diff(x)
    step = step[step != 0.0]
    if step.size < 2:
        return 0.0
    turns = np.flatnonzero(np.sign(step[1:]) != np.sign(step[:-1])) + 1
    if turns.size == 0:
        return 0.0
    levels = np.concatenate([[0.0], np.cumsum(step)])[np.concatenate([turns, [step.size]])]
    return float(np.max(np.abs(np.diff(levels))))


def _errors(sim: FloatArray, y: FloatArray,
            keep: slice | npt.NDArray[np.bool_]) -> tuple[float, float]:
    # (37) and RMS over the selected samples, both over the whole record's output range
    # (the same denominator for every order and for the straight line).
    span = float(np.ptp(y))
    error = sim[keep] - y[keep]
    return (float(np.max(np.abs(error))) / span,
            float(np.sqrt(np.mean(error * error))) / span)


def _linear_fit(x: FloatArray, y: FloatArray) -> FloatArray:
    slope, intercept = np.polyfit(x, y, 1)
    line: FloatArray = slope * x + intercept
    return line


def _quality_check(x: FloatArray, y: FloatArray, sim: FloatArray, start: int, n: int,
                   l: int, anchor: str, *,  # noqa: E741
                   chosen: bool = False) -> tuple[float, float, float]:
    # Every fit is judged against the straight line on the same samples; a fit that is
    # no better, or absurd, is refused: never a silent garbage model.
    keep = slice(start, None)
    peak, error = _errors(sim, y, keep)
    _, linear = _errors(_linear_fit(x[keep], y[keep]), y[keep], slice(None))
    if not (math.isfinite(error) and error < 1.0):
        msg = (f'the identified model (n={n}, l={l}) is absurd: its simulation is off by'
               f' {100 * error:.3g} % of the output range (RMS); check the input and'
               ' output columns/topics, their units and that they belong to one experiment')
        raise IdentificationError(msg)
    # An explicitly requested (0, 0) is the paper's linear model, reported even when a
    # line fits better; an order chosen by the search must beat the line.
    if (n + l > 0 or chosen) and error > linear:
        hint = ('the data may start at rest at the origin: try anchor=origin'
                if anchor == 'operating_point' else 'the default anchor=operating_point fits'
                ' records with a sensor zero, a bias or a falling sensor')
        if chosen:
            hint = (f'order auto chose n={n}, l={l} by the held-out peak error (37); give the'
                    f' order instead (e.g. 14,7); {hint}')
        msg = (f'the identified model (n={n}, l={l}) is worse than a straight line on the same'
               f' data: RMS error {100 * error:.3g} % of the output range vs {100 * linear:.3g}'
               ' % for the line; the output may not be a hysteretic function of this input'
               ' (wrong column or topic, unrelated signals, creep or drift dominating), or'
               f' the record too short; {hint}')
        raise IdentificationError(msg)
    return error, peak, linear
