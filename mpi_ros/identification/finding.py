# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
The dynamics finding of a record: a lag, a dead time, a tie or none; one rule, two commands.

``mpi-ros identify`` and ``mpi-ros diagnose`` state what moves the output after the input
from one analysis of the same record (:func:`record_dynamics`): the record prepared once
(time base, segments, ringing windows: :func:`~mpi_ros.identification.record.prepare_record`),
the dead-time and lag grids scored on held-out blocks of its busiest window
(:func:`estimate_record_dynamics`, the identification's own estimate), and the physical
check of the step response (:func:`~mpi_ros.identification.dynamics.step_onset`).  So the
two commands give the same finding on the same record; the diagnosis' validation then tests
the candidate effects on data the fit did not see, and states a tie when it disagrees.

The rule (:func:`dynamics_finding`), on the held-out blocks both commands score:

- a kind *explains* the record when it beats the static model beyond the noise (a paired
  test over the held-out blocks, :func:`~mpi_ros.identification.ties.compare_on_blocks`)
  and by at least :data:`EXPLAIN_FLOOR` of its error (a consistent gain smaller than that
  is not worth a finding);
- a dead time must show in the step response: after an input step the output stays still
  for the dead time.  A fitted dead time longer than the onset the record's steps show (plus
  one sample for the step's place between two samples) is not physical, and does not
  explain anything;
- both kinds explain and their held-out errors are within the noise of each other (the same
  paired test between the two): a **tie** (one excitation rate cannot tell a lag from a
  dead time; a step or bursts at two rates can);
- else the kind that explains better; ``none`` when neither does; ``unavailable`` without
  a time base.
"""

from collections.abc import Callable
from dataclasses import dataclass, field
import math
from typing import Any

import numpy as np
import numpy.typing as npt

from .dynamics import InputDynamics, step_onset, StepOnset
from .dynamics_grid import DynamicsEstimate, estimate_dynamics
from .fitter import fit_record
from .folds import held_out_rows
from .record import prepare_record, PreparedRecord
from .ties import BlockComparison

__all__ = ['DYNAMICS_WINDOW', 'DynamicsFinding', 'dynamics_finding', 'estimate_record_dynamics',
           'EXPLAIN_FLOOR', 'FINDING_KINDS', 'finding_of', 'MODEL_GAIN', 'record_dynamics',
           'reference_order', 'SEPARATE_LAG_AND_DEAD_TIME']

FloatArray = npt.NDArray[np.float64]

#: A kind explains the record only when it beats the static model's held-out error by at
#: least this fraction, besides beating it beyond the noise of the held-out blocks.
EXPLAIN_FLOOR = 0.03

#: The identification models a kind when it cuts the static model's held-out error by this
#: fraction (the bar of :func:`~mpi_ros.identification.dynamics_grid.estimate_dynamics`).
MODEL_GAIN = 0.1

#: The findings.
FINDING_KINDS = ('none', 'lag', 'dead_time', 'tie', 'unavailable')

#: What separates a lag from a dead time (the report's words).
SEPARATE_LAG_AND_DEAD_TIME = (
    'a step (a dead time holds the output still for its length, a lag moves it at once),'
    " or bursts at two or more rates (a lag's phase saturates and its amplitude falls with"
    " the frequency, a dead time's phase grows in proportion to it)")

#: Samples of the window the dynamics grid runs on (a long record's busiest part).
DYNAMICS_WINDOW = 20000


@dataclass(frozen=True)
class DynamicsFinding:
    """
    What moves the output after the input, decided by :func:`dynamics_finding`.

    Attributes
    ----------
    kind : str
        ``'lag'``, ``'dead_time'``, ``'tie'``, ``'none'`` or ``'unavailable'`` (no time
        base).
    dead_time, lag_time_constant : float
        The best of each kind on the held-out blocks [s].
    static_error, dead_time_error, lag_error : float
        Their held-out RMS errors [fraction of the output range].
    onset : StepOnset
        How soon the output moves after the record's steps.
    dead_time_physical : bool
        The dead time fits inside the step response's onset (True without a step).
    modelled : InputDynamics
        What the identification models (a non-physical dead time is replaced by the lag
        when the lag clears the same bar, else nothing).
    reason : str
        The rule's words for this record.

    """

    kind: str = 'unavailable'
    dead_time: float = 0.0
    lag_time_constant: float = 0.0
    static_error: float = math.nan
    dead_time_error: float = math.nan
    lag_error: float = math.nan
    onset: StepOnset = field(default_factory=StepOnset)
    dead_time_physical: bool = True
    modelled: InputDynamics = field(default_factory=InputDynamics)
    reason: str = ''

    @property
    def separate_by(self) -> str:
        """Return what measurement would separate a tie ('' when there is none)."""
        return SEPARATE_LAG_AND_DEAD_TIME if self.kind == 'tie' else ''

    def describe(self) -> str:
        """Return the finding in words (one clause; '' when unavailable)."""
        if self.kind == 'unavailable':
            return ''
        text = f'dynamics finding: {self.kind.replace("_", " ")} ({self.reason})'
        if self.kind == 'tie':
            text += f'; to separate them: {self.separate_by}'
        return text

    def to_json(self) -> dict[str, Any]:
        """Return the JSON form."""
        def finite(value: float) -> float | None:
            return value if math.isfinite(value) else None
        return {'kind': self.kind, 'dead_time': self.dead_time,
                'lag_time_constant': self.lag_time_constant,
                'static_held_out_error': finite(self.static_error),
                'dead_time_held_out_error': finite(self.dead_time_error),
                'lag_held_out_error': finite(self.lag_error),
                'step_onset': finite(self.onset.bound), 'step_onset_steps': self.onset.steps,
                'dead_time_physical': self.dead_time_physical, 'reason': self.reason,
                'separate_by': self.separate_by, 'text': self.describe()}


def dynamics_finding(estimate: DynamicsEstimate, onset: StepOnset,
                     sample_period: float) -> DynamicsFinding:
    """
    Decide lag, dead time, tie or none from the held-out errors and the step response.

    Parameters
    ----------
    estimate : DynamicsEstimate
        The identification's estimate (:func:`estimate_record_dynamics`).
    onset : StepOnset
        The record's step response (:func:`~mpi_ros.identification.dynamics.step_onset`).
    sample_period : float
        The record's sample period [s] (a step falls between two samples).

    Returns
    -------
    DynamicsFinding
        The finding (see the module notes for the rule).

    """
    static, dead, lag = estimate.static_error, estimate.dead_time_error, estimate.lag_error
    if not (math.isfinite(static) and static > 0.0) or (
            estimate.dead_time == 0.0 and estimate.lag_time_constant == 0.0):
        return DynamicsFinding()
    common: dict[str, Any] = {
        'dead_time': estimate.dead_time, 'lag_time_constant': estimate.lag_time_constant,
        'static_error': static, 'dead_time_error': dead, 'lag_error': lag, 'onset': onset}
    physical = not estimate.dead_time > onset.bound + sample_period
    bar = (1.0 - EXPLAIN_FLOOR) * static
    against: dict[str, BlockComparison] = {
        'dead_time': estimate.compare('dead_time', 'static'),
        'lag': estimate.compare('lag', 'static')}
    explains = {'dead_time': physical and dead < bar and against['dead_time'].first_better,
                'lag': lag < bar and against['lag'].first_better}
    between = estimate.compare('dead_time', 'lag')
    errors = (f'held-out RMS: dead time {1e3 * estimate.dead_time:.3g} ms'
              f' {100 * dead:.3g} %, lag {1e3 * estimate.lag_time_constant:.3g} ms'
              f' {100 * lag:.3g} %, static {100 * static:.3g} %')
    unphysical = ('' if physical else
                  f'; a dead time of {1e3 * estimate.dead_time:.3g} ms is not physical:'
                  f' {onset.describe()}')
    floor = f'{100 * EXPLAIN_FLOOR:.0f} %'
    if explains['dead_time'] and explains['lag'] and between.tie:
        kind = 'tie'
        reason = (f'within the noise of each other ({between.describe()}), both better than'
                  f' the static model; {errors}')
    elif explains['dead_time'] or explains['lag']:
        kind = ('lag' if not explains['dead_time'] else 'dead_time' if not explains['lag']
                else 'lag' if lag < dead else 'dead_time')
        other = 'dead time' if kind == 'lag' else 'lag'
        name = 'dead_time' if other == 'dead time' else 'lag'
        why = (f'better than the {other} beyond the noise ({between.describe()})'
               if explains[name] else 'the dead time is ruled out by the step onset'
               if name == 'dead_time' and not physical else
               f'the {other} does not beat the static model beyond the noise and by {floor}'
               f' ({against[name].describe()})')
        reason = f'{why}; {errors}{unphysical}'
    else:
        kind = 'none'
        reason = (f'neither beats the static model beyond the noise and by {floor} (dead'
                  f' time {against["dead_time"].describe()}; lag {against["lag"].describe()});'
                  f' {errors}{unphysical}')
    modelled = estimate.modelled
    if modelled.dead_time > 0.0 and not physical:
        modelled = (InputDynamics(lag_time_constant=estimate.lag_time_constant)
                    if lag <= (1.0 - MODEL_GAIN) * static else InputDynamics())
    return DynamicsFinding(kind=kind, dead_time_physical=physical, modelled=modelled,
                           reason=reason, **common)


def estimate_record_dynamics(record: PreparedRecord, reference: tuple[int, int], *,
                             holdout: float = 0.3, choose: bool = True,
                             progress: Callable[[str], None] | None = None
                             ) -> DynamicsEstimate:
    """
    Estimate the input's dead time and lag on the record's busiest window, held out.

    The identification's estimate (:func:`~mpi_ros.identification.dynamics_grid.estimate_dynamics`
    on a window of at most :data:`DYNAMICS_WINDOW` samples, its start state chosen first),
    shared by ``identify`` and ``diagnose``.

    Parameters
    ----------
    record : PreparedRecord
        The record with a time base.
    reference : (int, int)
        The order of the trial fits.
    holdout : float
        Held-out fraction.
    choose : bool
        Choose the window's start state (False: a periodic record's).
    progress : callable, optional
        Called with a line of text per phase and trial fit.

    Returns
    -------
    DynamicsEstimate
        Both kinds, their held-out errors, whether they tie, what is modelled.

    """
    if record.time is None or not bool(np.all(np.diff(record.time) > 0.0)):
        return DynamicsEstimate()
    trial = record.window(DYNAMICS_WINDOW)
    held = held_out_rows(trial.current.size, holdout, trial.keep)
    if progress is not None:
        progress('dynamics: start state of the trial window')
    # The trial fits keep the start chosen jointly with the weights (their folds are one
    # split of short blocks; the rules are cross-validated in the final fit).
    base = fit_record(trial, *reference, held=held, choose=choose, rule='joint start')
    return estimate_dynamics(trial, *reference, held, base.segments, burn_in=base.burn_in,
                             progress=progress, rule=base.rule)


def record_dynamics(current: FloatArray, displacement: FloatArray, time: FloatArray, *,
                    holdout: float = 0.3, progress: Callable[[str], None] | None = None
                    ) -> tuple[DynamicsEstimate, DynamicsFinding]:
    """
    Analyse a record's dynamics as ``identify`` does: prepared once, estimated, decided.

    Parameters
    ----------
    current, displacement : ndarray of float, shape (N,)
        The record [A], [m].
    time : ndarray of float, shape (N,)
        Sample times [s].
    holdout : float
        Held-out fraction (``identify``'s default 0.3).
    progress : callable, optional
        Called with a line of text per phase and trial fit.

    Returns
    -------
    estimate : DynamicsEstimate
        The identification's estimate.
    finding : DynamicsFinding
        The finding ``identify`` states for the same record.

    """
    x = np.asarray(current, dtype=np.float64)
    y = np.asarray(displacement, dtype=np.float64)
    record = prepare_record(x, y, time=time)
    estimate = estimate_record_dynamics(record, reference_order(x.size), holdout=holdout,
                                        progress=progress)
    return estimate, finding_of(record, estimate)


def reference_order(size: int, n: int = 14, l: int = 7) -> tuple[int, int]:  # noqa: E741
    """Return the order dynamics and orders are decided at: (8, 4), lower for a short record."""
    return (8, 4) if size >= 10 * 15 else (min(n, 8), min(l, 4))


def finding_of(record: PreparedRecord, estimate: DynamicsEstimate) -> DynamicsFinding:
    """Return the finding of a prepared record's estimate (its steps' onset measured)."""
    t = record.time
    if t is None or t.size < 3:
        return DynamicsFinding()
    onset = step_onset(t, record.current, record.displacement, sign=record.sign)
    return dynamics_finding(estimate, onset, float(np.median(np.diff(t))))
