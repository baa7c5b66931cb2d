# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Identification of the MPI operator from measured data, section 4.2 of Kuhnen's paper.

The entry of :mod:`mpi_ros.identification`: :func:`identify` (order given or chosen on
held-out data by :func:`select_order` / :func:`select_record_order`) ties together
:mod:`.qp` (operating point, thresholds (28)-(31), checks of the data, the QP (34)-(36), the
straight-line baseline), :mod:`.procedure` (record, segments, start states, dynamics grid,
refusals, the start states) and :mod:`.dynamics`; the output mode of a record that rings is
fitted here (below, "The output mode").

Three parts, as in the paper:

1. Thresholds and initial states from the data: ``r_Hi = i/(n+1) ||x||_inf``
   (28), ``r'_S0 = 0`` (29), ``r'_Si = (i - 1/2)/l max y`` (30),
   ``r'_S-i = (i - 1/2)/l min y`` (31; the printed sign is a slip), ``z_H0 = 0`` (32).
2. The weights ``w_H`` of H and ``w'_S`` of the inverse superposition operator
   S' minimise the L2 norm of the generalised error
   ``E = w_H^T H_rH[x] - w'_S^T S_r'S[y]`` (33)-(34), subject to the
   invertibility constraints (35) and the equality constraint (36); a convex
   QP solved with OSQP.
3. ``S`` follows from ``S'`` by the laws (22)-(25).

Real records (documented in docs/design.md, "Identification on real records"):

- **Operating point.** The paper's data start at the origin (demagnetised actuator,
  displacement 0 at zero current).  A rig's data do not: the sensor has an arbitrary
  zero, the drive a bias, some sensors fall as the actuator extends, and a record starts
  mid-history.  By default (``anchor='operating_point'``) the input is centred on the
  middle of its range ``x0`` and scaled by half its range, so (28) places the play
  thresholds over the loops the data actually contain; the output is centred on the
  middle of its range, multiplied by the sign detected from the data (slope of the
  straight-line fit), and (29)-(31) place S' thresholds on both sides.  A constant term
  ``c`` in the generalised error, ``E = w_H^T H[x - x0] - w'_S^T S'[v] + c``, keeps the
  QP convex (it is eliminated exactly: the columns' covariance replaces their Gram
  matrix, and ``c = -mean(columns) . w``); since ``H[u] + c = H[u + c / sum w_H]``
  once the plays' states are set by the data, it is an exact shift of the input offset.
  The result is invariant to a constant added to the displacement or the current and
  to the output's sign.
  ``anchor='origin'`` is the paper's design as printed (for data that start at rest at
  the origin).
- **Unknown start state.** The plays start at the centre (``z = 0``), which is almost
  never the true state of a record that starts mid-history.  By the wiping-out property a
  play with threshold ``r`` forgets its initial state once the input has swept over a
  range of ``2 r``, and so does the actuator (any hysteresis with that property) once
  the input has visited both extremes of the record; the generalised error is
  therefore minimised only over the samples after the input first covered its range
  (99 %): the fit uses only what the data determine, not the initial loading curve.
  The returned model's initial states are the plays at rest at the record's lowest
  input (where an actuator rests when it is off; the paper's ``z_H0 = 0`` at ``x = 0``
  for data that start there): a compensator starts from that state.
- **Refusals.** A record whose output is not monotone in the input (correlation below
  0.3, or, anywhere in the record, burn-in included, a move against the input within one
  sweep of more than 15 % of the output range beyond the noise: butterfly loops), too
  little excitation for the order, or a fit no better than a straight line on the same
  samples or absurd is refused with :class:`IdentificationError`.
- The data are scaled internally; all thresholds follow the data, so results do not
  depend on units.
- A branch of S' the output never reaches (the output stays on one side of
  0 except for less than 1 % of its range) gets no thresholds: its weights
  would be undetermined by the data.
- A tiny ridge (1e-9 of the mean diagonal) makes the QP strictly convex,
  so the solution is unique even when plays are collinear on the data.
- The solver status is always checked and the constraints re-checked on the
  result: a failure raises :class:`IdentificationError`, never a silently
  non-invertible model.

**The output mode** of a record that rings after steps: fitted, judged, kept or not.

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

from collections.abc import Callable
from dataclasses import dataclass, field, replace
import math
import time as time_module
from typing import Any
import warnings

import numpy as np
import numpy.typing as npt

from .dynamics import return_point_drift
from .finding import DynamicsFinding, estimate_record_dynamics, finding_of, reference_order
from .procedure import (DynamicsEstimate, fit_record, fold_line_errors, FoldErrors, FOLDS,
                        held_out_rows, InputDynamics, prepare_record, PreparedRecord,
                        RecordFit, refuse_if_unmodellable, Segment, StartState)
from .qp import _check_excitation, _check_signals, _errors, _quality_check, ANCHORS, \
    DEFAULT_ORDERS, FloatArray, output_sign
from ..errors import DataError, IdentificationError, MPIWarning
from ..operators.model import MPIModel

