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

One class, :class:`Compensator`, serves every model: a plain MPI model (one compiled
step) or an extended model whose effect plugs in its exact per-step inverse
(:class:`InverseStep`, e.g. :class:`mpi_ros.extensions.creep.CreepInverse`).  It owns the
limits, the screening, the counters, the turning-point memory and the bumpless handover
between models of any kind (:meth:`Compensator.install`); a node only translates
messages and parameters.  :class:`FeedforwardCompensator` and
:class:`ExtendedCompensator` are its plain and extended constructors.
"""

from collections.abc import Callable, Sequence
from dataclasses import dataclass
import math
from typing import Any, Protocol

import numba
import numpy as np
import numpy.typing as npt

from .errors import DataError, ModelError
from .inverse import hysteresis_inverse_laws, hysteresis_inverse_states
from .memory import TurningPointMemory
from .model import _hysteresis_step, _superposition_value, MPIModel

__all__ = ['Compensator', 'ExtendedCompensator', 'FeedforwardCompensator', 'InverseStep',
           'MultiAxisCompensator',
           'gamma_of', 'inverse_step_of', 'kind_of', 'LinearMap', 'best_linear_map',
           'operating_range', 'screen_desired']

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


class InverseStep(Protocol):
    """
    An effect's exact per-step inverse, plugged into :class:`Compensator`.

    Per command the compensator calls ``prepare`` (the lag coefficients from the interval
    and the previous command), ``invert`` (the current for the step output ``v`` of S',
    through ``inverse(v, beta)`` = ``x0 + H~'[v]`` with ``H~`` = H whose first weight is
    raised by ``beta``, by (12)-(14)), then ``advance`` with the applied (clamped) current,
    which returns what the material (H) sees.  ``state`` holds the effect's slow states.
    """

    state: FloatArray

    def start(self, current: float) -> None:
        """Settle the slow states at a steady ``current`` [A]."""

    def carry(self, other: object) -> bool:
        """Take over another step's slow states when compatible; tell whether it did."""

    def prepare(self, previous: float, interval: float, started: bool) -> None:
        """Fix this step's coefficients."""

    def invert(self, v: float, previous: float, started: bool,
               inverse: Callable[[float, float], float]) -> float:
        """Return the current [A] whose step output is ``v``."""

    def advance(self, current: float, previous: float, started: bool) -> float:
        """Update the slow states with the applied current; return the material's input."""


def gamma_of(model: Any) -> MPIModel:
    """Return the forward Gamma of a plain or extended model (``model.model``)."""
    gamma = model if isinstance(model, MPIModel) else model.model
    return gamma.inverse() if gamma.is_inverse else gamma


def inverse_step_of(model: Any) -> 'InverseStep | None':
    """Return an extended model's per-step inverse, or None (plain, or not invertible)."""
    make = getattr(model, 'inverse_step', None)
    return None if make is None else make()


def kind_of(model: Any) -> str:
    """Name a model's effect: ``none``, its cause, or ``dead_time (not compensated)``."""
    if isinstance(model, MPIModel):
        return 'none'
    if inverse_step_of(model) is None:
        return f'{model.cause} (not compensated)'
    return str(model.cause)


