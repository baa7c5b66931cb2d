# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Excitation signals: identification input (section 5 of the paper) and tracking trajectories.

:func:`identification_excitation` produces the coil current for identifying Γ (26): a
decaying-amplitude oscillation around the bias current with nested minor loops, so that the
major loop, the internal minor loops and their branchings are all excited, plus optional holds
(creep) and high-frequency bursts (rate dependence).  :func:`tracking_trajectory` produces a
smooth desired displacement with minor loops for measuring the control error (38).
:func:`diagnostic_excitation` produces a validation input with the structure the diagnosis'
signatures need (major loops, holds approached from both sides, bursts); the plant simulator
plays it too.

Both signals are piecewise defined through knots joined by half-cosine segments,
``x(t) = x_k + (x_{k+1} - x_k) (1 - cos(pi (t - t_k) / (t_{k+1} - t_k))) / 2``, or as sums of
sinusoids, so they are smooth, never leave the range spanned by their knots and are
deterministic given the seed.
"""

import math

import numpy as np
import numpy.typing as npt

from ..errors import DataError

__all__ = ['diagnostic_excitation', 'identification_excitation', 'tracking_trajectory']

FloatArray = npt.NDArray[np.float64]

_BURST_CYCLES = 5
_BURST_AMPLITUDE = 0.25  # fraction of the amplitude
_MIN_SAMPLES_PER_PERIOD = 20


def identification_excitation(duration: float, *, sample_rate: float, bias: float = 1.0,
                              amplitude: float = 0.8, seed: int | None = None,
                              holds: bool = True, bursts: bool = True,
                              main_frequency: float = 1.0, burst_frequency: float = 10.0,
                              hold_duration: float = 2.0, final_amplitude: float = 0.1,
                              ramp_duration: float = 1.0) -> tuple[FloatArray, FloatArray]:
    """
    Build a coil-current signal for identification, like the paper's Fig. 8 experiment.

    Parameters
    ----------
    duration : float
        Length of the signal [s].
    sample_rate : float
        Samples per second [Hz]; at least 20 per period of the fastest content.
    bias : float, optional
        Bias current [A]; 1.0 as in the paper.
    amplitude : float, optional
        Half-width of the operating range [A]; 0.8 as in the paper (1 A +- 0.8 A).
    seed : int or None, optional
        Seed of :func:`numpy.random.default_rng` that places the minor loops; ``None`` draws
        fresh entropy (numpy's convention), so pass a seed for a reproducible signal.
    holds : bool, optional
        Insert holds of constant current at turning points (exposes creep).
    bursts : bool, optional
        Insert bursts of five cycles at ``burst_frequency`` at turning points (exposes rate
        dependence); their amplitude is a quarter of ``amplitude``.
    main_frequency : float, optional
        Frequency [Hz] of a full-swing major loop; minor segments take at most twice the
        rate, so the default 1 Hz gives quasi-static 1-2 Hz loops.
    burst_frequency : float, optional
        Frequency of the bursts [Hz].
    hold_duration : float, optional
        Length of each hold [s].
    final_amplitude : float, optional
        Envelope at the end of the decay, as a fraction of ``amplitude``.
    ramp_duration : float, optional
        Length of the initial ramp from 0 A to the bias [s] (at most 10 % of ``duration``).

    Returns
    -------
    time : ndarray of float, shape (N,)
        Sample times [s], ``arange(N) / sample_rate`` with ``N = round(duration *
        sample_rate) + 1``.
    current : ndarray of float, shape (N,)
        Coil current [A].  Starts at 0 A, ramps to ``bias`` and then stays within
        ``[bias - amplitude, bias + amplitude]``.

    Raises
    ------
    DataError
        A non-finite or non-positive setting, too low a sample rate, or a duration too short
        for the requested holds and bursts.

    Notes
    -----
    After the ramp, half-cycles alternate between ``bias +- e(tau) amplitude``, the envelope
    ``e`` decaying linearly from 1 to ``final_amplitude`` over the main part.  Half of the
    half-cycles are interrupted by a reversal (``a -> p -> q -> b``), some of them by a
    nested one (``a -> p -> q -> p' -> q' -> b``), which excites internal minor loops at
    many levels.  Holds and bursts (one per about 20 s and 30 s, 1 to 3 of each) are spread
    evenly over the main part.

    Examples
    --------
    >>> t, i = identification_excitation(20.0, sample_rate=500.0, seed=1)
    >>> float(i[0]), bool(i[t >= 2.0].min() >= 0.2 and i.max() <= 1.8)
    (0.0, True)

    """
    for name, value in (('duration', duration), ('sample_rate', sample_rate),
                        ('amplitude', amplitude), ('main_frequency', main_frequency),
                        ('burst_frequency', burst_frequency),
                        ('hold_duration', hold_duration), ('final_amplitude', final_amplitude),
                        ('ramp_duration', ramp_duration)):
        _require_positive(name, value)
    _require_finite('bias', bias)
    if final_amplitude > 1:
        msg = f'final_amplitude must be in (0, 1]; found {final_amplitude!r}'
        raise DataError(msg)
    fastest = max(main_frequency * 2, burst_frequency if bursts else 0.0)
    _require_sample_rate(sample_rate, fastest)
    rng = np.random.default_rng(seed)
    ramp = min(ramp_duration, 0.1 * duration)
    n_holds = min(max(round(duration / 20), 1), 3) if holds else 0
    n_bursts = min(max(round(duration / 30), 1), 3) if bursts else 0
    burst_time = _BURST_CYCLES / burst_frequency
    main_time = duration - ramp - n_holds * hold_duration - n_bursts * burst_time
    if main_time < 0.5 * duration:
        msg = (f'duration {duration!r} s is too short for {n_holds} hold(s) of'
               f' {hold_duration!r} s and {n_bursts} burst(s); use a longer duration, a'
               ' shorter hold_duration, or holds=False / bursts=False')
        raise DataError(msg)
    extras = _interleave(['hold'] * n_holds, ['burst'] * n_bursts)
    extra_at = [main_time * (k + 1) / (len(extras) + 1) for k in range(len(extras))]

    half_period = 0.5 / main_frequency
    lo, hi = bias - amplitude, bias + amplitude
    knot_t = [0.0, ramp]
    knot_x = [0.0, bias]
    tau = 0.0  # time in the main part, without holds and bursts
    shift = ramp  # start of the main part plus the holds and bursts inserted so far
    level = bias
    direction = 1.0
    while knot_t[-1] < duration:
        envelope = 1.0 - (1.0 - final_amplitude) * min(tau / main_time, 1.0)
        target = bias + direction * envelope * amplitude
        for x_next in _branch(level, target, rng):
            tau += half_period * max(abs(x_next - level) / (2 * amplitude), 0.5)
            knot_t.append(shift + tau)
            knot_x.append(x_next)
            level = x_next
        direction = -direction
        while extras and tau >= extra_at[0]:
            kind = extras.pop(0)
            extra_at.pop(0)
            if kind == 'hold':
                shift += hold_duration
                knot_t.append(shift + tau)
                knot_x.append(level)
            else:
                dip = level - _BURST_AMPLITUDE * amplitude * (1.0 if level >= bias else -1.0)
                for k in range(2 * _BURST_CYCLES):
                    shift += 0.5 / burst_frequency
                    knot_t.append(shift + tau)
                    knot_x.append(dip if k % 2 == 0 else level)

    n_samples = int(round(duration * sample_rate)) + 1
    time = np.arange(n_samples) / sample_rate
    current = _half_cosine(np.asarray(knot_t), np.asarray(knot_x), time)
    main = time >= ramp
    current[main] = np.clip(current[main], lo, hi)
    return time, current


def tracking_trajectory(duration: float, *, sample_rate: float, low: float, high: float,
                        frequencies: tuple[float, ...] = (0.23, 0.61, 1.47),
                        weights: tuple[float, ...] = (0.55, 0.3, 0.15),
                        ramp_duration: float = 2.0,
                        final_envelope: float = 0.5) -> tuple[FloatArray, FloatArray]:
    """
    Build a smooth desired-displacement trajectory with minor loops inside ``[low, high]``.

    Parameters
    ----------
    duration, sample_rate : float
        Length [s] and samples per second [Hz] (at least 20 per period of the fastest
        sinusoid).
    low, high : float
        Range of the desired displacement [m], ``low < high``; the trajectory starts at
        ``low``.
    frequencies : tuple of float, optional
        Frequencies of the sinusoids [Hz].
    weights : tuple of float, optional
        Their relative amplitudes (non-negative, normalised to sum 1); decreasing weights
        give minor loops riding on larger ones.
    ramp_duration : float, optional
        Length of the smooth fade-in from ``low`` [s].
    final_envelope : float, optional
        Envelope at the end, as a fraction of the initial one (amplitudes decay linearly).

    Returns
    -------
    time : ndarray of float, shape (N,)
        Sample times [s], ``arange(N) / sample_rate``, ``N = round(duration * sample_rate) +
        1``.
    desired_displacement : ndarray of float, shape (N,)
        Desired displacement [m], within ``[low, high]``.

    Raises
    ------
    DataError
        Non-finite or inconsistent settings.

    Notes
    -----
    ``d(t) = low + (high - low) w(t) (1 + e(t) c(t)) / 2`` with the raised-cosine fade-in
    ``w`` (0 -> 1 over ``ramp_duration``), the envelope ``e`` (1 -> ``final_envelope``) and
    ``c(t) = sum_i a_i sin(2 pi f_i t + phi_i)``, ``sum_i a_i = 1``, with fixed phases
    ``phi_i = i * 2.0`` rad.  Since ``|e c| <= 1``, ``low <= d <= high``.  The function is
    deterministic (it takes no seed).

    Examples
    --------
    >>> t, d = tracking_trajectory(10.0, sample_rate=100.0, low=5e-6, high=3.5e-5)
    >>> float(d[0]), bool(d.min() >= 5e-6 and d.max() <= 3.5e-5)
    (5e-06, True)

    """
    for name, value in (('duration', duration), ('sample_rate', sample_rate),
                        ('ramp_duration', ramp_duration), ('final_envelope', final_envelope)):
        _require_positive(name, value)
    _require_finite('low', low)
    _require_finite('high', high)
    if not low < high:
        msg = f'low must be < high; found low={low!r}, high={high!r}; swap or widen the range'
        raise DataError(msg)
    freq = np.asarray(frequencies, dtype=np.float64)
    amp = np.asarray(weights, dtype=np.float64)
    if freq.ndim != 1 or freq.size == 0 or freq.shape != amp.shape:
        msg = (f'frequencies and weights must be non-empty and of equal length; found'
               f' {freq.size} and {amp.size}')
        raise DataError(msg)
    if not (np.all(np.isfinite(freq)) and np.all(freq > 0)):
        msg = f'frequencies must be finite and > 0 [Hz]; found {list(frequencies)!r}'
        raise DataError(msg)
    if not (np.all(np.isfinite(amp)) and np.all(amp >= 0) and amp.sum() > 0):
        msg = f'weights must be finite, >= 0 and not all 0; found {list(weights)!r}'
        raise DataError(msg)
    if final_envelope > 1:
        msg = f'final_envelope must be in (0, 1]; found {final_envelope!r}'
        raise DataError(msg)
    _require_sample_rate(sample_rate, float(freq.max()))
    amp = amp / amp.sum()
    n_samples = int(round(duration * sample_rate)) + 1
    time = np.arange(n_samples) / sample_rate
    phases = 2.0 * np.arange(freq.size)
    carrier = np.sin(2 * np.pi * freq[None, :] * time[:, None] + phases[None, :]) @ amp
    envelope = 1.0 - (1.0 - final_envelope) * time / duration
    fade = 0.5 * (1.0 - np.cos(np.pi * np.clip(time / ramp_duration, 0.0, 1.0)))
    desired = low + (high - low) * fade * (1.0 + np.clip(envelope * carrier, -1.0, 1.0)) / 2
    return time, np.clip(desired, low, high)


def diagnostic_excitation(*, sample_rate: float, bias: float = 1.0, amplitude: float = 0.8,
                          seed: int | None = None, hold_duration: float = 4.0,
                          burst_frequencies: tuple[float, ...] = (
                              5.0, 7.0, 10.0, 14.0, 20.0, 28.0, 40.0),
                          burst_cycles: int = 6, loop_frequency: float = 0.5,
                          repeats: int = 2) -> tuple[FloatArray, FloatArray]:
    """
    Build a validation input with the structure the signatures need (about 50 s).

    ``repeats`` times: two quasi-static major loops, then holds at a low and a high level,
    each approached once from below and once from above (order drawn from ``seed``).  Then
    sinusoidal bursts
    of a quarter of ``amplitude`` around ``bias`` at log-spaced frequencies, each followed
    by a short hold.

    Parameters
    ----------
    sample_rate : float
        Samples per second [Hz]; at least 20 per period of the fastest burst.
    bias : float
        Centre current [A].
    amplitude : float
        Half-width of the range [A].
    seed : int or None
        Seed of :func:`numpy.random.default_rng` (order of the approaches).
    hold_duration : float
        Length of each hold [s].
    burst_frequencies : tuple of float
        Burst frequencies [Hz] (three or more for the frequency-response test).
    burst_cycles : int
        Cycles per burst.
    loop_frequency : float
        Frequency of the major loops [Hz].
    repeats : int
        Number of loop-and-hold blocks (slow effects need a record longer than their time
        constant to be tested).

    Returns
    -------
    time : ndarray of float, shape (N,)
        Sample times [s], ``arange(N) / sample_rate``.
    current : ndarray of float, shape (N,)
        Input [A], from 0 (rest) within ``[bias - amplitude, bias + amplitude]``.

    Raises
    ------
    DataError
        A non-positive setting or too low a sample rate.

    """
    values = (sample_rate, amplitude, hold_duration, loop_frequency, burst_cycles, repeats,
              *burst_frequencies)
    if not all(math.isfinite(v) and v > 0 for v in values):
        msg = 'diagnostic_excitation settings must be finite and > 0'
        raise DataError(msg)
    if sample_rate < 20.0 * max(burst_frequencies, default=0.0):
        msg = (f'sample_rate must be >= 20 x the fastest burst frequency'
               f' ({max(burst_frequencies)} Hz); found {sample_rate}')
        raise DataError(msg)
    rng = np.random.default_rng(seed)
    h = 1.0 / sample_rate
    rate = 4.0 * amplitude * loop_frequency
    knots_t, knots_x = [0.0], [0.0]

    def move(target: float, duration: float | None = None) -> None:
        d = abs(target - knots_x[-1]) / rate if duration is None else duration
        knots_t.append(knots_t[-1] + max(d, h))
        knots_x.append(target)

    move(bias)
    step = 0.3 * amplitude
    for _ in range(int(repeats)):
        for _ in range(2):
            move(bias + amplitude)
            move(bias - amplitude)
        for level in (bias - 0.6 * amplitude, bias + 0.6 * amplitude):
            first_up = bool(rng.integers(2))
            for up in (first_up, not first_up):
                move(level - step if up else level + step)
                move(level)
                move(level, hold_duration)
    move(bias)
    move(bias, 0.3)
    t = np.arange(0.0, knots_t[-1] + h / 2, h)
    parts = [np.interp(t, knots_t, knots_x)]
    for f in burst_frequencies:
        tt = np.arange(1, int(round(burst_cycles / f * sample_rate)) + 1) * h
        parts.append(bias + 0.25 * amplitude * np.sin(2.0 * math.pi * f * tt))
        parts.append(np.full(int(0.3 * sample_rate), bias))
    current = np.concatenate(parts, dtype=np.float64)
    return np.arange(current.size, dtype=np.float64) * h, current


def _branch(start: float, target: float, rng: np.random.Generator) -> list[float]:
    """Return the knots from ``start`` to ``target``, with 0, 1 or 2 nested reversals."""
    if rng.random() >= 0.5:
        return [target]
    p = start + rng.uniform(0.35, 0.8) * (target - start)
    q = p - rng.uniform(0.2, 0.6) * (p - start)
    if rng.random() >= 0.4:
        return [p, q, target]
    p2 = q + rng.uniform(0.3, 0.8) * (p - q)
    q2 = p2 - rng.uniform(0.2, 0.6) * (p2 - q)
    return [p, q, p2, q2, target]


def _interleave(first: list[str], second: list[str]) -> list[str]:
    """Merge two lists alternately, the rest of the longer one at the end."""
    merged = []
    for k in range(max(len(first), len(second))):
        merged.extend(first[k:k + 1] + second[k:k + 1])
    return merged


def _half_cosine(knot_t: FloatArray, knot_x: FloatArray, time: FloatArray) -> FloatArray:
    """Join the knots with half-cosine segments and sample them at ``time``."""
    idx = np.clip(np.searchsorted(knot_t, time, side='right') - 1, 0, knot_t.size - 2)
    span = knot_t[idx + 1] - knot_t[idx]
    frac = np.clip((time - knot_t[idx]) / span, 0.0, 1.0)
    weight = 0.5 * (1.0 - np.cos(np.pi * frac))
    return knot_x[idx] + (knot_x[idx + 1] - knot_x[idx]) * weight


def _require_finite(name: str, value: float) -> None:
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)) \
            or not math.isfinite(value):
        msg = f'{name} must be a finite number; found {value!r}'
        raise DataError(msg)


def _require_positive(name: str, value: float) -> None:
    _require_finite(name, value)
    if not value > 0:
        msg = f'{name} must be > 0; found {value!r}'
        raise DataError(msg)


def _require_sample_rate(sample_rate: float, fastest: float) -> None:
    needed = _MIN_SAMPLES_PER_PERIOD * fastest
    if sample_rate < needed:
        msg = (f'sample_rate must be >= {needed:g} Hz ({_MIN_SAMPLES_PER_PERIOD} samples per'
               f' period of the fastest content, {fastest:g} Hz); found {sample_rate!r} Hz;'
               ' raise the sample rate or lower the frequencies')
        raise DataError(msg)
