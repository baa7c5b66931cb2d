# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Resonance extension: a lightly damped mechanical mode between Gamma and the sensor.

``s = R[Gamma[x]]``: the actuator's displacement ``g = Gamma[x]`` drives a second-order mode
of unit DC gain,

``p'' + (2 / T) p' + omega^2 p = omega^2 g``,  ``omega = 2 pi f``,

with natural frequency ``f`` [Hz] and the decay time constant ``T`` [s] of the ringing's
envelope (damping ratio ``zeta = 1 / (omega T)``, below 1/2 for a fitted mode: it rings).  It
is an output stage: it acts on the displacement, after the hysteresis (and after any input
stage and material effect).  A step of the input makes the output overshoot and ring at
about ``f`` for a few ``T``; slow excitation passes with gain ``1 / (1 - (f_x / f)^2)``.

The mode is advanced exactly for a displacement linear between samples (first-order hold;
any sampling, uniform or not): with the slope ``q`` of ``g`` over the interval ``h``, the
particular solution is ``g - (2 / (omega^2 T)) q`` and the deviation from it rotates and
decays by the closed-form 2 x 2 matrix exponential of the mode.  The model's simulation starts
at rest at Gamma's first output, displaced by its ``initial_deflection`` (the mode's position
minus Gamma's output at the first sample, with zero velocity).  That deflection is the
identification record's, part of its start (``record_start.resonance.initial_deflection``): a
record that starts just after an unrecorded step (the TUM piezo captures) starts ringing, one
that starts at rest has 0.  A new input starts with the mode at rest unless the record's start
is asked for (:mod:`mpi_ros.operators.start`).

