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
   :func:`mpi_ros.identification.identify` (operating point, detected sign, burn-in, the
   order selection of ``order='auto'``); a record it refuses (worse than a straight line,
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
   - *signature* (:mod:`mpi_ros.diagnosis.signatures`, computed from the baseline
     residual and the input alone): creep needs a ``log t`` component during holds;
     thermal drift a smooth drift during holds *without* one; rate dependence and dead
     time a frequency-dependent burst response that follows the lag law
     (``atan(w tau)``, falling amplitude) resp. the delay law (phase linear in ``w``)
     better than the other.  Each test runs at ``alpha / 4`` (Bonferroni over the four
     causes).  A record without holds (bursts) leaves the slow (fast) signatures
     *unavailable*; they then do not veto, and the report says so.

   The cause is the candidate with the largest gain among those that are significant and
   whose signature is present (or unavailable); ``none`` when there is none, or when the
   baseline residual does not exceed the noise floor by ``noise_factor``.
"""

from dataclasses import asdict, dataclass, field, replace
import math
from typing import Any, Callable

import numpy as np
import numpy.typing as npt

from .invertibility import check_invertible_class, InvertibilityCheck, \
    OUTSIDE_INVERTIBLE_CLASS
from .signatures import burst_signature, hold_segments, hold_signature
from .time_base import implausible_time_constants, time_base_warning
from ..errors import DataError, IdentificationError
from ..extensions import EFFECTS
from ..extensions._common import rate_cross_correlation
from ..extensions._signals import first_order_lag
from ..identification import burn_in, identify, output_sign
from ..identification.start_state import estimate_start_state
from ..metrics import range_error, rms_range_error
from ..model import MPIModel
from ..params import OPERATING_POINT_KEYS
from ..recordings.recording import check_magnitudes, Recording

__all__ = ['DiagnosisReport', 'diagnose', 'CAUSES', 'noise_floor']

FloatArray = npt.NDArray[np.float64]

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
        ``creep``, ``rate_dependence``, ``thermal_drift``, ``dead_time``, ``none`` or
        ``outside_invertible_class``.
    baseline : dict
        ``order``, ``rms_error``, ``nonlinearity_error`` of Gamma on the validation data
        (fractions of its output range), ``linear_rms_error`` (the training data's straight
        line), ``validation_output_offset`` [m] (the re-estimated sensor zero of a separate
        validation record; 0 for a split), ``training_rms_error``, ``operating_point``.
    extended : dict
        The same for the chosen model (the baseline for ``none``), plus ``parameters``.
    gain : float
        Relative reduction of the validation RMS error, 0..1 (0 for ``none``).
    candidates : list of dict
        Per candidate: ``cause``, ``rms_error``, ``nonlinearity_error``, ``gain``,
        ``validation_output_offset``,
        ``z`` (Diebold-Mariano statistic), ``bandwidth`` (HAC lags), ``significant``,
        ``signature`` (``present``, ``absent`` or ``unavailable``), ``parameters``.
    evidence : str
        One or two sentences a control engineer can check.
    residual : dict
        Structure of the baseline residual (noise floor, holds, rate, power, lag).
    decision : dict
        The rule's thresholds and the steps taken.
    data : dict
        Sources, sample counts, split, ``output_sign``, burn-ins,
        ``output_offset_reestimated``.
    warnings : list of str
        What looks wrong without stopping the diagnosis, one sentence each: time constants
        the record's time base makes implausible (:mod:`mpi_ros.diagnosis.time_base`).
    model : object
        The extended model (or the baseline MPIModel); not serialised.
    series : dict
        Arrays for plots (not serialised).

    """

    cause: str
    baseline: dict[str, Any]
    extended: dict[str, Any]
    gain: float
    candidates: list[dict[str, Any]]
    evidence: str
    residual: dict[str, Any] = field(default_factory=dict)
    decision: dict[str, Any] = field(default_factory=dict)
    data: dict[str, Any] = field(default_factory=dict)
    warnings: list[str] = field(default_factory=list)
    model: Any = None
    series: dict[str, Any] = field(default_factory=dict, repr=False)

    def to_json(self) -> dict[str, Any]:
        """Return the JSON-ready dictionary (no arrays, no model objects)."""
        form: dict[str, Any] = _jsonable({
            'cause': self.cause, 'gain': self.gain, 'evidence': self.evidence,
            'baseline': self.baseline, 'extended': self.extended,
            'candidates': self.candidates, 'residual': self.residual,
            'decision': self.decision, 'data': self.data, 'warnings': self.warnings})
        return form

    def parameters(self) -> dict[str, Any]:
        """Return the flat parameters of the extended model (what the compensator reads)."""
        return dict(self.model.to_params()) if self.model is not None else {}


def noise_floor(displacement: npt.ArrayLike) -> float:
    """
    Estimate the white sensor-noise standard deviation from second differences.

    ``sigma = 1.4826 MAD(d2 y) / sqrt(6)``: the second difference of a smooth, densely
    sampled signal is almost only noise (variance ``6 sigma^2``); the median absolute
    deviation ignores the few samples with fast content.

    Parameters
    ----------
    displacement : array_like of float, shape (N,)
        Output [m].

    Returns
    -------
    float
        Noise standard deviation [m] (an upper bound when the signal is not smooth).

    """
    d2 = np.diff(np.asarray(displacement, dtype=np.float64), 2)
    if d2.size == 0:
        return 0.0
    return float(1.4826 * np.median(np.abs(d2 - np.median(d2))) / math.sqrt(6.0))


def diagnose(recording: Any, *, validation: Any = None, split: float = 0.6,
             order: str | tuple[int, int] = 'auto', causes: tuple[str, ...] | None = None,
             min_gain: float = 0.05, z_critical: float = 1.645, alpha: float = 0.05,
             bandwidth: int | None = None, noise_factor: float = 1.2,
             progress: Callable[[str], None] | None = None
             ) -> DiagnosisReport:
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
        Fraction of the record used for training when no validation is given, in (0, 1).
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

    Returns
    -------
    DiagnosisReport
        The verdict, the errors, all candidates and the evidence.

    Raises
    ------
    DataError
        Malformed data, a bad option, or a record too short to split.
    IdentificationError
        When :func:`mpi_ros.identification.identify` refuses the training record, or the
        baseline is no better than a straight line on the validation data.

    """
    say = progress or (lambda line: None)
    catalogue = tuple(EFFECTS)
    causes = catalogue if causes is None else tuple(causes)
    unknown = [c for c in causes if c not in catalogue]
    if unknown:
        msg = f'unknown cause(s) {unknown}; the catalogue is {", ".join(catalogue)}'
        raise DataError(msg)
    t, x, y = _arrays(recording, 'recording')
    if validation is None:
        if not 0.1 <= split <= 0.9:
            msg = f'split must be in [0.1, 0.9]; found {split!r}'
            raise DataError(msg)
        n_train = int(round(split * t.size))
        tt, xt, yt = t[:n_train], x[:n_train], y[:n_train]
        tv, xv, yv, start = t, x, y, n_train
        data = {'source': getattr(recording, 'source', ''), 'samples': int(t.size),
                'split': split, 'training_samples': n_train,
                'validation': f'samples {n_train}..{t.size - 1} of the same record'}
    else:
        tt, xt, yt = t, x, y
        tv, xv, yv = _arrays(validation, 'validation')
        start = 0
        data = {'source': getattr(recording, 'source', ''), 'samples': int(t.size),
                'validation': getattr(validation, 'source', '') or 'separate recording',
                'validation_samples': int(tv.size)}
    if tt.size < 200 or tv.size - start < 100:
        msg = (f'too few samples to diagnose: {tt.size} for training and {tv.size - start}'
               ' for validation; record at least a few loops (>= 300 samples)')
        raise DataError(msg)
    # The sensor may fall as the actuator extends: the class check (a rising map) and the
    # model (model.output_sign) use the sign detected on the training data.
    sign, _ = output_sign(xt, yt)
    data['output_sign'] = sign
    series: dict[str, Any] = {'time': tv, 'current': xv, 'displacement': yv,
                              'start': start}
    check = _class_check(xt, sign * yt, xv[start:], sign * yv[start:], validation is not None)
    if not check.inside:
        say(f'outside the invertible class: {check.reason}')
        return DiagnosisReport(
            cause=OUTSIDE_INVERTIBLE_CLASS, baseline={}, extended={}, gain=0.0,
            candidates=[], evidence=check.reason[0].upper() + check.reason[1:] + '.',
            residual={'reversal_ratio': check.reversal_ratio, 'branches': check.branches},
            decision={'rule': 'invertible-class check failed; no model fitted'}, data=data,
            series=series)
    say(f'identifying the baseline MPI model on {tt.size} samples (order {order})')
    if order == 'auto':
        base = identify(xt, yt, order='auto')
    else:
        base = identify(xt, yt, n=int(order[0]), l=int(order[1]))
    n, l = base.order  # noqa: E741
    data['training_burn_in'] = base.burn_in
    estimate_start = False
    if validation is not None:
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
        series['start'] = start
        data['validation_burn_in'] = start
        data['validation_scored'] = {
            'from_sample': start, 'samples': int(tv.size - start), 'left_out': left_out,
            'start_state': ('estimated for each model (its weights kept)' if estimate_start
                            else 'set by the data before the scored part')}
    val = slice(start, None)

    def on_validation(model: Any) -> FloatArray:
        # The model's simulation of the validation record, from the start state that fits
        # a separate record best (the split's validation continues the training record).
        if not estimate_start:
            return (np.asarray(model.simulate(xv), dtype=np.float64)
                    if isinstance(model, MPIModel) else model.simulate(tv, xv))
        rows = np.arange(tv.size) >= start
        fitted, _, _ = estimate_start_state(model, xv, yv, time=tv, rows=rows,
                                            offset_free=True)
        return (np.asarray(fitted.simulate(xv), dtype=np.float64)
                if isinstance(fitted, MPIModel) else fitted.simulate(tv, xv))
    # Only the validation record's output offset (its sensor zero) is re-estimated, for the
    # baseline, the straight line and every candidate alike; nothing else is refitted.
    reestimate = validation is not None
    data['output_offset_reestimated'] = reestimate
    line = _linear_fit(xt[base.burn_in:], yt[base.burn_in:])
    linear = np.asarray(np.polyval(line, xv), dtype=np.float64)
    linear_shift = _zero_shift(linear[val], yv[val], reestimate)
    sim0 = on_validation(base.model)
    shift0 = _zero_shift(sim0[val], yv[val], reestimate)
    sim0 = sim0 + shift0
    r0 = yv[val] - sim0[val]
    sigma = noise_floor(yv[val])
    baseline: dict[str, Any]
    baseline = {'order': [n, l], **_errors(sim0[val], yv[val]),
                'training_rms_error': base.rms_error,
                'validation_output_offset': shift0,
                'linear_rms_error': _errors(linear[val] + linear_shift, yv[val])['rms_error'],
                'operating_point': {'input_offset': base.model.input_offset,
                                    'output_offset': base.model.output_offset,
                                    'output_sign': base.model.output_sign}}
    say(f'baseline order n={n}, l={l}: validation RMS error {baseline["rms_error"]:.4f}'
        f' of the output range (straight line {baseline["linear_rms_error"]:.4f}),'
        f' (37) {baseline["nonlinearity_error"]:.4f}'
        + (f'; validation output offset re-estimated: {shift0:+.4g} m' if reestimate else ''))
    if not baseline['rms_error'] < baseline['linear_rms_error']:
        msg = (f'the baseline MPI model (n={n}, l={l}) is no better than a straight line on'
               f' the validation data: RMS error {100 * baseline["rms_error"]:.3g} % of the'
               f' output range vs {100 * baseline["linear_rms_error"]:.3g} % for the line'
               ' fitted on the training data; check that both records come from the same'
               ' actuator, with the same columns/topics, units and sign, and that the'
               ' validation record sweeps the range of the training record')
        raise IdentificationError(msg)
    residual = _residual_structure(tv, xv, yv, sim0, start, sigma)
    holds = hold_signature(tv[val], xv[val], r0)
    bursts = burst_signature(tv[val], xv[val], yv[val], sim0[val])
    residual['hold_signature'] = asdict(holds) if holds is not None else None
    residual['burst_signature'] = (
        {**asdict(bursts), 'law': bursts.law,
         'log_ratio': [[v.real, v.imag] for v in bursts.log_ratio]}
        if bursts is not None else None)
    candidates = []
    sims = {}
    residuals: dict[str, FloatArray] = {}
    for cause in causes:
        say(f'fitting candidate {cause}')
        model = EFFECTS[cause].fit(tt, xt, yt, order=(n, l))
        sim = on_validation(model)
        shift = _zero_shift(sim[val], yv[val], reestimate)
        sim = sim + shift
        sims[cause] = sim
        rc = yv[val] - sim[val]
        residuals[cause] = rc
        errs = _errors(sim[val], yv[val])
        # A baseline without error leaves nothing to gain (and no ratio to form).
        gain = (1.0 - errs['rms_error'] / baseline['rms_error']
                if baseline['rms_error'] > 0.0 else 0.0)
        z, lags = _dm_statistic(r0, rc, bandwidth)
        params = {k: v for k, v in model.to_params().items()
                  if not k.startswith(('model.hysteresis', 'model.superposition'))
                  and k not in OPERATING_POINT_KEYS}
        determined = slice(base.burn_in, None)
        train = rms_range_error(model.simulate(tt, xt)[determined], yt[determined])
        candidates.append({'cause': cause, **errs, 'gain': gain, 'z': z, 'bandwidth': lags,
                           'training_rms_error': train, 'validation_output_offset': shift,
                           'parameter_count': EFFECTS[cause].parameter_count(params),
                           'parameters': params, 'model': model})
        say(f'  {cause}: validation RMS error {errs["rms_error"]:.4f}, gain {gain:+.3f},'
            f' z {z:.1f}')
    excess = math.sqrt(float(np.mean(r0 ** 2))) > noise_factor * sigma
    level = alpha / len(catalogue)               # Bonferroni over the catalogue
    verdicts = {cause: EFFECTS[cause].signature(residual, level) for cause in causes}
    for c in candidates:
        c['signature'] = verdicts[c['cause']]
        c['significant'] = bool(excess and c['gain'] >= min_gain and c['z'] >= z_critical)
    decision: dict[str, Any]
    decision = {'min_gain': min_gain, 'z_critical': z_critical, 'alpha': alpha,
                'signature_level': level, 'bandwidth': bandwidth,
                'noise_factor': noise_factor, 'noise_floor': sigma,
                'baseline_above_noise': bool(excess), 'steps': []}
    chosen = _decide(candidates, excess, decision['steps'])
    ties = _ties(chosen, candidates, residuals, z_critical, bandwidth, decision['steps'])
    decision['ranking'] = _ranking(chosen, candidates, residuals, bandwidth)
    decision['ambiguous'] = bool(ties)
    decision['tied_with'] = [c['cause'] for c in ties]
    decision['separate_by'] = (_separation([chosen['cause'], *decision['tied_with']])
                               if chosen is not None and ties else '')
    series.update({'baseline': sim0, 'candidates': sims})
    if chosen is None:
        cause, model, extended, gain = 'none', base.model, dict(baseline), 0.0
    else:
        cause, model, gain = chosen['cause'], chosen['model'], float(chosen['gain'])
        extended = {'cause': cause, 'rms_error': chosen['rms_error'],
                    'nonlinearity_error': chosen['nonlinearity_error'],
                    'parameters': chosen['parameters']}
    extended.setdefault('parameters', {})
    evidence = _evidence(cause, baseline, candidates, residual, sigma, yv[val], data)
    if decision['ambiguous']:
        evidence += (f' Ambiguous: {", ".join(decision["tied_with"])} explain(s) the validation'
                     f' data as well, within the noise (ranked by gain; the signature'
                     f' decided). To separate them: {decision["separate_by"]}.')
    records = ([('record', t)] if validation is None
               else [('training record', t), ('validation record', tv)])
    warning = time_base_warning(implausible_time_constants(candidates, residual), records)
    warnings = [] if warning is None else [warning]
    for text in warnings:
        say(f'warning: {text}')
    say(f'verdict: {cause} (gain {gain:.3f})')
    public = [{k: v for k, v in c.items() if k != 'model'} for c in candidates]
    return DiagnosisReport(cause=cause, baseline=baseline, extended=extended, gain=gain,
                           candidates=public, evidence=evidence, residual=residual,
                           decision=decision, data=data, warnings=warnings, model=model,
                           series=series)


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


def _decide(candidates: list[dict[str, Any]], excess: bool,
            steps: list[str]) -> dict[str, Any] | None:
    if not excess:
        steps.append('the baseline residual does not exceed the noise floor: none')
        return None
    for c in candidates:
        steps.append(f'{c["cause"]}: gain {c["gain"]:+.3f}, z {c["z"]:.1f}'
                     f' ({"" if c["significant"] else "not "}significant), signature'
                     f' {c["signature"]}')
    eligible = [c for c in candidates if c['significant'] and c['signature'] != 'absent']
    if not eligible:
        steps.append('no candidate is both significant and physically supported: none')
        return None
    best = max(eligible, key=lambda c: c['gain'])
    note = (' (signature unavailable in this record: decided on the gain alone)'
            if best['signature'] == 'unavailable' else '')
    steps.append(f'largest gain among the eligible: {best["cause"]}'
                 f' ({best["gain"]:.3f}){note}')
    return best


def _ties(best: dict[str, Any] | None, candidates: list[dict[str, Any]],
          residuals: dict[str, FloatArray], z_critical: float, bandwidth: int | None,
          steps: list[str]) -> list[dict[str, Any]]:
    # The significant candidates the chosen one does not beat significantly (a one-sided
    # Diebold-Mariano test between the two): within the noise of each other.
    if best is None:
        return []
    tied = []
    for c in candidates:
        if c is best or not c['significant']:
            continue
        z, _ = _dm_statistic(residuals[c['cause']], residuals[best['cause']], bandwidth)
        if z < z_critical:
            tied.append(c)
            steps.append(f'{c["cause"]} is within the noise of {best["cause"]} (z {z:.1f} <'
                         f' {z_critical}): ambiguous')
    return tied


def _ranking(best: dict[str, Any] | None, candidates: list[dict[str, Any]],
             residuals: dict[str, FloatArray],
             bandwidth: int | None) -> list[dict[str, Any]]:
    # Every candidate by its validation gain, with its z against the chosen one.
    out = []
    for c in sorted(candidates, key=lambda c: -c['gain']):
        z = (math.nan if best is None or c is best else
             _dm_statistic(residuals[c['cause']], residuals[best['cause']], bandwidth)[0])
        out.append({'cause': c['cause'], 'gain': c['gain'], 'z_against_chosen': z,
                    'significant': c['significant'], 'signature': c['signature']})
    return out


#: What separates two causes that tie (the record cannot tell them apart).
_SEPARATIONS = {
    frozenset({'rate_dependence', 'dead_time'}):
        "bursts at two or more rates: a lag's phase saturates and its amplitude falls with"
        " the frequency, a dead time's phase grows in proportion to it",
    frozenset({'creep', 'thermal_drift'}):
        'holds after steps up and down: creep follows log t in the direction of the step,'
        ' thermal drift follows the input power whatever the step',
}


def _separation(causes: list[str]) -> str:
    pairs = [_SEPARATIONS[frozenset(pair)] for pair in
             ((a, b) for i, a in enumerate(causes) for b in causes[i + 1:])
             if frozenset(pair) in _SEPARATIONS]
    general = 'holds (creep, thermal drift) and bursts at several rates (lag, dead time)'
    what = '; '.join(pairs) or general
    return (f'{what}; mpi-ros diagnose --excitation validation_input.csv writes such an input'
            ' (holds from both sides, bursts at 5-40 Hz): play it on the rig and pass the record'
            ' as --validate')


def _residual_structure(t: FloatArray, x: FloatArray, y: FloatArray, sim: FloatArray,
                        start: int, sigma: float) -> dict[str, Any]:
    val = slice(start, None)
    r = (y - sim)[val]
    tv, xv = t[val], x[val]
    scale = float(np.ptp(y[val]))
    out: dict[str, Any] = {'rms': float(np.sqrt(np.mean(r ** 2))), 'noise_floor': sigma,
                           'noise_floor_relative': sigma / scale if scale else 0.0}
    holds = hold_segments(tv, xv, 0.5)
    moves = [float(r[j] - r[k]) for k, j in holds]
    steps = [float(np.sign(xv[k] - xv[max(k - int(0.2 * (j - k)) - 1, 0)])) for k, j in holds]
    out['holds'] = {'count': len(holds),
                    'mean_abs_residual_change': float(np.mean(np.abs(moves))) if moves else 0.0,
                    'change_along_last_step': float(np.mean(np.array(moves) * np.array(
                        steps))) if moves else 0.0}
    rate = np.gradient(xv, tv)
    out['rate_correlation'] = _corr(r, rate)
    order = np.argsort(np.abs(rate))
    quint = np.array_split(order, 5)
    out['rms_by_rate_quintile'] = [float(np.sqrt(np.mean(r[q] ** 2))) for q in quint]
    duration = float(t[-1] - t[0])
    power = first_order_lag(t, x * x, duration / 3.0)[val]
    out['power_correlation'] = _corr(r, power - power.mean())
    # The lag window (0.2 s, or 5 % of the record) shrinks to half the scored samples when
    # those are fewer (a validation record scored only after a long burn-in).
    lags, xc = rate_cross_correlation(tv, y[val], sim[val], min(0.2, 0.05 * duration))
    out['lag_of_best_correlation'] = float(lags[int(np.argmax(xc))])
    return out


def _corr(a: FloatArray, b: FloatArray) -> float:
    if a.size < 3 or np.std(a) == 0.0 or np.std(b) == 0.0:
        return 0.0
    return float(np.corrcoef(a, b)[0, 1])


def _evidence(cause: str, baseline: dict[str, Any], candidates: list[dict[str, Any]],
              residual: dict[str, Any], sigma: float, y: FloatArray,
              data: dict[str, Any]) -> str:
    span = float(np.ptp(y))
    shift = baseline.get('validation_output_offset', 0.0)
    zero = (f'; the validation record has its own sensor zero: only its output offset was'
            f' re-estimated, for every model alike (baseline {shift:+.3g} m)'
            if data.get('output_offset_reestimated') else '')
    base = (f'The MPI simulation misses {100 * baseline["rms_error"]:.2f} % of the output range'
            f' (RMS) on validation data (noise floor {100 * sigma / span:.2f} %{zero})')
    ranked = sorted(candidates, key=lambda c: -c['gain'])
    listing = ', '.join(f'{c["cause"]} {100 * c["gain"]:+.0f} %' for c in ranked)
    if cause == 'none':
        return f'{base}; no extension reduces it significantly ({listing}).'
    c = next(c for c in candidates if c['cause'] == cause)
    detail = EFFECTS[cause].evidence(residual) if cause in EFFECTS else None
    if detail is None:
        detail = 'the record has no holds or bursts to check the physical signature'
    return (f'{base}; the {cause} extension cuts it by {100 * c["gain"]:.0f} % (z ='
            f' {c["z"]:.1f}; all: {listing}), and {detail}.')


def _jsonable(value: Any) -> Any:
    if isinstance(value, dict):
        return {str(k): _jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_jsonable(v) for v in value]
    if isinstance(value, np.ndarray):
        return [_jsonable(v) for v in value.tolist()]
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    if isinstance(value, (int, np.integer)):
        return int(value)
    if isinstance(value, (float, np.floating)):
        v = float(value)
        return v if math.isfinite(v) else None
    return value
