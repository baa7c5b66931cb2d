# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
The output mode of a record that rings after steps: fitted, judged, kept or not.

A rate-independent Gamma cannot follow ringing: :mod:`.dynamics` finds the windows after
steps where the output rings and leaves them out of the QP.  With a time base the
identification then models the ringing as a lightly damped mechanical mode after Gamma
(:mod:`mpi_ros.extensions.resonance`, ``s = R[Gamma[x]]``):

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

from dataclasses import dataclass, replace
import math
from typing import Any

import numpy as np

from .procedure import fit_record, InputDynamics, PreparedRecord, RecordFit
from .qp import FloatArray
from ..errors import DataError, IdentificationError

__all__ = ['ResonanceEstimate', 'estimate_resonance', 'model_with_resonance', 'with_mode',
           'RESONANCE_GAIN', 'OUTSIDE_TOLERANCE']

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
    from ..extensions.resonance import fit_mode, output_mode
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


def model_with_resonance(model: Any, estimate: ResonanceEstimate) -> Any:
    """
    Return a model with the output mode after it (the model itself when none is modelled).

    Parameters
    ----------
    model : MPIModel or extended model
        Gamma, or Gamma with input dynamics (a dead-time or rate-dependence model).
    estimate : ResonanceEstimate
        The mode.

    Returns
    -------
    MPIModel, ResonanceModel or CompositeModel
        ``R[model]``.

    """
    if not estimate.modelled:
        return model
    from ..extensions import CompositeModel
    from ..extensions.resonance import ResonanceModel
    gamma = getattr(model, 'model', model)
    mode = ResonanceModel(gamma, estimate.frequency, estimate.decay, estimate.deflection)
    if gamma is model:
        return mode
    return CompositeModel(gamma, (model, mode))


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
    from ..extensions.resonance import output_mode
    return output_mode(time, simulation, estimate.frequency, estimate.decay,
                       estimate.deflection)


def _whole(fit: RecordFit) -> FloatArray:
    # The model simulated over the whole record from its first sample (its initial states).
    return np.asarray(fit.model.simulate(fit.material_input), dtype=np.float64)


def _rms(sim: FloatArray, y: FloatArray, span: float) -> float:
    return float(np.sqrt(np.mean((sim - y) ** 2)) / span)