A compensator cannot invert a lightly damped mode causally: its inverse is a second
derivative of the desired displacement (a non-causal, noise-amplifying lead); it inverts Gamma
only and warns (the compensator's ``kind`` reads ``resonance (not compensated)``).  The mode is
left to feedback, or to an input shaper / notch at ``f`` on the desired displacement.

The identification (:func:`mpi_ros.identify`, with a time base) fits the mode
when the record rings after steps (:func:`fit_mode`, least squares of ``R[Gamma[x]]`` against
the measured output, from the ringing frequency the analysis detected), then Gamma again on the
output with the mode's part taken out; the mode is kept when it lowers the whole-record error
clearly (:func:`estimate_resonance`; below, "The output mode").

Parameter keys (besides Gamma's ``model.*`` keys, operating point included):
``model.resonance.frequency`` (``f`` [Hz], 0: no mode), ``model.resonance.decay`` (``T``
[s], above ``1 / omega``) and the record's start ``record_start.resonance.initial_deflection``
([m], 0: at rest; ``model.resonance.initial_deflection`` of an older file is read as it).

**The output mode** of a record that rings after steps: fitted, judged, kept or not.

A rate-independent Gamma cannot follow ringing: :mod:`.dynamics` finds the windows after
steps where the output rings and leaves them out of the QP.  With a time base the
identification then models the ringing as a lightly damped mechanical mode after Gamma
(``s = R[Gamma[x]]``):

1. the mode (natural frequency, decay, and the initial deflection when the record starts
   ringing) is fitted by least squares of ``R[g]`` against the measured output, ``g`` the
   static model simulated from the first sample, starting from the detected ringing
   frequency;
2. Gamma is fitted again, with the same order, burn-in and input dynamics, its start states
   chosen afresh, on the output with the mode's part taken out, ``y - (R[g] - g)`` (the
   ringing windows still left out); the mode is fitted again on the new ``g``.  The ringing's
   tails beyond the windows and the mode's gain at the excitation's frequencies
   (``1 / (1 - (f_x / f)^2)``) no longer bias Gamma, nor the choice of its start state;
3. of the two, the one with the lower RMS error of the model simulated over the whole record
   from its first sample (ringing windows are never held out: this is the error the mode can
   change) is kept when that error falls by :data:`RESONANCE_GAIN` or more, and the error
   outside the ringing windows rises by at most :data:`OUTSIDE_TOLERANCE` of the output's
   range.  Otherwise the static model stays (the windows stay left out) and the mode found
   is reported as not modelled.

Why the second condition: Gamma is piecewise linear (each play that starts to move changes its
slope at once), and the mode rings after every such kink, as a real, smooth hysteresis does
not make it ring.  On slow excitation the ripple is below the noise; on the TUM piezo's 100 Hz
cycles it doubles the error outside the start's ringing (0.33 % -> 0.61 %), more than the start
ringing's share of the whole record gains: the mode is found there, and not modelled.
"""

from collections.abc import Mapping
from dataclasses import dataclass, replace
import math
from typing import Any, NamedTuple

import numba
import numpy as np
import numpy.typing as npt
from scipy.optimize import least_squares

from .effect import Effect, EffectParameter, ExtendedModelBase, FAST_TIME_LIMIT, PlantChunk, \
    PlantEffect, PlantParameter
from .fitting import AxisUnits, check_series, Order, resolve_order, scalar_parameter
from ..errors import DataError, IdentificationError, ModelError
from ..identification.dynamics import InputDynamics
from ..identification.fitter import fit_record, RecordFit
from ..identification.record import prepare_record, PreparedRecord
from ..operators.model import MPIModel

__all__ = ['ResonanceModel', 'ModeFit', 'fit_mode', 'fit_resonance', 'output_mode',
           'mode_state', 'mode_stream', 'RESONANCE_FREQUENCY', 'RESONANCE_DECAY',
           'RESONANCE_DEFLECTION', 'LEGACY_DEFLECTION', 'MAX_DAMPING_RATIO',
           'estimate_resonance', 'ResonanceEstimate', 'with_mode', 'RESONANCE_GAIN',
           'OUTSIDE_TOLERANCE']

FloatArray = npt.NDArray[np.float64]

RESONANCE_FREQUENCY = 'model.resonance.frequency'
RESONANCE_DECAY = 'model.resonance.decay'
#: The record's start: the mode's deflection at its first sample.
RESONANCE_DEFLECTION = 'record_start.resonance.initial_deflection'
#: Where files written before the split hold it (read as the record start; never written).
LEGACY_DEFLECTION = 'model.resonance.initial_deflection'

#: Largest damping ratio of a fitted mode: above it the output does not ring (a mode that
#: damped is a low-pass, which an input lag models).
MAX_DAMPING_RATIO = 0.5


@dataclass(frozen=True, eq=False)
class ResonanceModel(ExtendedModelBase):
    """
    MPI model followed by a lightly damped output mode: ``s = R_(f, T)[Gamma[x]]``.

    Parameters
    ----------
    model : MPIModel
        Forward model Gamma.
    frequency : float
        Natural frequency ``f`` [Hz] of the mode (0: no mode, ``s = Gamma[x]``).
    decay : float
        Time constant ``T`` [s] of the ringing's envelope, above ``1 / (2 pi f)`` (the mode
        rings); ignored without a mode.
    initial_deflection : float
        The mode's position minus Gamma's output at the first sample [m] (at rest there,
        zero velocity): the identification record's start; 0: the simulation starts at
        rest.

    """

    model: MPIModel
    frequency: float
    decay: float
    initial_deflection: float = 0.0
    cause = 'resonance'

    def __post_init__(self) -> None:
        """Validate ``f``, ``T`` (the mode must ring) and the deflection."""
        params = {RESONANCE_FREQUENCY: self.frequency, RESONANCE_DECAY: self.decay,
                  RESONANCE_DEFLECTION: self.initial_deflection}
        frequency = scalar_parameter(params, RESONANCE_FREQUENCY, unit='Hz')
        decay = scalar_parameter(params, RESONANCE_DECAY)
        deflection = scalar_parameter(params, RESONANCE_DEFLECTION, minimum=-math.inf,
                                      unit='m')
        if frequency > 0.0 and not decay > 1.0 / (2.0 * math.pi * frequency):
            msg = (f'{RESONANCE_DECAY} must be above 1 / (2 pi f) ='
                   f' {1.0 / (2.0 * math.pi * frequency):.4g} s for {RESONANCE_FREQUENCY}'
                   f' = {frequency:g} Hz (a mode that rings: damping ratio below 1); found'
                   f' {decay!r}; give the decay time constant of the ringing envelope [s],'
                   f' or 0 Hz for no mode')
            raise ModelError(msg)
        object.__setattr__(self, 'frequency', frequency)
        object.__setattr__(self, 'decay', decay)
        object.__setattr__(self, 'initial_deflection', deflection)

    @classmethod
    def from_params(cls, mapping: Mapping[str, Any]) -> 'ResonanceModel':
        """Build from Gamma's keys, ``model.resonance.*`` and the record start (0 if absent)."""
        key = next((k for k in (RESONANCE_DEFLECTION, LEGACY_DEFLECTION)
                    if mapping.get(k) is not None), None)
        deflection = (0.0 if key is None else
                      scalar_parameter(mapping, key, minimum=-math.inf, unit='m'))
        return cls(MPIModel.from_params(mapping),
                   scalar_parameter(mapping, RESONANCE_FREQUENCY, unit='Hz'),
                   scalar_parameter(mapping, RESONANCE_DECAY), deflection)

    def to_params(self) -> dict[str, Any]:
        """Return the flat parameter form."""
        params: dict[str, Any] = self.model.to_params()
        params[RESONANCE_FREQUENCY] = float(self.frequency)
        params[RESONANCE_DECAY] = float(self.decay)
        params[RESONANCE_DEFLECTION] = float(self.initial_deflection)
        return params

    @property
    def damping_ratio(self) -> float:
        """Return ``zeta = 1 / (omega T)`` (NaN without a mode)."""
        if self.frequency <= 0.0:
            return math.nan
        return 1.0 / (2.0 * math.pi * self.frequency * self.decay)

    @property
    def uncompensated_effect(self) -> str:
        """Say what the compensator leaves to the user (it inverts Gamma only)."""
        return (f'the output rings at about {self.frequency:.4g} Hz (decay'
                f' {1e3 * self.decay:.3g} ms) after fast changes of the desired displacement;'
                ' leave the mode to feedback, or shape the desired displacement (a notch or'
                f' an input shaper at {self.frequency:.4g} Hz)')

    def output_signal(self, time: npt.ArrayLike, displacement: npt.ArrayLike) -> FloatArray:
        """Return the measured displacement [m] for Gamma's output (this output stage's)."""
        t, g = check_series(time, displacement)
        return output_mode(t, g, self.frequency, self.decay, self.initial_deflection)

    def simulate(self, time: npt.ArrayLike, current: npt.ArrayLike) -> FloatArray:
        """Return the displacement [m] for a current [A] sampled at ``time`` [s]."""
        t, x = check_series(time, current)
        return self.output_signal(t, self.model.simulate(x))


