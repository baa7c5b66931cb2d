# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
The parts of a diagnosis report as typed records: one field per fact, named as in the JSON.

:class:`~mpi_ros.diagnosis.diagnose.DiagnosisReport` holds a :class:`Baseline`, the
:class:`Extended` model, the :class:`ScoredCandidate` list, a :class:`Residual`, a
:class:`Decision`, the :class:`RecordFacts` and the :class:`Series` (a record outside the
invertible class: :class:`Reversals` and :class:`Refusal`, no baseline, no extended model).  The
JSON (``to_json``), the summary lines, ``summary.md``, the plot titles and the captions
are written from these fields, so they cannot disagree; a field's name is its JSON key.

Each part is also a read-only mapping from its JSON keys to the plain form of its values
(``decision['steps']``, ``residual['hold_signature']['log_p']``): the form the effects'
signature tests and evidence sentences read (:attr:`mpi_ros.extensions.Effect.signature`),
and the form of the JSON before the non-finite numbers become ``null``.  Setting an item
sets the field of that name; a name that is no field raises :class:`KeyError` (add the
field here, where the report's facts are listed once).
"""

from collections.abc import Iterator, Mapping
from dataclasses import asdict, dataclass, field, fields
import math
from typing import Any, cast, ClassVar

import numpy as np
import numpy.typing as npt

from .signatures import BurstSignature, HoldSignature
from ..extensions import EFFECTS
from ..extensions.effect import key_words
from ..identification.finding import DynamicsFinding

__all__ = ['ReportPart', 'Baseline', 'OperatingPoint', 'Residual', 'HoldCount', 'StepOnsetCheck',
           'Reversals', 'Decision', 'Ranked', 'Refusal', 'RecordFacts', 'ScoredPart',
           'ReturnPoints', 'Series', 'FittedParameter', 'ScoredCandidate', 'Extended',
           'jsonable']

FloatArray = npt.NDArray[np.float64]


class ReportPart(Mapping[str, Any]):
    """
    A typed part of the report, readable as a mapping by its JSON keys.

    A subclass is a dataclass; the fields named in :attr:`optional` are left out of the
    JSON (and of the mapping) while they hold None: keys only some reports have (a split's
    ``training_samples``, a weak verdict's ``weak_reason``).

    """

    #: Fields left out while they hold None.
    optional: ClassVar[frozenset[str]] = frozenset()

    def to_dict(self) -> dict[str, Any]:
        """Return the plain form: nested parts as dicts, arrays and numbers as they are."""
        return {key: self[key] for key in self}

    def to_json(self) -> dict[str, Any]:
        """Return the JSON form (lists and finite floats; non-finite numbers as None)."""
        form: dict[str, Any] = jsonable(self.to_dict())
        return form

    def _keys(self) -> list[str]:
        return [f.name for f in fields(cast(Any, self))
                if not (f.name in self.optional and getattr(self, f.name) is None)]

    def __getitem__(self, key: str) -> Any:
        """Return the plain form of the field ``key`` (KeyError when it is absent)."""
        if key not in self._keys():
            raise KeyError(key)
        return _plain(getattr(self, key))

    def __setitem__(self, key: str, value: Any) -> None:
        """Set the field ``key``; a name that is no field raises KeyError."""
        if key not in {f.name for f in fields(cast(Any, self))}:
            msg = (f'{type(self).__name__} has no field {key!r}; add it to'
                   ' mpi_ros/diagnosis/facts.py')
            raise KeyError(msg)
        setattr(self, key, value)

    def __iter__(self) -> Iterator[str]:
        """Iterate over the keys present."""
        return iter(self._keys())

    def __len__(self) -> int:
        """Return the number of keys present."""
        return len(self._keys())


@dataclass(eq=False)
class OperatingPoint(ReportPart):
    """
    The baseline's operating point (:attr:`mpi_ros.MPIModel.input_offset` and so on).

    Attributes
    ----------
    input_offset : float
        ``x0`` [A or V].
    output_offset : float
        ``y0`` [m].
    output_sign : int
        +1, or -1 for a falling sensor.

    """

    input_offset: float
    output_offset: float
    output_sign: int


@dataclass(eq=False)
class Baseline(ReportPart):
    """
    Gamma alone on the validation data.

    Attributes
    ----------
    order : (int, int)
        ``(n, l)``.
    rms_error, nonlinearity_error : float
        Its RMS error and (37) on the scored validation data, fractions of the measured
        output's range.
    training_rms_error : float
        Its RMS error on the training record's determined samples (after its burn-in,
        simulated from the record's start), a fraction of that output's range: measured as
        each candidate's (``identify``'s own figure leaves out the samples its fit does not
        use, so an effect fitted off read up to 1.49x it on the wide sweep).
    validation_output_offset : float
        The re-estimated sensor zero of a separate validation record [m]; 0 for a split.
    linear_rms_error : float
        The training data's straight line on the scored validation data, a fraction of
        the output's range.
    operating_point : OperatingPoint
        ``x0``, ``y0``, the sign.

    """

    order: tuple[int, int]
    rms_error: float
    nonlinearity_error: float
    training_rms_error: float
    validation_output_offset: float
    linear_rms_error: float
    operating_point: OperatingPoint


@dataclass(frozen=True)
class FittedParameter:
    """
    One fitted parameter of a candidate, with its unit from the registry.

    Attributes
    ----------
    key : str
        The parameter key (``model.dead_time``, ``model.creep.time_constants``).
    value : float or tuple of float
        The fitted value, in ``unit``.
    unit : str
        Its SI unit (:attr:`mpi_ros.extensions.effect.EffectParameter.unit`; '' when
        dimensionless or not registered).
    name : str
        Its name in the report's words (:attr:`mpi_ros.extensions.effect.EffectParameter.words`;
        the key's last part when not registered: ``model.resonance.frequency``: frequency).

    """

    key: str
    value: float | tuple[float, ...]
    unit: str
    name: str


@dataclass(frozen=True, eq=False)
class ScoredCandidate(ReportPart):
    """
    One candidate extension as the report states it, scored on the validation data.

    Attributes
    ----------
    cause : str
        The effect's name (two joined by ``' + '`` for a pair).
    rms_error, nonlinearity_error : float
        Its validation errors, fractions of the output range.
    gain : float
        Relative reduction of the baseline's validation RMS error.
    z : float
        Diebold-Mariano statistic against the baseline (one-sided).
    bandwidth : int
        Its HAC lags.
    training_rms_error : float
        Its RMS error on the training record's determined samples, a fraction of that
        output's range.
    validation_output_offset : float
        The validation record's re-estimated sensor zero for it [m].
    parameter_count : int
        Free parameters of the effect(s).
    parameters : dict of str to float or list of float
        The effect's identified parameters, in the units of :meth:`fitted` (Gamma's left
        out, and those in ``not_identified``).
    not_identified : dict of str to str
        Parameter key -> why the fit could not identify it (at a bound of its search range).
    signature : str
        ``present``, ``absent`` or ``unavailable`` (the physical signature).
    significant : bool
        Gain and z above the bars, and the baseline above the noise.
    parts : list of str or None
        A pair's effects (None, and absent from the JSON, for one effect).
    part_gains, part_z : dict of str to float or None
        For a pair: each effect's gain beyond the other alone, and its z.

    """

    optional: ClassVar[frozenset[str]] = frozenset({'parts', 'part_gains', 'part_z'})

    cause: str
    rms_error: float
    nonlinearity_error: float
    gain: float
    z: float
    bandwidth: int
    training_rms_error: float
    validation_output_offset: float
    parameter_count: int
    parameters: dict[str, Any]
    not_identified: dict[str, str]
    signature: str
    significant: bool
    parts: list[str] | None = None
    part_gains: dict[str, float] | None = None
    part_z: dict[str, float] | None = None

    @property
    def effects(self) -> list[str]:
        """Return the effects it is made of: a pair's parts, or its own name."""
        return list(self.parts) if self.parts else [self.cause]

    def fitted(self) -> list[FittedParameter]:
        """
        Return the identified parameters, in the order of :attr:`parameters`, with units.

        A number becomes a float, a list of numbers a tuple of floats; the unit and the
        name are the registry's (:class:`mpi_ros.extensions.effect.EffectParameter`).

        """
        registered = {p.key: p for e in EFFECTS.values() for p in e.parameters}
        out = []
        for key, value in self.parameters.items():
            known = registered.get(key)
            unit = known.unit if known else ''
            name = known.words if known else key_words(key)
            if isinstance(value, (list, tuple, np.ndarray)):
                out.append(FittedParameter(key, tuple(float(v) for v in value), unit, name))
            elif isinstance(value, (int, float, np.number)) and not isinstance(value, bool):
                out.append(FittedParameter(key, float(value), unit, name))
        return out