__all__ = ['DEFAULT_ORDERS', 'estimate_resonance', 'IdentificationResult', 'identify',
           'model_with_dynamics', 'model_with_resonance', 'OUTSIDE_TOLERANCE', 'RESONANCE_GAIN',
           'ResonanceEstimate', 'select_order', 'select_record_order', 'with_mode']

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


def _finite(value: float) -> float | None:
    return value if math.isfinite(value) else None


def _rms(sim: FloatArray, y: FloatArray, span: float) -> float:
    return float(np.sqrt(np.mean((sim - y) ** 2)) / span)


@dataclass(frozen=True)
class IdentificationResult:
    """
    Outcome of :func:`identify`.

    Attributes
    ----------
    model : MPIModel
        The identified Gamma (SI units); its initial states are the record's start state.
        With input dynamics (``dynamics``), Gamma of the delayed / lagged input: the whole
        model is :attr:`full_model`.
    order : tuple of int
        ``(n, l)``.
    nonlinearity_error : float
        (37) of the model's simulation on the fitted samples (those the weights were
        fitted on; :attr:`whole_record_rms_error` covers every sample), with the output's
        range in place of ``max|Gamma[x]|`` (the two agree when the output starts at 0, as
        in the paper; the range does not depend on the sensor's zero) [fraction].
    rms_error : float
        RMS error of the simulation on the fitted samples over the output's range.
    samples : int
        Number of samples in the record.
    solver_status : str
        OSQP's status text (always ``'solved'`` for a returned result).
    iterations : int
        OSQP iterations.
    solve_time : float
        Wall time of the whole identification [s].
    order_table : list of dict
        Rows ``{'n', 'l', 'nonlinearity_error', 'rms_error'}`` (held-out data)
        of the order selection; empty when the order was given.
    linear_rms_error : float
        RMS error of the best straight line ``y = a x + b`` on the same samples, over the
        output's range: the baseline every fit is checked against.
    burn_in : int
        Samples at the start left out of the fit because no start state explains them
        (0 when the start state is determined; see :mod:`.procedure`, "Start states").
    whole_record_rms_error : float
        RMS error of the model simulated over the whole record from its first sample
        (ringing and burn-in included), over the output's range.
    start_state : dict
        How the record starts: ``kind``, ``levels`` (turning points, input unit),
        ``description``.
    segments : list of dict
        The experiments of a stitched record: ``start``, ``stop``, ``reason``,
        ``start_state``.
    dynamics : InputDynamics
        Dead time and lag of the input path modelled with Gamma (zeros: none).
    dynamics_estimate : DynamicsEstimate
        Both kinds as estimated (with a time base), their held-out errors, whether they tie.
    dynamics_finding : DynamicsFinding
        Lag, dead time, tie or none (:mod:`.finding`: the rule ``mpi-ros diagnose`` states
        for the same record, with the step response's check of a dead time).
    findings : str
        What moves the output against the input (ringing, lag, dead time), in words.
    excluded : int
        Samples of ringing the analysis found after steps (left out of the static fit).
    resonance : ResonanceEstimate
        The lightly damped output mode fitted on the ringing (with a time base), and whether
        the model carries it (:attr:`full_model`; see "The output mode" above).
    notes : list of str
        What the identification changed or noticed (lowered order, burn-in, ...).
    held_out_error : float
        RMS output error of the fit's procedure on the record's held-out blocks (blocked
        cross-validation: :data:`~mpi_ros.identification.procedure.FOLDS` contiguous folds of
        the record's first 100000 samples, each held out once), over the output's range.
    held_out_errors : list of float
        The same per fold, in the record's order.
    line_held_out_error : float
        The straight line's on the same folds (fitted on the others).
    line_held_out_errors : list of float
        The line's per fold.
    weights_from : str
        Where the weights came from: ``'determined'`` (the rows after the plays are
        determined; the start state explains the rows before with those weights) or
        ``'joint'`` (every row with the start state), chosen by the held-out error.

    """

    model: MPIModel
    order: tuple[int, int]
    nonlinearity_error: float
    rms_error: float
    samples: int
    solver_status: str
    iterations: int
    solve_time: float
    order_table: list[dict[str, Any]] = field(default_factory=list)
    linear_rms_error: float = math.nan
    burn_in: int = 0
    whole_record_rms_error: float = math.nan
    start_state: dict[str, Any] = field(default_factory=dict)
    segments: list[dict[str, Any]] = field(default_factory=list)
    dynamics: InputDynamics = field(default_factory=InputDynamics)
    dynamics_estimate: DynamicsEstimate = field(default_factory=DynamicsEstimate)
    dynamics_finding: DynamicsFinding = field(default_factory=DynamicsFinding)
    findings: str = ''
    excluded: int = 0
    notes: list[str] = field(default_factory=list)
    resonance: ResonanceEstimate = field(default_factory=ResonanceEstimate)
    held_out_error: float = math.nan
    held_out_errors: list[float] = field(default_factory=list)
    line_held_out_error: float = math.nan
    line_held_out_errors: list[float] = field(default_factory=list)
    weights_from: str = 'joint'

    @property
    def full_model(self) -> Any:
        """Return the model with its input dynamics and output mode (Gamma when none)."""
        return model_with_resonance(model_with_dynamics(self.model, self.dynamics),
                                    self.resonance)

    def summary(self) -> dict[str, Any]:
        """Return the result as a JSON-ready dict: ``order``, errors, ``samples``, table."""
        m = self.model
        return {'order': list(self.order), 'nonlinearity_error': self.nonlinearity_error,
                'rms_error': self.rms_error, 'linear_rms_error': self.linear_rms_error,
                'whole_record_rms_error': self.whole_record_rms_error,
                'samples': self.samples, 'burn_in': self.burn_in,
                'excluded_ringing_samples': self.excluded,
                'operating_point': {'input_offset': m.input_offset,
                                    'output_offset': m.output_offset,
                                    'output_sign': m.output_sign},
                'start_state': self.start_state, 'segments': self.segments,
                'dynamics': {**self.dynamics_estimate.to_json(), 'findings': self.findings,
                             'finding': self.dynamics_finding.to_json()},
                'resonance': self.resonance.to_json(),
                'notes': list(self.notes),
                'solver_status': self.solver_status, 'iterations': self.iterations,
                'solve_time': self.solve_time, 'order_table': self.order_table,
                'held_out': {'folds': len(self.held_out_errors),
                             'rms_error': _finite(self.held_out_error),
                             'per_fold': [_finite(v) for v in self.held_out_errors],
                             'line_rms_error': _finite(self.line_held_out_error),
                             'line_per_fold': [_finite(v) for v in self.line_held_out_errors],
                             'weights_from': self.weights_from}}


