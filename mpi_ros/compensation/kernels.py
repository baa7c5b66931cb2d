# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Compiled steps of the compensator: (14), then (27) with the operating point, then clamping.

One step (:func:`_compensate_step`), a chunk of steps with the screening and counters in one
loop (:func:`_compensate_batch`), and the per-step inverse of H with its first weight raised
(:func:`_inverse_value`, for the effects' exact inverses).  The laws themselves are in
:mod:`mpi_ros.inverse` and :mod:`mpi_ros.play`, once.
"""

import numba
import numpy as np
import numpy.typing as npt

from ..inverse import hysteresis_inverse_laws, hysteresis_inverse_states
from ..model import _hysteresis_step, _superposition_value

FloatArray = npt.NDArray[np.float64]


@numba.njit(cache=True, nogil=True)
def _compensate_step(s_c: float, lo: float, hi: float, r_h: FloatArray, w_h: FloatArray,
                     z_h: FloatArray, r_h_inv: FloatArray, w_h_inv: FloatArray,
                     z_inv: FloatArray, r_s_inv: FloatArray, w_s_inv: FloatArray,
                     point: FloatArray) -> tuple[float, float]:  # pragma: no cover
    # point = (x0, y0, sign), the operating point: x = x0 + H'[S'[sign (s_c - y0)]].
    x0 = point[0]
    hysteresis_inverse_states(w_h, z_h, z_inv)              # (14): from the forward state
    raw = x0 + _hysteresis_step(_superposition_value(point[2] * (s_c - point[1]), r_s_inv,
                                                     w_s_inv), r_h_inv, w_h_inv, z_inv)  # (27)
    current = raw
    if current < lo:
        current = lo
    elif current > hi:
        current = hi
    _hysteresis_step(current - x0, r_h, w_h, z_h)           # forward plays, applied current
    return current, raw


@numba.njit(cache=True, nogil=True)
def _compensate_batch(desired: FloatArray, displacement_lo: float, displacement_hi: float,
                      lo: float, hi: float, r_h: FloatArray, w_h: FloatArray, z_h: FloatArray,
                      r_h_inv: FloatArray, w_h_inv: FloatArray, z_inv: FloatArray,
                      r_s_inv: FloatArray, w_s_inv: FloatArray, point: FloatArray,
                      last: float, counts: npt.NDArray[np.int64],
                      out: FloatArray) -> float:  # pragma: no cover - compiled
    # screen_desired + _compensate_step per sample, in one compiled loop; counts holds
    # (nonfinite_input, out_of_range, clamped).  Returns the last command.
    margin = 10.0 * (displacement_hi - displacement_lo)
    for k in range(desired.shape[0]):
        s_c = desired[k]
        if not np.isfinite(s_c):
            counts[0] += 1
            out[k] = last
            continue
        if s_c < displacement_lo or s_c > displacement_hi:
            counts[1] += 1
            s_c = min(max(s_c, displacement_lo - margin), displacement_hi + margin)
        current, raw = _compensate_step(s_c, lo, hi, r_h, w_h, z_h, r_h_inv, w_h_inv, z_inv,
                                        r_s_inv, w_s_inv, point)
        if current != raw:
            counts[2] += 1
        out[k] = current
        last = current
    return last


@numba.njit(cache=True, nogil=True)
def _inverse_value(v: float, r_h: FloatArray, w_h: FloatArray, beta: float,
                   z_h: FloatArray) -> float:  # pragma: no cover - compiled
    # H~ = H with w_H0 + beta; inverse by (12)-(13), its state by (14); z_h is not changed.
    n1 = w_h.shape[0]
    w = w_h.copy()
    w[0] += beta
    r_inv = np.empty(n1)
    w_inv = np.empty(n1)
    z_inv = np.empty(n1)
    hysteresis_inverse_laws(r_h, w, r_inv, w_inv)                  # (12)-(13)
    hysteresis_inverse_states(w, z_h, z_inv)                       # (14)
    return _hysteresis_step(v, r_inv, w_inv, z_inv)


def _warm_up(kernel: tuple[FloatArray, ...], s_c: float, output_min: float,
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
    _compensate_step(s_c, output_min, output_max, r_h, w_h, z_h.copy(), r_hi, w_hi,
                     z_i.copy(), r_si, w_si, point)
    _hysteresis_step(output_min - point[0], r_h, w_h, z_h.copy())
    _inverse_value(_superposition_value(0.0, r_si, w_si), r_h, w_h, 0.0, z_h)
