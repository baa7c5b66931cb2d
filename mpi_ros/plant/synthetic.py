# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Synthetic rig records: the built-in actuator as a real rig shows it.

For tests, benchmarks and a user's own checks of a pipeline: the magnetostrictive-like
actuator of :mod:`mpi_ros.plant.actuator` (not an MPI model) driven through an unrecorded history
before the record starts (at rest after a descent, virgin, or mid-history), with the rig's
dynamics (an input lag, a dead time, a lightly damped mechanical resonance that rings after
steps), sensor noise, an arbitrary sensor zero and sign.  Each record says what is in it
(:attr:`SyntheticRecord.truth`), so an identification can be checked against it.  The
dynamics are the registered effects' plant steps (:func:`~mpi_ros.extensions.effect.plant_switch`):
the eddy-current lag, the dead time and the mechanical resonance
(:mod:`mpi_ros.extensions.resonance`, natural frequency 500-1000 Hz, envelope decay 13 ms).

The kinds (:data:`SYNTHETIC_KINDS`): lag 0.5-5 ms at 1-10 kHz,
dead time of 1-10 samples, 500-1000 Hz ringing after steps, starts at rest, virgin and
mid-history, rising-amplitude sines, and one quasi-static loop of 300 samples.
"""

from dataclasses import dataclass, field
from typing import Any

import numpy as np
import numpy.typing as npt

from .actuator import ActuatorConfig, MagnetostrictiveActuator
from .excitation import identification_excitation
from ..errors import DataError
from ..extensions.effect import plant_switch

__all__ = ['SyntheticRecord', 'synthetic_record', 'SYNTHETIC_KINDS', 'rising_amplitude_sine',
           'RING_DECAY', 'rates_record', 'TWIN_KINDS', 'twin_record']

#: The records :func:`twin_record` builds: what real captures were refused for, or passed
#: with, without the true cause being named.
TWIN_KINDS = ('leakage drift', 'deepening FORC')

FloatArray = npt.NDArray[np.float64]

#: Displacement range of the built-in actuator over 0.2-1.8 A [m] (about).
_RANGE_M = 3.4e-5

#: Time constant of the ringing envelope of the ringing kinds [s] (a damping ratio of
#: 0.012-0.024 at 1000-500 Hz; the TUM piezo rig's is 12-15 ms).
RING_DECAY = 0.013

#: The kinds of record :func:`synthetic_record` builds.
SYNTHETIC_KINDS = (
    'lag 1.5 ms at 1 kHz', 'lag 3 ms at 1 kHz', 'lag 0.5 ms at 10 kHz', 'lag 5 ms at 10 kHz',
    'dead time 2 samples at 1 kHz', 'dead time 5 samples at 1 kHz',
    'dead time 1 sample at 10 kHz', 'dead time 10 samples at 10 kHz',
    'ringing 500 Hz', 'ringing 740 Hz', 'ringing 1000 Hz',
    'at rest, rising-amplitude sine', 'virgin', 'mid-history', '300-sample loop',
)


@dataclass(frozen=True)
class SyntheticRecord:
    """
    One synthetic record and what is in it.

    Attributes
    ----------
    time : ndarray of float, shape (N,), or None
        Sample times [s]; None for a quasi-static record without a time base.
    current : ndarray of float, shape (N,)
        Input [A].
    displacement : ndarray of float, shape (N,)
        Measured output [m] (sensor zero, sign, noise included).
    truth : dict
        ``lag_time_constant`` [s], ``dead_time`` [s], ``resonance_hz`` (natural frequency of
        the output mode, 0: none), ``resonance_decay`` [s], ``noise`` (RMS noise over the
        output's range), ``start`` (the history before the record).

    """

    time: FloatArray | None
    current: FloatArray
    displacement: FloatArray
    truth: dict[str, Any] = field(default_factory=dict)


def rising_amplitude_sine(sample_rate: float, frequency: float, *, cycles: int = 20,
                          low: float = 0.2, high: float = 1.8,
                          hold: float = 0.2) -> tuple[FloatArray, FloatArray]:
    """
    Return a hold at ``low``, then raised-cosine cycles of rising amplitude from ``low``.

    The stimulus of the TUM piezo captures (``../shared/data/measured/tum_piezo``): nested
    loops that share their lower turning point, the last one the major loop.

    Parameters
    ----------
    sample_rate : float
        Samples per second [Hz].
    frequency : float
        Cycle frequency [Hz].
    cycles : int
        Number of cycles (the last reaches ``high``).
    low, high : float
        Input range [A].
    hold : float
        Hold at ``low`` before the cycles [s].

    Returns
    -------
    time, current : ndarray of float
        Sample times [s] and the input [A].

    """
    period = int(round(sample_rate / frequency))
    if period < 4 or cycles < 1:
        msg = (f'rising_amplitude_sine needs at least 4 samples per cycle and one cycle; found'
               f' {period} and {cycles}')
        raise DataError(msg)
    j = np.arange(period)
    parts = [np.full(int(hold * sample_rate), low)]
    parts += [low + (high - low) * k / cycles * (1.0 - np.cos(2.0 * np.pi * j / period)) / 2.0
              for k in range(1, cycles + 1)]
    current = np.concatenate(parts)
    return np.arange(current.size) / sample_rate, current


def synthetic_record(kind: str, seed: int, *, noise: float = 0.002) -> SyntheticRecord:
    """
    Build one synthetic rig record of a kind in :data:`SYNTHETIC_KINDS`.

    Parameters
    ----------
    kind : str
        One of :data:`SYNTHETIC_KINDS`.
    seed : int
        Seed of the excitation, the noise, the sensor zero and sign.
    noise : float
        Sensor noise, RMS, as a fraction of the displacement range.

    Returns
    -------
    SyntheticRecord
        The record and its truth.

    """
    if kind not in SYNTHETIC_KINDS:
        msg = f'unknown synthetic record {kind!r}; one of: {", ".join(SYNTHETIC_KINDS)}'
        raise DataError(msg)
    rng = np.random.default_rng(seed)
    zero = float(rng.uniform(-2e-5, 2e-5))
    sign = 1 if rng.random() < 0.7 else -1
    rest = [0.0, 2.0]                            # a descent from above: at rest, low end
    truth: dict[str, Any] = {'lag_time_constant': 0.0, 'dead_time': 0.0,
                             'resonance_hz': 0.0, 'resonance_decay': 0.0,
                             'start': 'at rest after a descent'}
    config: dict[str, float] = {}
    rate = 1000.0
    if kind.startswith(('lag', 'dead time')):
        rate = 1000.0 if '1 kHz' in kind else 10000.0
        value = float(kind.split()[1 if kind.startswith('lag') else 2])
        # The plant's switches of the effects, from the registry.
        if kind.startswith('lag'):
            truth['lag_time_constant'] = config[plant_switch('rate_dependence')] = value * 1e-3
        else:
            truth['dead_time'] = config[plant_switch('dead_time')] = value / rate
        if rate == 1000.0:
            t, x = identification_excitation(30.0, sample_rate=rate, seed=seed,
                                             burst_frequency=40.0, hold_duration=2.0,
                                             main_frequency=2.0)
        else:
            t, x = rising_amplitude_sine(rate, 20.0 if kind.startswith('lag') else 40.0)
    elif kind.startswith('ringing'):
        rate = 10000.0
        t, x = _steps_and_sines(rate, rng)
        # A mechanical mode after the actuator (output side), from the registry's plant step.
        truth['resonance_hz'] = config[plant_switch('resonance')] = float(kind.split()[1])
        truth['resonance_decay'] = config['resonance_decay_s'] = RING_DECAY
    elif kind == 'at rest, rising-amplitude sine':
        rate = 10000.0
        t, x = rising_amplitude_sine(rate, 20.0, cycles=15)
    elif kind == 'virgin':
        rate = 200.0
        t, x = identification_excitation(20.0, sample_rate=rate, seed=seed, ramp_duration=0.5)
        rest, truth['start'] = [], 'virgin (at rest at 0 A, never driven)'
    elif kind == 'mid-history':
        rate = 200.0
        t, x = identification_excitation(20.0, sample_rate=rate, seed=seed + 7)
        cut = 300                                 # the record starts 1.5 s into the run
        y = _measured(t, x, config, seed, [], noise)
        truth['start'] = 'mid-history (the first 1.5 s of the run not recorded)'
        return SyntheticRecord(t[cut:] - t[cut], x[cut:], zero + sign * y[cut:],
                               {**truth, 'noise': noise})
    else:                                         # one quasi-static loop, no time base
        x = np.concatenate([np.linspace(1.0, 1.8, 75), np.linspace(1.8, 0.2, 150),
                            np.linspace(0.2, 1.0, 75)])
        y = _measured(np.arange(x.size, dtype=np.float64), x, config, seed, [0.0, 1.8, 0.2],
                      noise)
        truth['start'] = 'one period of a repeated loop'
        return SyntheticRecord(None, x, zero + sign * y, {**truth, 'noise': noise})
    y = _measured(t, x, config, seed, rest + [float(x[0])] if rest else [], noise)
    return SyntheticRecord(t, x, zero + sign * y, {**truth, 'noise': noise})


def rates_record(effect: str, value: float, seed: int, *,
                 rates: tuple[float, ...] = (20.0, 100.0), noise: float = 0.002,
                 sample_rate: float = 10000.0) -> SyntheticRecord:
    """
    Build a record of rising-amplitude sines at one or more rates, with a lag or a dead time.

    One rate cannot tell a first-order lag from a dead time (each shifts the phase of the one
    frequency); two rates can (a lag's phase saturates, a dead time's grows with the
    frequency).  The sines follow each other without a step (each starts at the lower end
    with zero slope), so the step response does not decide either.

    Parameters
    ----------
    effect : {'lag', 'dead_time'}
        The input path's dynamics.
    value : float
        Its time constant or dead time [s].
    seed : int
        Seed of the noise, the sensor zero and sign.
    rates : tuple of float
        Cycle frequencies [Hz] of the parts (10 cycles at the first, 30 at the others).
    noise : float
        Sensor noise, RMS, as a fraction of the displacement range.
    sample_rate : float
        Samples per second [Hz].

    Returns
    -------
    SyntheticRecord
        The record and its truth.

    """
    if effect not in ('lag', 'dead_time'):
        msg = f"rates_record: effect must be 'lag' or 'dead_time'; found {effect!r}"
        raise DataError(msg)
    rng = np.random.default_rng(seed)
    zero = float(rng.uniform(-2e-5, 2e-5))
    sign = 1 if rng.random() < 0.7 else -1
    parts = [rising_amplitude_sine(sample_rate, f, cycles=10 if k == 0 else 30,
                                   hold=0.2 if k == 0 else 0.05)[1]
             for k, f in enumerate(rates)]
    x = np.concatenate(parts)
    t = np.arange(x.size) / sample_rate
    key = plant_switch('rate_dependence' if effect == 'lag' else 'dead_time')
    y = _measured(t, x, {key: value}, seed, [0.0, 2.0, float(x[0])], noise)
    truth = {'lag_time_constant': value if effect == 'lag' else 0.0,
             'dead_time': value if effect == 'dead_time' else 0.0, 'resonance_hz': 0.0,
             'resonance_decay': 0.0, 'start': 'at rest after a descent', 'noise': noise,
             'rates': list(rates)}
    return SyntheticRecord(t, x, zero + sign * y, truth)


def twin_record(kind: str, seed: int, *, drift: float = 0.3,
                noise: float = 0.002) -> SyntheticRecord:
    """
    Build the synthetic twin of a real capture whose refusal named the wrong cause.

    ``'leakage drift'``: first-order reversal curves from the top of the range, reaching
    lower each time (a ferroelectric film's FORC measurement), on top of a monotone drift
    of the output over the record (the integrated charge of a leakage current), ``drift``
    times the loops' range in all.  ``'deepening FORC'``: the same curves without drift,
    the later ones reaching below everything the first 60 % of the record reached (a
    validation part beyond the training range).

    Parameters
    ----------
    kind : str
        One of :data:`TWIN_KINDS`.
    seed : int
        Seed of the noise, the sensor zero and sign.
    drift : float
        The drift over the record, as a fraction of the loops' output range.
    noise : float
        Sensor noise, RMS, as a fraction of the displacement range.

    Returns
    -------
    SyntheticRecord
        The record; its truth holds ``drift`` (fraction) and ``training_low`` (the lowest
        input of the first 60 %, A).

    """
    if kind not in TWIN_KINDS:
        msg = f'unknown twin record {kind!r}; one of: {", ".join(TWIN_KINDS)}'
        raise DataError(msg)
    rng = np.random.default_rng(seed)
    zero = float(rng.uniform(-2e-5, 2e-5))
    rate = 1000.0
    levels = (np.linspace(1.4, 0.2, 7) if kind == 'leakage drift'
              else np.array([1.5, 1.4, 1.3, 1.2, 1.1, 0.6, 0.2]))
    parts = [np.linspace(1.0, 1.8, 200)]
    for level in levels:
        parts += [np.linspace(1.8, level, 300), np.linspace(level, 1.8, 300)]
    x = np.concatenate(parts)
    t = np.arange(x.size) / rate
    y = _measured(t, x, {}, seed, [0.0, 2.0, 0.2, float(x[0])], noise)
    amount = drift if kind == 'leakage drift' else 0.0
    y = y + amount * _RANGE_M * (t - t[0]) / (t[-1] - t[0])
    truth = {'lag_time_constant': 0.0, 'dead_time': 0.0, 'resonance_hz': 0.0,
             'resonance_decay': 0.0, 'start': 'at rest after a descent', 'noise': noise,
             'drift': amount, 'training_low': float(x[:int(0.6 * x.size)].min())}
    return SyntheticRecord(t, x, zero + y, truth)


def _measured(t: FloatArray, x: FloatArray, config: dict[str, float], seed: int,
              history: list[float], noise: float) -> FloatArray:
    # The actuator driven through `history` (ramps of 0.3 s, then 0.1 s at the first
    # value) before the record; the record's part of its output, noisy.
    actuator = MagnetostrictiveActuator(ActuatorConfig.from_mapping(config), seed=seed)
    dt = float(t[1] - t[0])
    if history:
        ramps = [np.linspace(a, b, max(int(0.3 / dt), 3), endpoint=False)
                 for a, b in zip(history[:-1], history[1:])]
        before = np.concatenate(ramps + [np.full(max(int(0.1 / dt), 3), history[-1])])
        th = t[0] - dt * np.arange(before.size, 0, -1)
        y = actuator.simulate(np.concatenate([th, t]), np.concatenate([before, x]))
        y = y[before.size:]
    else:
        y = actuator.simulate(t, x)
    rng = np.random.default_rng(seed + 1000)
    return y + rng.normal(0.0, noise * _RANGE_M, y.size)


def _steps_and_sines(rate: float, rng: np.random.Generator,
                     duration: float = 4.0) -> tuple[FloatArray, FloatArray]:
    # Quarter-second pieces: a step to a random level and a hold, or a sine of 2-20 Hz.
    t = np.arange(int(duration * rate)) / rate
    x = np.empty(t.size)
    piece = int(0.25 * rate)
    level = 1.0
    for k in range(0, t.size, piece):
        n = min(piece, t.size - k)
        if rng.integers(3) == 0:
            level = float(rng.uniform(0.2, 1.8))
            x[k:k + n] = level
        else:
            amplitude = float(rng.uniform(0.2, 0.8))
            centre = float(np.clip(level, 0.2 + amplitude, 1.8 - amplitude))
            x[k:k + n] = centre + amplitude * np.sin(
                2.0 * np.pi * rng.uniform(2.0, 20.0) * np.arange(n) / rate)
            level = float(x[k + n - 1])
    return t, x