def model_with_dynamics(model: MPIModel, dynamics: InputDynamics) -> Any:
    """
    Return Gamma with input dynamics as the extended model the compensator reads.

    Parameters
    ----------
    model : MPIModel
        Gamma (of the delayed / lagged input).
    dynamics : InputDynamics
        Dead time and lag.

    Returns
    -------
    MPIModel or extended model
        Gamma itself, a dead-time model or a rate-dependence (input lag) model.

    """
    if not dynamics.present:
        return model
    from ..extensions import DeadTimeModel, RateDependentModel
    if dynamics.lag_time_constant > 0.0 and dynamics.dead_time > 0.0:
        msg = 'a dead time and a lag together are not supported yet'
        raise IdentificationError(msg)
    if dynamics.lag_time_constant > 0.0:
        return RateDependentModel(model, dynamics.lag_time_constant)
    return DeadTimeModel(model, dynamics.dead_time)


def identify(current: npt.ArrayLike, displacement: npt.ArrayLike, *, n: int | None = None,
             l: int | None = None, order: str | tuple[int, int] | None = None,  # noqa: E741
             epsilon: float = 1e-6, holdout: float = 0.3,
             anchor: str = 'operating_point', periodic: bool = False,
             time: npt.ArrayLike | None = None, dynamics: str = 'auto',
             progress: Callable[[str], None] | None = None) -> IdentificationResult:
    """
    Identify a modified Prandtl-Ishlinskii model from measured input/output data.

    The whole record is used from its first sample: the start state is estimated (see
    :mod:`.procedure`, "Start states"), ringing after steps is left out, lag and dead time are
    measured and, with a time base, modelled (see :mod:`.procedure`); with a time base,
    ringing after steps is then modelled as a lightly damped output mode when that lowers
    the whole-record error clearly (see "The output mode" in this module;
    :attr:`IdentificationResult.full_model` carries it).  The record may have any
    sensor zero, input bias or output sign.  The fit is refused, never returned, for a
    butterfly loop or switching transients, an output unrelated to the input, a fit no
    better than a straight line on the same data or absurd, or too little excitation.

    Parameters
    ----------
    current : array_like of float, shape (N,)
        Measured input ``x`` (coil current [A]; any unit works, results scale).
    displacement : array_like of float, shape (N,)
        Measured output ``y`` (displacement [m]; any zero, either sign).
    n, l : int, optional
        Model orders (default 14 and 7, the paper's final order).
    order : 'auto' or (int, int), optional
        ``'auto'`` raises the order until the held-out error saturates; a tuple gives
        ``(n, l)``.
    epsilon : float
        The small positive bound in (8) and (19), relative to the scaled data.
    holdout : float
        Held-out fraction (order selection and dynamics).
    anchor : {'operating_point', 'origin'}
        Where thresholds and states are anchored, see :func:`scaled_design`.
    periodic : bool
        The record is one period of a periodic excitation the actuator had been following
        (e.g. a single measured loop that ends where it starts): its start state is the
        state at its end, instead of the one estimated.  Needs an explicit order.
    time : array_like of float, shape (N,), optional
        Sample times [s]: lag and dead time are then measured in seconds and modelled
        (``dynamics``); a stitched record's clock may restart (a join).
    dynamics : {'auto', 'off'}
        ``'auto'``: with a time base, estimate the input's dead time and lag and model them
        when they cut the held-out error clearly, and an output mode when the output rings
        after steps; ``'off'``: the static model only (the diagnosis' baseline).
    progress : callable, optional
        Called with a line of text at each phase, each trial fit of the dynamics grid and
        each order tried (for a progress display such as :class:`mpi_ros.app.progress.Progress`).

    Returns
    -------
    IdentificationResult
        The model and its fit statistics.

    Raises
    ------
    DataError
        For malformed data (lengths, non-finite values) or options.
    IdentificationError
        For an output the MPI model cannot represent (the message names the cause), too
        little excitation, a failed QP, or a fit no better than a straight line.

    Examples
    --------
    >>> import numpy as np
    >>> t = np.linspace(0.0, 1.0, 2001)
    >>> x = np.sin(2 * np.pi * 3 * t) * np.exp(-t)
    >>> truth = MPIModel.from_params({
    ...     'model.hysteresis.thresholds': [0.0, 0.3], 'model.hysteresis.weights': [1.0, 0.4],
    ...     'model.superposition.thresholds': [0.0], 'model.superposition.weights': [2e-5]})
    >>> y = 3.0 - truth.simulate(x)          # a sensor with its own zero, falling
    >>> result = identify(x, y, n=4, l=2)
    >>> result.nonlinearity_error < 0.05, result.model.output_sign
    (True, -1)

    """
    started = time_module.perf_counter()
    x, y = _check_signals(current, displacement)
    t = _check_time(time, x.size)
    if anchor not in ANCHORS:
        msg = f"anchor must be one of {', '.join(ANCHORS)}; found {anchor!r}"
        raise DataError(msg)
    if dynamics not in ('auto', 'off'):
        msg = f"dynamics must be 'auto' or 'off'; found {dynamics!r}"
        raise DataError(msg)
    if not 0.0 < holdout < 1.0:
        msg = f'holdout must be a fraction in (0, 1); found {holdout}'
        raise DataError(msg)
    auto = order == 'auto'
    if order is not None and not auto:
        if isinstance(order, str) or len(order) != 2:
            msg = f"order must be 'auto' or a pair (n, l); found {order!r}"
            raise DataError(msg)
        n, l = int(order[0]), int(order[1])  # noqa: E741
    n = 14 if n is None else int(n)
    l = 7 if l is None else int(l)  # noqa: E741
    if n < 0 or l < 0:
        msg = f'model orders must be >= 0; found n={n}, l={l}'
        raise DataError(msg)
    if periodic:
        _check_one_period(x, order)
    _check_levels(x, y)
    say = progress if progress is not None else _silent
    say(f'analysing the record ({x.size} samples)')
    record = prepare_record(x, y, time=t, anchor=anchor, epsilon=epsilon)
    keep = record.keep
    _, correlation = output_sign(x[keep], y[keep])
    try:
        refuse_if_unmodellable(record, correlation)
    except IdentificationError as err:
        raise _true_cause(err, x, y) from None
    notes: list[str] = []
    if periodic:
        record = replace(record, segments=[Segment(0, x.size, 'start', StartState('periodic'))])
    n, l, lowered = _supported_order(x.size, n, l, auto)  # noqa: E741
    if lowered:
        notes.append(lowered)
    _check_excitation(x, y, n if not auto else 0, l if not auto else 0, anchor=anchor)
    choose = not periodic
    # Dynamics and the order are decided at (8, 4) (or lower for a record too short for
    # it): rich enough that a lag does not stand in for the hysteresis a low order misses.
    reference = reference_order(x.size, n, l)
    estimate = DynamicsEstimate()
    if t is not None and dynamics == 'auto':
        # On a window of a long record: trials cost the window, not the record (the
        # analysis `mpi-ros diagnose` states for the same record).
        estimate = estimate_record_dynamics(record, reference, holdout=holdout, choose=choose,
                                            progress=progress)
    # Lag, dead time, tie or none, with the step response's check of a dead time.
    finding = finding_of(record, estimate) if dynamics == 'auto' else DynamicsFinding()
    if finding.kind != 'unavailable':
        estimate = replace(estimate, modelled=finding.modelled)
    found = estimate.modelled
    table: list[dict[str, Any]] = []
    if auto:
        trial = record.window(_ORDER_WINDOW)
        held = held_out_rows(trial.current.size, holdout, trial.keep)
        say('order selection: start state of the trial window')
        base = fit_record(trial, *reference, dynamics=found, held=held, choose=choose,
                          rule='joint start')
        (n, l), table = select_record_order(trial, held, found, base.segments,
                                            burn_in=base.burn_in, progress=progress,
                                            rule=base.rule)
        n, l = _excited_order(x, y, (n, l), table, anchor, notes)  # noqa: E741
    say(f'fitting n={n}, l={l} on the whole record')
    fit = fit_record(record, n, l, dynamics=found, choose=choose, memory_steps=True,
                     validate=True)
    notes.extend(fit.notes)
    held_out = fit.folds.get(fit.rule, FoldErrors())
    scored = keep.copy()
    scored[:fit.burn_in] = False
    line = fold_line_errors(x, y, scored)
    resonance = ResonanceEstimate()
    if t is not None and dynamics == 'auto' and record.analysis.ringing:
        say('ringing: fitting the output mode')
        resonance, fit = estimate_resonance(record, fit, n, l, found)
    say('judging the fit against the straight line')
    sim = with_mode(t, fit.simulate(), resonance)    # each segment from its start state
    fitted = fit.fitted if fit.fitted is not None else keep
    try:
        rms, peak, linear = _quality_check(x, y, sim, fitted, n, l, anchor, chosen=auto)
        notes.extend(_judge_held_out(held_out, line, rms, (n, l), auto, table, x,
                                     record.window(_ORDER_WINDOW).current.size))
    except IdentificationError as err:
        raise _true_cause(err, x, y) from None
    drift = return_point_drift(x, y)
    if drift.drifts:
        # Modelled better than a line on the held-out blocks, but not what the model misses.
        note = (f'warning: {drift.describe()}: the MPI model cannot follow it; its held-out'
                f' RMS error {100 * held_out.error:.3g} % of the range (the line'
                f' {100 * line.error:.3g} %) includes it')
        warnings.warn(note, MPIWarning, stacklevel=2)
        notes.append(note)
    # What `mpi-ros simulate` gives: the model from its initial states, straight through
    # (Gamma of the input after the dynamics, then the output mode if one is modelled); one
    # segment from sample 0 without a mode is that already.
    if resonance.modelled:
        full = model_with_resonance(model_with_dynamics(fit.model, found), resonance)
        straight = full.simulate(t, x)
    else:
        one = len(fit.segments) == 1 and fit.segments[0].start == 0
        straight = sim if one else fit.model.simulate(fit.material_input)
    whole = _rms(straight, y, float(np.ptp(y)))
    design = fit.design
    first = fit.segments[0].start_state

    def to_input(level: float) -> float:
        return float(design.input_offset + level * design.x_scale)

    start = ({**first.to_json(to_input), 'description': first.describe(to_input, 'A')}
             if first is not None else {'kind': 'continue', 'levels': [],
                                        'description': 'continues'})
    segments = [{'start': s.start, 'stop': s.stop, 'reason': s.reason,
                 'start_state': (s.start_state.to_json(to_input) if s.start_state is not None
                                 else {'kind': 'continue', 'levels': []})}
                for s in fit.segments]
    if len(fit.segments) > 1:
        notes.append(f'{len(fit.segments)} segments (joins at samples '
                     f'{", ".join(str(s.start) for s in fit.segments[1:])}: '
                     f'{"; ".join(s.reason for s in fit.segments[1:])}), each with its own'
                     ' start state')
    findings = '; '.join(part for part in (record.analysis.describe(), resonance.describe(),
                                           estimate.describe(), finding.describe()) if part)
    info = fit.info
    return IdentificationResult(
        model=fit.model, order=(n, l), nonlinearity_error=peak, rms_error=rms,
        samples=int(x.size), solver_status=str(info.status), iterations=int(info.iter),
        solve_time=time_module.perf_counter() - started, order_table=table,
        linear_rms_error=linear, burn_in=int(fit.burn_in), whole_record_rms_error=whole,
        start_state=start, segments=segments, dynamics=found, dynamics_estimate=estimate,
        dynamics_finding=finding, findings=findings,
        excluded=int(np.count_nonzero(~keep)), notes=notes, resonance=resonance,
        held_out_error=held_out.error, held_out_errors=list(held_out.per_fold),
        line_held_out_error=line.error, line_held_out_errors=list(line.per_fold),
        weights_from=fit.rule)