class ModeFit(NamedTuple):
    """
    The mode :func:`fit_mode` found.

    Attributes
    ----------
    frequency : float
        Natural frequency [Hz].
    decay : float
        Time constant of the ringing's envelope [s].
    deflection : float
        Initial deflection [m] (0 unless fitted).
    error : float
        RMS error of ``R[g]`` against the output over the output's range.

    """

    frequency: float
    decay: float
    deflection: float
    error: float


def output_mode(time: npt.ArrayLike, displacement: npt.ArrayLike, frequency: float,
                decay: float, deflection: float = 0.0) -> FloatArray:
    """
    Pass a displacement through the mode, starting at rest at its first value (+ deflection).

    Parameters
    ----------
    time : array_like of float, shape (N,)
        Sample times [s], strictly increasing.
    displacement : array_like of float, shape (N,)
        The mode's drive ``g`` [m] (Gamma's output).
    frequency : float
        Natural frequency ``f`` [Hz] (0: no mode, ``g`` is returned).
    decay : float
        Envelope time constant ``T`` [s], above ``1 / (2 pi f)``.
    deflection : float
        The mode's position minus ``g`` at the first sample [m] (zero velocity).

    Returns
    -------
    ndarray of float, shape (N,)
        The mode's position [m].

    Examples
    --------
    >>> t = np.arange(400) * 1e-4
    >>> g = np.where(t < 5e-3, 0.0, 1.0)            # a unit step at 5 ms
    >>> p = output_mode(t, g, 1000.0, 0.01)
    >>> bool(p[:50].max() == 0.0), bool(p.max() > 1.7), bool(abs(p[-1] - 1.0) < 0.2)
    (True, True, True)

    """
    t = np.ascontiguousarray(time, dtype=np.float64).reshape(-1)
    g = np.ascontiguousarray(displacement, dtype=np.float64).reshape(-1)
    if frequency <= 0.0 or g.size == 0:
        return g.copy()
    state = mode_state()
    state[3] = g[0] + deflection
    return np.asarray(mode_stream(t, g, 2.0 * math.pi * frequency, 1.0 / decay, state),
                      dtype=np.float64)


