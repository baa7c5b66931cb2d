# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
A record checked and analysed for trial fits: its experiments (segments), refusals.

A record stitched from several experiments (time gaps, time running back, output jumps the
input does not explain) is cut at the joins (:func:`find_segments`); each segment gets its own
start state (:mod:`.start_states`).  :func:`prepare_record` analyses the record
(:mod:`.dynamics`: ringing left out, output jumps) and :func:`refuse_if_unmodellable` refuses
a record the MPI model cannot represent, naming the cause.
"""

from dataclasses import dataclass, replace
import math

import numpy as np
import numpy.typing as npt

from .dynamics import analyse_dynamics, DynamicsAnalysis
from .qp import FloatArray, output_sign
from .start_states import StartState
from ..errors import IdentificationError

__all__ = ['PreparedRecord', 'Segment', 'find_segments', 'prepare_record',
           'refuse_if_unmodellable']


#: A time gap: a sample interval this many times the median one.
_GAP_FACTOR = 5.0

#: A record is cut into at most this many experiments, each of at least _MIN_SEGMENT
#: samples; a time column that runs back or jumps more often is not used for joins.
_MAX_SEGMENTS = 20
_MIN_SEGMENT = 50


@dataclass(frozen=True)
class Segment:
    """
    One experiment of a record: samples ``[start, stop)`` and how it begins.

    Attributes
    ----------
    start, stop : int
        Its samples.
    reason : str
        Why a new segment begins here (``'start'`` for the first).
    start_state : StartState or None
        The chosen start state (None: continues from the previous segment).

    """

    start: int
    stop: int
    reason: str = 'start'
    start_state: StartState | None = None


@dataclass(frozen=True)
class PreparedRecord:
    """
    A record checked and analysed, ready for trial fits.

    Attributes
    ----------
    time : ndarray of float or None
        Sample times [s] (None: no time base).
    current, displacement : ndarray of float, shape (N,)
        The data.
    keep : ndarray of bool, shape (N,)
        Samples that enter the fit (outside ringing).
    segments : list of Segment
        The experiments of the record.
    analysis : DynamicsAnalysis
        What moves the output against the input.
    sign : int
        Whether the output rises (1) or falls (-1) with the input.
    anchor : str
        The design's anchor.
    epsilon : float
        The bound of (8)/(19).

    """

    time: FloatArray | None
    current: FloatArray
    displacement: FloatArray
    keep: npt.NDArray[np.bool_]
    segments: list[Segment]
    analysis: DynamicsAnalysis
    sign: int
    anchor: str = 'operating_point'
    epsilon: float = 1e-6

    def window(self, size: int) -> 'PreparedRecord':
        """
        Return the part of the record with the most input travel, at most ``size`` samples.

        Trial fits on a long record (dynamics grid, order selection) run on such a window:
        its content (the most sweeps, the fastest rates) decides them, and it keeps their
        cost independent of the record's length.  The window is a record of its own: its
        start state is chosen afresh.

        Parameters
        ----------
        size : int
            Largest number of samples.

        Returns
        -------
        PreparedRecord
            This record when it is short enough, else the window.

        """
        n = self.current.size
        if n <= size:
            return self
        travel = np.concatenate([[0.0], np.cumsum(np.abs(np.diff(self.current)))])
        start = int(np.argmax(travel[size - 1:] - travel[:n - size + 1]))
        stop = start + size
        segments = [replace(s, start=max(s.start, start) - start,
                            stop=min(s.stop, stop) - start,
                            start_state=None if s.start > start else s.start_state)
                    for s in self.segments if s.stop > start and s.start < stop]
        segments[0] = replace(segments[0], start_state=None, reason='start')
        time = None if self.time is None else self.time[start:stop]
        return replace(self, time=time, current=self.current[start:stop],
                       displacement=self.displacement[start:stop],
                       keep=self.keep[start:stop], segments=segments)


def find_segments(time: FloatArray | None, analysis: DynamicsAnalysis, size: int,
                  jumps: list[int] | None = None) -> list[Segment]:
    """
    Cut a record at the joins of the experiments it was stitched from.

    A join is a time gap (an interval over five times the median one), time running back
    (each experiment's clock restarting), or an output jump the input does not explain
    (the unrecorded input between two experiments) after the record's first samples.  At
    most :data:`_MAX_SEGMENTS` experiments of at least :data:`_MIN_SEGMENT` samples each; a
    time column that runs back or jumps more often is not a clock of stitched experiments
    (duplicated, constant or scrambled time) and gives no joins.

    Parameters
    ----------
    time : ndarray of float or None
        Sample times [s].
    analysis : DynamicsAnalysis
        The record's analysis (its output jumps).
    size : int
        Number of samples.
    jumps : list of int, optional
        Output jumps the input does not explain (from the analysis).

    Returns
    -------
    list of Segment
        At least one.

    """
    cuts: dict[int, str] = {}
    if time is not None and size > 2:
        steps = np.diff(time)
        positive = steps[steps > 0.0]
        typical = float(np.median(positive)) if positive.size else 0.0
        back = np.flatnonzero(steps <= 0.0)
        gaps = (np.flatnonzero(steps > _GAP_FACTOR * typical) if typical > 0.0
                else np.zeros(0, dtype=np.int64))
        # A clock that runs back or jumps at many samples is no clock of a few stitched
        # experiments (a duplicated, constant or scrambled time column): no joins from it.
        if back.size + gaps.size <= _MAX_SEGMENTS:
            for k in back.tolist():
                cuts[k + 1] = 'time runs back'
            for k in gaps.tolist():
                cuts.setdefault(k + 1, f'time gap of {steps[k]:.4g} s')
    for k in jumps or []:
        if all(abs(k - c) > _MIN_SEGMENT for c in cuts):
            cuts[k] = 'output jump the input does not explain'
    bounds: list[int] = []
    for c in sorted(cuts):               # experiments of at least _MIN_SEGMENT samples
        if c - (bounds[-1] if bounds else 0) >= _MIN_SEGMENT and size - c >= _MIN_SEGMENT:
            bounds.append(c)
    bounds = bounds[:_MAX_SEGMENTS - 1]
    starts = [0] + bounds
    stops = bounds + [size]
    return [Segment(a, b, 'start' if a == 0 else cuts[a]) for a, b in zip(starts, stops)]


def prepare_record(current: FloatArray, displacement: FloatArray, *,
                   time: FloatArray | None = None, anchor: str = 'operating_point',
                   epsilon: float = 1e-6, sign: int | None = None) -> PreparedRecord:
    """
    Analyse a record: dynamics, ringing, segments (no refusal here).

    Parameters
    ----------
    current, displacement : ndarray of float, shape (N,)
        The data.
    time : ndarray of float, optional
        Sample times [s]; None for a record without a time base.
    anchor : str
        The design's anchor.
    epsilon : float
        The bound of (8)/(19).
    sign : int, optional
        The output's sign (detected by default).

    Returns
    -------
    PreparedRecord
        The record and what was found.

    """
    x = np.asarray(current, dtype=np.float64)
    y = np.asarray(displacement, dtype=np.float64)
    if sign is None:
        sign, _ = output_sign(x, y)
    analysis = analyse_dynamics(_joined_time(time), x, y, sign=sign)
    keep = analysis.mask(x.size)
    segments = find_segments(time, analysis, x.size, jumps=analysis.jumps)
    return PreparedRecord(time, x, y, keep, segments, analysis, int(sign), anchor, epsilon)


def _joined_time(time: FloatArray | None) -> FloatArray | None:
    # The clock of a stitched record with its joins closed: a time gap or a restart of the
    # clock becomes one typical interval, so each experiment's dynamics (ringing after its
    # start, lag) are measured in its own time.
    if time is None or time.size < 3:
        return time
    steps = np.diff(time)
    positive = steps[steps > 0.0]
    if not positive.size:
        return None
    typical = float(np.median(positive))
    joins = (steps <= 0.0) | (steps > _GAP_FACTOR * typical)
    if not np.any(joins):
        return time
    steps = np.where(joins, typical, steps)
    return np.concatenate([[float(time[0])], float(time[0]) + np.cumsum(steps)])


def refuse_if_unmodellable(record: PreparedRecord, correlation: float) -> None:
    """
    Refuse a record the MPI model cannot represent, naming the cause found.

    Parameters
    ----------
    record : PreparedRecord
        The analysed record.
    correlation : float
        Pearson correlation of input and output (outside ringing).

    Raises
    ------
    IdentificationError
        For a butterfly loop, switching transients, an output unrelated to the input or a
        counter-movement nothing explains.

    """
    a = record.analysis
    x = record.current
    move = 100.0 * a.static_counter_move
    first, last = a.worst_sweep
    found, large = a.band_sweeps
    if a.verdict == 'butterfly':
        lo, hi = a.band if a.band is not None else (math.nan, math.nan)
        msg = (f'the output is not monotone in the input: a butterfly loop (ferroelectric'
               f' switching) or another non-monotone map; in {found} of the {large} large'
               f' sweeps of the input the output moves against it by up to {move:.3g} % of'
               f' its range, over the input band {lo:.4g} to {hi:.4g} (samples {first} to'
               f' {last}), well inside the sweep, not after the reversal; no delay or lag'
               f' shorter than {_limit(a)} explains it, and no ringing window covers it.'
               ' The MPI model (a monotone hysteresis) cannot represent it: lower the'
               ' amplitude below the coercive field, record a unipolar excitation, or check'
               ' the input and output columns/topics')
        raise IdentificationError(msg)
    if a.verdict == 'switching':
        msg = (f'the output is not monotone in the input: switching transients'
               f' (ferroelectric switching, as in a butterfly loop); while the input holds'
               f' after a step, the output moves against it by up to'
               f' {move:.3g} % of its range (samples {first} to {last}), for longer than'
               f' {_limit(a)}, without ringing; the MPI model cannot represent it: stay'
               ' below the coercive field, or leave the switching part out of the record')
        raise IdentificationError(msg)
    if abs(correlation) < _MIN_CORRELATION:
        msg = (f'the output is not monotone in the input, nor related to it as a hysteresis:'
               f' their correlation is {correlation:.2f} outside ringing windows (a'
               f' hysteresis loop gives'
               f' 0.3 or more) and the output moves against the input by up to {move:.3g} %'
               ' of its range within one sweep; check the input and output columns/topics'
               ' and that they belong to one experiment')
        raise IdentificationError(msg)
    if a.verdict == 'unexplained':
        msg = (f'the output is not monotone in the input: it moves against the input by up'
               f' to {move:.3g} % of its range within one sweep (samples {first} to {last});'
               f' neither a delay or lag'
               f' shorter than {_limit(a)} ({100 * a.explained_counter_move:.3g} % would be'
               ' left), nor ringing after a step, nor switching over a fixed input band'
               ' explains it: drift, transients or a second input dominate; the MPI model'
               ' cannot represent it; check that the record is one experiment and that'
               ' nothing else drives the output')
        raise IdentificationError(msg)
    del x


def _limit(a: DynamicsAnalysis) -> str:
    if a.unit == 's':
        return f'{1e3 * a.explain_limit:.3g} ms'
    return f'{a.explain_limit:.3g} samples'


#: Below this |correlation| between input and output (outside ringing) the output is not
#: related to the input as a hysteresis.
_MIN_CORRELATION = 0.3