@dataclass(frozen=True, eq=False)
class Extended(ReportPart):
    """
    The chosen model on the validation data: an extension, or the baseline for ``none``.

    For ``none`` it is the :class:`Baseline` (its fields, no ``cause``); for an effect the
    chosen candidate's errors.  Both have ``parameters`` and ``not_identified`` (empty for
    the baseline).

    Attributes
    ----------
    cause : str or None
        The chosen candidate (None, and absent from the JSON, for the baseline).
    order : (int, int) or None
        The baseline's ``(n, l)`` (only for the baseline).
    rms_error, nonlinearity_error : float
        Its RMS error and (37) on the scored validation data, fractions of the output's
        range.
    training_rms_error, validation_output_offset, linear_rms_error : float or None
        The baseline's (only for the baseline; see :class:`Baseline`).
    operating_point : OperatingPoint or None
        The baseline's (only for the baseline).
    parameters : dict of str to float or list of float
        The chosen candidate's identified parameters (:attr:`ScoredCandidate.parameters`).
    not_identified : dict of str to str
        Its parameters at a bound of their search range, with why.

    """

    optional: ClassVar[frozenset[str]] = frozenset({
        'cause', 'order', 'training_rms_error', 'validation_output_offset',
        'linear_rms_error', 'operating_point'})

    cause: str | None
    order: tuple[int, int] | None
    rms_error: float
    nonlinearity_error: float
    training_rms_error: float | None
    validation_output_offset: float | None
    linear_rms_error: float | None
    operating_point: OperatingPoint | None
    parameters: dict[str, Any]
    not_identified: dict[str, str]

    @classmethod
    def of_baseline(cls, baseline: Baseline) -> 'Extended':
        """Return the baseline as the chosen model (no effect named)."""
        return cls(None, baseline.order, baseline.rms_error, baseline.nonlinearity_error,
                   baseline.training_rms_error, baseline.validation_output_offset,
                   baseline.linear_rms_error, baseline.operating_point, {}, {})

    @classmethod
    def of_candidate(cls, candidate: ScoredCandidate) -> 'Extended':
        """Return the chosen candidate's model."""
        return cls(candidate.cause, None, candidate.rms_error, candidate.nonlinearity_error,
                   None, None, None, None, dict(candidate.parameters),
                   dict(candidate.not_identified))