def _silent(text: str) -> None:
    pass


def _true_cause(err: IdentificationError, x: FloatArray, y: FloatArray) -> IdentificationError:
    # A refusal of a record whose output drifts at the input's return points names the
    # drift first (a leakage drift under loops looks unrelated, or worse than a line).
    drift = return_point_drift(x, y)
    if not drift.drifts:
        return err
    return IdentificationError(f'{drift.describe()}: the MPI model cannot follow it; {err}')


#: A held-out error this many times the in-sample one (and :data:`_FAR_ABSOLUTE` of the
#: output's range above it) is far from it: a warning, with the numbers.
_FAR_FACTOR = 2.0
_FAR_ABSOLUTE = 0.005


def _judge_held_out(held_out: FoldErrors, line: FoldErrors, rms: float, order: tuple[int, int],
                    auto: bool, table: list[dict[str, Any]], x: FloatArray,
                    window: int) -> list[str]:
    # The fit on the record's own held-out blocks: refused when no better than a straight
    # line there, a warning when far from its in-sample figure or from its order-table row.
    n, l = order  # noqa: E741
    if not math.isfinite(held_out.error):
        return []
    folds = ', '.join(f'{100 * v:.3g}' for v in held_out.per_fold)
    lines = ', '.join(f'{100 * v:.3g}' for v in line.per_fold)
    worst = int(np.nanargmax(np.where(np.isfinite(held_out.per_fold), held_out.per_fold,
                                      -np.inf)))
    outside = _outside_fraction(x, worst, len(held_out.per_fold))
    where = (f'fold {worst + 1} of {len(held_out.per_fold)} is worst'
             + (f'; {100 * outside:.3g} % of its input lies outside the range of the other'
                ' folds (the model extrapolates there)' if outside > 0.0 else ''))
    notes: list[str] = []
    if (n + l > 0 or auto) and math.isfinite(line.error) and held_out.error >= line.error:
        # Clearly worse (by more than _FAR_ABSOLUTE of the range: folds of small loops tie
        # with the line at the noise) on most folds, where the input stays inside the range
        # the fold was fitted on (a fold that holds the record's widest sweep extrapolates:
        # a warning below, not a refusal).
        pairs = [(m, b) for m, b in zip(held_out.interior_per_fold, line.interior_per_fold)
                 if math.isfinite(m) and math.isfinite(b)]
        worse = sum(1 for m, b in pairs if m > b + _FAR_ABSOLUTE)
        if 2 * worse > len(held_out.per_fold):
            msg = (f'the identified model (n={n}, l={l}) is no better than a straight line on'
                   f" the record's held-out blocks ({FOLDS} contiguous folds, each fitted on"
                   f' the others): RMS {100 * held_out.error:.3g} % of the output range vs'
                   f' {100 * line.error:.3g} % for the line (per fold {folds} % vs {lines} %;'
                   f' {where}); in sample it is {100 * rms:.3g} %: the fit does not carry over'
                   ' within its own record (drift or leakage, switching, or a part of the'
                   ' record no other part resembles); record more cycles of the same'
                   ' excitation, or remove the drift')
            raise IdentificationError(msg)
        note = (f"warning: on the record's held-out blocks the model is worse than a straight"
                f' line ({100 * held_out.error:.3g} % vs {100 * line.error:.3g} % RMS; per'
                f' fold {folds} % vs {lines} %; {where}), clearly so inside the range each fold'
                f' was fitted on on {worse} of {len(held_out.per_fold)} folds only;'
                f' {100 * held_out.outside:.3g} % of the held-out input lies outside that range:'
                ' keep new inputs inside the identified range')
        warnings.warn(note, MPIWarning, stacklevel=3)
        notes.append(note)
    # The median fold: the fold of the record's start (its transient, the input outside
    # the range) alone is no reason to expect worse on new inputs; several folds are.
    typical = float(np.nanmedian(held_out.per_fold))
    if typical > max(_FAR_FACTOR * rms, rms + _FAR_ABSOLUTE):
        note = (f"warning: on the record's held-out blocks the model is off by"
                f' {100 * held_out.error:.3g} % RMS of the output range (per fold {folds} %,'
                f' median {100 * typical:.3g} %; {where}), against {100 * rms:.3g} % in'
                f' sample; better than a straight line there ({100 * line.error:.3g} %), but'
                ' expect the larger figure on new inputs')
        warnings.warn(note, MPIWarning, stacklevel=3)
        notes.append(note)
    row = next((r for r in table if (r['n'], r['l']) == order), None)
    if row is not None and not (0.5 * row['rms_error'] <= held_out.error
                                <= _FAR_FACTOR * row['rms_error'] + _FAR_ABSOLUTE):
        scope = (f'the busiest {window} samples' if window < x.size else 'the whole record')
        notes.append(f"the order table's row for n={n}, l={l} (held-out RMS"
                     f" {100 * row['rms_error']:.3g} %) and the chosen model's held-out error"
                     f' ({100 * held_out.error:.3g} %) differ: the table holds out 30 short'
                     f' blocks of {scope} (every kind of excitation on both sides), the'
                     f' model {FOLDS} long contiguous folds of the record ({where})')
    return notes


