# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Identify a model from a record: Gamma, its order, input dynamics and output mode, judged.

The procedure above the effects: :func:`identify` (order given or chosen on held-out data
by :mod:`mpi_ros.identification.order_selection`) ties together
:mod:`mpi_ros.identification` (operating point, thresholds (28)-(31), checks of the data, the
QP (34)-(36), the straight-line baseline, record, segments, start states, dynamics grid,
refusals), the input dynamics it finds (modelled as :mod:`mpi_ros.extensions.dead_time` or
:mod:`mpi_ros.extensions.rate_dependence`) and the output mode of a record that rings
(:func:`mpi_ros.extensions.resonance.estimate_resonance`); it returns an
:class:`IdentificationResult`.

Section 4.2 of Kuhnen's paper, on real records.  Steps (documented in docs/design.md,
"Identification on real records"):

1. **What moves the output against the input** (:mod:`mpi_ros.identification.dynamics`): a
   butterfly loop, switching transients or an output unrelated to the input are refused,
   naming the cause; ringing after steps is left out of the fit; lag and dead time are
   measured.
2. **Segments**: a record stitched from several experiments (time gaps, time running back,
   output jumps the input does not explain) is cut at the joins; each segment gets its own
   start state (:mod:`mpi_ros.identification.record`).
3. **Start state** (:mod:`mpi_ros.identification.start_states`): one QP per candidate
   history; the best is the record's start state, written into the model, so that the model
   simulated from the first sample reproduces the record.  A burn-in is kept only where no
   candidate explains the start (reported).
4. **Dynamics** (with a time base): a grid over the dead time and the time constant of a
   first-order lag of the input, one QP each, scored on held-out blocks by the output's
   RMS error; kept when it beats the static model on them clearly
   (:mod:`mpi_ros.identification.dynamics_grid`).
5. **Order** (``order='auto'``): raised until the held-out error saturates
   (:mod:`mpi_ros.identification.order_selection`).
6. **Judgement**: the model, simulated over the whole record from its start state, against
   the best straight line on the same samples; never a model worse than the line.

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


