# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Fit Gamma on a prepared record: start states, weights, burn-in, cross-validation.

:func:`fit_record` fits Gamma on the samples a :class:`~.record.PreparedRecord` keeps, each
segment from the start state chosen for it (:mod:`.start_states`: one QP per candidate
history on Gram matrices accumulated once per segment and start state), with the input
dynamics given, a burn-in where no start state explains the record's start, and the weights'
rule chosen by blocked cross-validation on the record's own folds (:mod:`.folds`).
"""

from dataclasses import dataclass, field, replace
import math
from typing import Any

import numpy as np
import numpy.typing as npt

from .dynamics import InputDynamics
from .folds import better_on_folds, fold_excursion, fold_index, FoldErrors, RECORD_FOLDS
from .qp import fit_generalized_error, FloatArray, GramParts, IDLE_PLAY, OUTER_SLOPE, \
    regressor_gram, scaled_design, ScaledDesign
from .record import PreparedRecord, Segment
from .start_states import determined_from, end_state, refine_memory, start_candidates, \
    StartState, turning_point_candidates
from ..errors import DataError, IdentificationError
from ..operators.deadzone import dead_zone_operator
from ..operators.model import MPIModel
from ..operators.play import play_operator

__all__ = ['RecordFit', 'fit_record', 'fold_line_errors', 'AVERAGED']

#: The rule of a tie: the mean of the weights of ``'joint start'`` and ``'determined'`` (the
#: rows after the plays are determined), where blocked cross-validation cannot tell the two
#: apart and the joint start is a memory (every play's state free).  They differ in the
#: weights of plays the record never wipes out, which a new trajectory may reach: taking
#: either one risks its whole error there, the mean half of it.
#: The constraints are linear, so the mean is a feasible (invertible) model.
AVERAGED = 'averaged'


#: Tolerance of the OSQP solves (polished): trial fits are compared on held-out rows,
#: which an unpolished solution can be off by a factor of two in ill-conditioned directions.
_TRIAL_TOLERANCE = 1e-9

#: The cross-validation covers the record's first samples, at most this many (a long
#: record's cost stays that of a window; the start is where the rules differ).
_CV_WINDOW = 100000

#: Blocks of the rows before the plays are determined, alternately refined on and held out
#: when a memory is refined.
_PREFIX_BLOCKS = 8

#: Rounds of the joint estimate of the plays' start states (refine, refit).
_MEMORY_ROUNDS = 3

#: A start state explains the record's start when the generalised RMS error before the
#: plays are determined is at most this many times the error after, or below
#: :data:`_START_FLOOR` (1 % of H's scaled range of 2): model error, not a wrong state.
_START_TOLERANCE = 3.0
_START_FLOOR = 0.02


@dataclass(frozen=True)
class RecordFit:
    """
    One fit of Gamma on a prepared record.

    Attributes
    ----------
    model : MPIModel
        Gamma (SI units) with the first segment's start state as its initial states.
    design : ScaledDesign
        Its design.
    segments : list of Segment
        With the chosen start states.
    material_input : ndarray of float, shape (N,)
        The input Gamma saw (after the dynamics).
    train_error, held_error : float
        Generalised RMS error on the training and held-out rows, in the input's unit
        (NaN without held-out rows).
    burn_in : int
        Samples at the start left out of the fit because no start state explains them.
    info : object
        OSQP's info structure of the final solve.
    notes : list of str
        What the fit noticed (burn-in, weights fitted after the start).
    fitted : ndarray of bool, shape (N,)
        The samples the weights were fitted on (training rows, outside ringing, after a
        burn-in, and, when enough samples follow, after the plays are determined).
    rule : str
        Where the weights came from (see :class:`FoldErrors`).
    folds : dict
        The cross-validation of each rule compared, by rule (empty when none ran).

    """

    model: MPIModel
    design: ScaledDesign
    segments: list[Segment]
    material_input: FloatArray
    train_error: float
    held_error: float
    burn_in: int = 0
    info: Any = None
    notes: list[str] = field(default_factory=list)
    fitted: npt.NDArray[np.bool_] | None = None
    rule: str = 'joint'
    folds: dict[str, FoldErrors] = field(default_factory=dict)

    def simulate(self) -> FloatArray:
        """Return the model's output over the record, each segment from its start state."""
        out = np.empty(self.material_input.size)
        state: FloatArray | None = None
        z_first = np.asarray(self.model.hysteresis.initial_states, dtype=np.float64)
        for seg in self.segments:
            part = self.material_input[seg.start:seg.stop]
            if seg.start_state is None and state is not None:
                z = state
            else:
                z = self._state_of(seg) if seg.start != 0 else z_first
            # The compiled Gamma (plays, H, S in one pass), as ``MPIModel.simulate``.
            out[seg.start:seg.stop], state = self.model.run(part, z)
        return out

    def _state_of(self, seg: Segment) -> FloatArray:
        d = self.design
        u = d.scaled_input(self.material_input[seg.start:seg.stop])
        assert seg.start_state is not None
        z = seg.start_state.states(float(u[0]), d.hysteresis_thresholds,
                                   end_state(u, d.hysteresis_thresholds))
        return _to_model_states(z, d, self.model)


