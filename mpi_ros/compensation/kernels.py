# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Compiled steps of the compensator: (14), then (27) with the operating point, then clamping.

One step (:func:`compensate_step`); a samples x axes block with the screening, counters
and turning points in one compiled loop (:func:`compensate_axes`: a chunk of one axis is a
one-column block); and the per-step inverse of H with its first weight raised
(:func:`inverse_value`, for the effects' exact inverses).  The laws themselves are in
:mod:`mpi_ros.operators.inverse` and :mod:`mpi_ros.operators.play`, once.
"""

import numba
import numpy as np
import numpy.typing as npt

from .screening import SATURATION_RANGES
from ..operators.inverse import hysteresis_inverse_laws, hysteresis_inverse_states
from ..operators.memory import memory_push
from ..operators.model import hysteresis_step, superposition_value

__all__ = ['compensate_axes', 'compensate_step', 'COMPILED', 'INDEX_COLUMNS', 'inverse_value',
           'LAST_COMMAND', 'TABLE_COLUMNS', 'warm_up']

FloatArray = npt.NDArray[np.float64]


@numba.njit(cache=True, nogil=True, inline='always')
def compensate_step(s_c: float, lo: float, hi: float, r_h: FloatArray, w_h: FloatArray,
                    z_h: FloatArray, r_h_inv: FloatArray, w_h_inv: FloatArray,
                    z_inv: FloatArray, r_s_inv: FloatArray, w_s_inv: FloatArray,
                    point: FloatArray, hold: float) -> tuple[float, float]:  # pragma: no cover
    """
    Compute one compensator command: (14), then (27) with the operating point, clamped.

    ``x = x0 + H'[S'[sign (s_c - y0)]]``, ``point = (x0, y0, sign)``.  A non-finite raw
    command (a model that overflows) is never passed on: the last command ``hold`` is,
    inside ``[lo, hi]``; the caller counts ``raw != current``.

    Parameters
    ----------
    s_c : float
        Desired displacement [m].
    lo, hi : float
        Current limits [A].
    r_h, w_h, z_h : ndarray of float, shape (n+1,)
        H's thresholds [A], weights and play states [A] (advanced in place by the applied
        current).
    r_h_inv, w_h_inv, z_inv : ndarray of float, shape (n+1,)
        H''s thresholds, weights and states (set from ``z_h`` by (14)).
    r_s_inv, w_s_inv : ndarray of float, shape (l,)
        S''s thresholds [m] and weights [A/m].
    point : ndarray of float, shape (3,)
        The operating point.
    hold : float
        The last command [A].

    Returns
    -------
    current, raw : float
        The command sent [A] and the unclamped one.

    """
    x0 = point[0]
    hysteresis_inverse_states(w_h, z_h, z_inv)              # (14): from the forward state
    raw = x0 + hysteresis_step(superposition_value(point[2] * (s_c - point[1]), r_s_inv,
                                                   w_s_inv), r_h_inv, w_h_inv, z_inv)  # (27)
    current = raw
    if not np.isfinite(current):
        current = hold
    if current < lo:
        current = lo
    elif current > hi:
        current = hi
    elif not current >= lo:                                 # NaN hold (never: hold is safe)
        current = lo
    hysteresis_step(current - x0, r_h, w_h, z_h)           # forward plays, applied current
    return current, raw


#: Columns of a packed compensator's ``table`` (one row per axis).
TABLE_COLUMNS = ('input_offset', 'output_offset', 'output_sign', 'displacement_lo',
                 'displacement_hi', 'output_min', 'output_max', 'last_command')
#: Columns of its integer ``index`` (one row per axis).
INDEX_COLUMNS = ('coefficients_start', 'hysteresis_size', 'superposition_size',
                 'states_start', 'compiled')
#: The column of ``table`` holding each axis' last command.
LAST_COMMAND = TABLE_COLUMNS.index('last_command')
#: The column of ``index`` telling whether an axis runs compiled.
COMPILED = INDEX_COLUMNS.index('compiled')


@numba.njit(cache=True, nogil=True)
def compensate_axes(desired: FloatArray, out: FloatArray, coefficients: FloatArray,
                    states: FloatArray, index: npt.NDArray[np.int64], table: FloatArray,
                    counts: npt.NDArray[np.int64], memory: FloatArray,
                    memory_state: npt.NDArray[np.int64]) -> None:  # pragma: no cover
    """
    Compensate a samples x axes block in one compiled loop, axis by axis.

    The arrays are a packed compensator's (:func:`mpi_ros.compensation.compensator.pack`);
    ``out`` receives the commands [A], ``counts``, ``memory`` and ``memory_state`` are
    advanced in place.

    """
    # Every axis of a samples x axes block in one compiled loop: axis a runs the screening
    # and compensate_step on its own slices of the packed arrays, so its column is
    # exactly what its single-axis compensator gives.  Per axis, coefficients holds r_H, w_H,
    # r_H', w_H' (n+1 each), r_S', w_S' (l+1 each) from index[a, 0]; states holds z_H,
    # z' from index[a, 3]; table and index as TABLE_COLUMNS / INDEX_COLUMNS.  Axes with
    # index[a, 4] == 0 (effects, disabled) are left to the caller.
    for a in range(desired.shape[1]):            # axes are independent: axis by axis
        if index[a, 4] == 0:
            continue
        c0, n1, m1, s0 = index[a, 0], index[a, 1], index[a, 2], index[a, 3]
        r_h, w_h = coefficients[c0:c0 + n1], coefficients[c0 + n1:c0 + 2 * n1]
        r_h_inv = coefficients[c0 + 2 * n1:c0 + 3 * n1]
        w_h_inv = coefficients[c0 + 3 * n1:c0 + 4 * n1]
        r_s_inv = coefficients[c0 + 4 * n1:c0 + 4 * n1 + m1]
        w_s_inv = coefficients[c0 + 4 * n1 + m1:c0 + 4 * n1 + 2 * m1]
        z_h, z_inv = states[s0:s0 + n1], states[s0 + n1:s0 + 2 * n1]
        row, count, points, point = table[a], counts[a], memory[a], table[a, 0:3]
        held = memory_state[a]
        lo, hi = row[3], row[4]
        # The screening of screen_desired, written out here (as a called function it
        # made the loop three times slower).
        for k in range(desired.shape[0]):
            s_c = desired[k, a]
            count[0] += 1
            if not np.isfinite(s_c):
                count[1] += 1
                out[k, a] = row[7]
                continue
            if s_c < lo or s_c > hi:
                count[2] += 1
                margin = SATURATION_RANGES * (hi - lo)
                s_c = min(max(s_c, lo - margin), hi + margin)
            current, raw = compensate_step(s_c, row[5], row[6], r_h, w_h, z_h, r_h_inv,
                                           w_h_inv, z_inv, r_s_inv, w_s_inv, point, row[7])
            if not np.isfinite(raw):
                count[4] += 1
            elif current != raw:
                count[3] += 1
            memory_push(points, held, current)
            out[k, a] = current
            row[7] = current


@numba.njit(cache=True, nogil=True)
def inverse_value(v: float, r_h: FloatArray, w_h: FloatArray, beta: float,
                  z_h: FloatArray) -> float:  # pragma: no cover - compiled
    """
    Return ``H~'[v]``, the inverse of H with its first weight raised by ``beta``; compiled.

    The inverse by (12)-(13), its state by (14); ``z_h`` is not changed.

    Parameters
    ----------
    v : float
        The inverse's input [A].
    r_h, w_h, z_h : ndarray of float, shape (n+1,)
        H's thresholds [A], weights and play states [A].
    beta : float
        Added to the first weight.

    Returns
    -------
    float
        The current [A], relative to the input offset.

    """
    n1 = w_h.shape[0]
    w = w_h.copy()
    w[0] += beta
    r_inv = np.empty(n1)
    w_inv = np.empty(n1)
    z_inv = np.empty(n1)
    hysteresis_inverse_laws(r_h, w, r_inv, w_inv)                  # (12)-(13)
    hysteresis_inverse_states(w, z_h, z_inv)                       # (14)
    return hysteresis_step(v, r_inv, w_inv, z_inv)


def warm_up(kernel: tuple[FloatArray, ...], s_c: float, output_min: float,
            output_max: float) -> None:
    """
    Run the compiled steps once on copies of the play states.

    The first real command then does not pay numba's dispatch (about 7 ms on first use,
    2 us afterwards).

    Parameters
    ----------
    kernel : tuple
        The compensator's kernel arrays (left unchanged: the play states are copied).
    s_c : float
        A displacement inside the operating range [m].
    output_min, output_max : float
        Current limits [A].

    """
    r_h, w_h, z_h, r_hi, w_hi, z_i, r_si, w_si, point = kernel
    compensate_step(s_c, output_min, output_max, r_h, w_h, z_h.copy(), r_hi, w_hi,
                    z_i.copy(), r_si, w_si, point, output_min)
    hysteresis_step(output_min - point[0], r_h, w_h, z_h.copy())
    inverse_value(superposition_value(0.0, r_si, w_si), r_h, w_h, 0.0, z_h)