The output mode: see :mod:`mpi_ros.extensions.resonance`, "The output mode".
"""

from collections.abc import Callable
from dataclasses import dataclass, field, replace
import math
import time as time_module
from typing import Any
import warnings

import numpy as np
import numpy.typing as npt

from .errors import DataError, IdentificationError, MPIWarning
from .extensions import CompositeModel, DeadTimeModel, RateDependentModel
from .extensions.resonance import estimate_resonance, ResonanceEstimate, ResonanceModel, \
    with_mode
from .identification.dynamics import InputDynamics, return_point_drift
from .identification.dynamics_grid import DynamicsEstimate
from .identification.finding import DynamicsFinding, estimate_record_dynamics, finding_of, \
    reference_order
from .identification.fitter import fit_record, fold_line_errors, RecordFit
from .identification.folds import FoldErrors, held_out_rows, RECORD_FOLDS
from .identification.order_selection import ORDER_WINDOW, select_record_order
from .identification.qp import ANCHORS, check_excitation, check_quality, check_signals, \
    FloatArray, output_sign
from .identification.record import prepare_record, PreparedRecord, refuse_if_unmodellable, \
    Segment
from .identification.start_states import StartState
from .operators.model import MPIModel

__all__ = ['IdentificationResult', 'identify', 'model_with_dynamics', 'model_with_resonance']


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
        (0 when the start state is determined; see
        :mod:`mpi_ros.identification.start_states`).
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
        Lag, dead time, tie or none (:mod:`mpi_ros.identification.finding`: the rule
        ``mpi-ros diagnose`` states for the same record, with the step response's check of
        a dead time).
    findings : str
        What moves the output against the input (ringing, lag, dead time), in words.
    excluded : int
        Samples of ringing the analysis found after steps (left out of the static fit).
    resonance : ResonanceEstimate
        The lightly damped output mode fitted on the ringing (with a time base), and whether
        the model carries it (:attr:`full_model`; see "The output mode" in
        :mod:`mpi_ros.extensions.resonance`).
    notes : list of str
        What the identification changed or noticed (lowered order, burn-in, ...).
    held_out_error : float
        RMS output error of the fit's procedure on the record's held-out blocks (blocked
        cross-validation: :data:`~mpi_ros.identification.folds.RECORD_FOLDS` contiguous folds of
        the record's first 100000 samples, each held out once), over the output's range.
    held_out_errors : list of float
        The same per fold, in the record's order.
    line_held_out_error : float
        The straight line's on the same folds (fitted on the others).
    line_held_out_errors : list of float
        The line's per fold.
    held_out_judged : list of bool
        Per fold: it judges the model (its input stays inside the range its model was fitted
        on, :data:`~mpi_ros.identification.folds.JUDGED_MARGIN`); a fold that holds an
        excursion the others never make is reported, not judged: the refusal against the
        straight line reads the judged folds.
    weights_from : str
        Where the weights came from: ``'determined'`` (the rows after the plays are
        determined; the start state explains the rows before with those weights),
        ``'joint'`` (every row with the start state chosen under those weights), ``'joint
        start'`` (every row, the start state chosen jointly with the weights) or
        ``'averaged'`` (the mean of the weights of ``'joint start'`` and ``'determined'``,
        where their held-out errors tie: the record cannot tell them apart, and they differ
        in plays it never wipes out), chosen by the held-out error.

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
    held_out_judged: list[bool] = field(default_factory=list)
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
                             'judged': list(self.held_out_judged),
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
    :mod:`mpi_ros.identification.start_states`), ringing after steps is left
    out, lag and dead time are measured and, with a time base, modelled (see
    :mod:`mpi_ros.identification.fitter`); with a time base, ringing after steps is then
    modelled as a lightly damped output mode when that lowers the whole-record error clearly
    (see "The output mode" in :mod:`mpi_ros.extensions.resonance`;
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
        Where thresholds and states are anchored, see
        :func:`~mpi_ros.identification.scaled_design`.
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
        little excitation, a start that no history explains over more than half of the
        record, a failed QP, or a fit no better than a straight line.

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
    x, y, t, n, l, auto = _checked_arguments(  # noqa: E741
        current, displacement, time, n=n, l=l, order=order, anchor=anchor, dynamics=dynamics,
        holdout=holdout, periodic=periodic)
    say = progress if progress is not None else _silent
    say(f'analysing the record ({x.size} samples)')
    record = _analysed_record(x, y, t, anchor=anchor, epsilon=epsilon, periodic=periodic)
    notes: list[str] = []
    n, l = _order_the_record_supports(x, y, n, l, auto, anchor, notes)  # noqa: E741
    choose = not periodic
    # Dynamics and the order are decided at (8, 4) (or lower for a record too short for
    # it): rich enough that a lag does not stand in for the hysteresis a low order misses.
    reference = reference_order(x.size, n, l)
    estimate, finding = _input_dynamics(record, reference, dynamics=dynamics, holdout=holdout,
                                        choose=choose, progress=progress)
    found = estimate.modelled
    table: list[dict[str, Any]] = []
    if auto:
        (n, l), table = _selected_order(record, x, y, reference, found,  # noqa: E741
                                        holdout=holdout, choose=choose, anchor=anchor,
                                        notes=notes, say=say, progress=progress)
    say(f'fitting n={n}, l={l} on the whole record')
    fit = fit_record(record, n, l, dynamics=found, choose=choose, memory_steps=True,
                     validate=True)
    notes.extend(fit.notes)
    _check_burn_in(fit.burn_in, record.keep, (n, l))
    held_out = fit.folds.get(fit.rule, FoldErrors())
    line = _line_on_folds(x, y, record.keep, fit.burn_in)
    resonance = ResonanceEstimate()
    if t is not None and dynamics == 'auto' and record.analysis.ringing:
        say('ringing: fitting the output mode')
        resonance, fit = estimate_resonance(record, fit, n, l, found)
    say('judging the fit against the straight line')
    sim = with_mode(t, fit.simulate(), resonance)    # each segment from its start state
    fitted = fit.fitted if fit.fitted is not None else record.keep
    try:
        rms, peak, linear = check_quality(x, y, sim, fitted, n, l, anchor, chosen=auto)
        # Called here, not in a step of its own: its warnings name identify's caller.
        notes.extend(_judge_held_out(held_out, line, rms, (n, l), auto, table, x,
                                     record.window(ORDER_WINDOW).current.size))
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
    whole = _whole_record_error(fit, found, resonance, sim, t, x, y)
    return IdentificationResult(
        model=fit.model, order=(n, l), nonlinearity_error=peak, rms_error=rms,
        samples=int(x.size), solver_status=str(fit.info.status),
        iterations=int(fit.info.iter), solve_time=time_module.perf_counter() - started,
        order_table=table, linear_rms_error=linear, burn_in=int(fit.burn_in),
        whole_record_rms_error=whole, start_state=_start_of(fit),
        segments=_segments_of(fit, notes), dynamics=found, dynamics_estimate=estimate,
        dynamics_finding=finding,
        findings='; '.join(part for part in (record.analysis.describe(), resonance.describe(),
                                             estimate.describe(), finding.describe()) if part),
        excluded=int(np.count_nonzero(~record.keep)), notes=notes, resonance=resonance,
        held_out_error=held_out.error, held_out_errors=list(held_out.per_fold),
        line_held_out_error=line.error, line_held_out_errors=list(line.per_fold),
        held_out_judged=list(held_out.judged),
        weights_from=fit.rule)


def _checked_arguments(current: npt.ArrayLike, displacement: npt.ArrayLike,
                       time: npt.ArrayLike | None, *, n: int | None, l: int | None,  # noqa: E741
                       order: str | tuple[int, int] | None, anchor: str, dynamics: str,
                       holdout: float, periodic: bool) -> tuple[
                           FloatArray, FloatArray, FloatArray | None, int, int, bool]:
    # The data and the options, checked once (DataError or IdentificationError naming the
    # first thing wrong): x, y, t, the order and whether it is chosen ('auto').
    x, y = check_signals(current, displacement)
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
    return x, y, t, n, l, auto


def _analysed_record(x: FloatArray, y: FloatArray, t: FloatArray | None, *, anchor: str,
                     epsilon: float, periodic: bool) -> PreparedRecord:
    # The record analysed (dynamics, ringing, segments), refused when the MPI model cannot
    # represent it; a periodic record is one segment that starts where it ends.
    record = prepare_record(x, y, time=t, anchor=anchor, epsilon=epsilon)
    keep = record.keep
    _, correlation = output_sign(x[keep], y[keep])
    try:
        refuse_if_unmodellable(record, correlation)
    except IdentificationError as err:
        raise _true_cause(err, x, y) from None
    if periodic:
        record = replace(record, segments=[Segment(0, x.size, 'start', StartState('periodic'))])
    return record


def _order_the_record_supports(x: FloatArray, y: FloatArray, n: int, l: int,  # noqa: E741
                               auto: bool, anchor: str, notes: list[str]) -> tuple[int, int]:
    # A short record's order lowered (with a note); a record that cannot determine the
    # weights of the order given refused.
    n, l, lowered = _supported_order(x.size, n, l, auto)  # noqa: E741
    if lowered:
        notes.append(lowered)
    check_excitation(x, y, n if not auto else 0, l if not auto else 0, anchor=anchor)
    return n, l


def _input_dynamics(record: PreparedRecord, reference: tuple[int, int], *, dynamics: str,
                    holdout: float, choose: bool, progress: Callable[[str], None] | None
                    ) -> tuple[DynamicsEstimate, DynamicsFinding]:
    # Dead time and lag of the input path (with a time base), and the finding: lag, dead
    # time, tie or none, with the step response's check of a dead time.
    estimate = DynamicsEstimate()
    if record.time is not None and dynamics == 'auto':
        # On a window of a long record: trials cost the window, not the record (the
        # analysis `mpi-ros diagnose` states for the same record).
        estimate = estimate_record_dynamics(record, reference, holdout=holdout, choose=choose,
                                            progress=progress)
    finding = finding_of(record, estimate) if dynamics == 'auto' else DynamicsFinding()
    if finding.kind != 'unavailable':
        estimate = replace(estimate, modelled=finding.modelled)
    return estimate, finding


def _selected_order(record: PreparedRecord, x: FloatArray, y: FloatArray,
                    reference: tuple[int, int], found: InputDynamics, *, holdout: float,
                    choose: bool, anchor: str, notes: list[str],
                    say: Callable[[str], None], progress: Callable[[str], None] | None
                    ) -> tuple[tuple[int, int], list[dict[str, Any]]]:
    # order='auto': the order chosen on held-out blocks of the busiest window, lowered
    # when the record's excitation does not support it; and the order table.
    trial = record.window(ORDER_WINDOW)
    held = held_out_rows(trial.current.size, holdout, trial.keep)
    say('order selection: start state of the trial window')
    base = fit_record(trial, *reference, dynamics=found, held=held, choose=choose,
                      rule='joint start')
    order, table = select_record_order(trial, held, found, base.segments,
                                       burn_in=base.burn_in, progress=progress,
                                       rule=base.rule)
    return _excited_order(x, y, order, table, anchor, notes), table


def _line_on_folds(x: FloatArray, y: FloatArray, keep: npt.NDArray[np.bool_],
                   burn: int) -> FoldErrors:
    # The straight line's held-out errors on the record's folds, on the samples scored.
    scored = keep.copy()
    scored[:burn] = False
    return fold_line_errors(x, y, scored)


def _whole_record_error(fit: RecordFit, found: InputDynamics, resonance: ResonanceEstimate,
                        sim: FloatArray, t: FloatArray | None, x: FloatArray,
                        y: FloatArray) -> float:
    # What `mpi-ros simulate` gives: the model from its initial states, straight through
    # (Gamma of the input after the dynamics, then the output mode if one is modelled); one
    # segment from sample 0 without a mode is that already.
    if resonance.modelled:
        full = model_with_resonance(model_with_dynamics(fit.model, found), resonance)
        straight = full.simulate(t, x)
    else:
        one = len(fit.segments) == 1 and fit.segments[0].start == 0
        straight = sim if one else fit.model.simulate(fit.material_input)
    return _rms(straight, y, float(np.ptp(y)))


def _to_input(fit: RecordFit) -> Callable[[float], float]:
    design = fit.design

    def to_input(level: float) -> float:
        return float(design.input_offset + level * design.x_scale)

    return to_input


def _start_of(fit: RecordFit) -> dict[str, Any]:
    # How the record starts, in the input's unit, with its description.
    first = fit.segments[0].start_state
    to_input = _to_input(fit)
    return ({**first.to_json(to_input), 'description': first.describe(to_input, 'A')}
            if first is not None else {'kind': 'continue', 'levels': [],
                                       'description': 'continues'})


def _segments_of(fit: RecordFit, notes: list[str]) -> list[dict[str, Any]]:
    # The experiments of a stitched record, each with its start state (and a note).
    to_input = _to_input(fit)
    segments = [{'start': s.start, 'stop': s.stop, 'reason': s.reason,
                 'start_state': (s.start_state.to_json(to_input) if s.start_state is not None
                                 else {'kind': 'continue', 'levels': []})}
                for s in fit.segments]
    if len(fit.segments) > 1:
        notes.append(f'{len(fit.segments)} segments (joins at samples '
                     f'{", ".join(str(s.start) for s in fit.segments[1:])}: '
                     f'{"; ".join(s.reason for s in fit.segments[1:])}), each with its own'
                     ' start state')
    return segments


def _silent(text: str) -> None:
    pass


def _check_burn_in(burn_in: int, keep: npt.NDArray[np.bool_], order: tuple[int, int]) -> None:
    # A record whose start no candidate history explains leaves its first samples out (the
    # burn-in); when that is most of the record, the weights rest on its last samples only
    # and the model explains the rest no better than chance: refused.  (A cut record could
    # keep 19 of 280 samples for an order (8, 4) and then reproduce itself from sample 0 at
    # 112 % of the output range, against 17 % for a straight line.)  Counted among the
    # samples the fit may use (``keep``: outside ringing windows).
    left_out = int(np.count_nonzero(keep[:burn_in]))
    fitted = int(np.count_nonzero(keep[burn_in:]))
    if left_out <= fitted:
        return
    n, l = order  # noqa: E741
    kept = left_out + fitted
    msg = (f'no start state explains the first {left_out} of {kept} samples'
           f' ({100 * left_out / kept:.3g} %): the plays are determined only after them (the'
           f" record's widest excursion comes late) and no candidate history before the record"
           f' reproduces them, so the model (n={n}, l={l}) would rest on its last'
           f' {fitted} samples; start the record with a sweep over the whole input range'
           ' (or at rest after a descent to the lowest input), or give the whole record')
    raise IdentificationError(msg)


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


def _warn(note: str, notes: list[str]) -> None:
    # A warning of the held-out check, in the caller's caller's name (identify's caller),
    # and kept with the result's notes.
    warnings.warn(note, MPIWarning, stacklevel=4)
    notes.append(note)


def _judge_held_out(held_out: FoldErrors, line: FoldErrors, rms: float, order: tuple[int, int],
                    auto: bool, table: list[dict[str, Any]], x: FloatArray,
                    window: int) -> list[str]:
    # The fit on the record's own held-out blocks: refused when no better than a straight
    # line on the folds that can judge it, a warning when far from its in-sample figure or
    # from its order-table row.  A fold that holds an excursion no other fold makes (the
    # record's widest cycle, once) is reported, not judged: its fold model extrapolates
    # there, in the input and in the plays' memory, where the model of the whole record
    # does not (JUDGED_MARGIN).
    n, l = order  # noqa: E741
    if not math.isfinite(held_out.error):
        return []
    count = len(held_out.per_fold)
    folds = ', '.join(f'{100 * v:.3g}' for v in held_out.per_fold)
    lines = ', '.join(f'{100 * v:.3g}' for v in line.per_fold)
    flags = held_out.judged or [True] * count
    judged = [j and math.isfinite(m) and math.isfinite(b)
              for j, m, b in zip(flags, held_out.per_fold, line.per_fold)]
    notes: list[str] = []
    beyond = [k for k in range(count) if not flags[k] and math.isfinite(held_out.per_fold[k])
              and math.isfinite(held_out.excursions[k])]
    if beyond:
        which = ', '.join(
            f'fold {k + 1} (its input goes {100 * held_out.excursions[k]:.3g} % of the span'
            f' beyond the range its model was fitted on; {100 * held_out.per_fold[k]:.3g} % vs'
            f' {100 * line.per_fold[k]:.3g} % for the line)' for k in beyond)
        notes.append(f'held-out blocks not judged: {which} of {count}: each holds an excursion'
                     ' the rows its model was fitted on never make, where that model'
                     ' extrapolates; the model identified on the whole record covers that range')
    used = sum(judged)
    if n + l > 0 or auto:
        if used >= 2:
            model_error, line_error = held_out.pooled(judged), line.pooled(judged)
            pairs = [(m, b) for m, b, j in zip(held_out.per_fold, line.per_fold, judged) if j]
            worse = sum(1 for m, b in pairs if m > b + _FAR_ABSOLUTE)
            scope = (f'judged on the {used} of {count} that stay inside the range they were'
                     f' fitted on' if used < count else f'all {count} judged')
            if model_error > line_error + _FAR_ABSOLUTE or 2 * worse > used:
                msg = (f'the identified model (n={n}, l={l}) is no better than a straight line'
                       f" on the record's held-out blocks ({RECORD_FOLDS} contiguous folds, each"
                       f' fitted on the others; {scope}): RMS {100 * model_error:.3g} % of the'
                       f' output range vs {100 * line_error:.3g} % for the line, clearly worse on'
                       f' {worse} of {used} folds (per fold {folds} % vs {lines} %); in sample it'
                       f' is {100 * rms:.3g} %: the fit does not carry over within its own record'
                       ' (drift or leakage, switching, or a part of the record no other part'
                       ' resembles); record more cycles of the same excitation, or remove the'
                       ' drift')
                raise IdentificationError(msg)
            if model_error >= line_error:
                note = (f"warning: on the record's held-out blocks ({scope}) the model ties with"
                        f' a straight line: RMS {100 * model_error:.3g} % vs'
                        f' {100 * line_error:.3g} % of the output range, within'
                        f' {100 * _FAR_ABSOLUTE:.3g} %: a line would do as well')
                _warn(note, notes)
        else:
            note = (f"warning: the record's held-out blocks cannot judge the model: {used} of"
                    f' {count} folds hold scored rows inside the range their model was fitted'
                    f' on (per fold'
                    f' {folds} % vs {lines} % for a straight line): the record holds too few'
                    ' cycles of its widest excursions; the in-sample check alone passed it:'
                    ' validate it on another record of the actuator (mpi-ros diagnose'
                    ' --validate)')
            _warn(note, notes)
    # The median judged fold: the fold of the record's start (its transient) alone is no
    # reason to expect worse on new inputs; several folds are.
    scored = [m for m, j in zip(held_out.per_fold, judged) if j]
    typical = float(np.median(scored)) if scored else math.nan
    if typical > max(_FAR_FACTOR * rms, rms + _FAR_ABSOLUTE):
        note = (f"warning: on the record's held-out blocks the model is off by"
                f' {100 * typical:.3g} % RMS of the output range (the median of the judged'
                f' folds; per fold {folds} % vs {lines} % for a straight line), against'
                f' {100 * rms:.3g} % in sample: expect the larger figure on new inputs')
        _warn(note, notes)
    row = next((r for r in table if (r['n'], r['l']) == order), None)
    if row is not None and not (0.5 * row['rms_error'] <= held_out.error
                                <= _FAR_FACTOR * row['rms_error'] + _FAR_ABSOLUTE):
        scope = (f'the busiest {window} samples' if window < x.size else 'the whole record')
        notes.append(f"the order table's row for n={n}, l={l} (held-out RMS"
                     f" {100 * row['rms_error']:.3g} %) and the chosen model's held-out error"
                     f' ({100 * held_out.error:.3g} %) differ: the table holds out 30 short'
                     f' blocks of {scope} (every kind of excitation on both sides), the'
                     f' model {RECORD_FOLDS} long contiguous folds of the record')
    return notes


def _excited_order(x: FloatArray, y: FloatArray, order: tuple[int, int],
                   table: list[dict[str, Any]], anchor: str,
                   notes: list[str]) -> tuple[int, int]:
    # The order chosen, or, when the record's excitation does not support it, the best
    # lower order of the table that it supports (refused only when none is).
    try:
        check_excitation(x, y, *order, anchor=anchor)
        return order
    except IdentificationError as err:
        first = err
    lower = sorted((r for r in table if not r['unstable']
                    and r['n'] + 2 * r['l'] < order[0] + 2 * order[1]),
                   key=lambda r: r['rms_error'])
    for row in lower:
        try:
            check_excitation(x, y, row['n'], row['l'], anchor=anchor)
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
    check_excitation(x, y, 0, 0)


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
    gamma = getattr(model, 'model', model)
    mode = ResonanceModel(gamma, estimate.frequency, estimate.decay, estimate.deflection)
    if gamma is model:
        return mode
    return CompositeModel(gamma, (model, mode))


def _finite(value: float) -> float | None:
    return value if math.isfinite(value) else None


def _rms(sim: FloatArray, y: FloatArray, span: float) -> float:
    return float(np.sqrt(np.mean((sim - y) ** 2)) / span)