def mode_state() -> FloatArray:
    """
    Return the state of a mode at rest at 0, before its first sample.

    Returns
    -------
    ndarray of float, shape (5,)
        ``[has previous sample, its time [s], its drive, position, velocity]``, zeros.

    """
    return np.zeros(5)


@numba.njit(cache=True, nogil=True)
def mode_stream(time: FloatArray, drive: FloatArray, omega: float, sigma: float,
                state: FloatArray) -> FloatArray:  # pragma: no cover - compiled
    """
    Return the mode's position over a chunk; advance its state in place.

    ``p'' + 2 sigma p' + omega^2 p = omega^2 g`` for a drive ``g`` linear between samples;
    the first sample of a fresh state is applied with no elapsed time (the position stays).

    Parameters
    ----------
    time : ndarray of float, shape (N,)
        Sample times [s], after the state's previous sample.
    drive : ndarray of float, shape (N,)
        The drive ``g``.
    omega : float
        ``2 pi f`` [rad/s], > 0.
    sigma : float
        ``1 / T`` [1/s], in (0, omega).
    state : ndarray of float, shape (5,)
        :func:`mode_state` ``()`` (or with a start position), updated.

    Returns
    -------
    ndarray of float, shape (N,)
        Position of the mode.

    """
    n = time.shape[0]
    out = np.empty(n)
    w2 = omega * omega
    wd = math.sqrt(max(w2 - sigma * sigma, 0.0))
    lead = 2.0 * sigma / w2            # the particular solution lags a ramp by this time
    for k in range(n):
        if state[0] > 0.0:
            h = time[k] - state[1]
            q = (drive[k] - state[2]) / h
            d0 = state[3] - (state[2] - lead * q)
            e0 = state[4] - q
            decay = math.exp(-sigma * h)
            c = math.cos(wd * h)
            s = math.sin(wd * h) / wd if wd * h > 1e-12 else h
            d1 = decay * ((c + sigma * s) * d0 + s * e0)
            e1 = decay * (-w2 * s * d0 + (c - sigma * s) * e0)
            state[3] = drive[k] - lead * q + d1
            state[4] = q + e1
        state[0] = 1.0
        state[1] = time[k]
        state[2] = drive[k]
        out[k] = state[3]
    return out