@dataclass(eq=False)
class HoldCount(ReportPart):
    """
    The input holds in the scored part and the baseline residual's change over them.

    Attributes
    ----------
    count : int
        Holds of ``minimum_duration`` or more.
    minimum_duration : float
        Shortest hold counted [s].
    signature_minimum_duration : float
        Shortest hold the hold signature test uses [s].
    mean_abs_residual_change : float
        Mean absolute change of the residual over a hold [m].
    change_along_last_step : float
        Mean change in the direction of the step before the hold [m].

    """

    count: int
    minimum_duration: float
    signature_minimum_duration: float
    mean_abs_residual_change: float
    change_along_last_step: float


@dataclass(eq=False)
class StepOnsetCheck(ReportPart):
    """
    How fast the output follows the record's steps, and what that says of a dead time.

    Attributes
    ----------
    bound : float
        The output moves within this time of a step [s].
    steps : int
        Steps measured.
    dead_time_check : str
        The decision step when the fitted dead time exceeds it ('' when it does not).

    """

    bound: float
    steps: int
    dead_time_check: str


@dataclass(eq=False)
class Residual(ReportPart):
    """
    The structure of the baseline's residual on the scored validation data.

    Attributes
    ----------
    rms : float
        RMS residual [m].
    noise_floor : float
        Sensor-noise standard deviation [m] (:func:`mpi_ros.diagnosis.noise_floor`).
    noise_floor_relative : float
        The same over the output's range.
    holds : HoldCount
        The input holds.
    rate_correlation, power_correlation : float
        Correlation of the residual with the input rate and the lagged input power.
    rms_by_rate_quintile : list of float
        RMS residual [m] in five classes of input speed, slowest first.
    lag_of_best_correlation : float
        Lag of the best rate cross-correlation of measured and simulated output [s].
    hold_signature : HoldSignature or None
        The hold test (None: no hold long enough).
    burst_signature : BurstSignature or None
        The burst test (None: no bursts it can use).
    step_onset : StepOnsetCheck or None
        The step response's onset (None: no step measured).

    """

    rms: float
    noise_floor: float
    noise_floor_relative: float
    holds: HoldCount
    rate_correlation: float
    rms_by_rate_quintile: list[float]
    power_correlation: float
    lag_of_best_correlation: float
    hold_signature: HoldSignature | None = None
    burst_signature: BurstSignature | None = None
    step_onset: StepOnsetCheck | None = None