def fit_record(record: PreparedRecord, n: int, l: int, *,  # noqa: E741
               dynamics: InputDynamics = InputDynamics(),
               held: npt.NDArray[np.bool_] | None = None,
               starts: list[Segment] | None = None, choose: bool = True,
               tolerance: float = 1e-9, burn_in: int | None = None,
               memory_steps: bool = False, rule: str | None = None,
               validate: bool = False) -> RecordFit:
    """
    Fit Gamma on a prepared record, choosing each segment's start state.

    Start states are chosen with the weights of the rows after the plays are determined
    fixed (:meth:`_Fitter.choose_starts_determined`), where enough such rows exist (else
    jointly with the weights, one QP per candidate).  The final weights come from the
    determined rows alone (``rule='determined'``) or from every row with the chosen start
    states (``'joint'``), or the start states are chosen jointly with the weights (``'joint
    start'``, the choice before cross-validation): by default the rule with the smallest
    held-out error of blocked cross-validation (:meth:`_Fitter.fold_errors`), beyond the
    folds' noise (:func:`better_on_folds`); where ``'joint start'`` starts from a memory and
    ties with ``'determined'``, the mean of their weights (:data:`AVERAGED`).

    Parameters
    ----------
    record : PreparedRecord
        The record.
    n, l : int
        Model orders.
    dynamics : InputDynamics
        Dead time and lag applied to the input before the fit.
    held : ndarray of bool, shape (N,), optional
        Held-out rows (scored, not fitted).
    starts : list of Segment, optional
        Segments with start states to use (e.g. from a fit at another order); chosen
        afresh when None or when ``choose`` is True.
    choose : bool
        Choose the start states.
    tolerance : float
        OSQP's tolerance of the final solve.
    burn_in : int, optional
        Samples at the start to leave out (trial fits compared with a reference fit use
        its burn-in); by default 0, or found when the start states are chosen and none
        explains the record's start.
    memory_steps : bool
        Where a memory beats every simple history, refine it also by the steps between
        plays (see :func:`refine_memory`); the final fit of :func:`mpi_ros.identify` does,
        the trial fits of the order selection and the dynamics grid do not.
    rule : {'determined', 'joint', 'joint start', 'averaged'}, optional
        Where the weights come from (``'joint start'``: every row, the start states chosen
        jointly with the weights, one QP per candidate; ``'averaged'``: the mean of the
        weights of ``'joint start'`` and of ``'determined'``, the start states of ``'joint
        start'``); None: the one of the three with the smallest held-out error of blocked
        cross-validation when the start states are chosen (:func:`better_on_folds`), and
        ``'averaged'`` where ``'joint start'`` starts from a memory and ties with
        ``'determined'``; ``'joint'`` otherwise (trial fits pass their reference fit's
        rule).
    validate : bool
        Cross-validate the rule used (``RecordFit.folds[rule]``) when it was not already.

    Returns
    -------
    RecordFit
        The fit.

    """
    x = record.current
    if dynamics.present:
        if record.time is None:
            msg = 'input dynamics need a time base'
            raise DataError(msg)
        x = dynamics.apply(record.time, x)
    y = record.displacement
    design = scaled_design(x, y, n, l, anchor=record.anchor,
                           sign=record.sign if record.anchor != 'origin' else None)
    xs, ys = design.scaled_input(x), design.scaled_output(y)
    classes = np.where(record.keep, 0, -1).astype(np.int8)
    if held is not None:
        classes[held & record.keep] = 1
    fitter = _Fitter(xs, ys, design, classes, record.epsilon)
    segments = list(starts) if starts is not None else list(record.segments)
    if record.anchor == 'origin':
        segments = [replace(s, start_state=StartState('virgin', (0.0,))) for s in segments]
        choose = False
    notes: list[str] = []
    folds: dict[str, FoldErrors] = {}
    if choose or any(s.start_state is None and s.start == 0 for s in segments):
        picked = (fitter.choose_starts_determined(segments, memory_steps=memory_steps)
                  if rule in (None, 'determined', 'joint') else None)
        jointly = (fitter.choose_starts(segments, memory_steps=memory_steps)
                   if picked is None or rule is None else segments)
        if picked is None:
            segments, rule = jointly, ('joint' if rule is None else rule)
        elif rule is not None:
            segments = picked
        else:
            # The rules, judged on held-out folds: weights of the determined rows or of
            # every row, with the start states chosen under the determined rows' weights;
            # every row with the start states chosen jointly (the start may pull weights).
            # A rule replaces the best so far only when it is lower beyond the folds' noise
            # (see better_on_folds); on a tie the in-sample choice stays (the start chosen
            # jointly: it also reproduces the record's start best).
            options = {'joint start': jointly, 'determined': picked, 'joint': picked}
            for label, option in options.items():
                folds[label] = fitter.fold_errors(option, _weight_rule(label), x, y)
                if rule is None or better_on_folds(folds[label], folds[rule]):
                    rule, segments = label, option
            # Where the start chosen jointly is a memory (a state of its own for every play,
            # free to trade against the weights of plays the record never wipes out) and stays
            # only because the determined rows' weights do not beat it beyond the folds'
            # noise, nor it them: a tie, the mean of the two.  A simple history (virgin, a
            # descent, reversals) has too few parameters to pull a weight.
            if (rule == 'joint start' and _has_memory(jointly)
                    and fitter.determined_parts(jointly) is not None
                    and not better_on_folds(folds['joint start'], folds['determined'])):
                rule = AVERAGED
                folds[rule] = fitter.fold_errors(jointly, AVERAGED, x, y)
    rule = rule or 'joint'
    if rule in ('determined', AVERAGED) and fitter.determined_parts(segments) is None:
        rule = 'joint' if rule == 'determined' else 'joint start'
    burn = int(burn_in or 0)
    every = fitter
    fitter, parts, weights = _solve_rule(every, segments, rule, burn, tolerance)
    if burn_in is None and choose:
        burn = every.undetermined_start(segments, weights)
    if burn and not burn_in:
        fitter, parts, weights = _solve_rule(every, segments, rule, burn, tolerance)
        notes.append(f'the first {burn} samples are left out of the fit: no start state'
                     ' explains them (the record starts on a transient or after a history'
                     ' none of the candidates covers)')
    fit = _finish(record, design, fitter, parts, weights, segments, x, held, burn, notes)
    if _weight_rule(rule) == 'determined' and fit.fitted is not None:
        fitted = fit.fitted.copy()
        for seg in segments:
            fitted[seg.start:fitter.split(seg)] = False
        fit = replace(fit, fitted=fitted)
    if validate and rule not in folds:
        folds[rule] = _rule_fitter(every, segments, 'joint', burn).fold_errors(
            segments, _weight_rule(rule), x, y)
    return replace(fit, rule=rule, folds=folds)


