# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Inverse feed-forward compensation of the extended models, step by step and exact.

Every extension keeps the per-step map from the present current ``x_k`` to the output a
modified Prandtl-Ishlinskii operator once the slow states (lags) are fixed, so the inverse
follows from the transformation laws (12)-(14) and (22)-(25) at every step, without root
finding:

- ``creep``: ``v_k = H[x]_k + sum_j w_Cj c_jk`` with ``c_jk = p_j + b_j x_k`` (first-order
  hold lag update, ``p_j`` known before the step).  So ``v_k = H~[x]_k + P`` where ``H~``
  is H with the first weight ``w_H0 + beta``, ``beta = sum_j w_Cj b_j`` and
  ``P = sum_j w_Cj p_j``; ``x_k = H~'[S'[s_c] - P]`` with ``H~'`` from (12)-(13) and its
  state from (14) applied to the forward play state.  Exact.
- ``rate_dependence``: the material sees the lagged current ``x_e``; ``x_e,k = Gamma^-1[s_c]``
  and the lag update solved for the present current, ``x_k = x_(k-1) + (x_e,k - a x_e,(k-1)
  - (1 - a) x_(k-1)) / b`` (the discrete lead filter ``x = x_e + tau dx_e/dt``).  Exact.
- ``thermal_drift``: ``v_k = H[x]_k + w_T T_k``; the thermal state is predicted from the
  previous current (``T_k = a T_(k-1) + (1 - a) x_(k-1)^2``, the first-order-hold term
  ``b (x_k^2 - x_(k-1)^2)`` with ``b ~ h / (2 tau_T)`` is dropped) and subtracted before
  ``H'``: exact up to a relative ``h / tau_T`` (the first sample, where the state starts at
  ``x_0^2``, takes a few fixed-point sweeps).
- ``dead_time``: not invertible causally (it needs the future); :func:`compensator_from_params`
  returns the plain :class:`~mpi_ros.compensation.FeedforwardCompensator` of Gamma and warns.