def fit_mode(time: npt.ArrayLike, model_output: npt.ArrayLike, displacement: npt.ArrayLike,
             frequency: float, *, decay: float | None = None, deflection: bool = False,
             rows: npt.NDArray[np.bool_] | None = None) -> ModeFit:
    """
    Fit the mode to a record: least squares of ``R[g]`` against the measured output.

    The natural frequency stays within a factor 1.5 of ``frequency`` (the ringing the
    analysis detected, to the nearest half-period in samples) and below 0.45 of the
    sample rate; the decay is at least ``1 / (MAX_DAMPING_RATIO omega)`` (the mode rings)
    and at most the record's duration.  Without a given ``decay`` three starts (3, 10 and 30
    periods) are tried; the best is returned.

    Parameters
    ----------
    time : array_like of float, shape (N,)
        Sample times [s], strictly increasing.
    model_output : array_like of float, shape (N,)
        The model's output without the mode, from the first sample [m].
    displacement : array_like of float, shape (N,)
        The measured output [m].
    frequency : float
        Start value of the natural frequency [Hz], > 0.
    decay : float, optional
        Start value of the decay time constant [s].
    deflection : bool
        Fit the initial deflection too (the record starts ringing); else it is 0.
    rows : ndarray of bool, shape (N,), optional
        Samples the error covers (default: all).

    Returns
    -------
    ModeFit
        The mode and its error.

    """
    t, g, y = check_series(time, model_output, displacement)
    span = float(np.ptp(y)) or 1.0
    dt = float(np.median(np.diff(t)))
    low = frequency / 1.5
    high = max(min(1.5 * frequency, 0.45 / dt), 1.01 * low)
    shortest = 1.0 / (MAX_DAMPING_RATIO * 2.0 * math.pi * low)
    longest = max(float(t[-1] - t[0]), 2.0 * shortest)
    keep = slice(None) if rows is None else rows

    def residual(p: FloatArray) -> FloatArray:
        d0 = float(p[2]) * span if deflection else 0.0
        r = output_mode(t, g, math.exp(p[0]), math.exp(p[1]), d0) - y
        return np.asarray(r[keep] / span, dtype=np.float64)

    lower = [math.log(low), math.log(shortest)] + ([-10.0] if deflection else [])
    upper = [math.log(high), math.log(longest)] + ([10.0] if deflection else [])
    f0 = min(max(frequency, low), high)
    starts = [decay] if decay is not None else [k / f0 for k in (3.0, 10.0, 30.0)]
    best: Any = None
    for start in starts:
        d_start = min(max(float(start), 1.001 * shortest), 0.999 * longest)
        p0 = [math.log(f0), math.log(d_start)] + ([0.0] if deflection else [])
        sol = least_squares(residual, p0, bounds=(lower, upper), x_scale='jac')
        if best is None or sol.cost < best.cost:
            best = sol
    f, tau = math.exp(best.x[0]), math.exp(best.x[1])
    d = float(best.x[2]) * span if deflection else 0.0
    error = float(np.sqrt(np.mean(residual(best.x) ** 2)))
    return ModeFit(f, tau, d, error)


def fit_resonance(time: npt.ArrayLike, current: npt.ArrayLike, displacement: npt.ArrayLike,
                  *, order: Order, epsilon: float = 1e-6) -> ResonanceModel:
    """
    Identify Gamma and the output mode (the diagnosis' candidate).

    Gamma is fitted as :func:`mpi_ros.model_fit.identify` fits it (ringing left out),
    the mode on the ringing after steps, then Gamma again on the output without the mode's
    part (:func:`estimate_resonance`).  A record that does
    not ring, or whose ringing the mode does not explain clearly, gives no mode
    (``frequency`` 0: the model is Gamma).

    Parameters
    ----------
    time, current, displacement : array_like of float, shape (N,)
        The record: sample times [s], coil current [A], displacement [m].
    order : (int, int) or 'auto'
        ``(n, l)`` of Gamma; ``'auto'``: :func:`~mpi_ros.identification.select_order`.
    epsilon : float
        Bound of (8)/(19).

    Returns
    -------
    ResonanceModel
        The identified model.

    """
    t, x, y = check_series(time, current, displacement)
    (n, l), _ = resolve_order(x, y, order)  # noqa: E741
    record = prepare_record(x, y, time=t, epsilon=epsilon)
    fit = fit_record(record, n, l)
    estimate, final = estimate_resonance(record, fit, n, l)
    if not estimate.modelled:
        return ResonanceModel(fit.model, 0.0, 0.0)
    return ResonanceModel(final.model, estimate.frequency, estimate.decay, estimate.deflection)


#: The mode is kept when it lowers the whole-record RMS error by this fraction ...
RESONANCE_GAIN = 0.1

#: ... and raises the RMS error outside the ringing windows by at most this fraction of the
#: output's range (the order selection's absolute tolerance: smaller differences count as
#: equal).
OUTSIDE_TOLERANCE = 1e-3