def _weight_rule(label: str) -> str:
    # 'joint start' (start states chosen jointly with the weights) fits the weights jointly;
    # 'averaged' is cross-validated as itself (the mean of both rules' weights per fold).
    if label in ('determined', AVERAGED):
        return label
    return 'joint'


def _has_memory(segments: list[Segment]) -> bool:
    # Whether a segment starts from a memory (every play's state estimated).
    return any(seg.start_state is not None and seg.start_state.kind == 'memory'
               for seg in segments)


def _solve_rule(every: '_Fitter', segments: list[Segment], rule: str, burn: int,
                tolerance: float) -> tuple['_Fitter', GramParts,
                                           tuple[FloatArray, FloatArray, float, Any]]:
    # The final weights of a rule: its fitter (the burn-in's rows left out), the Gram parts
    # of its training rows and the QP's solution; for 'averaged' the fitter and parts of
    # every row, and the mean of the joint and the determined rows' solutions.
    if rule != AVERAGED:
        fitter = _rule_fitter(every, segments, _weight_rule(rule), burn)
        parts = fitter.parts(segments)
        if fitter is every and rule == 'determined':
            parts = fitter.determined_parts(segments) or parts      # cached: no new pass
        return fitter, parts, fitter.solve(parts, tolerance)
    fitter, parts, joint = _solve_rule(every, segments, 'joint', burn, tolerance)
    _, _, determined = _solve_rule(every, segments, 'determined', burn, tolerance)
    return fitter, parts, _mean_weights(joint, determined)


def _mean_weights(a: tuple[FloatArray, FloatArray, float, Any],
                  b: tuple[FloatArray, FloatArray, float, Any]) -> tuple[
                      FloatArray, FloatArray, float, Any]:
    # The mean of two solutions of the QP (the first one's solver info).
    return (0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1]), 0.5 * (a[2] + b[2]), a[3])


def _rule_fitter(fitter: '_Fitter', segments: list[Segment], rule: str,
                 burn: int) -> '_Fitter':
    # The fitter of the final weights: rows of the burn-in left out, and with the rule
    # 'determined' the rows before each segment's plays are determined (without a burn-in
    # the fitter itself: its determined_parts are those rows).
    if not burn:
        return fitter
    classes = fitter.classes.copy()
    classes[:burn] = -1
    if rule == 'determined':
        for seg in segments:
            classes[seg.start:fitter.split(seg)] = -1
    return _Fitter(fitter.xs, fitter.ys, fitter.design, classes, fitter.epsilon)