The compensator's state is driven by the current actually commanded (after clamping),
so clamping never leaves the inverse out of step with the actuator.
"""

from collections.abc import Mapping
import math
from typing import Any
import warnings

import numba
import numpy as np
import numpy.typing as npt

from ._signals import lag_coefficients
from .creep import CreepModel
from .dead_time import DeadTimeModel
from .rate_dependence import RateDependentModel
from .thermal_drift import ThermalDriftModel
from ..compensation import (best_linear_map, FeedforwardCompensator, operating_range,
                            screen_desired)
from ..errors import ModelError, MPIWarning
from ..inverse import hysteresis_inverse_laws, hysteresis_inverse_states
from ..memory import TurningPointMemory
from ..model import _hysteresis_step, _superposition_value, MPIModel

__all__ = ['ExtendedCompensator', 'compensator_from_params']

FloatArray = npt.NDArray[np.float64]
InvertibleModel = CreepModel | RateDependentModel | ThermalDriftModel


@numba.njit(cache=True, nogil=True)
def _inverse_value(v, r_h, w_h, beta, z_h):  # pragma: no cover - compiled
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


class ExtendedCompensator:
    """
    Streaming inverse of a creep, rate-dependence or thermal-drift model, clamped.

    Same interface as :class:`mpi_ros.compensation.FeedforwardCompensator`.

    Parameters
    ----------
    model : CreepModel, RateDependentModel or ThermalDriftModel
        The extended forward model.
    output_min, output_max : float
        Safe current range [A]; every output lies inside it.
    enabled : bool
        False: output the best linear map of Gamma instead (for comparison).
    sample_period : float
        Interval [s] assumed between two commands when :meth:`command` gets no ``time``.

    Attributes
    ----------
    counters : dict[str, int]
        ``messages``, ``nonfinite_input``, ``out_of_range``, ``clamped``, ``bad_time``.
    version : int
        Incremented by every accepted model swap.

    """

    def __init__(self, model: InvertibleModel, *, output_min: float, output_max: float,
                 enabled: bool = True, sample_period: float = 1e-3) -> None:
        FeedforwardCompensator._check_limits(output_min, output_max)
        if not (math.isfinite(sample_period) and sample_period > 0.0):
            msg = f'sample_period must be finite and > 0 [s]; found {sample_period!r}'
            raise ModelError(msg)
        self.output_min = float(output_min)
        self.output_max = float(output_max)
        self.enabled = bool(enabled)
        self.sample_period = float(sample_period)
        self.counters = {'messages': 0, 'nonfinite_input': 0, 'out_of_range': 0,
                         'clamped': 0, 'bad_time': 0}
        self.version = 0
        self.memory = TurningPointMemory()
        self.last_command = float(np.clip(0.0, self.output_min, self.output_max))
        self._last_time: float | None = None
        self._started = False
        self._slow = np.zeros(0)
        self._material_input = self.last_command
        self._install(model, replay=False)
        self.version = 1

    def _install(self, model: InvertibleModel, *, replay: bool) -> None:
        if not isinstance(model, (CreepModel, RateDependentModel, ThermalDriftModel)):
            msg = (f'ExtendedCompensator needs a creep, rate_dependence or thermal_drift model;'
                   f' found {type(model).__name__}; use compensator_from_params')
            raise ModelError(msg)
        gamma = model.model
        inverse = gamma.inverse()
        h = gamma.hysteresis
        z_h = np.array(h.initial_states, dtype=np.float64)
        if replay and len(self.memory):
            _, z_h = gamma.hysteresis_output(self.memory.points, z_h)
        if isinstance(model, CreepModel):
            taus = np.asarray(model.time_constants, dtype=np.float64)
            if self._slow.size != taus.size:
                self._slow = np.full(taus.size, self.last_command)
        else:
            self._slow = self._slow[:1] if self._slow.size else np.zeros(1)
            if not self._started:
                self._slow[0] = (self.last_command ** 2 if isinstance(model, ThermalDriftModel)
                                 else self.last_command)
        self._kernel = (np.ascontiguousarray(h.thresholds), np.ascontiguousarray(h.weights),
                        z_h, np.ascontiguousarray(inverse.superposition.thresholds),
                        np.ascontiguousarray(inverse.superposition.weights))
        # Operating point: x = x0 + H'[S'[sign (s_c - y0)] - ...], plays see x - x0.
        self._point = (gamma.input_offset, gamma.output_offset, float(gamma.output_sign))
        self.model = model
        self.displacement_range = operating_range(gamma, self.output_min, self.output_max)
        self.linear_map = best_linear_map(gamma, self.output_min, self.output_max)
        # Run the compiled steps once on copies: the first real command does not pay
        # numba's dispatch (milliseconds on first use).
        r_h, w_h, z_h, r_si, w_si = self._kernel
        v = _superposition_value(0.0, r_si, w_si)
        _hysteresis_step(_inverse_value(v, r_h, w_h, 0.0, z_h), r_h, w_h, z_h.copy())

    def swap_model(self, model: InvertibleModel) -> None:
        """
        Switch to a new extended model of the same kind, bumplessly.

        The play state is replayed from the stored turning points through the new H (as in
        :class:`~mpi_ros.compensation.FeedforwardCompensator`); the lag states carry over.

        Parameters
        ----------
        model : CreepModel, RateDependentModel or ThermalDriftModel
            The new model; of the same extension as the current one.

        Raises
        ------
        ModelError
            When the extension differs (build a new compensator instead).

        """
        if type(model) is not type(self.model):
            msg = (f'swap_model needs a {type(self.model).__name__}; found'
                   f' {type(model).__name__}; build a new compensator with'
                   ' compensator_from_params')
            raise ModelError(msg)
        self._install(model, replay=True)
        self.version += 1

    def set_limits(self, output_min: float, output_max: float) -> None:
        """Change the safe current range [A] (validated; the model is kept)."""
        FeedforwardCompensator._check_limits(output_min, output_max)
        self.output_min, self.output_max = float(output_min), float(output_max)
        gamma = self.model.model
        self.displacement_range = operating_range(gamma, self.output_min, self.output_max)
        self.linear_map = best_linear_map(gamma, self.output_min, self.output_max)

    @property
    def state(self) -> FloatArray:
        """Forward play state ``z_H`` [A] at the operating point (a copy)."""
        return self._kernel[2].copy()

    @property
    def slow_state(self) -> FloatArray:
        """Lag states: creep lags [A], the lagged current [A] or the thermal state [A^2]."""
        return self._slow.copy()

    def command(self, desired: float, *, time: float | None = None) -> float:
        """
        Return the current command [A] for a desired displacement [m].

        Parameters
        ----------
        desired : float
            Desired displacement ``s_c`` [m].
        time : float, optional
            Time stamp [s] of this command; the interval to the previous one drives the
            lags.  Without it (or when it does not increase) ``sample_period`` is used.

        Returns
        -------
        float
            Finite current inside ``[output_min, output_max]``.

        """
        c = self.counters
        s_c = screen_desired(desired, c, self.displacement_range)
        if s_c is None:
            return self.last_command
        h = self._interval(time)
        r_h, w_h, z_h, r_si, w_si = self._kernel
        x0, y0, sign = self._point
        v_c = _superposition_value(sign * (s_c - y0), r_si, w_si)      # S'[...] (27)
        model = self.model
        x_prev = self.last_command
        if isinstance(model, CreepModel):
            if self._started:
                coef = [lag_coefficients(h, tau) for tau in model.time_constants]
                a = np.array([v[0] for v in coef])
                b = np.array([v[1] for v in coef])
                p = a * self._slow + (1.0 - a) * x_prev - b * x_prev
            else:
                b, p = np.ones(self._slow.size), np.zeros(self._slow.size)
            beta = float(np.dot(model.weights, b))
            # The lags see x - x0: c_rel = c - x0 (a lag of a constant is the constant).
            offset = float(np.dot(model.weights, p - x0 * (1.0 - b)))
            if self.enabled:
                raw = x0 + _inverse_value(v_c - offset, r_h, w_h, beta, z_h)
            else:
                raw = self.linear_map(s_c)
            current = min(max(raw, self.output_min), self.output_max)
            self._slow = p + b * current
            material = current
        elif isinstance(model, RateDependentModel):
            if self._started and model.time_constant > 0.0:
                a, b = lag_coefficients(h, model.time_constant)
            else:
                a, b = 0.0, 1.0
            xe_prev = float(self._slow[0])
            if self.enabled:
                target = x0 + _inverse_value(v_c, r_h, w_h, 0.0, z_h)
                raw = x_prev + (target - a * xe_prev - (1.0 - a) * x_prev) / b
                if not self._started:
                    raw = target
            else:
                raw = self.linear_map(s_c)
            current = min(max(raw, self.output_min), self.output_max)
            material = (a * xe_prev + (1.0 - a) * x_prev + b * (current - x_prev)
                        if self._started else current)
            self._slow[0] = material
        else:
            if self._started:
                a, _ = lag_coefficients(h, model.time_constant)
                thermal = a * float(self._slow[0]) + (1.0 - a) * x_prev ** 2
            else:
                thermal = None
            if self.enabled:
                v = v_c
                if thermal is not None:
                    raw = x0 + _inverse_value(v - model.weight * thermal, r_h, w_h, 0.0, z_h)
                else:
                    # First sample: the state starts at x_0^2 (steady state); a few
                    # fixed-point sweeps x <- H'[v - w_T x^2] (a contraction for the small
                    # w_T a drift has) settle it.
                    raw = x_prev
                    for _ in range(8):
                        raw = x0 + _inverse_value(v - model.weight * raw * raw, r_h, w_h,
                                                  0.0, z_h)
            else:
                raw = self.linear_map(s_c)
            current = min(max(raw, self.output_min), self.output_max)
            self._slow[0] = thermal if thermal is not None else current ** 2
            material = current
        if not math.isfinite(raw):
            raw = current = x_prev
        if current != raw:
            c['clamped'] += 1
        _hysteresis_step(material - x0, r_h, w_h, z_h)
        self.memory.push(material)
        self._started = True
        self.last_command = current
        return current

    def _interval(self, time: float | None) -> float:
        if time is None:
            return self.sample_period
        t = float(time)
        last, self._last_time = self._last_time, t
        if last is None:
            return self.sample_period
        if not (math.isfinite(t) and t > last):
            self.counters['bad_time'] += 1
            self._last_time = last
            return self.sample_period
        return t - last


def compensator_from_params(mapping: Mapping[str, Any], *, output_min: float,
                            output_max: float, enabled: bool = True,
                            sample_period: float = 1e-3
                            ) -> FeedforwardCompensator | ExtendedCompensator:
    """
    Build the right compensator for a parameter set (plain or extended model).

    Parameters
    ----------
    mapping : Mapping[str, Any]
        Flat parameters: Gamma's five ``model.*`` keys plus at most one extension's keys.
    output_min, output_max : float
        Safe current range [A].
    enabled : bool
        False: the best linear map instead of the inverse.
    sample_period : float
        Nominal command interval [s] (extended compensators only).

    Returns
    -------
    FeedforwardCompensator or ExtendedCompensator
        Plain keys: :class:`~mpi_ros.compensation.FeedforwardCompensator`; creep,
        rate-dependence or thermal-drift keys: :class:`ExtendedCompensator`; dead-time
        keys: the plain compensator of Gamma, with an :class:`~mpi_ros.errors.MPIWarning`
        (a dead time cannot be inverted causally).

    Raises
    ------
    ModelError
        Invalid parameters (the message names the key).

    """
    from . import extended_model_from_params
    model = extended_model_from_params(mapping)
    if isinstance(model, MPIModel):
        return FeedforwardCompensator(model, output_min=output_min, output_max=output_max,
                                      enabled=enabled)
    if isinstance(model, DeadTimeModel):
        msg = (f'model.dead_time = {model.dead_time} s cannot be inverted causally (it needs'
               ' the future); compensating Gamma only - the output lags the desired'
               ' displacement by the dead time')
        warnings.warn(msg, MPIWarning, stacklevel=2)
        return FeedforwardCompensator(model.model, output_min=output_min,
                                      output_max=output_max, enabled=enabled)
    return ExtendedCompensator(model, output_min=output_min, output_max=output_max,
                               enabled=enabled, sample_period=sample_period)
