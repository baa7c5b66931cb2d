# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
What moves the output against the input: dynamics (lag, dead time, ringing) or a butterfly.

A rate-independent hysteresis operator (PI, Preisach, MPI with positive weights) never
moves its output against its input: after every reversal of the input the output reverses
at once.  Three kinds of record break that rule, and they are told apart by *where* and
*for how long* the output moves against the input:

- **Lag and dead time** (eddy currents, amplifiers, sensor filters, transport delays): the
  output keeps going after each input reversal for a fixed *time* (the dead time, or about
  the time constant), whatever the rate.  Shifting the output back by that time (a delay)
  or passing the input through a first-order lag removes the counter-movement.
- **Ringing** (a lightly damped mechanical resonance excited by a step of the input, or by
  a step that happened just before the record): the output oscillates around its new level
  and decays.  It is recognised as a chain of alternating output extrema after a step,
  spaced at most a few milliseconds (or samples) apart; the window until it has decayed is
  left out of the fit and of this check.
- **A butterfly loop** (ferroelectric switching beyond the coercive field): the output
  moves against the input over the same *input band* in every cycle, far from the reversals,
  whatever the rate; no delay or lag shorter than the sweeps explains it.  The MPI model
  cannot represent it: such a record is refused, naming the butterfly.

:func:`analyse_dynamics` measures the counter-movement (the largest fall of the output
against the input within one monotone sweep, beyond the noise), the windows of ringing,
the output's turning delay after the input's reversals, and the shortest delay or lag that
explains the counter-movement.  Its :class:`DynamicsAnalysis` says which of the three it
found, in words a control engineer can check.
"""

from dataclasses import dataclass, field, replace
import math
from typing import Any

import numba
import numpy as np
import numpy.typing as npt

__all__ = ['DynamicsAnalysis', 'analyse_dynamics', 'InputDynamics', 'noise_std',
           'MAX_COUNTER_MOVE', 'StepOnset', 'step_onset', 'ReturnPointDrift', 'return_point_drift',
           'DRIFT_LIMIT']

#: A monotone change of the output at the input's extreme over the record, as a fraction of
#: the output's range, from which the record is said to drift.
DRIFT_LIMIT = 0.05

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]

#: Largest excursion of the output against the input's direction within one monotone
#: sweep of the input (beyond 4 noise standard deviations), as a fraction of the output
#: range, for a record the static model can represent.  Hysteresis loops (also with creep,
#: small lags and rate dependence) stay below 0.1; butterfly loops reach 0.2-0.9.
MAX_COUNTER_MOVE = 0.15

#: A turning point of the input: it retreats by this fraction of its range.
_TURN_FRACTION = 0.05

#: An input step: the input moves by this fraction of its range within two samples.
_STEP_FRACTION = 0.1

#: A delay or lag explains a counter-movement only if it is at most this fraction of the
#: time the input takes for the middle 80 % of its large sweeps.
_EXPLAIN_FRACTION = 0.25

#: An output jump this close to the record's first sample began before the record.
_START_SAMPLES = 10

#: Ringing: successive alternating extrema of the output at most this far apart [s] (200 Hz
#: and faster), or, without a time base, this many samples.
_RING_SPACING_S = 5e-3
_RING_SPACING_SAMPLES = 8


def noise_std(y: npt.ArrayLike) -> float:
    """
    Estimate the white sensor-noise standard deviation from second differences.

    ``sigma = 1.4826 MAD(d2 y) / sqrt(6)``: the second difference of a smooth, densely
    sampled signal is almost only noise (variance ``6 sigma^2``); the median absolute
    deviation ignores the few samples with fast content.

    Parameters
    ----------
    y : array_like of float, shape (N,)
        Output [m].

    Returns
    -------
    float
        Noise standard deviation [m] (an upper bound when the signal is not smooth).

    """
    arr = np.asarray(y, dtype=np.float64).reshape(-1)
    if arr.size < 3:
        return 0.0
    d2 = np.diff(arr, 2)
    return 1.4826 * float(np.median(np.abs(d2 - np.median(d2)))) / math.sqrt(6.0)


@dataclass(frozen=True)
class DynamicsAnalysis:
    """
    Outcome of :func:`analyse_dynamics`.

    Attributes
    ----------
    verdict : str
        ``'static'`` (the output follows the input's direction: nothing to explain),
        ``'lag'`` or ``'dead_time'`` (a counter-movement a first-order lag or a delay of
        the input explains), ``'ringing'`` (only the windows after steps move against the
        input), ``'butterfly'`` (the output moves against the input mid-sweep, over the same
        input band in every cycle) or ``'unexplained'`` (a counter-movement that none of
        these explains: switching transients, drift, unrelated signals).
    counter_move : float
        Largest counter-movement in the whole record, beyond the noise [fraction of the
        output range].
    static_counter_move : float
        The same outside the ringing windows.
    explained_counter_move : float
        The same after the best delay or lag (``delay`` / ``lag_time_constant``).
    worst_sweep : (int, int)
        First and last sample of the sweep with the largest remaining counter-movement.
    delay : float
        Delay [s, or samples without a time base] that explains the counter-movement best
        (0 when none is needed).
    lag_time_constant : float
        First-order lag time constant [s, or samples] that explains it best (0 likewise).
    turning_delay : float
        Median time [s, or samples] from an input reversal to the output's reversal
        (0 for a rate-independent hysteresis); NaN when the record has no clear reversal.
    turning_delays : (float, float)
        10th and 90th percentile of the turning delays.
    steps : int
        Input steps and unexplained output jumps (where ringing may follow).
    ringing : list of (int, int)
        Windows ``[start, stop)`` of samples where the output rings after a step.
    ringing_frequency : float
        Median frequency of the ringing [Hz, or 1/sample]; NaN when there is none.
    band : (float, float) or None
        For a butterfly: the input band [unit of the input] where the output moves
        against the input.
    band_sweeps : (int, int)
        For a butterfly: the sweeps that show the counter-movement, and the large sweeps.
    explain_limit : float
        Longest delay or lag [s, or samples] allowed as an explanation.
    unit : str
        ``'s'`` or ``'samples'``.
    jumps : list of int
        Where the output jumps without an input step and rings (an unrecorded input: the
        start of a record, or a join of stitched experiments).

    """

    verdict: str
    counter_move: float
    static_counter_move: float
    explained_counter_move: float
    worst_sweep: tuple[int, int]
    delay: float = 0.0
    lag_time_constant: float = 0.0
    turning_delay: float = math.nan
    turning_delays: tuple[float, float] = (math.nan, math.nan)
    steps: int = 0
    ringing: list[tuple[int, int]] = field(default_factory=list)
    ringing_frequency: float = math.nan
    band: tuple[float, float] | None = None
    band_sweeps: tuple[int, int] = (0, 0)
    explain_limit: float = 0.0
    unit: str = 's'
    jumps: list[int] = field(default_factory=list)

    @property
    def excluded(self) -> int:
        """Return the number of samples in the ringing windows."""
        return int(sum(b - a for a, b in self.ringing))

    def mask(self, size: int) -> npt.NDArray[np.bool_]:
        """Return a boolean mask of the samples outside the ringing windows."""
        keep = np.ones(size, dtype=bool)
        for a, b in self.ringing:
            keep[a:b] = False
        return keep

    def describe(self) -> str:
        """Return one or two sentences on what was found (for the CLI and the JSON)."""
        u = self.unit
        parts = []
        if self.ringing:
            freq = (f' at about {self.ringing_frequency:.0f} Hz' if u == 's'
                    and math.isfinite(self.ringing_frequency) else '')
            parts.append(f'the output rings{freq} after {len(self.ringing)} step(s);'
                         f' {self.excluded} samples of ringing are left out of the fit')
        if math.isfinite(self.turning_delay) and self.turning_delay > 0.0:
            lo, hi = self.turning_delays
            parts.append(f'the output turns {_duration(self.turning_delay, u)} after the'
                         f' input (median over the reversals; 10-90 %:'
                         f' {_duration(lo, u)}-{_duration(hi, u)})')
        if self.verdict in ('lag', 'dead_time'):
            what = (f'a delay of {_duration(self.delay, u)}' if self.verdict == 'dead_time'
                    else f'a first-order lag of {_duration(self.lag_time_constant, u)}')
            parts.append(f'the output keeps moving after the input reverses (by'
                         f' {100 * self.static_counter_move:.3g} % of its range); {what}'
                         f' explains it ({100 * self.explained_counter_move:.2g} % left):'
                         ' dynamics, not a butterfly')
        return '; '.join(parts)


def analyse_dynamics(time: npt.ArrayLike | None, current: npt.ArrayLike,
                     displacement: npt.ArrayLike, *, sign: int = 1) -> DynamicsAnalysis:
    """
    Tell dynamics (lag, dead time, ringing) from a butterfly loop in a record.

    Parameters
    ----------
    time : array_like of float, shape (N,), or None
        Sample times [s]; None for a record without a time base (quasi-static loops):
        delays are then counted in samples.
    current : array_like of float, shape (N,)
        Input [A].
    displacement : array_like of float, shape (N,)
        Output [m].
    sign : {1, -1}
        Whether the output rises (1) or falls (-1) with the input.

    Returns
    -------
    DynamicsAnalysis
        The verdict and its measurements (see the module notes).

    """
    x = np.ascontiguousarray(current, dtype=np.float64).reshape(-1)
    v = sign * np.ascontiguousarray(displacement, dtype=np.float64).reshape(-1)
    n = x.size
    unit = 's' if time is not None else 'samples'
    t = (np.ascontiguousarray(time, dtype=np.float64).reshape(-1) if time is not None
         else np.arange(n, dtype=np.float64))
    span_x, span_y = float(np.ptp(x)), float(np.ptp(v))
    if n < 8 or not span_x > 0.0 or not span_y > 0.0:
        return DynamicsAnalysis('static', 0.0, 0.0, 0.0, (0, 0), unit=unit)
    sigma = noise_std(v)
    margin = 4.0 * sigma
    turns = _turning_points(x, _TURN_FRACTION * span_x)
    everything = np.ones(n, dtype=np.bool_)
    raw, _, _ = _counter_move(x, v, turns, everything)
    steps = _steps(x, v, span_x, span_y, margin)
    ringing, frequency, jumps = _ringing(t, v, steps, margin, span_y, time is not None)
    keep = np.ones(n, dtype=np.bool_)
    for a, b in ringing:
        keep[a:b] = False
    static, first, last = _counter_move(x, v, turns, keep)
    delays = _turning_delays(t, x, v, turns, keep, margin)
    turning = (float(np.median(delays)) if delays.size else math.nan,
               (float(np.percentile(delays, 10)), float(np.percentile(delays, 90)))
               if delays.size else (math.nan, math.nan))
    limit = _EXPLAIN_FRACTION * _sweep_time(t, x, turns)
    counter = (raw - margin) / span_y
    static_excess = (static - margin) / span_y
    common: dict[str, Any] = {
        'counter_move': max(counter, 0.0), 'static_counter_move': max(static_excess, 0.0),
        'turning_delay': turning[0], 'turning_delays': turning[1], 'steps': len(steps[1]),
        'ringing': ringing, 'ringing_frequency': frequency, 'explain_limit': limit,
        'unit': unit, 'jumps': jumps}
    if static_excess <= MAX_COUNTER_MOVE:
        verdict = 'ringing' if counter > MAX_COUNTER_MOVE else 'static'
        return DynamicsAnalysis(verdict, explained_counter_move=max(static_excess, 0.0),
                                worst_sweep=(int(first), int(last)), **common)
    kind, value, remaining, worst = _explain(t, x, v, keep, limit, margin, span_x, span_y)
    if remaining <= MAX_COUNTER_MOVE:
        return DynamicsAnalysis(
            kind, explained_counter_move=max(remaining, 0.0), worst_sweep=worst,
            delay=value if kind == 'dead_time' else 0.0,
            lag_time_constant=value if kind == 'lag' else 0.0, **common)
    verdict, band, counts = _butterfly_band(x, v, turns, keep, margin, span_x, span_y)
    return DynamicsAnalysis(verdict, explained_counter_move=max(remaining, 0.0),
                            worst_sweep=(int(first), int(last)), band=band,
                            band_sweeps=counts, **common)


@dataclass(frozen=True)
class StepOnset:
    """
    How soon the output moves after the record's steps: the longest dead time it allows.

    Attributes
    ----------
    bound : float
        Longest dead time [s] the steps allow: over the steps, the smallest time from the
        last sample before the step to the output's first sample beyond the noise; a dead
        time ``L`` holds the output still for ``L`` after a step.  Infinite when the record
        has no step.
    sample : int
        The sample of that step (-1: none).
    steps : int
        Steps measured.
    at_start : bool
        That step is the one just before the record (the output jumps at its start with
        the input already at its new level), taken as at most one sample before it.

    """

    bound: float = math.inf
    sample: int = -1
    steps: int = 0
    at_start: bool = False

    def describe(self) -> str:
        """Return where the output moved, in words (empty without a step)."""
        if not math.isfinite(self.bound):
            return ''
        where = ('the step just before the record' if self.at_start
                 else f'the input step at sample {self.sample}')
        return (f'the output moves within {1e3 * self.bound:.3g} ms of {where} (the shortest'
                f' onset of {self.steps} step(s))')


def step_onset(time: npt.ArrayLike, current: npt.ArrayLike, displacement: npt.ArrayLike, *,
               sign: int = 1) -> StepOnset:
    """
    Measure how soon the output moves after each input step: a dead time must show there.

    Input steps are those :func:`analyse_dynamics` finds (the input moves by 10 % of its
    range within two samples); an output jump in the record's first samples while the input
    holds is the step just before the record (taken as one sample before its first).  After
    each, the output's first sample that differs from its level before the step by more than
    four noise standard deviations (:func:`noise_std`) in the step's direction is its onset
    (an input that keeps moving fast around its steps moves the output too: the bound is
    then shorter than the true onset, never longer).

    Parameters
    ----------
    time : array_like of float, shape (N,)
        Sample times [s].
    current : array_like of float, shape (N,)
        Input [A].
    displacement : array_like of float, shape (N,)
        Output [m].
    sign : {1, -1}
        Whether the output rises (1) or falls (-1) with the input.

    Returns
    -------
    StepOnset
        The longest dead time the steps allow (infinite without a step).

    """
    t = np.ascontiguousarray(time, dtype=np.float64).reshape(-1)
    x = np.ascontiguousarray(current, dtype=np.float64).reshape(-1)
    v = sign * np.ascontiguousarray(displacement, dtype=np.float64).reshape(-1)
    span_x, span_y = float(np.ptp(x)) if x.size else 0.0, float(np.ptp(v)) if v.size else 0.0
    if x.size < 8 or not span_x > 0.0 or not span_y > 0.0:
        return StepOnset()
    margin = 4.0 * noise_std(v)
    input_steps, events = _steps(x, v, span_x, span_y, margin)
    dt = float(np.median(np.diff(t)))
    best = StepOnset()
    count = 0
    for k in events:
        at_start = k not in input_steps
        if at_start and k > _START_SAMPLES:
            continue                     # a jump inside the record: its step is unknown
        if at_start:
            k0, level, direction = 0, v[0], float(np.sign(v[min(k + 5, v.size - 1)] - v[0]))
            before = t[0] - dt
        else:
            k0 = k if abs(x[k + 1] - x[k]) > 0.5 * abs(x[k + 2] - x[k]) else k + 1
            level, direction = v[k0], float(np.sign(x[min(k + 2, x.size - 1)] - x[k]))
            before = t[k0]
        later = [s for s in input_steps if s > k + 2]
        stop = later[0] if later else v.size       # the output's answer to this step only
        moved = np.flatnonzero(direction * (v[k0 + 1:stop] - level) > margin)
        if not moved.size or direction == 0.0:
            continue
        count += 1
        onset = float(t[k0 + 1 + int(moved[0])] - before)
        if onset < best.bound:
            best = StepOnset(onset, int(k0), 0, at_start)
    return replace(best, steps=count) if count else StepOnset()


@dataclass(frozen=True)
class ReturnPointDrift:
    """
    The output at the input's repeated extreme: a hysteresis returns there, a drift does not.

    Attributes
    ----------
    visits : int
        Times the input reached its extreme (within 1 % of its range), at separate turns.
    change : float
        Output at the last visit minus the first, over the output's range (signed).
    monotone : bool
        The output moved the same way from each visit to the next.
    end : str
        ``'maximum'`` or ``'minimum'`` of the input.

    """

    visits: int = 0
    change: float = 0.0
    monotone: bool = False
    end: str = 'maximum'

    @property
    def drifts(self) -> bool:
        """Return True when the output drifts: monotone over three visits or more, 5 % or more."""
        return self.visits >= 3 and self.monotone and abs(self.change) >= DRIFT_LIMIT

    def describe(self) -> str:
        """Return the finding in words (empty when the record does not drift)."""
        if not self.drifts:
            return ''
        return (f"the output drifts: at the input's {self.end}, reached {self.visits} times, it"
                f' moves monotonically by {100 * self.change:+.3g} % of its range (a'
                ' rate-independent hysteresis returns to the same output there; leakage,'
                ' creep or thermal drift do not)')


def return_point_drift(current: npt.ArrayLike, displacement: npt.ArrayLike) -> ReturnPointDrift:
    """
    Measure how the output at the input's repeated extreme moves over a record.

    By the return-point memory of a rate-independent hysteresis (and of the MPI model) the
    output is the same each time the input comes back to its largest (smallest) value.  A
    monotone change there over the visits is a drift the model cannot follow: leakage (the
    integrated charge of a ferroelectric film), creep, thermal drift.

    Parameters
    ----------
    current : array_like of float, shape (N,)
        Input [A].
    displacement : array_like of float, shape (N,)
        Output [m].

    Returns
    -------
    ReturnPointDrift
        Of the ends the input returns to three times or more, the one with the larger
        change (else the other).

    """
    x = np.asarray(current, dtype=np.float64).reshape(-1)
    y = np.asarray(displacement, dtype=np.float64).reshape(-1)
    span_x, span_y = float(np.ptp(x)) if x.size else 0.0, float(np.ptp(y)) if y.size else 0.0
    if x.size < 8 or not span_x > 0.0 or not span_y > 0.0:
        return ReturnPointDrift()
    best = ReturnPointDrift()
    for end, near in (('maximum', x >= x.max() - 0.01 * span_x),
                      ('minimum', x <= x.min() + 0.01 * span_x)):
        # Separate visits: runs of samples near the extreme, apart by a move of 10 %.
        away = np.abs(x - (x.max() if end == 'maximum' else x.min())) > 0.1 * span_x
        values, inside, left = [], False, True
        for k in range(x.size):
            if near[k] and left:
                values.append([float(y[k])])
                inside, left = True, False
            elif near[k] and inside:
                values[-1].append(float(y[k]))
            elif away[k]:
                inside, left = False, True
            else:
                inside = False
        levels = np.array([np.median(v) for v in values])
        if levels.size < 2:
            continue
        steps = np.diff(levels)
        found = ReturnPointDrift(int(levels.size), float((levels[-1] - levels[0]) / span_y),
                                 bool(np.all(steps > 0.0) or np.all(steps < 0.0)), end)
        # The end the input returns to (three visits or more) with the larger change.
        if (found.visits >= 3, abs(found.change)) > (best.visits >= 3, abs(best.change)):
            best = found
    return best


def _duration(value: float, unit: str) -> str:
    if unit == 's':
        return f'{1e3 * value:.3g} ms'
    return f'{value:.3g} samples'


@numba.njit(cache=True, nogil=True)
def _turning_points(x: FloatArray, tolerance: float) -> IntArray:  # pragma: no cover
    # Sample indices that split x into monotone sweeps: 0, each extreme of x before x
    # retreats from it by `tolerance`, and N - 1.  A turning point is the last sample
    # within a fifth of `tolerance` of the extreme (the end of a hold there): what the
    # output does during the hold belongs to the sweep that arrived.
    n = x.shape[0]
    turns = np.empty(n + 1, dtype=np.int64)
    count = 1
    turns[0] = 0
    direction = 0
    extreme = 0
    near = 0
    for k in range(1, n):
        if direction == 0:
            if abs(x[k] - x[0]) > tolerance:
                direction = 1 if x[k] > x[0] else -1
                extreme = k
                near = k
            continue
        if direction * (x[k] - x[extreme]) > 0.0:
            extreme = k
            near = k
        elif direction * (x[extreme] - x[k]) <= 0.2 * tolerance:
            near = k
        elif direction * (x[extreme] - x[k]) > tolerance:
            turns[count] = near
            count += 1
            direction = -direction
            extreme = k
            near = k
    turns[count] = n - 1
    count += 1
    return turns[:count]


@numba.njit(cache=True, nogil=True)
def _counter_move(x: FloatArray, v: FloatArray, turns: IntArray,
                  keep: npt.NDArray[np.bool_]) -> tuple[float, int, int]:  # pragma: no cover
    # Largest fall of v from its running maximum within one monotone sweep of x (v is the
    # output times its sign, so it should rise with x; the sweep's direction flips v);
    # samples not kept (ringing) are skipped.
    worst = 0.0
    first = 0
    last = 0
    for b in range(turns.shape[0] - 1):
        a, e = turns[b], turns[b + 1]
        s = 1.0 if x[e] >= x[a] else -1.0
        peak = -np.inf
        for k in range(a, e + 1):
            if not keep[k]:
                continue
            value = s * v[k]
            if value > peak:
                peak = value
            elif peak - value > worst:
                worst = peak - value
                first = a
                last = e
    return worst, first, last


def _steps(x: FloatArray, v: FloatArray, span_x: float, span_y: float,
           margin: float) -> tuple[list[int], list[int]]:
    # Input steps (the input moves by 10 % of its range within two samples) and output
    # jumps the input does not explain (the output moves by 10 % of its range within five
    # samples while the input moves by less than 1 %; e.g. a step just before the record).
    # Returns (input steps, all events), one sample per event, sorted.
    dx1 = np.abs(np.diff(x))
    moving = np.median(dx1[dx1 > 0.0]) if np.any(dx1 > 0.0) else 0.0
    dx2 = np.abs(x[2:] - x[:-2])
    input_steps = np.flatnonzero((dx2 > _STEP_FRACTION * span_x) & (dx2 > 20.0 * moving))
    w = min(5, x.size - 1)
    dxw = np.abs(x[w:] - x[:-w])
    dvw = np.abs(v[w:] - v[:-w])
    jumps = np.flatnonzero((dvw > _STEP_FRACTION * span_y + margin) & (dxw < 0.01 * span_x))
    return _first_of_runs(input_steps), _first_of_runs(np.union1d(input_steps, jumps))


def _first_of_runs(events: IntArray) -> list[int]:
    out: list[int] = []
    for k in events.tolist():
        if not out or k - out[-1] > 5:
            out.append(int(k))
    return out


def _ringing(t: FloatArray, v: FloatArray, steps: tuple[list[int], list[int]],
             margin: float, span_y: float,
             timed: bool) -> tuple[list[tuple[int, int]], float, list[int]]:
    # After each event: a chain of alternating extrema of the output, each at least
    # `tolerance` from the last and at most the ringing spacing apart; the window lasts
    # until the last extremum of the chain plus one spacing.  An event inside the window
    # of an earlier one belongs to it.
    n = v.size
    tolerance = max(margin, 0.005 * span_y)
    windows: list[tuple[int, int]] = []
    periods: list[float] = []
    input_steps, events = steps
    jumps: list[int] = []
    covered = -1
    for k in events:
        if k < covered:
            continue
        later = [s for s in input_steps if s > k + 5]
        stop = later[0] if later else n
        chain = _extrema_chain(t, v, k, stop, tolerance, timed)
        if len(chain) < 3:
            continue
        spacing = float(np.median(np.diff(t[chain])))
        end = min(int(np.searchsorted(t, t[chain[-1]] + spacing)) + 1, stop)
        # A jump within the first samples: the step of the input came just before the
        # record, and the samples before the jump still show the unrecorded input.
        windows.append((0 if k <= _START_SAMPLES else int(k), end))
        periods.append(2.0 * spacing)
        covered = end
        if k not in input_steps:
            jumps.append(int(k))
    frequency = (1.0 / float(np.median(periods)) if periods and timed else math.nan)
    return windows, frequency, jumps


def _extrema_chain(t: FloatArray, v: FloatArray, start: int, stop: int, tolerance: float,
                   timed: bool) -> list[int]:
    # Alternating extrema of v from `start`, each `tolerance` away from the previous one
    # (a zig-zag filter), kept while the gaps stay short (ringing, not the input's motion).
    limit = _RING_SPACING_S if timed else float(_RING_SPACING_SAMPLES)
    chain: list[int] = []
    direction = 0
    extreme = start
    k = start + 1
    while k < stop:
        if direction == 0:
            if abs(v[k] - v[start]) > tolerance:
                direction = 1 if v[k] > v[start] else -1
                extreme = k
        elif direction * (v[k] - v[extreme]) > 0.0:
            extreme = k
        elif direction * (v[extreme] - v[k]) > tolerance:
            if chain and t[extreme] - t[chain[-1]] > limit:
                break
            chain.append(extreme)
            direction = -direction
            extreme = k
        if chain and t[k] - t[chain[-1]] > 2.0 * limit:
            break
        k += 1
    return chain


def _sweep_time(t: FloatArray, x: FloatArray, turns: IntArray) -> float:
    # Median time the input takes for the middle 80 % of its large sweeps (at least half
    # its range): what a delay or lag may be compared with.
    span = float(np.ptp(x))
    times = []
    for a, e in zip(turns[:-1].tolist(), turns[1:].tolist()):
        height = x[e] - x[a]
        if abs(height) < 0.5 * span or e - a < 2:
            continue
        part = (x[a:e + 1] - x[a]) / height
        lo = int(np.argmax(part >= 0.1))
        hi = int(np.argmax(part >= 0.9))
        times.append(float(t[a + hi] - t[a + lo]))
    if not times:
        return float(t[-1] - t[0]) / 10.0
    return float(np.median(times))


def _turning_delays(t: FloatArray, x: FloatArray, v: FloatArray, turns: IntArray,
                    keep: npt.NDArray[np.bool_], margin: float) -> FloatArray:
    # For each input reversal (inner turning point): the time until the output reaches
    # its own extreme in the sweep that follows (v keeps rising after a maximum of x while
    # a lag or delay holds it back).  Reversals inside ringing are skipped.
    out = []
    for b in range(1, turns.size - 1):
        k, e = int(turns[b]), int(turns[b + 1])
        if not keep[k] or e - k < 3:
            continue
        s = 1.0 if x[k] >= x[turns[b - 1]] else -1.0      # direction before the reversal
        segment = s * v[k:e + 1]
        j = int(np.argmax(segment))
        if segment[j] - segment[0] <= margin:
            out.append(0.0)
            continue
        out.append(float(t[k + j] - t[k]))
    return np.asarray(out, dtype=np.float64)


def _explain(t: FloatArray, x: FloatArray, v: FloatArray, keep: npt.NDArray[np.bool_],
             limit: float, margin: float, span_x: float,
             span_y: float) -> tuple[str, float, float, tuple[int, int]]:
    # The shortest explanation: the delay (output shifted back) or first-order lag of the
    # input, up to `limit`, that leaves the smallest counter-movement.
    from ..operators.filters import first_order_lag
    n = x.size
    dt = float(np.median(np.diff(t)))
    best = ('unexplained', 0.0, math.inf, (0, 0))
    if not limit > 0.0 or not dt > 0.0:
        return best
    count = int(min(max(limit / dt, 1.0), n // 4))
    shifts = np.unique(np.round(np.geomspace(1, max(count, 1), 24)).astype(np.int64))
    for d in shifts.tolist():
        xs = np.ascontiguousarray(x[:n - d])
        turns = _turning_points(xs, _TURN_FRACTION * span_x)
        move, a, e = _counter_move(xs, np.ascontiguousarray(v[d:]), turns,
                                   np.ascontiguousarray(keep[d:] & keep[:n - d]))
        remaining = (move - margin) / span_y
        if remaining < best[2]:
            best = ('dead_time', float(t[d] - t[0]), remaining, (int(a), int(e + d)))
    for tau in np.geomspace(0.5 * dt, limit, 16).tolist():
        lagged = first_order_lag(t, x, tau)
        turns = _turning_points(lagged, _TURN_FRACTION * span_x)
        move, a, e = _counter_move(lagged, v, turns, keep)
        remaining = (move - margin) / span_y
        if remaining < best[2] - 1e-3:
            best = ('lag', float(tau), remaining, (int(a), int(e)))
    return best


def _butterfly_band(x: FloatArray, v: FloatArray, turns: IntArray,
                    keep: npt.NDArray[np.bool_], margin: float, span_x: float,
                    span_y: float) -> tuple[str, tuple[float, float] | None, tuple[int, int]]:
    # Ferroelectric switching shows in the large sweeps (40 % of the input's range or
    # more; counted against those of 75 % or more) in one of two ways: the output falls
    # against the input over an input band that starts well inside the sweep (a butterfly
    # loop, driven by a ramp), or it falls while
    # the input holds at the sweep's end (a switching transient after a step).  Returns
    # the kind ('butterfly', 'switching' or 'unexplained'), the input band, and the number
    # of large sweeps that show it against all large sweeps.
    bands = []
    holds = 0
    large = 0
    for a, e in zip(turns[:-1].tolist(), turns[1:].tolist()):
        height = x[e] - x[a]
        if abs(height) < 0.4 * span_x:
            continue
        large += abs(height) >= 0.75 * span_x
        s = 1.0 if height > 0.0 else -1.0
        segment = s * v[a:e + 1]
        ok = keep[a:e + 1]
        peak = -np.inf
        peak_at = a
        worst, start, stop = 0.0, a, a
        for k in range(segment.size):
            if not ok[k]:
                continue
            if segment[k] > peak:
                peak, peak_at = segment[k], a + k
            elif peak - segment[k] > worst:
                worst, start, stop = peak - segment[k], peak_at, a + k
        if (worst - margin) / span_y <= MAX_COUNTER_MOVE:
            continue
        # Where in the sweep the counter-movement begins (a fraction of the input's
        # travel), and whether the input still moves while the output goes against it.
        travelled = abs(x[start] - x[a]) / abs(height)
        if travelled < 0.2:
            continue                      # at the reversal: a lag, not switching
        if abs(x[stop] - x[start]) < 0.02 * span_x:
            holds += 1
        else:
            bands.append((min(x[start], x[stop]), max(x[start], x[stop])))
    found = len(bands) + holds
    # In every cycle: at least half of the large sweeps (one in a single-cycle record).
    if found == 0 or found < math.ceil(large / 2):
        return 'unexplained', None, (found, large)
    kind = 'switching' if holds > len(bands) else 'butterfly'
    if not bands:
        return kind, None, (found, large)
    lo = float(min(b[0] for b in bands))
    hi = float(max(b[1] for b in bands))
    return kind, (lo, hi), (found, large)


@dataclass(frozen=True)
class InputDynamics:
    """
    Dynamics of the input path found in a record (0: none).

    Attributes
    ----------
    dead_time : float
        Pure delay ``L`` [s] between input and output.
    lag_time_constant : float
        Time constant ``tau`` [s] of a first-order lag of the input.

    """

    dead_time: float = 0.0
    lag_time_constant: float = 0.0

    @property
    def present(self) -> bool:
        """Tell whether any dynamics is modelled."""
        return self.dead_time > 0.0 or self.lag_time_constant > 0.0

    def apply(self, time: FloatArray, current: FloatArray) -> FloatArray:
        """Return the input the hysteresis sees: delayed, then lagged."""
        from ..operators.filters import delay, first_order_lag
        x = delay(time, current, self.dead_time) if self.dead_time > 0.0 else current
        if self.lag_time_constant > 0.0:
            x = first_order_lag(time, x, self.lag_time_constant)
        return np.asarray(x, dtype=np.float64)

    def describe(self) -> str:
        """Return the dynamics in words."""
        parts = []
        if self.dead_time > 0.0:
            parts.append(f'a dead time of {1e3 * self.dead_time:.3g} ms')
        if self.lag_time_constant > 0.0:
            parts.append(f'a first-order lag of {1e3 * self.lag_time_constant:.3g} ms')
        return ' and '.join(parts) if parts else 'none'