@dataclass(frozen=True)
class ResonanceEstimate:
    """
    The output mode fitted on a record that rings, and whether the model carries it.

    Attributes
    ----------
    modelled : bool
        The model carries the mode.
    frequency : float
        Natural frequency [Hz] (0: none fitted).
    decay : float
        Time constant of the ringing's envelope [s].
    deflection : float
        The mode's deflection from Gamma's output at the first sample [m].
    detected_frequency : float
        The ringing frequency the analysis detected [Hz] (NaN: no ringing).
    static_error, error : float
        RMS error of the model simulated over the whole record from its first sample,
        without and with the mode [fraction of the output range].
    static_outside_error, outside_error : float
        The same on the samples outside the ringing windows.
    refitted : bool
        Gamma was fitted again on the output without the mode's part (step 2).

    """

    modelled: bool = False
    frequency: float = 0.0
    decay: float = 0.0
    deflection: float = 0.0
    detected_frequency: float = math.nan
    static_error: float = math.nan
    error: float = math.nan
    static_outside_error: float = math.nan
    outside_error: float = math.nan
    refitted: bool = False

    def describe(self) -> str:
        """Return what was found, in words (empty when no mode was fitted)."""
        if self.frequency <= 0.0:
            return ''
        what = (f'a lightly damped output mode rings at {self.frequency:.4g} Hz, decay'
                f' {1e3 * self.decay:.3g} ms')
        change = (f'whole-record RMS {100 * self.static_error:.3g} % ->'
                  f' {100 * self.error:.3g} %, outside the ringing'
                  f' {100 * self.static_outside_error:.3g} % -> {100 * self.outside_error:.3g}'
                  ' %')
        if self.modelled:
            return (f'{what}; modelled ({change}; the compensator inverts Gamma only: the mode'
                    ' is left to feedback or input shaping)')
        if self.error > (1.0 - RESONANCE_GAIN) * self.static_error:
            why = f'less than {100 * RESONANCE_GAIN:.0f} % better over the whole record'
        else:
            why = ('it rings after the kinks of the piecewise-linear Gamma where the record'
                   f' does not ring, raising the error there by more than'
                   f' {100 * OUTSIDE_TOLERANCE:.2g} % of the range')
        return f'{what}: not modelled ({change}: {why})'

    def to_json(self) -> dict[str, Any]:
        """Return the JSON form."""
        def finite(value: float) -> float | None:
            return value if math.isfinite(value) else None
        return {'modelled': self.modelled, 'frequency': self.frequency, 'decay': self.decay,
                'initial_deflection': self.deflection,
                'detected_frequency': finite(self.detected_frequency),
                'static_whole_record_rms_error': finite(self.static_error),
                'whole_record_rms_error': finite(self.error),
                'static_outside_ringing_rms_error': finite(self.static_outside_error),
                'outside_ringing_rms_error': finite(self.outside_error),
                'refitted': self.refitted}


def estimate_resonance(record: PreparedRecord, fit: RecordFit, n: int, l: int,  # noqa: E741
                       dynamics: InputDynamics = InputDynamics()
                       ) -> tuple[ResonanceEstimate, RecordFit]:
    """
    Fit the output mode of a record that rings after steps; keep it when it helps clearly.

    Parameters
    ----------
    record : PreparedRecord
        The record, with its analysis (ringing windows, detected frequency).
    fit : RecordFit
        Gamma fitted on the samples outside the ringing.
    n, l : int
        Its order.
    dynamics : InputDynamics
        The input dynamics modelled with Gamma.

    Returns
    -------
    estimate : ResonanceEstimate
        The mode found (``frequency`` 0: the record has no ringing to fit, or no time base).
    fit : RecordFit
        The fit of Gamma that goes with the mode: ``fit`` itself, or Gamma fitted again on
        the output without the mode's part (when that is better and the mode is kept).

    """
    t = record.time
    analysis = record.analysis
    if (t is None or not analysis.ringing or not math.isfinite(analysis.ringing_frequency)
            or not bool(np.all(np.diff(t) > 0.0))):
        return ResonanceEstimate(), fit
    y = record.displacement
    span = float(np.ptp(y))
    outside = record.keep
    start_rings = analysis.ringing[0][0] == 0          # the record starts ringing
    static = _whole(fit)
    first = fit_mode(t, static, y, analysis.ringing_frequency, deflection=start_rings)
    rung = output_mode(t, static, first.frequency, first.decay, first.deflection)
    options = [(first, fit, rung, False)]
    try:
        again = fit_record(replace(record, displacement=y - (rung - static)), n, l,
                           dynamics=dynamics, starts=fit.segments, burn_in=fit.burn_in)
    except (IdentificationError, DataError):
        again = None
    if again is not None:
        second = fit_mode(t, _whole(again), y, first.frequency, decay=first.decay,
                          deflection=start_rings)
        options.append((second, again, output_mode(t, _whole(again), second.frequency,
                                                   second.decay, second.deflection), True))
    static_error = _rms(static, y, span)
    static_outside = _rms(static[outside], y[outside], span)

    def passes(option: tuple[Any, RecordFit, FloatArray, bool]) -> bool:
        mode, _, sim, _ = option
        return bool(mode.error <= (1.0 - RESONANCE_GAIN) * static_error and _rms(
            sim[outside], y[outside], span) <= static_outside + OUTSIDE_TOLERANCE)

    kept = [option for option in options if passes(option)]
    mode, chosen, sim, refitted = min(kept or options, key=lambda option: option[0].error)
    estimate = ResonanceEstimate(
        modelled=bool(kept), frequency=mode.frequency, decay=mode.decay,
        deflection=mode.deflection, detected_frequency=analysis.ringing_frequency,
        static_error=static_error, error=mode.error, static_outside_error=static_outside,
        outside_error=_rms(sim[outside], y[outside], span), refitted=refitted)
    return estimate, (chosen if estimate.modelled else fit)


