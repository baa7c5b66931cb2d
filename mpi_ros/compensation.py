# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Inverse feed-forward compensation (Fig. 10 of Kuhnen's paper), the compensator node's core.

Per desired displacement ``s_c`` the compensator outputs the current
``Gamma^-1[s_c]`` (27), clamped to the actuator's safe range.  Its only state
is the play state ``z_H`` of the *forward* model driven by the current that
was actually commanded; the inverse play state follows from it by the
initial-state law (14) at every step.  Hence

- clamping never leaves the inverse out of step with the actuator;
- a newly pushed model starts from the operating point: the stored turning
  points of the commanded current are replayed through the new H and (14)
  gives the new inverse state (bumpless swap);
- non-finite input never reaches the output: the last command is held and
  the case is counted.
"""

from dataclasses import dataclass
import math

import numba
import numpy as np
import numpy.typing as npt

from .errors import ModelError
from .inverse import hysteresis_inverse_states
from .memory import TurningPointMemory
from .model import _hysteresis_step, _superposition_value, MPIModel

__all__ = ['FeedforwardCompensator', 'LinearMap', 'best_linear_map', 'operating_range',
           'screen_desired']

FloatArray = npt.NDArray[np.float64]


@numba.njit(cache=True, nogil=True)
def _compensate_step(s_c, lo, hi, r_h, w_h, z_h, r_h_inv, w_h_inv, z_inv,
                     r_s_inv, w_s_inv, point):  # pragma: no cover - compiled
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


def _warm_up(kernel: tuple, s_c: float, output_min: float, output_max: float) -> None:
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
        margin = 10.0 * (hi - lo)
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


def _major_loop(current_min: float, current_max: float, points: int = 401) -> FloatArray:
    # From the initial states (the rest at x0) to current_min, up, down, up: a play's
    # output depends only on the extremes of a monotone path, so the jump to current_min
    # equals a ramp there.
    up = np.linspace(current_min, current_max, points)
    return np.concatenate([up, up[::-1], up])


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
    s = model.simulate(_major_loop(current_min, current_max))
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
    x = _major_loop(current_min, current_max)
    gain, offset = np.polyfit(model.simulate(x), x, 1)
    return LinearMap(float(gain), float(offset))


class FeedforwardCompensator:
    """
    Streaming inverse compensator ``current = clamp(Gamma^-1[s_c])`` with safe swaps.

    Parameters
    ----------
    model : MPIModel
        The forward model Gamma (the inverse is computed here by (12)-(14), (22)-(25)).
    output_min, output_max : float
        Safe current range [A]; every output lies inside it.
    enabled : bool
        False: output the best linear map instead of Gamma^-1 (for comparison).

    Attributes
    ----------
    counters : dict[str, int]
        ``messages``, ``nonfinite_input``, ``out_of_range`` (desired outside the
        model's operating range), ``clamped``.
    version : int
        Incremented by every accepted model swap.

    """

    def __init__(self, model: MPIModel, *, output_min: float, output_max: float,
                 enabled: bool = True) -> None:
        self._check_limits(output_min, output_max)
        self.output_min = float(output_min)
        self.output_max = float(output_max)
        self.enabled = bool(enabled)
        self.counters = {'messages': 0, 'nonfinite_input': 0, 'out_of_range': 0, 'clamped': 0}
        self.version = 0
        self.memory = TurningPointMemory()
        self.last_command = float(np.clip(0.0, self.output_min, self.output_max))
        self._install(model, replay=False)
        self.version = 1

    @staticmethod
    def _check_limits(output_min: float, output_max: float) -> None:
        if not (np.isfinite(output_min) and np.isfinite(output_max)
                and output_min < output_max):
            msg = (f'output.min must be finite and below output.max; found {output_min} and'
                   f' {output_max}')
            raise ModelError(msg)

    def _install(self, model: MPIModel, *, replay: bool) -> None:
        if model.is_inverse:
            model = model.inverse()
        inverse = model.inverse()
        h, s_inv, h_inv = model.hysteresis, inverse.superposition, inverse.hysteresis
        z_h = np.array(h.initial_states, dtype=np.float64)
        if replay and len(self.memory):
            _, z_h = model.hysteresis_output(self.memory.points, z_h)
        lo, hi = operating_range(model, self.output_min, self.output_max)
        linear = best_linear_map(model, self.output_min, self.output_max)
        # One assignment of a tuple: the step never sees half of an old and a new model.
        self._kernel = (np.ascontiguousarray(h.thresholds), np.ascontiguousarray(h.weights),
                        z_h, np.ascontiguousarray(h_inv.thresholds),
                        np.ascontiguousarray(h_inv.weights), np.empty_like(z_h),
                        np.ascontiguousarray(s_inv.thresholds),
                        np.ascontiguousarray(s_inv.weights),
                        np.array([model.input_offset, model.output_offset,
                                  float(model.output_sign)]))
        _warm_up(self._kernel, lo, self.output_min, self.output_max)
        self.model = model
        self.displacement_range = (lo, hi)
        self.linear_map = linear

    def swap_model(self, model: MPIModel) -> None:
        """
        Switch to a new model bumplessly.

        The new forward play state is the replay of the commanded current's
        turning points through the new H; the inverse state follows by (14), so
        the next command differs from the old one only by what the new model
        itself implies at this operating point.

        Parameters
        ----------
        model : MPIModel
            The new (validated) forward model.

        """
        self._install(model, replay=True)
        self.version += 1

    def set_limits(self, output_min: float, output_max: float) -> None:
        """Change the safe current range [A] (validated; the model is kept)."""
        self._check_limits(output_min, output_max)
        self.output_min, self.output_max = float(output_min), float(output_max)
        self.displacement_range = operating_range(self.model, self.output_min, self.output_max)
        self.linear_map = best_linear_map(self.model, self.output_min, self.output_max)

    @property
    def state(self) -> FloatArray:
        """Forward play state ``z_H`` [A] at the operating point (a copy)."""
        return self._kernel[2].copy()

    def command(self, desired: float) -> float:
        """
        Return the current command [A] for a desired displacement [m].

        Parameters
        ----------
        desired : float
            Desired displacement ``s_c`` [m].

        Returns
        -------
        float
            Finite current inside ``[output_min, output_max]``.

        """
        c = self.counters
        s_c = screen_desired(desired, c, self.displacement_range)
        if s_c is None:
            return self.last_command
        r_h, w_h, z_h, r_hi, w_hi, z_i, r_si, w_si, point = self._kernel
        if self.enabled:
            current, raw = _compensate_step(s_c, self.output_min, self.output_max, r_h, w_h,
                                            z_h, r_hi, w_hi, z_i, r_si, w_si, point)
        else:
            raw = self.linear_map(s_c)
            current = min(max(raw, self.output_min), self.output_max)
            _hysteresis_step(current - point[0], r_h, w_h, z_h)
        if current != raw:
            c['clamped'] += 1
        self.memory.push(current)
        self.last_command = current
        return current