@dataclass(eq=False)
class Reversals(ReportPart):
    """
    The residual part of a record outside the invertible class (no model fitted).

    Attributes
    ----------
    reversal_ratio : float
        Output travel against the branch direction over the total travel.
    branches : int
        Long monotone input branches examined.

    """

    reversal_ratio: float
    branches: int


@dataclass(eq=False)
class Ranked(ReportPart):
    """
    One candidate in the ranking by validation gain.

    Attributes
    ----------
    cause : str
        The candidate.
    gain : float
        Its validation gain (relative cut of the baseline's RMS error).
    z_against_chosen : float
        Diebold-Mariano z of the chosen candidate against it (NaN for the chosen one).
    significant : bool
        Whether it counts.
    signature : str
        ``present``, ``absent`` or ``unavailable``.

    """

    cause: str
    gain: float
    z_against_chosen: float
    significant: bool
    signature: str


@dataclass(eq=False)
class Decision(ReportPart):
    """
    The rule's thresholds and the steps it took.

    Attributes
    ----------
    min_gain, z_critical, alpha, signature_level, noise_factor : float
        The thresholds (the options of :func:`~mpi_ros.diagnosis.diagnose`;
        ``signature_level`` is ``alpha`` over the number of registered effects).
    bandwidth : int or None
        The HAC bandwidth asked for (None: chosen per test).
    noise_floor : float
        The baseline's noise floor [m].
    baseline_above_noise : bool
        The baseline's residual exceeds ``noise_factor`` times the noise floor.
    steps : list of str
        The decision's steps, in order.
    ranking : list of Ranked
        Every candidate by gain, with its z against the chosen one.
    ambiguous : bool
        Some candidates tie with the chosen one.
    tied_with : list of str
        Those candidates.
    tie_reasons : dict of str to str
        Per tied candidate, why (the validation data's z, or the record's dynamics finding).
    separate_by : str
        The measurement that would separate the tied causes ('' without a tie).
    dynamics_finding : str
        The kind of the dynamics finding ``identify`` states for the record.
    strength_bar : float
        The gain from which a named effect is clear.
    strength : str
        ``none``, ``clear`` or ``present, weak``.
    weak_reason : str or None
        Why a named effect is weak (only then).

    """

    optional: ClassVar[frozenset[str]] = frozenset({'weak_reason'})

    min_gain: float
    z_critical: float
    alpha: float
    signature_level: float
    bandwidth: int | None
    noise_factor: float
    noise_floor: float
    baseline_above_noise: bool
    steps: list[str] = field(default_factory=list)
    ranking: list[Ranked] = field(default_factory=list)
    ambiguous: bool = False
    tied_with: list[str] = field(default_factory=list)
    tie_reasons: dict[str, str] = field(default_factory=dict)
    separate_by: str = ''
    dynamics_finding: str = 'unavailable'
    strength_bar: float = 0.0
    strength: str = 'none'
    weak_reason: str | None = None


@dataclass(eq=False)
class Refusal(ReportPart):
    """
    The decision part of a record outside the invertible class.

    Attributes
    ----------
    rule : str
        What was decided, in words.

    """

    rule: str


@dataclass(eq=False)
class ScoredPart(ReportPart):
    """
    The part of the validation record that is scored.

    Attributes
    ----------
    from_sample : int
        Its first sample.
    samples : int
        Its length.
    left_out : str
        What the samples before it are (``'nothing'`` when none).
    start_state : str
        Where each model starts on it.

    """

    from_sample: int
    samples: int
    left_out: str
    start_state: str


@dataclass(eq=False)
class ReturnPoints(ReportPart):
    """
    The output at the input's repeated extreme (a drift does not return there).

    Attributes
    ----------
    visits : int
        Visits of the extreme.
    change : float
        Output at the last visit minus the first, over the output's range.
    monotone : bool
        The output moved the same way between visits.
    end : str
        ``'maximum'`` or ``'minimum'``.
    drifts : bool
        The verdict: a drift.

    """

    visits: int
    change: float
    monotone: bool
    end: str
    drifts: bool


