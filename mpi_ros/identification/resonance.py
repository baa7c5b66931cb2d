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
2. Gamma is fitted again, with the same order, start states, burn-in and input dynamics, on
   the output with the mode's part taken out, ``y - (R[g] - g)``, on every sample the first
   fit used and the ringing windows (the mode explains them); the mode is fitted again on the
   new ``g``.  The mode's gain at the excitation's frequencies (``1 / (1 - (f_x / f)^2)``) is
   then no longer absorbed twice, and the holds after steps enter Gamma's fit;
3. the better of the two is kept when it lowers the RMS error of the model simulated over the
   whole record from its first sample by :data:`RESONANCE_GAIN` or more (ringing windows are
   never held out, so this is the error the mode can change); otherwise the static model
   stays and the windows stay left out.
"""

from dataclasses import dataclass, replace
import math
from typing import Any

import numpy as np

from .procedure import fit_record, InputDynamics, PreparedRecord, RecordFit
from .qp import FloatArray
from ..errors import DataError, IdentificationError

__all__ = ['ResonanceEstimate', 'estimate_resonance', 'model_with_resonance', 'with_mode',
           'RESONANCE_GAIN']

#: The mode is kept when it lowers the whole-record RMS error by this fraction.
RESONANCE_GAIN = 0.1


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
    refitted: bool = False

    def describe(self) -> str:
        """Return what was found, in words (empty when no mode was fitted)."""
        if self.frequency <= 0.0:
            return ''
        what = (f'a lightly damped output mode rings at {self.frequency:.4g} Hz, decay'
                f' {1e3 * self.decay:.3g} ms')
        change = (f'whole-record RMS {100 * self.static_error:.3g} % ->'
                  f' {100 * self.error:.3g} %')
        if not self.modelled:
            return (f'{what}: not modelled ({change}, less than'
                    f' {100 * RESONANCE_GAIN:.0f} % better)')
        return (f'{what}; modelled ({change}; the compensator inverts Gamma only: the mode is'
                ' left to feedback or input shaping)')

    def to_json(self) -> dict[str, Any]:
        """Return the JSON form."""
        def finite(value: float) -> float | None:
            return value if math.isfinite(value) else None
        return {'modelled': self.modelled, 'frequency': self.frequency, 'decay': self.decay,
                'initial_deflection': self.deflection,
                'detected_frequency': finite(self.detected_frequency),
                'static_whole_record_rms_error': finite(self.static_error),
                'whole_record_rms_error': finite(self.error), 'refitted': self.refitted}


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
    start_rings = analysis.ringing[0][0] == 0          # the record starts ringing
    static = _whole(fit)
    static_error = _rms(static, y, span)
    first = fit_mode(t, static, y, analysis.ringing_frequency, deflection=start_rings)
    options = [(first, fit, False)]
    rung = output_mode(t, static, first.frequency, first.decay, first.deflection)
    try:
        again = fit_record(replace(record, displacement=y - (rung - static)), n, l,
                           dynamics=dynamics, starts=fit.segments, burn_in=fit.burn_in)
    except (IdentificationError, DataError):
        again = None
    if again is not None:
        second = fit_mode(t, _whole(again), y, first.frequency, decay=first.decay,
                          deflection=start_rings)
        options.append((second, again, True))
    mode, chosen, refitted = min(options, key=lambda option: option[0].error)
    estimate = ResonanceEstimate(
        modelled=bool(mode.error <= (1.0 - RESONANCE_GAIN) * static_error),
        frequency=mode.frequency, decay=mode.decay, deflection=mode.deflection,
        detected_frequency=analysis.ringing_frequency, static_error=static_error,
        error=mode.error, refitted=refitted)
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