def with_mode(time: FloatArray | None, simulation: FloatArray,
              estimate: ResonanceEstimate) -> FloatArray:
    """
    Return a simulation of the model without the mode passed through the mode, if modelled.

    Parameters
    ----------
    time : ndarray of float, shape (N,), or None
        Sample times [s] (None: no mode can be modelled).
    simulation : ndarray of float, shape (N,)
        The model's output without the mode [m].
    estimate : ResonanceEstimate
        The mode.

    Returns
    -------
    ndarray of float, shape (N,)
        ``R[simulation]``, or ``simulation`` itself.

    """
    if time is None or not estimate.modelled:
        return simulation
    return output_mode(time, simulation, estimate.frequency, estimate.decay,
                       estimate.deflection)


def _plot(ax: Any, time: FloatArray, current: FloatArray, measured: FloatArray,
          baseline: FloatArray, extended: FloatArray, start: int, *,
          units: AxisUnits | None = None, parameters: Mapping[str, Any] | None = None) -> None:
    # The largest step of the input in the scored part, and the output around it: the
    # baseline settles at once, the mode rings with the measured output.
    units = units or AxisUnits()
    fitted = parameters or {}
    f = float(fitted.get(RESONANCE_FREQUENCY, 0.0))
    decay = float(fitted.get(RESONANCE_DECAY, 0.0))
    x = current[start:]
    k = start + (int(np.argmax(np.abs(np.diff(x)))) + 1 if x.size > 1 else 0)
    # A step: the input moves by a tenth of its range between two samples (the analysis'
    # definition); else the plot shows the largest change of a smooth input, and says so.
    jump = float(abs(current[k] - current[k - 1])) if k > 0 else 0.0
    stepped = jump >= 0.1 * float(np.ptp(x)) if x.size > 1 else False
    span = 6.0 * decay if decay > 0.0 else 0.05
    keep = (time >= time[k] - 0.2 * span) & (time <= time[k] + span)
    ms = 1e3 * (time[keep] - time[k])
    ax.plot(ms, units.scale * measured[keep], lw=0.8, color='k', label='measured')
    ax.plot(ms, units.scale * baseline[keep], lw=0.8, label='baseline MPI')
    ax.plot(ms, units.scale * extended[keep], lw=0.8, label='MPI + mode')
    what = 'the largest input step' if stepped else 'the largest input change (no step)'
    ax.set_xlabel(f'time after {what} [ms]')
    ax.set_ylabel(f'displacement [{units.displacement}]')
    mode = (f'the mode f = {f:.4g} Hz, decay {1e3 * decay:.3g} ms' if f > 0.0
            else 'no mode fitted')
    head = ('resonance: the output after the largest input step;\n' if stepped else
            'resonance: the validation input has no step\n(it moves by at most'
            f' {100 * jump / max(float(np.ptp(x)), 1e-300):.2g} % of its range per sample);\n')
    ax.set_title(f'{head}{mode}', fontsize=10)


