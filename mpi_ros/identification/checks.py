# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
What the identification refuses, and how a fit is judged.

Malformed signals, too little excitation; the fit against the straight line on the same
samples.  (What moves the output against the input - butterflies, ringing, lag - is
:mod:`.dynamics`; the start state is :mod:`.start_state`.)
"""

import math

import numpy as np
import numpy.typing as npt

from .design import FloatArray
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
    # The least-squares line in closed form (np.polyfit's lstsq costs 0.4 s on 1e6 samples).
    xc = x - float(np.mean(x))
    denominator = float(np.sum(xc * xc))
    slope = float(np.sum(xc * (y - float(np.mean(y))))) / denominator if denominator else 0.0
    line: FloatArray = float(np.mean(y)) + slope * xc
    return line


def _quality_check(x: FloatArray, y: FloatArray, sim: FloatArray,
                   fitted: slice | int | npt.NDArray[np.bool_], n: int,
                   l: int, anchor: str, *,  # noqa: E741
                   chosen: bool = False) -> tuple[float, float, float]:
    # Every fit is judged against the straight line on the same samples; a fit that is
    # no better, or absurd, is refused: never a silent garbage model.
    keep = slice(fitted, None) if isinstance(fitted, int) else fitted
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
