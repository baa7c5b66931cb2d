# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
The compensator's time base and the bounded lead (issue 24, item 3).

A feed-forward chain must not depend on when DDS delivers a message: the lags of an extended
model are inverted on the stream's own time base (``message_time``: nominal, or arrival with
pauses only), and the lead filter that inverts an input lag is bounded.  No timing here:
arrival sequences are simulated.
"""

import math

from mpi_ros.compensation import Compensator
from mpi_ros.compensation.message_time import MessageClock, pause_threshold
from mpi_ros.errors import ModelError
from mpi_ros.extensions import CreepModel, extended_model_from_params, fit_rate_dependence, \
    RateDependentModel, ThermalDriftModel
from mpi_ros.extensions.rate_dependence import LEAD_GAIN, RateDependenceInverse
from mpi_ros.model_fit import identify
from mpi_ros.plant.actuator import ActuatorConfig, MagnetostrictiveActuator
from mpi_ros.plant.excitation import identification_excitation, tracking_trajectory
import numpy as np
import pytest

from .core_models import random_model

ROUND_OFF = 1e-12      # [A] the same commands up to the rounding of the stream times
PERIOD = 1e-3          # [s] the nominal sample period of these streams


def jittered_arrivals(rng, size, period=PERIOD):
    """
    Return DDS-like arrival times: on schedule plus latency, bunched, late and out of order.

    Every gap stays below the pause threshold.
    """
    latency = rng.lognormal(math.log(0.3e-3), 1.0, size)
    late = rng.random(size) < 0.02
    latency[late] += rng.uniform(5e-3, 40e-3, int(late.sum()))     # a busy executor
    arrivals = np.arange(size) * period + latency
    bunched = np.flatnonzero(rng.random(size - 1) < 0.05)
    arrivals[bunched + 1] = arrivals[bunched] + 1e-6               # two in one callback
    return 50.0 + arrivals


def _models(rng):
    gamma = random_model(rng, n=6, l=3)
    rate = RateDependentModel(gamma, 0.005)
    creep = CreepModel(gamma, np.array([0.01, 0.1, 1.0]), np.array([0.05, 0.1, 0.2]))
    both = extended_model_from_params({**creep.to_params(), **rate.to_params()})
    return [rate, creep, ThermalDriftModel(gamma, 2.0, 0.05), both]


def test_message_clock_is_nominal_until_the_stream_pauses():
    rng = np.random.default_rng(11)
    arrivals = jittered_arrivals(rng, 3000)
    assert np.min(np.diff(arrivals)) < 1e-5 and np.max(np.diff(arrivals)) > 5e-3
    clock = MessageClock()
    times = np.array([clock.time(a, PERIOD) for a in arrivals])
    np.testing.assert_allclose(np.diff(times), PERIOD, rtol=0.0, atol=1e-12)
    assert times[0] == arrivals[0] and clock.pauses == 0
    # A pause (2.5 s without a message): its whole periods are counted once, then nominal.
    later = [clock.time(a, PERIOD) for a in arrivals[-1] + np.array([2.5, 2.5004, 2.5021])]
    assert clock.pauses == 1
    np.testing.assert_allclose(later, times[-1] + np.array([2.5, 2.501, 2.502]), atol=1e-9)
    # Chunks: K samples a period apart, the first a period after the previous chunk.
    clock.reset()                                     # the clock never runs back
    assert clock.time(10.0, PERIOD) == pytest.approx(later[-1] + PERIOD, abs=1e-9)
    clock = MessageClock()
    first, second = clock.times(10.0, 3, PERIOD), clock.times(10.0000001, 4, PERIOD)
    np.testing.assert_allclose(first, [9.998, 9.999, 10.0], atol=1e-12)
    np.testing.assert_allclose(second, [10.001, 10.002, 10.003, 10.004], atol=1e-12)
    assert pause_threshold(1e-3) == 0.1 and pause_threshold(0.01) == 1.0


def test_message_clock_survives_clocks_that_run_back_or_are_not_finite():
    clock = MessageClock()
    times = [clock.time(a, PERIOD) for a in (5.0, 4.0, float('nan'), float('inf'), 5.0, -1e300)]
    assert np.all(np.isfinite(times))
    np.testing.assert_allclose(np.diff(times)[:2], PERIOD, atol=1e-12)
    assert np.all(np.diff(times) >= PERIOD - 1e-12)


@pytest.mark.parametrize('seed', range(3))
def test_bunched_and_late_arrivals_give_the_nominal_commands(seed):
    # message_time arrival (robust) against nominal: identical commands for every model with
    # lags, although the arrivals bunch (1 us apart), come late (up to 40 ms) and jitter.
    rng = np.random.default_rng(seed)
    size = 3000
    arrivals = jittered_arrivals(rng, size)
    for model in _models(rng):
        gamma = model.gamma
        desired = gamma.simulate(np.clip(1.0 + np.cumsum(rng.normal(0.0, 0.01, size)),
                                         0.2, 1.8))
        nominal = Compensator(model, output_min=0.2, output_max=1.8, sample_period=PERIOD)
        timed = Compensator(model, output_min=0.2, output_max=1.8, sample_period=PERIOD)
        clock = MessageClock()
        expected = [nominal.command(s) for s in desired]
        got = [timed.command(s, time=clock.time(a, PERIOD)) for s, a in zip(desired, arrivals)]
        np.testing.assert_allclose(got, expected, rtol=0.0, atol=ROUND_OFF)
        # The raw arrival times would have given other commands (the test can fail).
        raw = Compensator(model, output_min=0.2, output_max=1.8, sample_period=PERIOD)
        unsmoothed = [raw.command(s, time=a) for s, a in zip(desired, arrivals)]
        assert np.max(np.abs(np.subtract(unsmoothed, expected))) > 1e-6


def _lead(step, targets, intervals):
    # The step's commands for targets (Gamma^-1 taken as the identity), no clamping.
    commands = []
    previous = float(targets[0])
    step.start(previous)
    for k, (u, h) in enumerate(zip(targets, intervals)):
        started = k > 0
        step.prepare(previous, float(h), started)
        x = step.invert(float(u), previous, started, lambda v, beta: v)
        step.advance(x, previous, started)
        commands.append(x)
        previous = x
    return np.array(commands)


@pytest.mark.parametrize('interval', [1e-9, 1e-6, 1e-4, 1e-3, 0.02, 10.0])
def test_one_bunched_or_late_message_moves_the_command_at_most_lead_gain_times(interval):
    # A settled lead, then a target step of 1 mA arriving after `interval`: the bounded lead
    # moves the command by at most LEAD_GAIN x 1 mA; the exact lead by 1/b (100 x for a
    # message 0.1 ms after the previous one, 1e7 x for one 1 ns after).
    model = RateDependentModel(random_model(np.random.default_rng(0)), 0.005)
    targets = np.r_[np.full(50, 1.0), 1.001]
    intervals = np.r_[np.full(50, PERIOD), interval]
    bounded = _lead(RateDependenceInverse(model), targets, intervals)
    assert np.all(bounded[:50] == 1.0)
    assert abs(bounded[-1] - 1.0) <= LEAD_GAIN * 1e-3 + 1e-15
    assert bounded[-1] > 1.0
    exact = _lead(RateDependenceInverse(model, lead_gain=math.inf), targets, intervals)
    if interval <= 1e-4:
        assert abs(exact[-1] - 1.0) > 5 * LEAD_GAIN * 1e-3


@pytest.mark.parametrize('seed', range(4))
def test_bounded_lead_never_leaves_its_bound_whatever_the_intervals(seed):
    # |x - u| <= (G - 1) |u - g|, g the target filtered by tau_e / G (a convex combination of
    # the earlier targets), so the command never leaves the targets' range by more than
    # (G - 1) times that range, for intervals from 1 ns to 10 s.
    rng = np.random.default_rng(seed)
    model = RateDependentModel(random_model(rng), float(rng.uniform(1e-3, 0.02)))
    size = 2000
    targets = 1.0 + np.cumsum(rng.normal(0.0, 0.01, size))
    targets[rng.integers(0, size, 20)] += rng.normal(0.0, 0.3, 20)        # outliers
    intervals = 10.0 ** rng.uniform(-9.0, 1.0, size)
    commands = _lead(RateDependenceInverse(model), targets, intervals)
    tau_f = model.time_constant / LEAD_GAIN
    g = np.empty(size)
    g[0] = targets[0]
    for k in range(1, size):                  # the filter, first-order hold, written out
        h = intervals[k]
        a = math.exp(-h / tau_f)
        b = 1.0 - tau_f * (1.0 - a) / h
        g[k] = a * g[k - 1] + (1.0 - a) * targets[k - 1] + b * (targets[k] - targets[k - 1])
    np.testing.assert_allclose(commands, g + LEAD_GAIN * (targets - g), rtol=0, atol=1e-9)
    low = np.minimum.accumulate(targets)
    high = np.maximum.accumulate(targets)
    assert np.all(g >= low - 1e-12) and np.all(g <= high + 1e-12)
    spread = (LEAD_GAIN - 1.0) * (high - low)
    assert np.all(commands >= low - spread - 1e-9) and np.all(commands <= high + spread + 1e-9)
    exact = _lead(RateDependenceInverse(model, lead_gain=math.inf), targets, intervals)
    assert np.max(np.abs(exact - targets)) > 10.0 * np.max(np.abs(commands - targets))


def test_lead_gain_must_be_at_least_one():
    model = RateDependentModel(random_model(np.random.default_rng(1)), 0.005)
    with pytest.raises(ModelError, match=r'lead_gain must be >= 1 \(or inf'):
        RateDependenceInverse(model, lead_gain=0.5)
    with pytest.raises(ModelError, match='lead_gain must be >= 1'):
        Compensator(model, output_min=0.0, output_max=2.0, lead_gain=float('nan'))


def test_lagged_extended_compensator_wins_in_a_jittered_loop():
    # An eddy-current lag of 5 ms; both models from a 60 s identification record at 1 kHz.
    # The loop at 1 kHz: the plant steps at the (jittered, bunched, late) times its commands
    # arrive; the compensator gets the arrivals through the robust clock (the same commands
    # as nominal spacing), and the extended one tracks better than the plain one.
    cfg = ActuatorConfig(noise_std_m=4e-8, eddy_time_constant_s=0.005)
    t, x = identification_excitation(60.0, sample_rate=1000.0, seed=1)
    y = MagnetostrictiveActuator(cfg, seed=1).simulate(t, x)
    plain = identify(x, y, order='auto').model
    extended = fit_rate_dependence(t, x, y, order='auto')
    keep = t > 1.0
    span = np.ptp(y[keep])
    _, tracked = tracking_trajectory(20.0, sample_rate=1000.0,
                                     low=y[keep].min() + 0.1 * span,
                                     high=y[keep].max() - 0.1 * span)
    desired = np.concatenate([np.linspace(y[0], tracked[0], 1000), tracked])
    rng = np.random.default_rng(7)
    arrivals = jittered_arrivals(rng, desired.size)
    hop = rng.lognormal(math.log(0.3e-3), 1.0, desired.size)     # compensator to plant
    applied = np.maximum.accumulate(arrivals + hop)
    applied += np.arange(desired.size) * 1e-9          # the plant's times increase
    rms = []
    for model in (plain, extended):
        params = model.to_params()
        # A fresh plant starts where the identification record started (issue 24, item 2).
        comp = Compensator(extended_model_from_params(params), output_min=0.2,
                           output_max=1.8, sample_period=PERIOD, start='record')
        nominal = Compensator(extended_model_from_params(params), output_min=0.2,
                              output_max=1.8, sample_period=PERIOD, start='record')
        clock = MessageClock()
        plant = MagnetostrictiveActuator(cfg, seed=3)
        measured = np.empty(desired.size)
        for k, (s, a, p) in enumerate(zip(desired, arrivals, applied)):
            current = comp.command(float(s), time=clock.time(float(a), PERIOD))
            assert abs(current - nominal.command(float(s))) <= ROUND_OFF
            measured[k] = plant.step(float(p), current)
        error = (measured - desired)[1000:]
        rms.append(float(np.sqrt(np.mean(error ** 2)) / np.max(np.abs(desired[1000:]))))
    assert rms[1] <= 0.85 * rms[0], rms