def fold_line_errors(current: FloatArray, displacement: FloatArray,
                     rows: npt.NDArray[np.bool_], folds: int = RECORD_FOLDS) -> FoldErrors:
    """
    Return the straight line's held-out errors on the folds of :meth:`_Fitter.fold_errors`.

    Parameters
    ----------
    current, displacement : ndarray of float, shape (N,)
        The record (the input the model sees).
    rows : ndarray of bool, shape (N,)
        The rows that are fitted and scored (outside ringing).
    folds : int
        Blocks.

    Returns
    -------
    FoldErrors
        The line ``y = a x + b`` fitted on the other folds, scored on each.

    """
    size = min(current.size, _CV_WINDOW)
    fold = fold_index(size, folds)
    x, y, keep = current[:size], displacement[:size], rows[:size]
    span = float(np.ptp(displacement))
    per_fold: list[float] = []
    inner_per_fold: list[float] = []
    excursions: list[float] = []
    counts: list[int] = []
    total, count, inner, inner_count = 0.0, 0, 0.0, 0
    input_span = float(np.ptp(x))
    for k in range(folds):
        train, test = keep & (fold != k), keep & (fold == k)
        inner_per_fold.append(math.nan)
        excursions.append(fold_excursion(x[test], x[train], input_span))
        counts.append(int(np.count_nonzero(test)))
        if int(np.count_nonzero(train)) < 2 or not np.any(test):
            per_fold.append(math.nan)
            continue
        xt, yt = x[train], y[train]
        xc = xt - float(np.mean(xt))
        denominator = float(np.sum(xc * xc))
        slope = float(np.sum(xc * (yt - float(np.mean(yt))))) / denominator if denominator \
            else 0.0
        e = float(np.mean(yt)) + slope * (x[test] - float(np.mean(xt))) - y[test]
        per_fold.append(float(np.sqrt(np.mean(e * e))) / span)
        total += float(np.sum(e * e))
        count += int(e.size)
        inside = (x[test] >= float(np.min(xt))) & (x[test] <= float(np.max(xt)))
        inner += float(np.sum(e[inside] ** 2))
        inner_count += int(np.count_nonzero(inside))
        if np.any(inside):
            inner_per_fold[-1] = float(np.sqrt(np.mean(e[inside] ** 2))) / span
    pooled = math.sqrt(total / count) / span if count else math.nan
    interior = math.sqrt(inner / inner_count) / span if inner_count else math.nan
    return FoldErrors(pooled, per_fold, 'line', interior,
                      1.0 - inner_count / count if count else 0.0, inner_per_fold,
                      excursions, counts)


def _finish(record: PreparedRecord, design: ScaledDesign, fitter: '_Fitter',
            parts: GramParts, weights: tuple[FloatArray, FloatArray, float, Any],
            segments: list[Segment], x: FloatArray, held: npt.NDArray[np.bool_] | None,
            burn: int, notes: list[str]) -> RecordFit:
    # The model with the first segment's start state, and its errors.
    w_h, w_s, constant, info = weights
    xs = fitter.xs
    first = segments[0].start_state
    z0 = (first.states(float(xs[0]), design.hysteresis_thresholds,
                       fitter._end(segments[0]) if first.kind == 'periodic' else None)
          if first is not None else np.zeros(w_h.size))
    model = design.model(w_h, w_s, constant, initial_states=z0)
    train = fitter.error(parts, weights, 0) * design.x_scale
    held_error = (fitter.error(parts, weights, 1) * design.x_scale
                  if held is not None else math.nan)
    return RecordFit(model, design, segments, x, train, held_error, burn, info, notes,
                     fitter.classes == 0)


def _finish_model(fitter: '_Fitter', segments: list[Segment], material_input: FloatArray,
                  w_h: FloatArray, w_s: FloatArray, constant: float) -> RecordFit:
    # A fit of given weights with the segments' start states, for its simulation.
    design = fitter.design
    first = segments[0].start_state
    xs = fitter.xs
    z0 = (first.states(float(xs[0]), design.hysteresis_thresholds,
                       fitter._end(segments[0]) if first.kind == 'periodic' else None)
          if first is not None else np.zeros(w_h.size))
    model = design.model(w_h, w_s, constant, initial_states=z0)
    return RecordFit(model, design, segments, material_input, math.nan, math.nan)


def _placeholder(segments: list[Segment]) -> list[Segment]:
    # A start state for every segment that has none: the first segment's periodic one,
    # the others continue.
    return [replace(seg, start_state=seg.start_state or (
        StartState('periodic') if i == 0 else None)) for i, seg in enumerate(segments)]