def _whole(fit: RecordFit) -> FloatArray:
    # The model simulated over the whole record from its first sample (its initial states).
    return np.asarray(fit.model.simulate(fit.material_input), dtype=np.float64)


def _rms(sim: FloatArray, y: FloatArray, span: float) -> float:
    return float(np.sqrt(np.mean((sim - y) ** 2)) / span)


def _plant_start(values: Mapping[str, Any]) -> FloatArray:
    f = float(values['resonance_frequency_hz'])
    return np.array([2.0 * math.pi * f, 1.0 / float(values['resonance_decay_s']),
                     *mode_state()])


def _plant_run(state: FloatArray, chunk: PlantChunk, signal: FloatArray) -> FloatArray:
    moved: FloatArray = mode_stream(chunk.time, signal, float(state[0]), float(state[1]),
                                    state[2:])
    return moved


def _plant_check(values: Mapping[str, Any]) -> tuple[str, str] | None:
    f = float(values.get('resonance_frequency_hz', 0.0))
    if f > 0.0 and not float(values.get('resonance_decay_s', 0.013)) > 1.0 / (2.0 * math.pi * f):
        return ('resonance_decay_s', f'> 1 / (2 pi f) = {1.0 / (2.0 * math.pi * f):.4g} s for'
                f' a mode of {f:g} Hz (it must ring: damping ratio below 1)')
    return None


#: A mechanical mode in the simulated plant (output side, after the other output steps):
#: the displacement drives ``p'' + (2 / T) p' + (2 pi f)^2 (p - s) = 0``; at rest at 0 before
#: the first sample.
PLANT = PlantEffect(
    stage='output', label='mechanical resonance', start=_plant_start, run=_plant_run,
    check=_plant_check,
    parameters=(
        PlantParameter('resonance_frequency_hz', 0.0,
                       'natural frequency of a lightly damped output mode, 0 = off', 'Hz',
                       low=0.0, note='(0 switches it off)', switch=True),
        PlantParameter('resonance_decay_s', 0.013,
                       "time constant of the mode's ringing envelope", 's', low=0.0,
                       low_open=True)))

#: The resonance effect, for the registry (:mod:`mpi_ros.extensions.effect`).  It has no
#: ``inverse_step``: a lightly damped mode cannot be inverted causally.
EFFECT = Effect(
    name='resonance', formula='R_(f, T)[Gamma[x]]',
    parameters=(
        EffectParameter(RESONANCE_FREQUENCY, 'double', 0.0,
                        'Resonance extension: natural frequency f of a lightly damped output'
                        ' mode (not invertible: the compensator inverts Gamma only and warns);'
                        ' 0: no mode', 'Hz', (0.0, 1.0e9)),
        EffectParameter(RESONANCE_DECAY, 'double', 0.0,
                        'Resonance extension: time constant T of the ringing envelope, above'
                        ' 1 / (2 pi f)', 's', (0.0, 1.0e3), plausible_max=FAST_TIME_LIMIT),
        EffectParameter(RESONANCE_DEFLECTION, 'double', 0.0,
                        "The identification record's start: the mode's deflection from"
                        " Gamma's output at the record's first sample (a record that starts"
                        ' ringing; used by start_state record only); 0: at rest', 'm'),
        EffectParameter(LEGACY_DEFLECTION, 'double', 0.0,
                        'Where files written before record_start.* hold the record start'
                        ' (read as record_start.resonance.initial_deflection)', 'm')),
    model_class=ResonanceModel, fit=fit_resonance,
    parameter_count=lambda p: 2 + int(float(p.get(RESONANCE_DEFLECTION) or 0.0) != 0.0),
    plot=_plot, stage='output', plant=PLANT,
    caption='Resonance: measured, baseline and mode output after the largest input step of'
            ' the validation data (the title says when the input has no step).')