def _outside_fraction(x: FloatArray, fold: int, folds: int) -> float:
    # Fraction of a fold's input outside the range of the other folds' input.
    from .procedure import fold_index
    size = min(x.size, 100000)
    index = fold_index(size, folds)
    mine, others = x[:size][index == fold], x[:size][index != fold]
    if not mine.size or not others.size:
        return 0.0
    return float(np.mean((mine < np.min(others)) | (mine > np.max(others))))


def _excited_order(x: FloatArray, y: FloatArray, order: tuple[int, int],
                   table: list[dict[str, Any]], anchor: str,
                   notes: list[str]) -> tuple[int, int]:
    # The order chosen, or, when the record's excitation does not support it, the best
    # lower order of the table that it supports (refused only when none is).
    try:
        _check_excitation(x, y, *order, anchor=anchor)
        return order
    except IdentificationError as err:
        first = err
    lower = sorted((r for r in table if not r['unstable']
                    and r['n'] + 2 * r['l'] < order[0] + 2 * order[1]),
                   key=lambda r: r['rms_error'])
    for row in lower:
        try:
            _check_excitation(x, y, row['n'], row['l'], anchor=anchor)
        except IdentificationError:
            continue
        notes.append(f"order lowered from n={order[0]}, l={order[1]} to n={row['n']},"
                     f" l={row['l']} (the next best held-out error,"
                     f" {100 * row['rms_error']:.3g} %): {first}")
        return row['n'], row['l']
    raise first