class _Fitter:
    """Gram matrices per segment and start state, and the QP on their sum."""

    def __init__(self, xs: FloatArray, ys: FloatArray, design: ScaledDesign,
                 classes: npt.NDArray[np.int8], epsilon: float) -> None:
        self.xs, self.ys, self.design = xs, ys, design
        self.classes = classes
        self.epsilon = epsilon
        self.r_h = design.hysteresis_thresholds
        self.r_s = design.inverse_superposition_thresholds
        self._suffix: dict[int, tuple[int, GramParts]] = {}
        self._prefixes: dict[tuple[int, bytes], GramParts] = {}
        self._dead_zones: dict[int, FloatArray] = {}
        self._splits: dict[tuple[int, int], int] = {}
        self._ends: dict[tuple[int, int], FloatArray] = {}
        self._fold_suffix: dict[tuple[int, int, int], GramParts] = {}

    def _state(self, seg: Segment, previous: FloatArray | None) -> FloatArray:
        u = self.xs[seg.start:seg.stop]
        if seg.start_state is None:
            if previous is not None:
                return previous
            return StartState('periodic').states(float(u[0]), self.r_h, self._end(seg))
        end = self._end(seg) if seg.start_state.kind == 'periodic' else None
        return seg.start_state.states(float(u[0]), self.r_h, end)

    def _end(self, seg: Segment) -> FloatArray:
        # The plays' states at the segment's end (a periodic start), once per segment.
        key = (seg.start, seg.stop)
        if key not in self._ends:
            self._ends[key] = end_state(self.xs[seg.start:seg.stop], self.r_h)
        return self._ends[key]

    def _segment_parts(self, seg: Segment, z0: FloatArray) -> GramParts:
        # Rows of the segment once its plays are determined do not depend on its start
        # state: accumulated once and reused.
        split = self.split(seg)
        key = (seg.start, z0.tobytes())
        prefix = self._prefixes.get(key)
        if prefix is None:
            prefix = regressor_gram(self.xs, self.ys, self.r_h, self.r_s, state=z0,
                                    classes=self.classes, n_classes=2, start=seg.start,
                                    stop=split)
            self._prefixes[key] = prefix
        if split >= seg.stop:
            return prefix
        cached = self._suffix.get(seg.start)
        if cached is None or cached[0] != split:
            suffix = regressor_gram(self.xs, self.ys, self.r_h, self.r_s,
                                    state=prefix.end_state, classes=self.classes,
                                    n_classes=2, start=split, stop=seg.stop)
            self._suffix[seg.start] = (split, suffix)
        else:
            suffix = cached[1]
        return prefix + suffix

    def parts(self, segments: list[Segment]) -> GramParts:
        """Return the Gram parts of the whole record for these start states."""
        total: GramParts | None = None
        previous: FloatArray | None = None
        for seg in segments:
            p = self._segment_parts(seg, self._state(seg, previous))
            previous = p.end_state
            total = p if total is None else total + p
        assert total is not None
        return total

    def solve(self, parts: GramParts, tolerance: float,
              selected: tuple[int, ...] = (0,)) -> tuple[FloatArray, FloatArray, float, Any]:
        """Solve the QP on the rows of the selected classes (training: 0); see :meth:`parts`."""
        gram, mean, count = parts.normalised(selected)
        if count == 0:
            msg = 'no samples left to fit (all in ringing windows or held out)'
            raise IdentificationError(msg)
        n1 = self.r_h.size
        idle = None
        if self.design.constant:
            gram = gram - np.outer(mean, mean)
            variance = np.diag(gram)[:n1]
            idle = np.flatnonzero(variance <= IDLE_PLAY ** 2 * variance[0])
        w_h, w_s, _, info = fit_generalized_error(
            gram, 1.0 - self.r_h, n_hysteresis=n1, n_superposition=self.r_s.size,
            superposition_center=self.design.center, epsilon=self.epsilon, fixed_zero=idle,
            tolerance=tolerance, outer_slope=OUTER_SLOPE)
        constant = (-float(mean @ np.concatenate([w_h, w_s])) if self.design.constant
                    else 0.0)
        return w_h, w_s, constant, info

    def error(self, parts: GramParts, weights: tuple[FloatArray, FloatArray, float, Any],
              cls: int) -> float:
        """Return the generalised RMS error, in scaled units, on the rows of one class."""
        count = int(parts.counts[cls])
        if count == 0:
            return math.nan
        w = np.concatenate([weights[0], weights[1]])
        c = weights[2]
        value = (float(w @ parts.grams[cls] @ w) + 2.0 * c * float(parts.sums[cls] @ w)
                 + c * c * count) / count
        return math.sqrt(max(value, 0.0))

    def split(self, seg: Segment) -> int:
        """Return the first sample of a segment whose plays no longer depend on its start."""
        key = (seg.start, seg.stop)
        if key not in self._splits:
            self._splits[key] = seg.start + determined_from(self.xs[seg.start:seg.stop],
                                                            float(self.r_h[-1]))
        return self._splits[key]

    def choose_starts(self, segments: list[Segment], *,
                      memory_steps: bool = False) -> list[Segment]:
        """
        Choose each segment's start state (see "Start states" above).

        The simple candidates (and, after the first segment, "continues") are one QP each;
        the histories with turning points are scored with the best simple candidate's
        weights on the rows before the plays are determined, and the best of those is
        refitted; the smallest generalised error wins.  A winning memory is refined by the
        steps between plays too with ``memory_steps`` (see :func:`refine_memory`).
        """
        chosen = _placeholder(segments)
        for i, seg in enumerate(segments):
            u = self.xs[seg.start:seg.stop]
            candidates: list[StartState | None] = list(start_candidates(u))
            if i > 0:
                candidates.insert(0, None)                  # continues from the previous
            best: tuple[float, StartState | None, Any] | None = None
            for cand in candidates:
                error, weights = self._trial(chosen, i, cand)
                if best is None or error < best[0] * (1.0 - 1e-6):
                    best = (error, cand, weights)
            if best is None:
                continue
            chosen[i] = replace(seg, start_state=best[1])
            # Histories with turning points, scored without a QP, then the best refitted.
            previous = self._previous_state(chosen, i)
            scored: list[tuple[float, StartState | None]] = [
                (self._prefix_error(seg, cand, best[2], previous), cand)
                for cand in turning_point_candidates(u)]
            scored.append((self._prefix_error(seg, best[1], best[2], previous), best[1]))
            top = scored[-1]
            for item in scored:
                if item[0] < top[0] * (1.0 - 1e-6):
                    top = item
            if top[1] is not best[1]:
                error, weights = self._trial(chosen, i, top[1])
                if error < best[0] * (1.0 - 1e-6):
                    chosen[i] = replace(seg, start_state=top[1])
                    best = (error, top[1], weights)
            chosen[i] = self._refine_memory(chosen, i, best, previous, memory_steps)
        return chosen

    def determined_parts(self, segments: list[Segment]) -> GramParts | None:
        """
        Return the Gram parts of the rows after each segment's plays are determined.

        Those rows do not depend on any start state (wiping-out): they are the segments'
        cached suffixes (no pass over the record of their own).  None: fewer than ten rows
        per weight.
        """
        total: GramParts | None = None
        for seg in segments:
            split = self.split(seg)
            if split >= seg.stop:
                continue
            cached = self._suffix.get(seg.start)
            if cached is None or cached[0] != split:
                u0 = float(self.xs[seg.start])
                self._segment_parts(seg, StartState('descent').states(u0, self.r_h))
                cached = self._suffix[seg.start]
            total = cached[1] if total is None else total + cached[1]
        weights = self.r_h.size + self.r_s.size
        if total is None or int(total.counts[0]) < 10 * weights:
            return None
        return total

    def choose_starts_determined(self, segments: list[Segment], *,
                                 memory_steps: bool = False) -> list[Segment] | None:
        """
        Choose each segment's start state with the weights of the determined rows fixed.

        The weights are fitted on the rows after the plays are determined (one QP); every
        candidate history (simple ones, turning points, "continues") is then scored by the
        generalised error of the rows before, with those weights: the start state explains
        the first samples, it cannot pull weights that only it supports.  A memory (every
        play's state) is refined on half of those rows (alternate blocks) and kept only when
        it lowers the error of the other half (then refined on all of them).

        Returns
        -------
        list of Segment or None
            The segments with their start states; None when too few rows are determined (the
            joint choice of :meth:`choose_starts` applies).

        """
        determined = self.determined_parts(segments)
        if determined is None:
            return None
        try:
            weights = self.solve(determined, _TRIAL_TOLERANCE)
        except IdentificationError:
            return None
        chosen = _placeholder(segments)
        for i, seg in enumerate(segments):
            u = self.xs[seg.start:seg.stop]
            previous = self._previous_state(chosen, i)
            candidates: list[StartState | None] = [*start_candidates(u),
                                                   *turning_point_candidates(u)]
            if i > 0:
                candidates.insert(0, None)                  # continues from the previous
            best: tuple[float, StartState | None] | None = None
            for cand in candidates:
                error = self._prefix_error(seg, cand, weights, previous)
                if best is None or error < best[0] * (1.0 - 1e-6):
                    best = (error, cand)
            assert best is not None
            chosen[i] = replace(seg, start_state=best[1])
            chosen[i] = self._refine_held_out(chosen[i], weights, previous, memory_steps)
        return chosen

    def _refine_held_out(self, seg: Segment, weights: Any, previous: FloatArray | None,
                         memory_steps: bool) -> Segment:
        # The joint estimate of the plays' states with fixed weights, judged on held-out
        # blocks of the rows before the plays are determined.
        split = self.split(seg)
        rows = slice(seg.start, split)
        train = self.classes[rows] == 0
        if split - seg.start < 16 or int(np.count_nonzero(train)) < 16:
            return seg
        index = np.arange(split - seg.start)
        half = (index * _PREFIX_BLOCKS // index.size) % 2 == 0
        u = self.xs[rows]
        w_h, w_s, constant, _ = weights
        target = self.prefix_dead_zones(seg) @ w_s - constant
        z = self._state(seg, previous)

        def error(states: FloatArray, mask: npt.NDArray[np.bool_]) -> float:
            plays, _ = play_operator(u, self.r_h, states)
            e = (plays @ w_h - target)[mask]
            return float(np.mean(e * e)) if e.size else 0.0

        for tails in (False, True) if memory_steps else (False,):
            if tails and not (seg.start_state is not None and seg.start_state.kind == 'memory'):
                break
            trial, _ = refine_memory(u, self.r_h, z, w_h, target, train & half, tails=tails)
            if not error(trial, train & ~half) < error(z, train & ~half) * (1.0 - 1e-6):
                break
            z, _ = refine_memory(u, self.r_h, z, w_h, target, train, tails=tails)
            seg = replace(seg, start_state=StartState('memory', memory=tuple(
                (float(r), float(v - u[0])) for r, v in zip(self.r_h, z))))
        return seg

    def fold_errors(self, segments: list[Segment], rule: str, material_input: FloatArray,
                    displacement: FloatArray, folds: int = RECORD_FOLDS) -> 'FoldErrors':
        """
        Return the held-out errors of blocked cross-validation of this fit's rule.

        The first :data:`_CV_WINDOW` samples are cut into ``folds`` contiguous blocks; each
        is held out once: the weights are fitted on the training rows of the others (the
        rows before the plays are determined left out with ``rule='determined'``), the model
        is simulated from the record's start state (each segment from its own) and scored by
        the RMS output error on the block's rows.  The Gram matrices are accumulated once
        per block and added.  With ``rule='averaged'`` each fold's weights are the mean of
        the ``'joint'`` and the ``'determined'`` solutions on the other folds.
        """
        size = min(self.xs.size, _CV_WINDOW)
        fold = fold_index(size, folds)
        train = self.classes[:size] == 0
        present = [seg for seg in segments if seg.start < size]
        rules = ('joint', 'determined') if rule == AVERAGED else (rule,)
        built = [self._fold_parts(present, r, fold, train, folds) for r in rules]
        fold_parts = [parts for parts, _ in built]
        parts, classes = built[0]
        windowed = [replace(seg, stop=min(seg.stop, size)) for seg in present]
        span = float(np.ptp(displacement))
        per_fold: list[float] = []
        inner_per_fold: list[float] = []
        excursions: list[float] = []
        counts: list[int] = []
        total, count = 0.0, 0
        inner, inner_count = 0.0, 0
        input_span = float(np.ptp(self.xs[:size]))
        for k in range(folds):
            rows = train & (fold == k)
            others = tuple(c for c in range(folds) if c != k)
            fitted = np.isin(classes[:size], others)
            seen = self.xs[:size][fitted]
            if seen.size:
                inside = (self.xs[:size] >= float(np.min(seen))) & (
                    self.xs[:size] <= float(np.max(seen)))
            else:
                inside = np.zeros(size, dtype=bool)
            inner_per_fold.append(math.nan)
            excursions.append(fold_excursion(self.xs[:size][rows], seen, input_span))
            counts.append(int(np.count_nonzero(rows)))
            if not np.any(rows):
                per_fold.append(math.nan)
                continue
            if int(sum(int(parts.counts[c]) for c in others)) == 0:
                # Nothing to fit without this fold: the rule cannot predict it.
                per_fold.append(math.inf)
                total, count = math.inf, count + int(np.count_nonzero(rows))
                continue
            try:
                solutions = [self.solve(p, _TRIAL_TOLERANCE, others) for p in fold_parts]
                w_h, w_s, constant, _ = (solutions[0] if len(solutions) == 1
                                         else _mean_weights(*solutions))
            except IdentificationError:
                per_fold.append(math.inf)
                total, count = math.inf, count + int(np.count_nonzero(rows))
                continue
            fit = _finish_model(self, windowed, material_input[:size], w_h, w_s, constant)
            residual = fit.simulate() - displacement[:size]
            e = residual[rows]
            per_fold.append(float(np.sqrt(np.mean(e * e))) / span)
            total += float(np.sum(e * e))
            count += int(e.size)
            e = residual[rows & inside]
            inner += float(np.sum(e * e))
            inner_count += int(e.size)
            if e.size:
                inner_per_fold[-1] = float(np.sqrt(np.mean(e * e))) / span
        pooled = math.sqrt(total / count) / span if count else math.nan
        interior = math.sqrt(inner / inner_count) / span if inner_count else math.nan
        return FoldErrors(pooled, per_fold, rule, interior,
                          1.0 - inner_count / count if count else 0.0, inner_per_fold,
                          excursions, counts)

    def _fold_classes(self, segments: list[Segment], rule: str,
                      fold: npt.NDArray[np.int8], train: npt.NDArray[np.bool_]
                      ) -> npt.NDArray[np.int8]:
        # Each training row's fold (-1: not fitted; with 'determined' also the rows before
        # each segment's plays are determined).
        size = fold.size
        classes = np.full(self.xs.size, -1, dtype=np.int8)
        classes[:size] = np.where(train, fold, -1)
        if rule == 'determined':
            for seg in segments:
                classes[seg.start:min(self.split(seg), size)] = -1
        return classes

    def _fold_parts(self, segments: list[Segment], rule: str, fold: npt.NDArray[np.int8],
                    train: npt.NDArray[np.bool_], folds: int
                    ) -> tuple[GramParts, npt.NDArray[np.int8]]:
        # The Gram parts per fold of a rule's training rows, each segment from its start,
        # and each row's fold (see _fold_classes).
        classes = self._fold_classes(segments, rule, fold, train)
        size = fold.size
        parts: GramParts | None = None
        state: FloatArray | None = None
        for seg in segments:
            # The rows after the plays are determined are the same for every start state
            # and rule: accumulated once per segment.
            z0 = self._state(seg, state)
            stop = min(seg.stop, size)
            split = min(self.split(seg), stop)
            p = regressor_gram(self.xs, self.ys, self.r_h, self.r_s, state=z0,
                               classes=classes, n_classes=folds, start=seg.start, stop=split)
            if split < stop:
                key = (seg.start, stop, folds)
                if key not in self._fold_suffix:
                    self._fold_suffix[key] = regressor_gram(
                        self.xs, self.ys, self.r_h, self.r_s, state=p.end_state,
                        classes=classes, n_classes=folds, start=split, stop=stop)
                p = p + self._fold_suffix[key]
            state = p.end_state
            parts = p if parts is None else parts + p
        assert parts is not None
        return parts, classes

    def _refine_memory(self, chosen: list[Segment], i: int,
                       best: tuple[float, StartState | None, Any],
                       previous: FloatArray | None, memory_steps: bool) -> Segment:
        # A joint estimate of every play's start state (a history with more turning points
        # than the grid), kept when its refit beats the best history.
        seg = chosen[i]
        if self.split(seg) <= seg.start + 1 or best[2] is None:
            return seg
        u = self.xs[seg.start:seg.stop]
        error, _, weights = best
        z = self._state(seg, previous)
        rows = slice(seg.start, self.split(seg))
        # One play at a time; where that memory beats every simple history, the steps
        # between plays too (see refine_memory).
        for tails in (False, True) if memory_steps else (False,):
            if tails and not (seg.start_state is not None
                              and seg.start_state.kind == 'memory'):
                break
            for _ in range(_MEMORY_ROUNDS):       # refine with the weights, refit, again
                w_h, w_s, constant, _ = weights
                target = self.prefix_dead_zones(seg) @ w_s - constant
                refined, _ = refine_memory(self.xs[rows], self.r_h, z, w_h, target,
                                           self.classes[rows] == 0, tails=tails)
                if np.allclose(refined, z):
                    break
                memory = StartState('memory', memory=tuple(
                    (float(r), float(v - u[0])) for r, v in zip(self.r_h, refined)))
                trial_error, trial_weights = self._trial(chosen, i, memory)
                if not trial_error < error * (1.0 - 1e-6):
                    break
                # The steps may fit the generalised error of transients (ringing tails)
                # while the output gets worse: they must lower the output's error there too.
                if tails and trial_weights is not None and not (
                        self._output_error(seg, refined, trial_weights)
                        < self._output_error(seg, z, weights)):
                    break
                seg, error, weights, z = (replace(seg, start_state=memory), trial_error,
                                          trial_weights, refined)
        return seg

    def _output_error(self, seg: Segment, z0: FloatArray, weights: Any) -> float:
        # RMS error (scaled) of the model's output before the segment's plays are
        # determined (after that, the start state does not matter).
        rows_ = slice(seg.start, self.split(seg))
        train = self.classes[rows_] == 0
        if not np.any(train):
            return 0.0
        w_h, w_s, constant, _ = weights
        d = self.design
        model = d.model(w_h, w_s, constant, initial_states=z0)
        simulated = model.simulate(self.xs[rows_] * d.x_scale + d.input_offset)
        e = (d.scaled_output(simulated) - self.ys[rows_])[train]
        return float(np.sqrt(np.mean(e * e)))

    def _trial(self, chosen: list[Segment], i: int,
               cand: StartState | None) -> tuple[float, Any]:
        trial = chosen[:i] + [replace(chosen[i], start_state=cand)] + chosen[i + 1:]
        parts = self.parts(trial)
        try:
            weights = self.solve(parts, _TRIAL_TOLERANCE)
        except IdentificationError:
            return math.inf, None
        return self.error(parts, weights, 0), weights

    def _previous_state(self, chosen: list[Segment], i: int) -> FloatArray | None:
        if i == 0:
            return None
        return self.parts(chosen[:i]).end_state

    def _prefix_error(self, seg: Segment, cand: StartState | None, weights: Any,
                      previous: FloatArray | None) -> float:
        # Generalised RMS error on the training rows before the segment's plays are
        # determined, with fixed weights: what a start state changes.
        if weights is None:
            return math.inf
        return self._prefix_error_of(seg, self._state(replace(seg, start_state=cand), previous),
                                     weights)

    def _prefix_error_of(self, seg: Segment, z0: FloatArray, weights: Any) -> float:
        # The same for given start states of the plays.
        rows_ = slice(seg.start, self.split(seg))
        train = self.classes[rows_] == 0
        if not np.any(train):
            return 0.0
        plays, _ = play_operator(self.xs[rows_], self.r_h, z0)
        w_h, w_s, constant, _ = weights
        e = (plays @ w_h - self.prefix_dead_zones(seg) @ w_s + constant)[train]
        return float(np.sqrt(np.mean(e * e)))

    def prefix_dead_zones(self, seg: Segment) -> FloatArray:
        """Return S' regressors of the samples before the segment's plays are determined."""
        cached = self._dead_zones.get(seg.start)
        if cached is None:
            cached = dead_zone_operator(self.ys[seg.start:self.split(seg)], self.r_s)
            self._dead_zones[seg.start] = cached
        return cached

    def undetermined_start(self, segments: list[Segment],
                           weights: tuple[FloatArray, FloatArray, float, Any]) -> int:
        """Return a burn-in when the first segment's start is explained by no candidate."""
        seg = segments[0]
        split = self.split(seg)
        if split >= seg.stop or split < 10:
            return 0
        z0 = self._state(seg, None)
        rest = self._segment_parts(seg, z0)
        prefix = self._prefixes[(seg.start, z0.tobytes())]
        before = self.error(prefix, weights, 0)
        total = self.error(rest, weights, 0)
        if not (math.isfinite(before) and math.isfinite(total)):
            return 0
        after_sq = (total ** 2 * rest.counts[0] - before ** 2 * prefix.counts[0]) / max(
            int(rest.counts[0] - prefix.counts[0]), 1)
        after = math.sqrt(max(after_sq, 0.0))
        if before > max(_START_TOLERANCE * after, _START_FLOOR):
            return int(split)
        return 0


def _to_model_states(z: FloatArray, design: ScaledDesign, model: MPIModel) -> FloatArray:
    # Scaled play states -> the model's (SI, relative to its input offset): the plays of
    # (x - x0_design) / x_scale shifted by the constant's input shift.
    shift = design.input_offset - model.input_offset
    return np.asarray(z, dtype=np.float64) * design.x_scale + shift
