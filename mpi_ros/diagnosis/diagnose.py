# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Diagnosis: what the MPI model's simulation gets wrong, which extension explains it, the gain.

(Somewhat over 500 lines: the procedure below, its significance test and its residual
statistics are one decision; the effects' own parts live in their modules, the signature
tests in :mod:`mpi_ros.diagnosis.signatures`, the report in :mod:`mpi_ros.diagnosis.report`.)

Procedure (documented in ``docs/diagnosis.md``):

1. **Invertible class.**  :func:`check_invertible_class` on the output times the sign
   detected on the training data (a falling sensor is fine: the model gets
   ``model.output_sign = -1``); failing data get the verdict ``outside_invertible_class``
   and no fit.  A separate validation record is checked on its own.
2. **Baseline.**  Gamma is identified on the training data by
   :func:`mpi_ros.model_fit.identify` (operating point, detected sign, burn-in, the
   order selection of ``order='auto'``), with the record's time base when it has one: the
   same preparation as ``mpi-ros identify`` (segments, ringing after steps left out, start
   state; ``dynamics='off'``: the effects are the candidates).  The dynamics finding
   (lag, dead time, tie or none; :mod:`mpi_ros.identification.finding`) is the one
   ``identify`` states for the same record (``data['dynamics_finding']``); the verdict on
   the two input stages never contradicts it (a stated tie instead), and a dead time longer
   than the step response's onset is not physical (its signature absent).  A split
   divides the excited part (a hold at the record's start goes to training).  A validation
   input beyond the training input's range is warned about, with the fraction outside;
   a record it refuses (worse than a straight line,
   too little excitation, ...) is refused here with its message.  Training/validation: the
   ``validation`` recording if given (a separate experiment; best), else a split of the
   record at ``split`` (default 0.6): the model is simulated over the *whole* record and
   scored only after the split, so the validation part starts from the states the
   training part leaves.  A separate validation record starts from an unknown state: it
   is scored only after its own burn-in (its input covered its range), and it has its own
   sensor zero: **only its output offset is re-estimated** (the least-squares constant, the
   mean residual), for the baseline, the straight line and every candidate alike, and
   reported (``baseline['validation_output_offset']``).  A baseline no better than the
   straight line of the training data on the validation data is refused
   (:class:`IdentificationError`).  All errors are fractions of the validation output's
   range.
3. **Residual structure** of the baseline on the validation data: (37), RMS, the noise
   floor, the response during input holds, correlation with the input rate, with the
   thermal proxy ``x^2`` (lagged) and the lag of the best cross-correlation.
4. **Candidates** (:mod:`mpi_ros.extensions`) are fitted on the training data with the same
   order and the same design as the baseline (operating point, sign, constant term,
   burn-in) and simulated on the validation data, with their own re-estimated offset: a
   candidate gains only by its physics, not by absorbing a sensor zero.
5. **Decision** (two independent kinds of evidence, both on the validation data):

   - *significance*: the candidate's validation gain (relative RMS reduction) is at least
     ``min_gain`` and a Diebold-Mariano test on the squared errors rejects "no improvement"
     (``z >= z_critical``, one-sided).  The variance of the mean loss difference is a
     Newey-West (Bartlett) HAC estimate whose bandwidth follows the autocorrelation of the
     loss difference (Andrews' AR(1) plug-in), so a slow effect gets a long window;
   - *signature*: each registered effect's own test (``Effect.signature`` of
     :data:`mpi_ros.extensions.EFFECTS`, on the hold and burst tests of
     :mod:`mpi_ros.diagnosis.signatures`, computed from the baseline residual and the
     input alone; each effect module states what it looks for).  Each test runs at
     ``alpha`` over the number of registered effects (Bonferroni).  A record without
     holds (bursts) leaves the signatures shown by holds (bursts) *unavailable*
     (``Effect.signature_test``); they then do not veto, and the report says so.

   What separates tied causes is what their effects state (``Effect.separations``,
   ``Effect.signature_test``: :func:`mpi_ros.extensions.effect.separating_measurement`).

   The cause is the candidate with the largest gain among those that are significant and
   whose signature is present (or unavailable); ``none`` when there is none, or when the
   baseline residual does not exceed the noise floor by ``noise_factor``.
"""

from collections.abc import Iterator, Mapping
from copy import deepcopy
from dataclasses import dataclass, field, fields, replace
from functools import partial
import math
from typing import Any, Callable
from warnings import catch_warnings, simplefilter

import numpy as np
import numpy.typing as npt

from .facts import Baseline, Decision, Extended, HoldCount, jsonable, OperatingPoint, \
    Ranked, RecordFacts, Refusal, Residual, ReturnPoints, Reversals, ScoredCandidate, \
    ScoredPart, Series, StepOnsetCheck
from .invertibility import check_invertible_class, InvertibilityCheck, \
    OUTSIDE_INVERTIBLE_CLASS
from .notation import length, percent, signed_percent, significant
from .signatures import burst_signature, hold_signature
from .time_base import implausible_time_constants, time_base_warning
from ..errors import DataError, IdentificationError, ModelError, MPIWarning
from ..extensions import EFFECTS, extended_model_from_params, fit_composite
from ..extensions.composite import check_combination, composite_cause
from ..extensions.dead_time import DEAD_TIME
from ..extensions.effect import separating_measurement, unidentified_parameters
from ..extensions.fitting import hold_segments, rate_cross_correlation
from ..identification import burn_in, output_sign
from ..identification.dynamics import noise_std, return_point_drift, ReturnPointDrift, \
    step_onset, StepOnset
from ..identification.finding import DynamicsFinding, record_dynamics
from ..identification.record import prepare_record, refuse_if_unmodellable
from ..identification.start_states import estimate_start_state
from ..metrics import range_error, rms_range_error
from ..model_fit import identify
from ..operators.filters import first_order_lag
from ..operators.model import IDENTIFIED_INPUT_RANGE, MPIModel, OPERATING_POINT_KEYS
from ..recordings.recording import check_magnitudes, Recording

__all__ = ['Candidate', 'DiagnosisReport', 'diagnose', 'CAUSES', 'z_wording']

FloatArray = npt.NDArray[np.float64]

#: Validation gain from which a named effect counts as clear; below it (but significant,
#: with its signature) it is reported as "present, weak", with the reason.
STRONG_GAIN = 0.2

#: The built-in causes (the catalogue is the registry :data:`mpi_ros.extensions.EFFECTS`,
#: which may hold more).
CAUSES = tuple(EFFECTS)


@dataclass
class DiagnosisReport:
    """
    Outcome of :func:`diagnose` (JSON form by :meth:`to_json`).

    Attributes
    ----------
    cause : str
        A registered effect's name (:data:`mpi_ros.extensions.EFFECTS`), two joined by
        ``' + '`` for a pair, ``none`` or ``outside_invertible_class``.
    baseline : Baseline or None
        Gamma on the validation data (:class:`~mpi_ros.diagnosis.facts.Baseline`); None
        when no model was fitted.
    extended : Extended or None
        The same for the chosen model (the baseline for ``none``), plus ``parameters`` and
        ``not_identified`` (:class:`~mpi_ros.diagnosis.facts.Extended`); None when no
        model was fitted.
    gain : float
        Relative reduction of the validation RMS error, 0..1 (0 for ``none``).
    candidates : list of ScoredCandidate
        Per candidate: ``cause``, its errors, ``gain``, ``z`` (Diebold-Mariano statistic),
        ``bandwidth`` (HAC lags), ``significant``, ``signature`` (``present``, ``absent`` or
        ``unavailable``), ``parameters`` (with units: ``fitted()``), ``not_identified``, a
        pair's ``parts`` (:class:`~mpi_ros.diagnosis.facts.ScoredCandidate`).
    evidence : str
        One or two sentences a control engineer can check.
    residual : Residual or Reversals
        Structure of the baseline residual (noise floor, holds, rate, power, lag, the
        signature tests; :class:`~mpi_ros.diagnosis.facts.Residual`), or the reversals
        of a record outside the invertible class.
    decision : Decision or Refusal
        The rule's thresholds and the steps taken; ``tied_with`` and ``tie_reasons`` (per
        tied cause, why: the validation data's z, or the record's dynamics finding)
        (:class:`~mpi_ros.diagnosis.facts.Decision`).
    data : RecordFacts
        Sources, sample counts, split, sign, burn-ins, the dynamics finding ``identify``
        states for the record, the validation input outside the training range
        (:class:`~mpi_ros.diagnosis.facts.RecordFacts`).
    warnings : list of str
        What looks wrong without stopping the diagnosis, one sentence each: time constants
        the record's time base makes implausible (:mod:`mpi_ros.diagnosis.time_base`).
    model : object
        The extended model (or the baseline MPIModel); not serialised.
    series : Series
        Arrays for plots (not serialised).

    """

    cause: str
    baseline: Baseline | None
    extended: Extended | None
    gain: float
    candidates: list[ScoredCandidate]
    evidence: str
    residual: Residual | Reversals
    decision: Decision | Refusal
    data: RecordFacts
    series: Series = field(repr=False)
    warnings: list[str] = field(default_factory=list)
    model: Any = None

    def to_json(self) -> dict[str, Any]:
        """Return the JSON-ready dictionary (no arrays, no model objects)."""
        form: dict[str, Any] = jsonable({
            'cause': self.cause, 'gain': self.gain, 'evidence': self.evidence,
            'baseline': self.baseline if self.baseline is not None else {},
            'extended': self.extended if self.extended is not None else {},
            'candidates': self.candidates,
            'residual': self.residual, 'decision': self.decision, 'data': self.data,
            'warnings': self.warnings})
        return form

    def parameters(self) -> dict[str, Any]:
        """Return the flat parameters of the extended model (what the compensator reads)."""
        return dict(self.model.to_params()) if self.model is not None else {}


def diagnose(recording: Any, *, validation: Any = None, split: float = 0.6,
             order: str | tuple[int, int] = 'auto', causes: tuple[str, ...] | None = None,
             min_gain: float = 0.05, z_critical: float = 1.645, alpha: float = 0.05,
             bandwidth: int | None = None, noise_factor: float = 1.2,
             progress: Callable[[str], None] | None = None,
             validation_block: tuple[int, int] | None = None) -> DiagnosisReport:
    """
    Diagnose what the MPI model misses in a recording and fit the best extension.

    Parameters
    ----------
    recording : Recording-like
        Object with ``time`` [s], ``current`` [A], ``displacement`` [m] arrays (e.g.
        :class:`mpi_ros.recordings.Recording`); the training data.
    validation : Recording-like, optional
        A separate validation experiment.  Without it, the record is split at ``split``.
    split : float
        Fraction of the record used for training when no validation is given, in (0, 1):
        of the samples after a hold at the record's start (the hold goes to training).
    order : 'auto' or (int, int)
        Model order of Gamma (``'auto'``: the order selection of :func:`identify`).
    causes : tuple of str, optional
        Candidates to try (default: every registered effect, :data:`mpi_ros.extensions.EFFECTS`).
    min_gain : float
        Smallest validation gain that counts.
    z_critical : float
        Critical value of the Diebold-Mariano statistic (one-sided; 1.645 is p = 0.05).
    alpha : float
        Family-wise level of the signature tests (each runs at ``alpha`` over the number
        of registered effects: ``alpha / 4`` for the built-in four).
    bandwidth : int, optional
        HAC bandwidth [samples] of the Diebold-Mariano test; by default chosen from the
        autocorrelation of the loss difference (Andrews' AR(1) plug-in).
    noise_factor : float
        The baseline validation RMS residual must exceed this times the noise floor.
    progress : callable, optional
        Called with one line per step (the CLI prints them to stderr); each of the
        report's ``warnings`` as ``warning: ...``.
    validation_block : (int, int), optional
        Without ``validation``: samples ``[a, b)`` of the record held out for validation
        instead of the tail after ``split``; the rest, joined at a time gap, is the training
        record.  By default the tail; when the tail's training part is refused or no
        better than a straight line on the tail, and the tail leaves the training range,
        the latest block of the same length whose input lies inside the range of the rest
        is used instead (a record of one cycle: the tail holds an extreme of the input),
        and the report says why; a record ``identify`` refuses whole is refused with its
        message (the record's cause, not the split's).

    Returns
    -------
    DiagnosisReport
        The verdict, the errors, all candidates and the evidence.

    Raises
    ------
    DataError
        Malformed data, a bad option, or a record too short to split.
    IdentificationError
        When :func:`mpi_ros.model_fit.identify` refuses the training record, or the
        baseline is no better than a straight line on the validation data.

    """
    say = progress or (lambda line: None)
    run = _Options(recording, validation, split, order, _asked_causes(causes), min_gain,
                   z_critical, alpha, bandwidth, noise_factor, progress, validation_block)
    separate = validation is not None
    # The records: training, validation (a separate record or the split's tail), facts.
    t, training, checked, start, data = _records(recording, validation, split,
                                                 validation_block)
    retry = partial(_validate_on_inner_block, run, checked[0].size - start, data, say)
    # The class check, with the sign detected on the training data (outside: no fit).
    sign = _detected_sign(training, data)
    series = Series(*checked, start)
    timed = bool(getattr(recording, 'timed', True))
    refused = _outside_class(training, checked, start, sign, timed, separate, data, series,
                             say)
    if refused is not None:
        return refused
    # The baseline: Gamma on the training record, as `mpi-ros identify` fits it.
    say(f'identifying the baseline MPI model on {training[0].size} samples (order {order})')
    base = _identify_baseline(training, checked[:2], start, order, timed,
                              split_record=not separate,
                              block=validation_block is not None, retry=retry)
    if isinstance(base, DiagnosisReport):
        return base                     # validated on an inner block instead of the tail
    # The dynamics finding `identify` states for the record, and its steps' onset.
    whole, finding, onset = _dynamics(run, training, sign, timed, data, say)
    data.training_burn_in = base.burn_in
    # The scored part of the validation record, and each model's simulation of it.
    start, on_validation = _scored(run, checked, start, sign, data, series)
    # The baseline's errors on the scored part, beside the straight line's.
    baseline, sim0, r0, sigma = _baseline_errors(base, on_validation, training, checked,
                                                 start, separate, data, say)
    # The validation input outside the training range, the drift at return points, and
    # a baseline no better than the straight line refused (or validated on an inner block).
    drift, outside = _range_and_drift(run, training, checked[1][start:], whole, data)
    retried = _no_better_than_line(baseline, drift, outside, retry)
    if retried is not None:
        return retried
    # The residual evidence: the baseline residual's structure and signature tests.
    residual = _residual_evidence(checked, sim0, start, sigma, r0)
    # The candidates: each effect fitted, scored, its signature tested.
    scorer = _Scorer(on_validation, training, base.burn_in, checked[2], slice(start, None),
                     r0, baseline, bandwidth, separate, say)
    scorer.baseline_model = base.model
    candidates, decision, excess, unfitted = _judged_candidates(
        run, scorer, base, residual, r0, sigma, onset, whole[0])
    # The choice: the rule, a pair, the ties, the agreement with the dynamics finding.
    chosen = _choose(decision, candidates, scorer, finding, baseline.order, excess=excess,
                     separate=separate)
    series.baseline, series.candidates = sim0, scorer.sims
    # The report: the verdict, its evidence and warnings.
    records = ([('record', t)] if not separate
               else [('training record', t), ('validation record', checked[0])])
    return _report(chosen, base.model, baseline, candidates, residual, decision, data,
                   (checked[2][start:], sigma), records, (drift, outside, unfitted), series,
                   say)


@dataclass(frozen=True)
class _Options:
    """What diagnose was called with: a split's tail refused is diagnosed again with them."""

    recording: Any
    validation: Any
    split: float
    order: str | tuple[int, int]
    causes: tuple[str, ...]
    min_gain: float
    z_critical: float
    alpha: float
    bandwidth: int | None
    noise_factor: float
    progress: Callable[[str], None] | None
    validation_block: tuple[int, int] | None


def _asked_causes(causes: tuple[str, ...] | None) -> tuple[str, ...]:
    # The candidates asked for (default: every registered effect), each a registered one.
    catalogue = tuple(EFFECTS)
    asked = catalogue if causes is None else tuple(causes)
    unknown = [c for c in asked if c not in catalogue]
    if unknown:
        msg = f'unknown cause(s) {unknown}; the catalogue is {", ".join(catalogue)}'
        raise DataError(msg)
    return asked


def _identify_whole(recording: Any, order: str | tuple[int, int]) -> None:
    # A record identify refuses whole is refused with identify's message (its cause).
    tw, xw, yw = _arrays(recording, 'recording')
    timed = bool(getattr(recording, 'timed', True))
    whole = {'order': 'auto'} if order == 'auto' else {'n': int(order[0]),
                                                       'l': int(order[1])}
    with catch_warnings():
        simplefilter('ignore', MPIWarning)
        identify(xw, yw, time=tw if timed else None, dynamics='off', **whole)


def _validate_on_inner_block(run: _Options, tail: int, data: RecordFacts,
                             say: Callable[[str], None], reason: str) -> DiagnosisReport | None:
    # The tail of a split failed, for the split's sake: diagnose again on the latest block
    # whose input lies inside the rest's range (None: none does, or not a split's tail).
    if run.validation is not None or run.validation_block is not None:
        return None
    block = _inner_block(_arrays(run.recording, 'recording')[1], tail,
                         data.leading_hold or 0)
    if block is None:
        return None
    _identify_whole(run.recording, run.order)   # the record's own cause, not the split's
    say(f'the tail after the split is refused ({reason}); validating on samples'
        f' {block[0]}..{block[1] - 1} instead, whose input lies inside the range of the'
        ' rest of the record')
    report = diagnose(run.recording, split=run.split, order=run.order, causes=run.causes,
                      min_gain=run.min_gain, z_critical=run.z_critical, alpha=run.alpha,
                      bandwidth=run.bandwidth, noise_factor=run.noise_factor,
                      progress=run.progress, validation_block=block)
    report.data['validation'] += f'; the tail after the split was refused: {reason}'
    return report


def _detected_sign(training: tuple[FloatArray, FloatArray, FloatArray],
                   data: RecordFacts) -> int:
    # The sensor may fall as the actuator extends: the class check (a rising map) and the
    # model (model.output_sign) use the sign detected on the training data.
    sign, _ = output_sign(training[1], training[2])
    data.output_sign = sign
    return sign


def _outside_class(training: tuple[FloatArray, FloatArray, FloatArray],
                   checked: tuple[FloatArray, FloatArray, FloatArray], start: int, sign: int,
                   timed: bool, separate: bool, data: RecordFacts, series: Series,
                   say: Callable[[str], None]) -> DiagnosisReport | None:
    # Step 1: the invertible-class check; the report of a record outside it (None inside).
    _, xt, yt = training
    _, xv, yv = checked
    _refuse_constant_output(yt, yv, separate)
    check = _class_check(xt, sign * yt, xv[start:], sign * yv[start:], separate)
    if not check.inside:
        # One analysis: the identification's tests of the record (butterfly, switching,
        # drift, unrelated signals) name the cause, or explain the reversals (a lag).
        # Each record on its own; a split's whole record.
        analysed = [training, checked] if separate else [checked]
        check = _with_analysis(check, analysed, timed)
        data.class_check = check.reason
    if not check.inside:
        say(f'outside the invertible class: {check.reason}')
        return DiagnosisReport(
            cause=OUTSIDE_INVERTIBLE_CLASS, baseline=None, extended=None, gain=0.0,
            candidates=[], evidence=check.reason[0].upper() + check.reason[1:] + '.',
            residual=Reversals(check.reversal_ratio, check.branches),
            decision=Refusal('invertible-class check failed; no model fitted'), data=data,
            series=series)
    if data.class_check:
        say(f'invertible class: {check.reason}')
    return None


def _dynamics(run: _Options, training: tuple[FloatArray, FloatArray, FloatArray], sign: int,
              timed: bool, data: RecordFacts, say: Callable[[str], None]) -> tuple[
        tuple[FloatArray, FloatArray, FloatArray], DynamicsFinding, StepOnset]:
    # The dynamics finding `mpi-ros identify` states for DATA (the training record, or the
    # whole record of a split), and the step response's onset that bounds a dead time;
    # returns that record too.
    record = training if run.validation is not None else _arrays(run.recording, 'recording')
    finding, onset = _record_dynamics(*record, sign, timed, say)
    data.dynamics_finding = finding
    if finding.kind != 'unavailable':
        say(finding.describe())
    return record, finding, onset


def _scored(run: _Options, checked: tuple[FloatArray, FloatArray, FloatArray], start: int,
            sign: int, data: RecordFacts,
            series: Series) -> tuple[int, Callable[[Any], FloatArray]]:
    # The first validation sample scored (a separate record: after its own burn-in) and
    # each model's simulation of the validation record.
    estimate_start = False
    if run.validation is not None:
        start, estimate_start = _scored_part(*checked, sign, data)
        series.start = start
    return start, partial(_on_validation, checked, start, estimate_start)


def _on_validation(checked: tuple[FloatArray, FloatArray, FloatArray], start: int,
                   estimate_start: bool, model: Any) -> FloatArray:
    # The model's simulation of the validation record, from the start state that fits
    # a separate record best (the split's validation continues the training record).
    tv, xv, yv = checked
    if not estimate_start:
        return np.asarray(model.response(tv, xv), dtype=np.float64)
    rows = np.arange(tv.size) >= start
    fitted, _, _ = estimate_start_state(model, xv, yv, time=tv, rows=rows,
                                        offset_free=True)
    return np.asarray(fitted.response(tv, xv), dtype=np.float64)


def _baseline_errors(base: Any, on_validation: Callable[[Any], FloatArray],
                     training: tuple[FloatArray, FloatArray, FloatArray],
                     checked: tuple[FloatArray, FloatArray, FloatArray], start: int,
                     reestimate: bool, data: RecordFacts, say: Callable[[str], None]
                     ) -> tuple[Baseline, FloatArray, FloatArray, float]:
    # The baseline and the straight line of the training data on the scored part (the
    # baseline's simulation, its residual there, and the noise floor returned too).  Only
    # the validation record's output offset (its sensor zero) is re-estimated, for the
    # baseline, the straight line and every candidate alike; nothing else is refitted.
    _, xt, yt = training
    _, xv, yv = checked
    val = slice(start, None)
    n, l = base.order  # noqa: E741
    data.output_offset_reestimated = reestimate
    line = _linear_fit(xt[base.burn_in:], yt[base.burn_in:])
    linear = np.asarray(np.polyval(line, xv), dtype=np.float64)
    linear_shift = _zero_shift(linear[val], yv[val], reestimate)
    sim0 = on_validation(base.model)
    shift0 = _zero_shift(sim0[val], yv[val], reestimate)
    sim0 = sim0 + shift0
    r0 = yv[val] - sim0[val]
    sigma = noise_std(yv[val])
    errors = _errors(sim0[val], yv[val])
    baseline = Baseline(
        (n, l), errors['rms_error'], errors['nonlinearity_error'],
        rms_range_error(base.model.response(*training[:2])[base.burn_in:], yt[base.burn_in:]),
        shift0,
        _errors(linear[val] + linear_shift, yv[val])['rms_error'],
        OperatingPoint(base.model.input_offset, base.model.output_offset,
                       base.model.output_sign))
    say(f'baseline order n={n}, l={l}: validation RMS error'
        f' {percent(baseline.rms_error)} of the output range (straight line'
        f' {percent(baseline.linear_rms_error)}), (37) {percent(baseline.nonlinearity_error)}'
        + (f'; validation output offset re-estimated: {"+" if shift0 >= 0.0 else ""}'
           f'{length(shift0)}' if reestimate else ''))
    return baseline, sim0, r0, sigma


def _range_and_drift(run: _Options, training: tuple[FloatArray, FloatArray, FloatArray],
                     scored: FloatArray, whole: tuple[FloatArray, FloatArray, FloatArray],
                     data: RecordFacts) -> tuple[ReturnPointDrift, str]:
    # The scored validation input outside the training range (its sentence) and the
    # drift at the input's return points of the record the dynamics were found on; a
    # split's record that drifts is refused with identify's message.
    outside = _outside_training(training[1], scored, data)
    drift = return_point_drift(whole[1], whole[2])
    if drift.drifts and run.validation is None:
        _identify_whole(run.recording, run.order)   # a drift identify refuses the record for
    data.return_point_drift = ReturnPoints(drift.visits, drift.change, drift.monotone,
                                           drift.end, drift.drifts)
    return drift, outside


def _no_better_than_line(baseline: Baseline, drift: ReturnPointDrift, outside: str,
                         retry: Callable[[str], DiagnosisReport | None]
                         ) -> DiagnosisReport | None:
    # A baseline no better than the straight line on the validation data is refused, with
    # its likely cause; a split's tail outside the training range is validated on an inner
    # block instead (that report).  None: the baseline beats the line.
    if baseline.rms_error < baseline.linear_rms_error:
        return None
    n, l = baseline.order  # noqa: E741
    retried = (retry(f'the baseline is no better than a straight line on it'
                     f' ({100 * baseline.rms_error:.3g} % vs'
                     f' {100 * baseline.linear_rms_error:.3g} %); {outside}')
               if outside and not drift.drifts else None)
    if retried is not None:
        return retried
    likely = [text for text in (drift.describe(), outside) if text]
    cause = (f'; the likely cause: {"; and ".join(likely)}' if likely else
             '; check that both records come from the same actuator, with the same'
             ' columns/topics, units and sign, and that the validation record sweeps the'
             ' range of the training record')
    msg = (f'the baseline MPI model (n={n}, l={l}) is no better than a straight line on'
           f' the validation data: RMS error {100 * baseline.rms_error:.3g} % of the'
           f' output range vs {100 * baseline.linear_rms_error:.3g} % for the line'
           f' fitted on the training data{cause}')
    raise IdentificationError(msg)


def _residual_evidence(checked: tuple[FloatArray, FloatArray, FloatArray], sim0: FloatArray,
                       start: int, sigma: float, r0: FloatArray) -> Residual:
    # Step 3: the structure of the baseline residual on the scored part and the hold and
    # burst signature tests (the step onset is added with the candidates).
    tv, xv, yv = checked
    val = slice(start, None)
    residual = _residual_structure(tv, xv, yv, sim0, start, sigma)
    residual.hold_signature = hold_signature(tv[val], xv[val], r0)
    residual.burst_signature = burst_signature(tv[val], xv[val], yv[val], sim0[val])
    return residual


def _judged_candidates(run: _Options, scorer: '_Scorer', base: Any, residual: Residual,
                       r0: FloatArray, sigma: float, onset: StepOnset,
                       time: FloatArray) -> tuple[list['Candidate'], Decision, Any, list[str]]:
    # Step 4: each effect fitted on the training record at the baseline's order and scored;
    # its signature (at alpha over the catalogue, Bonferroni) and whether it is significant;
    # a dead time longer than the steps' onset.  Returns them, the decision's thresholds,
    # whether the baseline residual exceeds the noise floor and the effects not fitted.
    n, l = base.order  # noqa: E741
    candidates, unfitted = _fit_candidates(scorer, run.causes, (n, l), base.model)
    excess = math.sqrt(float(np.mean(r0 ** 2))) > run.noise_factor * sigma
    level = run.alpha / len(tuple(EFFECTS))     # Bonferroni over the catalogue
    for c in candidates:
        c.signature = EFFECTS[c.cause].signature(residual, level)
        c.significant = bool(excess and c.gain >= run.min_gain and c.z >= run.z_critical)
    unphysical = _unphysical_dead_time(candidates, onset, time)
    residual.step_onset = (StepOnsetCheck(onset.bound, onset.steps, unphysical)
                           if math.isfinite(onset.bound) else None)
    decision = Decision(run.min_gain, run.z_critical, run.alpha, level, run.bandwidth,
                        run.noise_factor, sigma, bool(excess))
    if unphysical:
        decision.steps.append(unphysical)
    decision.steps.extend(unfitted)
    return candidates, decision, excess, unfitted


def _report(chosen: 'Candidate | None', base_model: Any, baseline: Baseline,
            candidates: list['Candidate'], residual: Residual, decision: Decision,
            data: RecordFacts, scored: tuple[FloatArray, float],
            records: list[tuple[str, FloatArray]],
            notes: tuple[ReturnPointDrift, str, list[str]],
            series: Series,
            say: Callable[[str], None]) -> DiagnosisReport:
    # The verdict, the extended model's errors, the evidence sentences, the
    # warnings (time constants the time base makes implausible, the drift, the range).
    (measured, sigma), (drift, outside, unfitted) = scored, notes
    public = [c.public() for c in candidates]
    if chosen is None:
        cause, model, gain = 'none', base_model, 0.0
        extended = Extended.of_baseline(baseline)
    else:
        cause, model, gain = chosen.cause, chosen.model, float(chosen.gain)
        extended = Extended.of_candidate(next(p for c, p in zip(candidates, public)
                                              if c is chosen))
    evidence = _evidence(cause, baseline, public, residual, sigma, measured, data)
    evidence += _strength(decision, chosen, baseline, sigma, float(np.ptp(measured)))
    if extended.not_identified:
        evidence += ' ' + _unidentified_sentence(extended.not_identified)
    if decision.ambiguous:
        tied = '; '.join(f'{k} is tied ({v})' for k, v in decision.tie_reasons.items())
        evidence += (f' Ambiguous: {tied} ({_first(chosen, candidates)};'
                     f' {_who_decided(chosen)}).'
                     f' To separate them: {decision.separate_by}.')
    warning = time_base_warning(implausible_time_constants(public, residual), records)
    warnings = [] if warning is None else [warning]
    warnings += [text for text in (drift.describe(), outside, *unfitted) if text]
    for text in warnings:
        say(f'warning: {text}')
    unidentified = (f'; not identified: {", ".join(extended.not_identified)}'
                    if extended.not_identified else '')
    say(f'verdict: {cause} (validation gain {percent(gain)}{unidentified})')
    return DiagnosisReport(cause=cause, baseline=baseline, extended=extended, gain=gain,
                           candidates=public, evidence=evidence, residual=residual,
                           decision=decision, data=data, warnings=warnings, model=model,
                           series=series)


def _identify_baseline(training: tuple[FloatArray, FloatArray, FloatArray],
                       validation: tuple[FloatArray, FloatArray], start: int,
                       order: str | tuple[int, int], timed: bool, *,
                       split_record: bool, block: bool,
                       retry: Callable[[str], Any]) -> Any:
    # Step 2: Gamma on the training record, as `mpi-ros identify` fits it (the time base
    # when the record has one, its segments, the ringing after steps left out, the start
    # state; the effects are the candidates, so no dynamics).  A split's tail refused for
    # the split's sake is validated on an inner block instead (RETRY gives that report).
    tt, xt, yt = training
    tv, xv = validation
    # A block's training part is two experiments joined at a gap: segments need the time
    # base (a record without one has its sample index).
    prepared: dict[str, Any] = {'time': tt if timed or block else None, 'dynamics': 'off'}
    try:
        if order == 'auto':
            return identify(xt, yt, order='auto', **prepared)
        return identify(xt, yt, n=int(order[0]), l=int(order[1]), **prepared)
    except IdentificationError as err:
        # A split's training part that holds only part of the record's loops is refused for
        # what that part shows; the cause is the split: say so, with the fraction outside.
        outside = _outside_training(xt, xv[start:], None) if split_record else ''
        if block and not return_point_drift(xt, yt).drifts:
            msg = (f'the training part (the record without the validation block, samples'
                   f' {start}..{tv.size - 1}) is refused: {err}')
            raise IdentificationError(msg) from err
        if not outside or return_point_drift(xt, yt).drifts:
            raise                       # no split to blame, or a drift: the record's cause
        retried = retry(f'its training part is refused: {err}')
        if retried is not None:
            return retried
        msg = (f'the training part (the first {tt.size} of {tv.size} samples) is refused: {err};'
               f' the likely cause is the split: {outside}; pass a record of several cycles,'
               ' another --split, or a separate --validate record')
        raise IdentificationError(msg) from err


def _record_dynamics(t: FloatArray, x: FloatArray, y: FloatArray, sign: int, timed: bool,
                     say: Callable[[str], None]) -> tuple[DynamicsFinding, StepOnset]:
    # The dynamics finding `identify` states for the record and its steps' onset (none
    # without a time base).
    if not timed:
        return DynamicsFinding(), StepOnset()
    say('dynamics: the analysis identify makes of the record (dead time, lag, steps)')
    _, finding = record_dynamics(x, y, t)
    return finding, step_onset(t, x, y, sign=sign)


def _choose(decision: Decision, candidates: 'list[Candidate]', scorer: '_Scorer',
            finding: DynamicsFinding, order: tuple[int, int], *, excess: bool,
            separate: bool) -> 'Candidate | None':
    # Step 5: the rule (significance and signature), a pair of effects, the ties, and the
    # agreement with identify's dynamics finding; the steps are written into DECISION.
    min_gain, z_critical, bandwidth = decision.min_gain, decision.z_critical, decision.bandwidth
    chosen = _decide(candidates, excess, decision.steps, min_gain, z_critical)
    pair = _pair(candidates) if excess else None
    if pair is not None:
        chosen = _try_pair(scorer, pair, candidates, chosen, order, decision.steps,
                           min_gain=min_gain, z_critical=z_critical, excess=excess)
    _state_ties(decision, chosen, candidates, scorer.residuals, z_critical, bandwidth)
    beyond = _separate_evidence(separate, scorer.residuals, z_critical, bandwidth)
    agreed = _agree_with_finding(decision, chosen, candidates, finding, beyond)
    if agreed is not chosen:
        chosen = agreed
        _state_ties(decision, chosen, candidates, scorer.residuals, z_critical, bandwidth)
        _agree_with_finding(decision, chosen, candidates, finding, beyond)
    return chosen


@dataclass
class Candidate:
    """
    One candidate extension, scored on the validation data against the baseline.

    The fields of :class:`~mpi_ros.diagnosis.facts.ScoredCandidate` (the report's form,
    which documents them), with the fitted extended model in ``model``; ``parts`` is empty
    (not None) for one effect.
    """

    cause: str
    model: Any
    rms_error: float
    nonlinearity_error: float
    gain: float
    z: float
    bandwidth: int
    training_rms_error: float
    validation_output_offset: float
    parameter_count: int
    parameters: dict[str, Any]
    not_identified: dict[str, str] = field(default_factory=dict)
    signature: str = 'unavailable'
    significant: bool = False
    parts: list[str] = field(default_factory=list)
    part_gains: dict[str, float] = field(default_factory=dict)
    part_z: dict[str, float] = field(default_factory=dict)

    def public(self) -> ScoredCandidate:
        """Return the report's form (no model; a pair's parts only for a pair)."""
        values = {f.name: deepcopy(getattr(self, f.name)) for f in fields(ScoredCandidate)}
        if not self.parts:
            values.update(parts=None, part_gains=None, part_z=None)
        return ScoredCandidate(**values)


class _Scorer:
    """Scores candidate models on the validation data against the baseline."""

    def __init__(self, on_validation: Callable[[Any], FloatArray],
                 training: tuple[FloatArray, FloatArray, FloatArray], burn_in: int,
                 validation_output: FloatArray, scored: slice, r0: FloatArray,
                 baseline: Baseline, bandwidth: int | None, reestimate: bool,
                 say: Callable[[str], None]) -> None:
        self.on_validation = on_validation
        self.training = training
        self.determined = slice(burn_in, None)
        self.scored = scored
        self.measured = validation_output[scored]
        self.r0 = r0
        self.baseline = baseline
        self.bandwidth = bandwidth
        self.reestimate = reestimate
        self.say = say
        self.sims: dict[str, FloatArray] = {}
        self.residuals: dict[str, FloatArray] = {}
        self.baseline_model: Any = None

    def score(self, cause: str, model: Any, parameter_count: int) -> Candidate:
        """Simulate a fitted model on the validation record and measure its gain."""
        sim = self.on_validation(model)
        val = self.scored
        shift = _zero_shift(sim[val], self.measured, self.reestimate)
        sim = sim + shift
        self.sims[cause] = sim
        rc = self.measured - sim[val]
        self.residuals[cause] = rc
        errs = _errors(sim[val], self.measured)
        base = self.baseline.rms_error
        # A baseline without error leaves nothing to gain (and no ratio to form).
        gain = 1.0 - errs['rms_error'] / base if base > 0.0 else 0.0
        z, lags = _dm_statistic(self.r0, rc, self.bandwidth)
        unknown = unidentified_parameters(model)
        params = {k: v for k, v in model.to_params().items()
                  if not k.startswith(('model.hysteresis', 'model.superposition',
                                       'record_start.hysteresis'))
                  and k not in OPERATING_POINT_KEYS + (IDENTIFIED_INPUT_RANGE,)
                  and k not in unknown}
        tt, xt, yt = self.training
        keep = self.determined
        train = rms_range_error(model.response(tt, xt)[keep], yt[keep])
        self.say(f'  {cause}: validation RMS error {percent(errs["rms_error"])} of the output'
                 f' range, gain {signed_percent(gain)}, z {significant(z)}')
        return Candidate(cause, model, errs['rms_error'], errs['nonlinearity_error'], gain, z,
                         lags, train, shift, parameter_count, params, unknown)


def _fit_candidates(scorer: _Scorer, causes: tuple[str, ...], order: tuple[int, int],
                    baseline: Any) -> tuple[list[Candidate], list[str]]:
    # Each effect fitted on the training record at the baseline's order, then scored.  An
    # effect whose fit fails (the record refused for that fit, a model it cannot build) is
    # left out of the ranking with the reason, not the whole diagnosis: the other causes
    # are still judged.  Returns the candidates and those reasons.
    out, unfitted = [], []
    tt, xt, yt = scorer.training
    for cause in causes:
        scorer.say(f'fitting candidate {cause}')
        try:
            model = _nested(EFFECTS[cause].fit(tt, xt, yt, order=order), baseline, tt, xt)
        except (IdentificationError, ModelError) as err:
            unfitted.append(f'the {cause} candidate could not be fitted ({err}); it is left'
                            ' out of the ranking, so this diagnosis cannot name it')
            scorer.say(f'  {cause}: not fitted: {err}')
            continue
        out.append(scorer.score(cause, model,
                                EFFECTS[cause].parameter_count(model.to_params())))
    return out, unfitted


def _nested(model: Any, baseline: Any, time: FloatArray, current: FloatArray) -> Any:
    # A fit that switched its effect(s) off (its simulation on the training record is its
    # Gamma's) is the baseline itself: each effect nests the baseline, so its gain is 0,
    # not the difference between the effect fit's Gamma and identify's (on the wide sweep
    # an effect fitted off gained -0.36, and a pair of two effects fitted off -2.29, on a
    # Preisach core's validation record).
    gamma = getattr(model, 'model', None)
    if (isinstance(baseline, MPIModel) and isinstance(gamma, MPIModel)
            and np.array_equal(model.response(time, current), gamma.simulate(current))):
        return model.with_gamma(baseline)
    return model


def _try_pair(scorer: _Scorer, pair: tuple[Candidate, Candidate], candidates: list[Candidate],
              chosen: Candidate | None, order: tuple[int, int], steps: list[str], *,
              min_gain: float, z_critical: float, excess: bool) -> Candidate | None:
    # Two effects with their physical signatures, at different places of the chain (an
    # input stage and a material effect): fit both at once.  Each alone can miss on the
    # validation data (the other effect biases its fit), so the pair is tried whenever both
    # signatures are present; it is chosen when each effect adds beyond the other alone.
    names = sorted(c.cause for c in pair)
    cause = composite_cause(names)
    scorer.say(f'fitting candidate {cause} (both signatures present)')
    tt, xt, yt = scorer.training
    model = _nested(fit_composite(tt, xt, yt, names, order=order,
                                  fits={c.cause: c.model for c in pair}),
                    scorer.baseline_model, tt, xt)
    both = scorer.score(cause, model, sum(c.parameter_count for c in pair))
    both.signature = 'present'
    off = _parts_off(model, names, tt, xt)
    both.significant = bool(excess and both.gain >= min_gain and both.z >= z_critical
                            and not off)
    both.parts = names
    alone = {c.cause: c for c in pair}
    for name in names:
        other = alone[next(m for m in names if m != name)]
        both.part_gains[name] = (1.0 - both.rms_error / other.rms_error
                                 if other.rms_error > 0.0 else 0.0)
        both.part_z[name] = _dm_statistic(scorer.residuals[other.cause],
                                          scorer.residuals[cause], scorer.bandwidth)[0]
    candidates.append(both)
    each = all(both.part_gains[m] >= min_gain and both.part_z[m] >= z_critical for m in names)
    parts_text = ', '.join(f'{m} {100 * both.part_gains[m]:+.3g} % (z {both.part_z[m]:.3g},'
                           f' {z_wording(both.part_z[m], z_critical)})' for m in names)
    head = (f'{cause}: gain {100 * both.gain:+.3g} %, z {both.z:.3g}'
            f' ({z_wording(both.z, z_critical)})')
    if both.significant and each and (chosen is None or both.gain > chosen.gain):
        steps.append(f'{head}; each effect adds beyond the other alone ({parts_text}): both')
        return both
    why = (f'its fit switched {" and ".join(off)} off, so it is not this pair' if off else
           'the pair does not count' if not both.significant else
           'not each effect adds beyond the other alone' if not each else
           f'its gain is not above {chosen.cause if chosen is not None else "none"}\'s')
    steps.append(f'{head}; {why} ({parts_text}):'
                 f' {chosen.cause if chosen is not None else "none"}')
    return chosen


def _parts_off(model: Any, names: list[str], time: FloatArray,
               current: FloatArray) -> list[str]:
    # The effects of a pair's fit that the fit switched off: without an effect's keys the
    # model responds to the training record exactly as with them.  Such a fit is the other
    # effect alone, on another Gamma (on a fresh rate-dependence plant of the wide sweep,
    # seed 407, the pair with a thermal drift fitted off gained 0.34 where the lag alone
    # gained 0.13, and the pair was named: a drift the plant does not have).
    params = model.to_params()
    response = model.response(time, current)
    off = []
    for name in names:
        keys = set(EFFECTS[name].keys)
        try:
            rest: Any = extended_model_from_params(
                {k: v for k, v in params.items() if k not in keys})
        except ModelError:
            continue
        if np.array_equal(rest.response(time, current), response):
            off.append(name)
    return off


def _state_ties(decision: Decision, chosen: Candidate | None,
                candidates: list[Candidate], residuals: dict[str, FloatArray],
                z_critical: float, bandwidth: int | None) -> None:
    # The candidates within the noise of the chosen one, the ranking, how to separate them.
    ties = _ties(chosen, candidates, residuals, z_critical, bandwidth, decision.steps)
    decision.ranking = _ranking(chosen, candidates, residuals, bandwidth)
    decision.ambiguous = bool(ties)
    decision.tied_with = [c.cause for c in ties]
    # Why each is tied, in words written from the same z as the ranking's.
    z_of = {row.cause: row.z_against_chosen for row in decision.ranking}
    decision.tie_reasons = {
        c.cause: (_tie_reason(c, chosen, z_of[c.cause], z_critical, ' on the validation data')
                  if chosen is not None else '')
        for c in ties}
    decision.separate_by = (_separation([chosen.cause, *decision.tied_with])
                            if chosen is not None and ties else '')


def _first(chosen: Candidate | None, candidates: list[Candidate]) -> str:
    # Whether the chosen candidate ranks first by its validation gain, in words.
    name = chosen.cause if chosen is not None else 'none'
    top = max(candidates, key=lambda c: c.gain)
    if chosen is None or top.gain <= chosen.gain:
        return f'{name} ranks first by its validation gain'
    return f'{name} is chosen although {top.cause} has a larger validation gain'


def _tie_reason(c: Candidate, chosen: Candidate, z: float, z_critical: float,
                where: str = '') -> str:
    # A tied candidate is one the chosen one does not beat significantly (Z, of the chosen
    # against it, below z_critical), worded as the z test words Z: within the noise, or
    # significantly better than the chosen one (which its signature, or the record's
    # dynamics finding, chose).
    if z <= -z_critical:
        return (f'significantly better than {chosen.cause}{where} (z {z:.3g} <='
                f" -{z_critical:.4g}); {c.cause}'s physical signature is {c.signature},"
                f" {chosen.cause}'s {chosen.signature}")
    return f'within the noise of {chosen.cause}{where} (z {z:.3g} < {z_critical:.4g})'


def _who_decided(chosen: Candidate | None) -> str:
    # The words for what chose the verdict, from the chosen candidate's signature (the same
    # value the decision steps word).
    if chosen is None:
        return 'no candidate qualified'
    if chosen.signature == 'unavailable':
        return 'its signature is unavailable in this record: decided on the gain alone'
    return f'its physical signature is {chosen.signature}'


def _unidentified_sentence(unknown: dict[str, str]) -> str:
    # The parameters of the named effect its fit could not identify, and why.
    return ('Not identified (the fitted value lies at a bound of its search range, so it is'
            ' no physical value; the model keeps it to run): '
            + '; '.join(f'{key} {why}' for key, why in unknown.items()) + '.')


def _strength(decision: Decision, chosen: Candidate | None, baseline: Baseline,
              sigma: float, span: float) -> str:
    # A named effect whose gain stays below the bar a user can rely on is present but weak:
    # significant and physically supported, yet small against what else the plain model
    # misses (or the noise).  Returns the sentence the evidence gets.
    decision.strength_bar = STRONG_GAIN
    decision.strength = ('none' if chosen is None else
                         'clear' if chosen.gain >= STRONG_GAIN else 'present, weak')
    if chosen is None or decision.strength != 'present, weak':
        return ''
    reason = (
        f'{chosen.cause} is present, weak: its extension cuts the validation error by only'
        f' {100 * chosen.gain:.0f} % (below {100 * STRONG_GAIN:.0f} %), although the cut is'
        f' significant and the physical signature is {chosen.signature}; the plain model'
        f' misses {100 * baseline.rms_error:.2f} % of the range, the noise floor is'
        f' {100 * sigma / span:.2f} %: most of the error is not this effect (a longer record,'
        ' or an excitation that shows it more, e.g. longer holds for slow effects, measures'
        ' it better)')
    decision.weak_reason = reason
    # The cause is an identifier (``rate_dependence``): never capitalised, so the sentence
    # opens with a label, as the summary's ``Weak:`` line does.
    return ' Weak: ' + reason + '.'


def _records(recording: Any, validation: Any, split: float,
             block: tuple[int, int] | None = None) -> tuple[
        FloatArray, tuple[FloatArray, FloatArray, FloatArray],
        tuple[FloatArray, FloatArray, FloatArray], int, RecordFacts]:
    # The training and the validation record (a separate one, or the record's tail after
    # the split), the first validation sample scored, and what the report says of them.
    t, x, y = _arrays(recording, 'recording')
    if validation is None:
        if not 0.1 <= split <= 0.9:
            msg = f'split must be in [0.1, 0.9]; found {split!r}'
            raise DataError(msg)
        # The split divides the excited part: a long hold before the input first moves (a
        # capture that starts with 1.5 s at one level, a tenth of the record or more) goes
        # to training, else a short excitation after it would leave the training part
        # without motion.
        moving = np.flatnonzero(np.abs(x - x[0]) > 1e-3 * float(np.ptp(x)))
        lead = (int(moving[0]) if moving.size and moving[0] >= 0.1 * t.size
                and t.size - moving[0] >= 300 else 0)
        n_train = lead + int(round(split * (t.size - lead)))
        tt, xt, yt = t[:n_train], x[:n_train], y[:n_train]
        tv, xv, yv, start = t, x, y, n_train
        data = RecordFacts(
            getattr(recording, 'source', ''), int(t.size),
            f'samples {n_train}..{t.size - 1} of the same record', split=split,
            training_samples=n_train, leading_hold=lead,
            validation_scored=ScoredPart(n_train, int(t.size - n_train), 'the training part',
                                         'continues the training part'))
        if block is not None:
            # A block inside the record: trained on the rest, joined at a time gap (a
            # segment of its own); the models run from sample 0 to the block's end.
            a, b = int(block[0]), int(block[1])
            if not lead <= a < b <= t.size:
                msg = (f'validation_block must lie in [{lead}, {t.size}] with a < b; found'
                       f' {block!r}')
                raise DataError(msg)
            tt, xt, yt = (np.concatenate([v[:a], v[b:]]) for v in (t, x, y))
            tv, xv, yv, start = t[:b], x[:b], y[:b], a
            data = RecordFacts(
                getattr(recording, 'source', ''), int(t.size),
                f'samples {a}..{b - 1} of the same record',
                training_samples=int(tt.size), leading_hold=lead, validation_block=[a, b],
                validation_scored=ScoredPart(a, b - a,
                                             'the rest of the record, the training part',
                                             'continues the training part before it'))
    else:
        tt, xt, yt = t, x, y
        tv, xv, yv = _arrays(validation, 'validation')
        start = 0
        data = RecordFacts(getattr(recording, 'source', ''), int(t.size),
                           getattr(validation, 'source', '') or 'separate recording',
                           validation_samples=int(tv.size))
    if tt.size < 200 or tv.size - start < 100:
        msg = (f'too few samples to diagnose: {tt.size} for training and {tv.size - start}'
               ' for validation; record at least a few loops (>= 300 samples)')
        raise DataError(msg)
    return t, (tt, xt, yt), (tv, xv, yv), start, data


def _inner_block(x: FloatArray, length: int, lead: int) -> tuple[int, int] | None:
    # The latest block of `length` samples after the leading hold whose input lies inside
    # the range of the rest of the record (1 % of its range to spare), leaving 200 samples
    # to train on; None when no block does.
    size = x.size
    if length < 100 or size - length < 200:
        return None
    for a in range(size - length, lead, -max(size // 200, 1)):
        rest = np.concatenate([x[:a], x[a + length:]])
        lo, hi = float(rest.min()), float(rest.max())
        block = x[a:a + length]
        margin = 0.01 * (hi - lo)
        if float(block.min()) >= lo - margin and float(block.max()) <= hi + margin:
            return a, a + length
    return None


def _outside_training(xt: FloatArray, scored: FloatArray, data: RecordFacts | None) -> str:
    # The scored validation input beyond the training input's range (more than 1 % of the
    # training range outside): the models extrapolate there.  Stated in data (when given)
    # and worded.
    lo, hi = float(xt.min()), float(xt.max())
    margin = 0.01 * (hi - lo)
    beyond = (scored < lo - margin) | (scored > hi + margin)
    fraction = float(np.mean(beyond)) if scored.size else 0.0
    if data is not None:
        data.validation_outside_training_range = fraction
    if not beyond.any():
        return ''
    return (f'the validation input leaves the training range: {float(scored.min()):.4g} to'
            f' {float(scored.max()):.4g} against {lo:.4g} to {hi:.4g} seen in training;'
            f' {100 * fraction:.3g} % of the scored samples lie outside, where every model'
            " extrapolates (its errors there are not an effect's); record a training part"
            ' that covers the validation range')


def _scored_part(tv: FloatArray, xv: FloatArray, yv: FloatArray, sign: int,
                 data: RecordFacts) -> tuple[int, bool]:
    # The first sample of a separate validation record that is scored, and whether each
    # model's start state is estimated on it (stated in data.validation_scored).
    estimate_start = False
    # A separate experiment starts from its own state.  Scored once its input has
    # covered its range (the plays' and the effects' slow states then follow from the
    # data) when that leaves at least half of it; else from its first sample (after the
    # ringing of a step just before it), every model with the start state that explains
    # the samples before its plays are determined (its weights kept).
    covered = burn_in(xv, 0.99 * float(np.ptp(xv)), to_turning_point=True)
    if covered <= 0.5 * tv.size:
        start, left_out = covered, ('the samples before the input covered its range'
                                    ' (the start state of the plays and effects)')
    else:
        start = _leading_ringing(tv, xv, yv, sign)
        estimate_start = True
        left_out = ('the ringing after a step just before the record' if start
                    else 'nothing')
    if tv.size - start < 100:
        msg = ('too little to score: the validation record leaves only'
               f' {tv.size - start} samples (from sample {start}: {left_out}); record a'
               ' longer validation (e.g. mpi-ros diagnose --excitation)')
        raise DataError(msg)
    data.validation_burn_in = start
    data.validation_scored = ScoredPart(
        start, int(tv.size - start), left_out,
        'estimated for each model (its weights kept)' if estimate_start
        else 'set by the data before the scored part')
    return start, estimate_start


def _arrays(rec: Any, name: str) -> tuple[FloatArray, FloatArray, FloatArray]:
    try:
        t = np.asarray(rec.time, dtype=np.float64).reshape(-1)
        x = np.asarray(rec.current, dtype=np.float64).reshape(-1)
        y = np.asarray(rec.displacement, dtype=np.float64).reshape(-1)
    except AttributeError as err:
        msg = f'{name} must have time, current and displacement arrays; {err}'
        raise DataError(msg) from err
    if not t.size == x.size == y.size or t.size < 3:
        msg = f'{name}: time, current and displacement must have equal lengths >= 3'
        raise DataError(msg)
    if not (np.all(np.isfinite(t)) and np.all(np.isfinite(x)) and np.all(np.isfinite(y))):
        msg = f'{name} contains non-finite samples; drop or repair them'
        raise DataError(msg)
    if np.any(np.diff(t) <= 0.0):
        msg = f'{name}: time must be strictly increasing'
        raise DataError(msg)
    check_magnitudes(Recording(t, x, y, source=getattr(rec, 'source', '') or name))
    return t, x, y


def _leading_ringing(t: FloatArray, x: FloatArray, y: FloatArray, sign: int) -> int:
    # The end of the ringing window at a record's start (a step just before it), else 0.
    from ..identification.dynamics import analyse_dynamics
    windows = analyse_dynamics(t, x, y, sign=sign).ringing
    return int(windows[0][1]) if windows and windows[0][0] == 0 else 0


def _errors(sim: FloatArray, measured: FloatArray) -> dict[str, float]:
    # Over the measured output's range: independent of the sensor's zero and sign.
    return {'rms_error': rms_range_error(sim, measured),
            'nonlinearity_error': range_error(sim, measured)}


def _zero_shift(sim: FloatArray, measured: FloatArray, reestimate: bool) -> float:
    # The least-squares output offset of a model on a record with its own sensor zero
    # (the mean residual); 0 when the record shares the training record's zero.
    return float(np.mean(measured - sim)) if reestimate else 0.0


def _linear_fit(x: FloatArray, y: FloatArray) -> FloatArray:
    # Coefficients of the best straight line y = a x + b (np.polyval order).
    return np.asarray(np.polyfit(x, y, 1), dtype=np.float64)


def _refuse_constant_output(yt: FloatArray, yv: FloatArray, separate: bool) -> None:
    # A constant output (to rounding) has no loops: say so before the class check, whose
    # branch ratio would read rounding noise as a butterfly, and before the baseline's
    # error relative to a range of zero.
    for name, y in (('training', yt), ('validation', yv)):
        if y.size and np.ptp(y) <= 1e-9 * np.max(np.abs(y)):
            where = f' in the {name} record' if separate else (
                '' if name == 'training' else ' in the validation part')
            msg = (f'the displacement is constant{where}: check the output topic or column'
                   ' and that the actuator moved')
            raise DataError(msg)


def _with_analysis(check: InvertibilityCheck,
                   records: list[tuple[FloatArray, FloatArray, FloatArray]],
                   timed: bool) -> InvertibilityCheck:
    # The binned branch check saw the output move against the input.  The identification's
    # analysis of each record names the cause in identify's words (a butterfly, switching,
    # an output unrelated to the input, a drift at the input's return points), or explains
    # the reversals (a lag or dead time, ringing after steps): then the record is inside.
    verdicts = []
    for t, x, y in records:
        record = prepare_record(x, y, time=t if timed else None)
        _, correlation = output_sign(x[record.keep], y[record.keep])
        try:
            refuse_if_unmodellable(record, correlation)
        except IdentificationError as err:
            return replace(check, reason=str(err))
        drift = return_point_drift(x, y)
        if drift.drifts:
            return replace(check, reason=f'{drift.describe()}; the MPI model cannot follow it:'
                           " remove the drift (e.g. a leakage current's integrated charge)"
                           ' or record a shorter, drift-free part')
        verdicts.append(record.analysis.verdict)
    return replace(check, inside=True, reason=(
        f'the binned branches show the output against the input (reversal ratio'
        f' {check.reversal_ratio:.2f}), but the analysis identify makes of the record explains'
        f' it ({", ".join(verdicts)}: no butterfly, switching or drift); diagnosed'))


def _class_check(xt: FloatArray, yt: FloatArray, xv: FloatArray, yv: FloatArray,
                 separate: bool) -> InvertibilityCheck:
    # A separate validation record has its own sensor zero: each record is checked on its
    # own (joined, its zero jump would count as output travel); the worse verdict wins.
    if not separate:
        return check_invertible_class(np.concatenate([xt, xv]), np.concatenate([yt, yv]))
    checks = [check_invertible_class(xt, yt), check_invertible_class(xv, yv)]
    failed = [(name, c) for name, c in zip(('training', 'validation'), checks)
              if not c.inside]
    if failed:
        name, c = failed[0]
        return replace(c, reason=f'in the {name} record, {c.reason}')
    return max(checks, key=lambda c: c.reversal_ratio)


def _dm_statistic(r_a: FloatArray, r_b: FloatArray,
                  bandwidth: int | None) -> tuple[float, int]:
    """Diebold-Mariano z of ``mean(r_a^2 - r_b^2) > 0`` with a Newey-West variance."""
    d = r_a ** 2 - r_b ** 2
    e = d - d.mean()
    n = d.size
    gamma0 = float(np.dot(e, e)) / n
    if gamma0 == 0.0:
        return (math.inf if d.mean() > 0 else 0.0), 0
    if bandwidth is None:
        # Andrews (1991), Bartlett kernel, AR(1) plug-in: 1.1447 (alpha n)^(1/3).
        rho = min(float(np.dot(e[1:], e[:-1])) / n / gamma0, 0.999)
        alpha = 4.0 * rho ** 2 / (1.0 - rho ** 2) ** 2
        bandwidth = int(math.ceil(1.1447 * (alpha * n) ** (1.0 / 3.0)))
    lags = int(min(max(bandwidth, 0), n - 1))
    variance = gamma0
    for k in range(1, lags + 1):
        variance += 2.0 * (1.0 - k / (lags + 1.0)) * float(np.dot(e[k:], e[:-k])) / n
    return float(d.mean() / math.sqrt(max(variance, 1e-300) / n)), lags


def z_wording(z: float | None, z_critical: float) -> str:
    """
    Say what a Diebold-Mariano z of a candidate against the baseline means.

    ``z >= z_critical``: significantly better; ``z <= -z_critical``: significantly worse;
    else not significant (``z_critical`` the one-sided critical value the diagnosis used).
    The decision steps, the JSON and the report word every z with this one function; a z
    that is no number (None in the JSON, NaN in the report's fields) is 'not tested'.

    """
    if z is None or not math.isfinite(z):
        return 'not tested'
    if z >= z_critical:
        return 'significantly better'
    if z <= -z_critical:
        return 'significantly worse'
    return 'not significant'


def _decide(candidates: list[Candidate], excess: bool, steps: list[str], min_gain: float,
            z_critical: float) -> Candidate | None:
    if not excess:
        steps.append('the baseline residual does not exceed the noise floor: none')
        return None
    for c in candidates:
        # The z is worded as the report's table words it; whether the candidate counts
        # also needs the gain (one statement each, never "not significant" for a large z).
        short = ([] if c.gain >= min_gain else [f'gain below {100 * min_gain:.3g} %']) + (
            [] if c.z >= z_critical else [f'z below {z_critical:.4g}'])
        counts = 'counts' if c.significant else 'does not count: ' + ' and '.join(short)
        steps.append(f'{c.cause}: gain {100 * c.gain:+.3g} %, z {c.z:.3g}'
                     f' ({z_wording(c.z, z_critical)}), {counts}; signature {c.signature}')
    eligible = [c for c in candidates if c.significant and c.signature != 'absent']
    if not eligible:
        steps.append('no candidate is both significant and physically supported: none')
        return None
    best = max(eligible, key=lambda c: c.gain)
    steps.append(f'largest gain among the eligible: {best.cause}'
                 f' ({100 * best.gain:.3g} %; {_who_decided(best)})')
    return best


def _pair(candidates: list[Candidate]) -> tuple[Candidate, Candidate] | None:
    # The two candidates with their physical signatures present that chain (an input stage
    # beside a material effect), the largest summed gain first; two input stages (a lag and
    # a dead time) are told apart by two rates, not combined.
    present = [c for c in candidates if c.signature == 'present' and c.cause in EFFECTS]
    pairs = []
    for k, a in enumerate(present):
        for b in present[k + 1:]:
            if EFFECTS[a.cause].stage == EFFECTS[b.cause].stage:
                continue
            try:
                check_combination([a.cause, b.cause])
            except ModelError:
                continue
            pairs.append((a, b))
    return max(pairs, key=lambda p: p[0].gain + p[1].gain) if pairs else None


def _ties(best: Candidate | None, candidates: list[Candidate],
          residuals: dict[str, FloatArray], z_critical: float, bandwidth: int | None,
          steps: list[str]) -> list[Candidate]:
    # The significant candidates the chosen one does not beat significantly (a one-sided
    # Diebold-Mariano test between the two): within the noise of each other.  One whose
    # physical signature is absent is tied only where it fits significantly better (the
    # data and the signature disagree); within the noise, its signature separates it.
    if best is None:
        return []
    tied = []
    for c in candidates:
        if c is best or not c.significant:
            continue
        z, _ = _dm_statistic(residuals[c.cause], residuals[best.cause], bandwidth)
        if z < (-z_critical if c.signature == 'absent' else z_critical):
            tied.append(c)
            steps.append(f'{c.cause} is {_tie_reason(c, best, z, z_critical)}: ambiguous')
    return tied


class _FindingKinds(Mapping[str, str]):
    """Effect name -> the dynamics finding it is, read from the registry when used."""

    def __getitem__(self, name: str) -> str:
        kind = EFFECTS[name].dynamics_finding if name in EFFECTS else ''
        if not kind:
            raise KeyError(name)
        return kind

    def __iter__(self) -> Iterator[str]:
        return iter([name for name, e in EFFECTS.items() if e.dynamics_finding])

    def __len__(self) -> int:
        return sum(1 for e in EFFECTS.values() if e.dynamics_finding)


#: The input stages one excitation rate cannot tell apart (a lag, a dead time), and the
#: kind of dynamics finding each is (:attr:`mpi_ros.extensions.Effect.dynamics_finding`).
_INPUT_STAGES: Mapping[str, str] = _FindingKinds()


def _unphysical_dead_time(candidates: list[Candidate], onset: StepOnset,
                          time: FloatArray) -> str:
    # A dead time holds the output still after a step: one longer than the onset the
    # record's steps show (plus one sample for the step's place) is not physical, and its
    # physical signature is absent.  Returns the decision step ('' when it fits).
    if not math.isfinite(onset.bound) or time.size < 2:
        return ''
    period = float(np.median(np.diff(time)))
    for c in candidates:
        value = float(c.parameters.get(DEAD_TIME, 0.0)) if c.cause == 'dead_time' else 0.0
        if value > onset.bound + period:
            c.signature = 'absent'
            return (f'dead_time: a dead time of {1e3 * value:.3g} ms is not physical:'
                    f' {onset.describe()}; its signature is absent')
    return ''


def _separate_evidence(separate: bool, residuals: dict[str, FloatArray], z_critical: float,
                       bandwidth: int | None) -> Callable[[Candidate, Candidate | None], str]:
    # What a separate validation record (another experiment, often another rate: data the
    # analysis of the training record never saw) adds beyond that analysis: the chosen
    # candidate beats the other input stage significantly there.  '' for a split, whose
    # validation part is a part of the record the finding was made on.
    def beyond(chosen: Candidate, other: Candidate | None) -> str:
        if not separate:
            return ''
        if other is None:
            return f'the separate validation record shows it (z {chosen.z:.3g})'
        z, _ = _dm_statistic(residuals[other.cause], residuals[chosen.cause], bandwidth)
        return (f'the separate validation record separates them (z {z:.3g} >= {z_critical:.4g}'
                f' against {other.cause})' if z >= z_critical else '')
    return beyond


def _agree_with_finding(decision: Decision, chosen: Candidate | None,
                        candidates: list[Candidate], finding: DynamicsFinding,
                        beyond: Callable[[Candidate, Candidate | None], str]
                        ) -> Candidate | None:
    # The verdict on the two input stages never contradicts the finding `identify` states
    # for the same record (held-out blocks, step onset): when the validation data name the
    # other kind, or the finding is a tie, the verdict is a stated tie, unless the
    # validation's bursts at several rates separate them (one signature present, the other
    # absent) or a separate validation record does (`beyond`); when the finding is none,
    # the validation gain of a split alone does not name an input stage; in a tie nothing
    # separates, the one that can be inverted causally (the lag) is named.  Returns the
    # chosen candidate (another one only for a finding of none or an unseparated tie).
    decision.dynamics_finding = finding.kind
    if (chosen is None or chosen.cause not in _INPUT_STAGES
            or finding.kind in ('unavailable', _INPUT_STAGES[chosen.cause])):
        return chosen
    steps = decision.steps
    other = next((c for c in candidates if c.cause in _INPUT_STAGES
                  and c.cause != chosen.cause), None)
    if other is not None and chosen.signature == 'present' and other.signature == 'absent':
        steps.append(f"the analysis of the record (identify's) finds {finding.kind}; the"
                     f" validation data's bursts separate the two: {chosen.cause}")
        return chosen
    more = beyond(chosen, other if finding.kind != 'none' else None)
    if more:
        steps.append(f"the analysis of the training record (identify's) finds"
                     f' {finding.kind.replace("_", " ")}; {more}: {chosen.cause}')
        return chosen
    if finding.kind == 'none':
        rest = [c for c in candidates if c.cause not in _INPUT_STAGES and c.significant
                and c.signature != 'absent' and not set(c.parts) & set(_INPUT_STAGES)]
        after = max(rest, key=lambda c: c.gain) if rest else None
        steps.append(f"the analysis of the record (identify's held-out blocks) finds no lag"
                     f' or dead time that beats the static model ({finding.reason}), and no'
                     f' burst signature supports {chosen.cause}: it is not named;'
                     f' {after.cause if after is not None else "none"}')
        return after
    if other is not None and other.cause not in decision.tied_with:
        decision.tied_with.append(other.cause)
        why = ('a tie of lag and dead time' if finding.kind == 'tie'
               else f'{finding.kind.replace("_", " ")}, not {_INPUT_STAGES[chosen.cause]}'
               .replace('dead_time', 'dead time'))
        decision.tie_reasons[other.cause] = (
            f"the analysis of the record (identify's held-out blocks) finds {why}, and no"
            ' burst signature of the validation data separates them')
        steps.append(f'{other.cause} is tied with {chosen.cause}: the analysis of the record'
                     f' (identify\'s held-out blocks) finds {finding.kind.replace("_", " ")}'
                     f' ({finding.reason}): ambiguous')
    if (other is not None and other.significant and other.signature != 'absent'
            and not _causally_invertible(chosen) and _causally_invertible(other)):
        # Nothing separates the two: the one a compensator can invert is named (a dead
        # time needs the future), the tie stated.  Its validation gain alone would name a
        # dead time on a lag plant as often as a lag on a dead-time plant.
        steps.append(f'{other.cause} is named, not {chosen.cause}: the analysis of the record'
                     f' finds {finding.kind.replace("_", " ")}, and neither a burst signature'
                     f' nor a separate validation record shows {chosen.cause}; of the two,'
                     f' {other.cause} can be inverted causally (the tie stated)')
        return other
    decision.ambiguous = bool(decision.tied_with)
    decision.separate_by = _separation([chosen.cause, *decision.tied_with])
    return chosen


def _causally_invertible(c: Candidate) -> bool:
    # The candidate's model has a causal per-step inverse (a lag has; a dead time has not).
    inverse_step = getattr(c.model, 'inverse_step', None)
    return inverse_step is not None and inverse_step() is not None


def _ranking(best: Candidate | None, candidates: list[Candidate],
             residuals: dict[str, FloatArray],
             bandwidth: int | None) -> list[Ranked]:
    # Every candidate by its validation gain, with its z against the chosen one.
    out = []
    for c in sorted(candidates, key=lambda c: -c.gain):
        z = (math.nan if best is None or c is best else
             _dm_statistic(residuals[c.cause], residuals[best.cause], bandwidth)[0])
        out.append(Ranked(c.cause, c.gain, z, c.significant, c.signature))
    return out


def _separation(causes: list[str]) -> str:
    # What separates tied causes (the registered effects say it), and how to record it.
    return (f'{separating_measurement(causes)}; mpi-ros diagnose --excitation'
            ' validation_input.csv writes such an input (holds from both sides, bursts at'
            ' 5-40 Hz): play it on the rig and pass the record as --validate')


def _residual_structure(t: FloatArray, x: FloatArray, y: FloatArray, sim: FloatArray,
                        start: int, sigma: float) -> Residual:
    # The residual's statistics; the signature tests and the step onset are added later.
    val = slice(start, None)
    r = (y - sim)[val]
    tv, xv = t[val], x[val]
    scale = float(np.ptp(y[val]))
    holds = hold_segments(tv, xv, 0.5)
    moves = [float(r[j] - r[k]) for k, j in holds]
    steps = [float(np.sign(xv[k] - xv[max(k - int(0.2 * (j - k)) - 1, 0)])) for k, j in holds]
    count = HoldCount(len(holds), 0.5, 1.0,
                      float(np.mean(np.abs(moves))) if moves else 0.0,
                      float(np.mean(np.array(moves) * np.array(steps))) if moves else 0.0)
    rate = np.gradient(xv, tv)
    order = np.argsort(np.abs(rate))
    quint = np.array_split(order, 5)
    duration = float(t[-1] - t[0])
    power = first_order_lag(t, x * x, duration / 3.0)[val]
    # The lag window (0.2 s, or 5 % of the record) shrinks to half the scored samples when
    # those are fewer (a validation record scored only after a long burn-in).
    lags, xc = rate_cross_correlation(tv, y[val], sim[val], min(0.2, 0.05 * duration))
    return Residual(
        rms=float(np.sqrt(np.mean(r ** 2))), noise_floor=sigma,
        noise_floor_relative=sigma / scale if scale else 0.0, holds=count,
        rate_correlation=_corr(r, rate),
        rms_by_rate_quintile=[float(np.sqrt(np.mean(r[q] ** 2))) for q in quint],
        power_correlation=_corr(r, power - power.mean()),
        lag_of_best_correlation=float(lags[int(np.argmax(xc))]))


def _corr(a: FloatArray, b: FloatArray) -> float:
    if a.size < 3 or np.std(a) == 0.0 or np.std(b) == 0.0:
        return 0.0
    return float(np.corrcoef(a, b)[0, 1])


def _evidence(cause: str, baseline: Baseline, candidates: list[ScoredCandidate],
              residual: Residual, sigma: float, y: FloatArray, data: RecordFacts) -> str:
    span = float(np.ptp(y))
    shift = baseline.validation_output_offset
    zero = (f'; the validation record has its own sensor zero: only its output offset was'
            f' re-estimated, for every model alike (baseline {shift:+.3g} m)'
            if data.output_offset_reestimated else '')
    base = (f'The MPI simulation misses {100 * baseline.rms_error:.2f} % of the output range'
            f' (RMS) on validation data (noise floor {100 * sigma / span:.2f} %{zero})')
    ranked = sorted(candidates, key=lambda c: -c.gain)
    listing = ', '.join(f'{c.cause} {100 * c.gain:+.0f} %' for c in ranked)
    if cause == 'none':
        return f'{base}; no extension reduces it significantly ({listing}).'
    c = next(c for c in candidates if c.cause == cause)
    parts = c.effects
    details = [EFFECTS[p].evidence(residual) for p in parts if p in EFFECTS]
    detail = '; '.join(d for d in details if d is not None)
    if not detail:
        # From the same residual facts the report's Holds and Bursts lines are written from.
        holds = residual.hold_signature
        bursts = residual.burst_signature
        minimum = residual.holds.signature_minimum_duration
        used = (f'the hold signature test used {holds.holds} hold(s) of {minimum:g} s or'
                ' more' if holds is not None else f'the record has no hold of {minimum:g} s or'
                ' more')
        rates = (f'the burst signature test used bursts at {len(bursts.frequencies)}'
                 ' frequencies' if bursts is not None else 'no bursts the signature tests can'
                 ' use')
        detail = f'{used}, {rates}: its physical signature is {c.signature}'
    each = ''
    if c.part_gains:
        each = ('; each adds beyond the other alone: ' + ', '.join(
            f'{p} {100 * c.part_gains[p]:.0f} %' for p in parts))
    return (f'{base}; the {cause} extension cuts it by {100 * c.gain:.0f} % (z ='
            f' {c.z:.1f}; all: {listing}{each}), and {detail}.')