def _check_time(time: npt.ArrayLike | None, size: int) -> FloatArray | None:
    if time is None:
        return None
    t = np.asarray(time, dtype=np.float64).reshape(-1)
    if t.size != size:
        msg = f'time must have one value per sample ({size}); found {t.size}'
        raise DataError(msg)
    bad = np.flatnonzero(~np.isfinite(t))
    if bad.size:
        msg = (f'time contains {bad.size} non-finite value(s), the first at sample {bad[0]};'
               ' remove or repair them')
        raise DataError(msg)
    return t


def _check_levels(x: FloatArray, y: FloatArray) -> None:
    # Too few samples, or an input or output that does not move: nothing to identify.
    _check_excitation(x, y, 0, 0)


#: Samples of the window the order selection runs on.
_ORDER_WINDOW = 100000

#: Fewer samples than this (or than two per weight of the requested order) are too few to
#: lower the order for: the order stays and the excitation check refuses the record.
_SHORT_RECORD = 60


def _supported_order(size: int, n: int, l: int,  # noqa: E741
                     auto: bool) -> tuple[int, int, str]:
    # At least ten samples per weight (a short record, such as one quasi-static loop of a
    # few hundred samples, gets a lower order and a note, not a refusal).
    weights = n + 1 + 2 * l + 1
    if auto or size >= 10 * weights or size < max(_SHORT_RECORD, 2 * weights):
        # Below two samples per weight an explicit order is refused (excitation check).
        return n, l, ''
    scale = (size / 10.0 - 2.0) / (n + 2 * l) if n + 2 * l > 0 else 0.0
    n2 = max(int(n * scale), 0)
    l2 = max(int(l * scale), 0)  # noqa: E741
    note = (f'order lowered from n={n}, l={l} to n={n2}, l={l2}: the record has only {size}'
            ' samples (at least ten per weight are used)')
    return n2, l2, note