class Compensator:
    """
    The streaming inverse compensator ``current = clamp(Gamma^-1[s_c])``, for every model.

    One class owns the safe current range, the screening of the desired values, the
    counters, the turning-point memory and the bumpless handover between models of any
    kind: a plain MPI model (no effect: one compiled step), or an extended model whose
    effect plugs in its exact per-step inverse (:class:`InverseStep`).  A model whose effect
    cannot be inverted causally (dead time) is compensated through its Gamma alone.

    Parameters
    ----------
    model : MPIModel or extended model
        Forward model (the inverse is computed here by (12)-(14), (22)-(25)).
    output_min, output_max : float
        Safe current range [A]; every output lies inside it.
    enabled : bool
        False: output the best linear map of Gamma instead (for comparison).
    sample_period : float
        Interval [s] assumed between two commands when :meth:`command` gets no ``time``
        (effects with lags only).

    Attributes
    ----------
    counters : dict[str, int]
        ``messages``, ``nonfinite_input``, ``out_of_range`` (desired outside the model's
        operating range), ``clamped``, ``bad_time`` (time stamps that did not increase).
    version : int
        Incremented by every accepted model.

    """

    def __init__(self, model: Any, *, output_min: float, output_max: float,
                 enabled: bool = True, sample_period: float = 1e-3) -> None:
        self._check_limits(output_min, output_max)
        _check_sample_period(sample_period)
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
        self._step: InverseStep | None = None
        self._install(model, replay=False)
        self.version = 1

    @staticmethod
    def _check_limits(output_min: float, output_max: float) -> None:
        if not (np.isfinite(output_min) and np.isfinite(output_max)
                and output_min < output_max):
            msg = (f'output.min must be finite and below output.max; found {output_min} and'
                   f' {output_max}')
            raise ModelError(msg)

    def _install(self, model: Any, *, replay: bool) -> None:
        gamma = gamma_of(model)
        step = inverse_step_of(model)
        if step is not None and not step.carry(self._step):
            step.start(self.last_command)
        inverse = gamma.inverse()
        h, s_inv, h_inv = gamma.hysteresis, inverse.superposition, inverse.hysteresis
        z_h = np.array(h.initial_states, dtype=np.float64)
        if replay and len(self.memory):
            _, z_h = gamma.hysteresis_output(self.memory.points, z_h)
        lo, hi = operating_range(gamma, self.output_min, self.output_max)
        linear = best_linear_map(gamma, self.output_min, self.output_max)
        # One assignment of a tuple: the step never sees half of an old and a new model.
        self._kernel = (np.ascontiguousarray(h.thresholds), np.ascontiguousarray(h.weights),
                        z_h, np.ascontiguousarray(h_inv.thresholds),
                        np.ascontiguousarray(h_inv.weights), np.empty_like(z_h),
                        np.ascontiguousarray(s_inv.thresholds),
                        np.ascontiguousarray(s_inv.weights),
                        np.array([gamma.input_offset, gamma.output_offset,
                                  float(gamma.output_sign)]))
        _warm_up(self._kernel, lo, self.output_min, self.output_max)
        self._step = step
        self.model = model
        self.gamma = gamma
        self.displacement_range = (lo, hi)
        self.linear_map = linear

    def install(self, model: Any) -> None:
        """
        Switch to a new model of any kind, bumplessly.

        The new forward play state is the replay of the applied current's turning points
        through the new H (the inverse state follows by (14)); an effect of the same kind
        keeps its slow states, a new one starts them settled at the last command.  The
        counters go on.

        Parameters
        ----------
        model : MPIModel or extended model
            The new (validated) forward model.

        """
        self._install(model, replay=True)
        self.version += 1

    @property
    def has_effect(self) -> bool:
        """Tell whether an effect's per-step inverse is in use (its lags need times)."""
        return self._step is not None

    @property
    def kind(self) -> str:
        """Name the installed model's effect: ``none``, a cause, or ``... (not compensated)``."""
        return kind_of(self.model)

    def set_limits(self, output_min: float, output_max: float) -> None:
        """Change the safe current range [A] (validated; the model is kept)."""
        self._check_limits(output_min, output_max)
        self.output_min, self.output_max = float(output_min), float(output_max)
        self.displacement_range = operating_range(self.gamma, self.output_min,
                                                  self.output_max)
        self.linear_map = best_linear_map(self.gamma, self.output_min, self.output_max)

    @property
    def state(self) -> FloatArray:
        """Forward play state ``z_H`` [A] at the operating point (a copy)."""
        return self._kernel[2].copy()

    @property
    def slow_state(self) -> FloatArray:
        """Return the effect's slow states (creep lags [A], lagged current [A], thermal [A^2])."""
        return np.zeros(0) if self._step is None else self._step.state.copy()

    def command(self, desired: float, *, time: float | None = None) -> float:
        """
        Return the current command [A] for a desired displacement [m].

        Parameters
        ----------
        desired : float
            Desired displacement ``s_c`` [m].
        time : float, optional
            Time stamp [s] of this command; the interval to the previous one drives an
            effect's lags.  Without it (or when it does not increase) ``sample_period``
            is used.

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
        step = self._step
        if step is None:
            if self.enabled:
                current, raw = _compensate_step(s_c, self.output_min, self.output_max, r_h,
                                                w_h, z_h, r_hi, w_hi, z_i, r_si, w_si, point)
            else:
                raw = self.linear_map(s_c)
                current = min(max(raw, self.output_min), self.output_max)
                _hysteresis_step(current - point[0], r_h, w_h, z_h)
            material = current
        else:
            interval = self._interval(time)
            x0, y0, sign = float(point[0]), float(point[1]), float(point[2])
            previous, started = self.last_command, self._started
            step.prepare(previous, interval, started)
            if self.enabled:
                v = _superposition_value(sign * (s_c - y0), r_si, w_si)     # S' (27)

                def inverse(value: float, beta: float) -> float:
                    return x0 + float(_inverse_value(value, r_h, w_h, beta, z_h))

                raw = step.invert(v, previous, started, inverse)
            else:
                raw = self.linear_map(s_c)
            if not math.isfinite(raw):
                raw = previous
            current = min(max(raw, self.output_min), self.output_max)
            material = step.advance(current, previous, started)
            _hysteresis_step(material - x0, r_h, w_h, z_h)
            self._started = True
        if current != raw:
            c['clamped'] += 1
        self.memory.push(material)
        self.last_command = current
        return current

    def command_batch(self, desired: npt.ArrayLike,
                      times: npt.ArrayLike | None = None) -> FloatArray:
        """
        Return the commands for a chunk of desired displacements, as :meth:`command` would.

        A plain model runs the whole chunk in one compiled loop (screening, inverse,
        clamping, counters); an effect's model steps sample by sample.  The results and
        the state afterwards equal those of :meth:`command` called per sample.

        Parameters
        ----------
        desired : array_like of float, shape (K,)
            Desired displacements [m] (NaN/Inf hold the last command and are counted).
        times : array_like of float, shape (K,), optional
            Their time stamps [s] (effects with lags only).

        Returns
        -------
        ndarray of float, shape (K,)
            Current commands [A], finite and inside ``[output_min, output_max]``.

        """
        values = np.ascontiguousarray(desired, dtype=np.float64).reshape(-1)
        if self._step is not None or not self.enabled:
            stamps = (None,) * values.size if times is None else np.asarray(times, float)
            return np.array([self.command(float(v), time=None if t is None else float(t))
                             for v, t in zip(values, stamps)], dtype=np.float64)
        out = np.empty(values.size)
        counts = np.zeros(3, dtype=np.int64)
        lo, hi = self.displacement_range
        self.last_command = float(_compensate_batch(
            values, lo, hi, self.output_min, self.output_max, *self._kernel,
            self.last_command, counts, out))
        c = self.counters
        c['messages'] += int(values.size)
        c['nonfinite_input'] += int(counts[0])
        c['out_of_range'] += int(counts[1])
        c['clamped'] += int(counts[2])
        self.memory.extend(out)
        return out

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


class FeedforwardCompensator(Compensator):
    """
    The :class:`Compensator` of a plain MPI model (Fig. 10 of the paper).

    Parameters
    ----------
    model : MPIModel
        The forward model Gamma.
    output_min, output_max : float
        Safe current range [A]; every output lies inside it.
    enabled : bool
        False: output the best linear map instead of Gamma^-1 (for comparison).

    """

    def __init__(self, model: MPIModel, *, output_min: float, output_max: float,
                 enabled: bool = True) -> None:
        super().__init__(model, output_min=output_min, output_max=output_max,
                         enabled=enabled)

    def swap_model(self, model: MPIModel) -> None:
        """
        Switch to a new plain model bumplessly (see :meth:`Compensator.install`).

        Parameters
        ----------
        model : MPIModel
            The new (validated) forward model.

        """
        self.install(model)


class ExtendedCompensator(Compensator):
    """
    The :class:`Compensator` of a creep, rate-dependence or thermal-drift model.

    Parameters
    ----------
    model : extended model
        A model whose effect has an exact per-step inverse (``inverse_step()``).
    output_min, output_max : float
        Safe current range [A]; every output lies inside it.
    enabled : bool
        False: output the best linear map of Gamma instead (for comparison).
    sample_period : float
        Interval [s] assumed between two commands when :meth:`command` gets no ``time``.

    """

    def __init__(self, model: Any, *, output_min: float, output_max: float,
                 enabled: bool = True, sample_period: float = 1e-3) -> None:
        if inverse_step_of(model) is None:
            msg = (f'ExtendedCompensator needs a creep, rate_dependence or thermal_drift model;'
                   f' found {type(model).__name__}; use compensator_from_params')
            raise ModelError(msg)
        super().__init__(model, output_min=output_min, output_max=output_max,
                         enabled=enabled, sample_period=sample_period)

    def swap_model(self, model: Any) -> None:
        """
        Switch to a new extended model of the same kind, bumplessly.

        Parameters
        ----------
        model : extended model
            The new model; of the same extension as the current one.

        Raises
        ------
        ModelError
            When the extension differs (use :meth:`Compensator.install`).

        """
        if type(model) is not type(self.model):
            msg = (f'swap_model needs a {type(self.model).__name__}; found'
                   f' {type(model).__name__}; use install() to change the kind of model')
            raise ModelError(msg)
        self.install(model)


def _check_sample_period(sample_period: float) -> None:
    if not (math.isfinite(sample_period) and sample_period > 0.0):
        msg = f'sample_period must be finite and > 0 [s]; found {sample_period!r}'
        raise ModelError(msg)


class MultiAxisCompensator:
    """
    Several actuators, each with its own model and :class:`Compensator`, served together.

    A block of desired displacements, ``samples x axes`` (one row per sample, one column
    per axis, as in a ``Float64MultiArray`` chunk), gives a block of commands of the same
    shape; each column is exactly what that axis's single-axis compensator gives.

    Parameters
    ----------
    models : sequence of MPIModel or extended models
        One forward model per axis.
    output_min, output_max : float or sequence of float
        Safe current range [A], one for all axes or one per axis.
    enabled : bool
        False: the best linear maps instead of the inverses.
    sample_period : float
        Nominal command interval [s] (effects with lags only).

    """

    def __init__(self, models: Sequence[Any], *, output_min: float | Sequence[float],
                 output_max: float | Sequence[float], enabled: bool = True,
                 sample_period: float = 1e-3) -> None:
        if len(models) == 0:
            msg = 'a multi-axis compensator needs at least one axis model'
            raise ModelError(msg)
        count = len(models)
        lows = _per_axis(output_min, count, 'output.min')
        highs = _per_axis(output_max, count, 'output.max')
        self.axes = [Compensator(model, output_min=lo, output_max=hi, enabled=enabled,
                                 sample_period=sample_period)
                     for model, lo, hi in zip(models, lows, highs)]

    def __len__(self) -> int:
        """Return the number of axes."""
        return len(self.axes)

    def command(self, desired: npt.ArrayLike) -> FloatArray:
        """
        Return the commands for a block of desired displacements.

        Parameters
        ----------
        desired : array_like of float, shape (K, N) or (N,)
            Desired displacements [m]: K samples of N axes (one sample: shape (N,)).

        Returns
        -------
        ndarray of float, same shape as ``desired``
            Current commands [A].

        Raises
        ------
        DataError
            When the block does not have one column per axis.

        """
        block = np.asarray(desired, dtype=np.float64)
        single = block.ndim == 1
        rows = block.reshape(1, -1) if single else block
        if rows.ndim != 2 or rows.shape[1] != len(self.axes):
            msg = (f'desired displacements must be samples x axes with {len(self.axes)}'
                   f' axes; found shape {tuple(block.shape)}')
            raise DataError(msg)
        out = np.empty_like(rows)
        for axis, compensator in enumerate(self.axes):
            out[:, axis] = compensator.command_batch(rows[:, axis])
        return out[0] if single else out


def _per_axis(value: float | Sequence[float], count: int, name: str) -> list[float]:
    if isinstance(value, (int, float)):
        values = [float(value)] * count
    else:
        values = [float(v) for v in value]
    if len(values) != count:
        msg = f'{name} must be one value or one per axis ({count}); found {len(values)}'
        raise ModelError(msg)
    return values