@dataclass(eq=False)
class RecordFacts(ReportPart):
    """
    The records, their parts and what was found of them before any model.

    Attributes
    ----------
    source : str
        The training record.
    samples : int
        Its samples.
    validation : str
        The validation record (or which samples of the same record).
    validation_block : list of int or None
        A block inside the record held out for validation, ``[a, b)`` (samples).
    split, training_samples, leading_hold : float, int, int or None
        A split record: the training fraction, the training samples, the samples of a hold
        at the record's start given to training.
    validation_samples : int or None
        A separate validation record's samples.
    validation_scored : ScoredPart or None
        The scored part.
    output_sign : int or None
        The sign detected on the training data.
    class_check : str or None
        The invertible-class check's finding, when its branch test failed.
    dynamics_finding : DynamicsFinding or None
        What ``identify`` states of the record's dynamics.
    training_burn_in, validation_burn_in : int or None
        Samples before the plays are determined.
    output_offset_reestimated : bool or None
        Only the validation record's output offset is re-estimated.
    validation_outside_training_range : float or None
        Fraction of the scored samples whose input leaves the training range.
    return_point_drift : ReturnPoints or None
        The return-point test of a drift.
    units : dict of str to str or None
        ``time``, ``input``, ``output``, ``from`` (:func:`mpi_ros.diagnosis.report.data_units`).

    """

    optional: ClassVar[frozenset[str]] = frozenset({
        'split', 'training_samples', 'leading_hold', 'validation_block', 'validation_samples',
        'validation_scored', 'output_sign', 'class_check', 'dynamics_finding',
        'training_burn_in', 'validation_burn_in', 'output_offset_reestimated',
        'validation_outside_training_range', 'return_point_drift', 'units'})

    source: str
    samples: int
    validation: str
    split: float | None = None
    training_samples: int | None = None
    leading_hold: int | None = None
    validation_block: list[int] | None = None
    validation_samples: int | None = None
    validation_scored: ScoredPart | None = None
    output_sign: int | None = None
    class_check: str | None = None
    dynamics_finding: DynamicsFinding | None = None
    training_burn_in: int | None = None
    validation_burn_in: int | None = None
    output_offset_reestimated: bool | None = None
    validation_outside_training_range: float | None = None
    return_point_drift: ReturnPoints | None = None
    units: dict[str, str] | None = None


@dataclass(eq=False)
class Series(ReportPart):
    """
    The arrays the plots are drawn from (not serialised).

    Attributes
    ----------
    time, current, displacement : ndarray of float, shape (N,)
        The validation record (the whole record for a split) [s], [A or V], [m].
    start : int
        The first scored sample.
    baseline : ndarray of float, shape (N,), or None
        Gamma's simulation [m] (None: no model fitted).
    candidates : dict of str to ndarray
        Each candidate's simulation [m].

    """

    time: FloatArray
    current: FloatArray
    displacement: FloatArray
    start: int
    baseline: FloatArray | None = None
    candidates: dict[str, FloatArray] = field(default_factory=dict)


def jsonable(value: Any) -> Any:
    """
    Return ``value`` in JSON form: dicts, lists, bools, ints, finite floats, None, text.

    Parts become dicts, arrays lists, non-finite floats None.

    """
    if isinstance(value, (ReportPart, HoldSignature, BurstSignature, DynamicsFinding)):
        return jsonable(_plain(value))
    if isinstance(value, dict):
        return {str(k): jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [jsonable(v) for v in value]
    if isinstance(value, np.ndarray):
        return [jsonable(v) for v in value.tolist()]
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    if isinstance(value, (int, np.integer)):
        return int(value)
    if isinstance(value, (float, np.floating)):
        v = float(value)
        return v if math.isfinite(v) else None
    return value


def _plain(value: Any) -> Any:
    # The plain form of a field: parts and signatures as dicts (the JSON's shape), a
    # container holding some as a new container; anything else, the object itself (so that
    # part['steps'].append(...) appends to the field).
    if isinstance(value, ReportPart):
        return value.to_dict()
    if isinstance(value, HoldSignature):
        return asdict(value)
    if isinstance(value, BurstSignature):
        return {**asdict(value), 'law': value.law,
                'log_ratio': [[v.real, v.imag] for v in value.log_ratio]}
    if isinstance(value, DynamicsFinding):
        return value.to_json()
    if isinstance(value, (list, tuple)):
        items = [_plain(v) for v in value]
        if all(a is b for a, b in zip(items, value)):
            return value
        return items
    if isinstance(value, dict):
        converted = {k: _plain(v) for k, v in value.items()}
        if all(converted[k] is v for k, v in value.items()):
            return value
        return converted
    return value