def _check_one_period(x: npt.NDArray[Any], order: Any) -> None:
    span = float(np.ptp(x))
    if abs(float(x[-1]) - float(x[0])) > 0.02 * span:
        gap = 100.0 * abs(float(x[-1]) - float(x[0])) / span
        msg = (f'periodic: the record must end where it starts (one period); the input goes'
               f' from {float(x[0]):.6g} to {float(x[-1]):.6g}, {gap:.1f} % of its range'
               ' apart; cut it to whole periods')
        raise DataError(msg)
    if order == 'auto':
        msg = ("periodic: order 'auto' needs held-out data beyond one period; give the order"
               ' (e.g. 8,4), or record several periods and leave periodic off')
        raise DataError(msg)


def select_order(current: npt.ArrayLike, displacement: npt.ArrayLike, *,
                 orders: tuple[tuple[int, int], ...] = DEFAULT_ORDERS,
                 holdout: float = 0.3, tolerance: float = 0.02, patience: int = 3,
                 absolute_tolerance: float = 1e-3, epsilon: float = 1e-6,
                 anchor: str = 'operating_point'
                 ) -> tuple[tuple[int, int], list[dict[str, Any]]]:
    """
    Choose (n, l) as in the paper: raise the order until the held-out error saturates.

    The determined part of the record (after the burn-in of the highest order tried) is
    cut into ten blocks; ``holdout`` of them, spread over the record, are held out and
    the rest train each order.  The model is simulated over the whole record (so each
    held-out block starts from the state the data before it leave) and (37), over the
    output's range, is measured on the held-out blocks.  An order that is worse than a
    lower one does not stop the search while no order has halved the first (linear)
    order's error (low orders often are worse, on real records); after that it stops
    when ``patience`` successive orders fail to improve the best error by more than the
    tolerance: the error has saturated.  The tolerance is the larger
    of ``tolerance`` (relative) and ``absolute_tolerance`` (fraction of the output
    range: differences below it are noise) for the stop.  The chosen order is the
    smallest whose held-out error is within ``tolerance`` (relative) of the best.

    Parameters
    ----------
    current : array_like of float, shape (N,)
        Input [A].
    displacement : array_like of float, shape (N,)
        Output [m].
    orders : tuple of (int, int)
        Candidate orders in increasing complexity.
    holdout : float
        Fraction of the determined samples held out, in (0, 1).
    tolerance : float
        Relative difference that counts as significant.
    patience : int
        Saturated orders before the search stops.
    absolute_tolerance : float
        Difference, as a fraction of the output range, below which errors count as equal.
    epsilon : float
        Bound of (8)/(19), scaled units.
    anchor : {'operating_point', 'origin'}
        See :func:`scaled_design`.

    Returns
    -------
    order : (int, int)
        The chosen order.
    table : list of dict
        ``{'n', 'l', 'nonlinearity_error', 'rms_error'}`` per order tried (held-out
        blocks, fractions of the output's range).

    """
    x, y = _check_signals(current, displacement)
    if not 0.0 < holdout < 1.0:
        msg = f'holdout must be a fraction in (0, 1); found {holdout}'
        raise DataError(msg)
    record = prepare_record(x, y, anchor=anchor, epsilon=epsilon)
    held = held_out_rows(x.size, holdout, record.keep)
    n_ref = min(8, max(n for n, _ in orders))
    base = fit_record(record, n_ref, n_ref // 2, held=held)
    return select_record_order(record, held, InputDynamics(), base.segments, orders=orders,
                               tolerance=tolerance, patience=patience,
                               absolute_tolerance=absolute_tolerance, burn_in=base.burn_in,
                               rule=base.rule)


def select_record_order(record: PreparedRecord, held: npt.NDArray[np.bool_],
                        dynamics: InputDynamics, starts: list[Segment], *,
                        orders: tuple[tuple[int, int], ...] = DEFAULT_ORDERS,
                        tolerance: float = 0.02, patience: int = 3,
                        absolute_tolerance: float = 1e-3, burn_in: int = 0,
                        progress: Callable[[str], None] | None = None,
                        rule: str = 'joint') -> tuple[
                            tuple[int, int], list[dict[str, Any]]]:
    """
    Choose (n, l) as in the paper: raise the order until the held-out error saturates.

    Each order (with at least ten training samples per weight) is fitted on the training
    blocks with the record's start states and dynamics, simulated over the whole record
    and scored on the held-out blocks by its RMS error over the output's range (and (37),
    reported).  The search stops when ``patience`` successive orders fail to improve the
    best error by the tolerance once an order has halved the linear one's; the chosen
    order is the smallest within ``tolerance`` (relative) of the best.  Orders whose
    held-out error is absurd (over the output's range) are marked ``unstable`` and not
    considered.

    Parameters
    ----------
    record : PreparedRecord
        The record.
    held : ndarray of bool, shape (N,)
        Held-out rows.
    dynamics : InputDynamics
        The input's dynamics.
    starts : list of Segment
        Start states (their kinds are kept for every order).
    orders : tuple of (int, int)
        Candidate orders in increasing complexity.
    tolerance : float
        Relative difference of held-out RMS errors that counts as significant.
    patience : int
        Saturated orders before the search stops.
    absolute_tolerance : float
        Difference, as a fraction of the output range, below which errors count as equal
        for the stop.
    burn_in : int
        Samples at the start left out of every fit (the reference fit's burn-in).
    progress : callable, optional
        Called with a line of text before each order is fitted (a progress display).
    rule : {'joint', 'determined'}
        Where each order's weights come from (the reference fit's rule, see
        :func:`~mpi_ros.identification.procedure.fit_record`).

    Returns
    -------
    order : (int, int)
        The chosen order.
    table : list of dict
        ``{'n', 'l', 'nonlinearity_error', 'rms_error', 'unstable'}`` per order tried
        (held-out blocks, fractions of the output's range).

    """
    y = record.displacement
    train = int(np.count_nonzero(record.keep & ~held))
    table: list[dict[str, Any]] = []
    best = math.inf
    saturated = 0
    for i, (n, l) in enumerate(orders):  # noqa: E741
        if train < 10 * (n + 2 * l + 2) and table:
            break
        if progress is not None:
            progress(f'order selection: n={n}, l={l} ({i + 1} of at most {len(orders)})')
        try:
            fit = fit_record(record, n, l, dynamics=dynamics, held=held, starts=starts,
                             choose=False, burn_in=burn_in, rule=rule)
        except IdentificationError:
            continue
        peak, rms = _errors(fit.simulate(), y, held)
        unstable = not (math.isfinite(rms) and rms < 1.0)
        table.append({'n': n, 'l': l, 'nonlinearity_error': peak, 'rms_error': rms,
                      'unstable': unstable})
        if unstable:
            continue
        first = next(r for r in table if not r['unstable'])['rms_error']
        margin = max(tolerance * best, absolute_tolerance) if math.isfinite(best) else 0.0
        if rms < best - margin or not math.isfinite(best):
            saturated = 0
        elif best < 0.5 * first:
            saturated += 1      # no better, once hysteresis models work: saturating
        best = min(best, rms)
        if saturated >= patience:
            break
    stable = [r for r in table if not r['unstable']]
    if not stable:
        msg = ('no order could be evaluated on the held-out blocks (every fit was absurd or'
               ' failed); give the order (e.g. 8,4), or record more cycles')
        raise IdentificationError(msg)
    chosen = next(r for r in stable if r['rms_error'] <= best * (1.0 + tolerance))
    return (chosen['n'], chosen['l']), table
