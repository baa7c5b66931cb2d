# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""Tests of the excitation signals (mpi_ros.plant.excitation)."""

from mpi_ros.errors import DataError
from mpi_ros.plant.excitation import identification_excitation, tracking_trajectory
import numpy as np
import pytest

RATE = 1000.0  # Hz


def _turning_points(signal, time):
    """Return (times, values) of the input reversals, holds collapsed."""
    moving = np.flatnonzero(np.diff(signal) != 0)
    direction = np.sign(np.diff(signal)[moving])
    turn = moving[1:][direction[1:] != direction[:-1]]
    return time[turn], signal[turn]


def _nested_minor_loops(values):
    """Count reversal pairs strictly inside the preceding pair (max, min, max, min)."""
    count = 0
    for k in range(values.size - 3):
        a, b, c, d = values[k:k + 4]
        if (a > b and c < a and d > b and c > d) or (a < b and c > a and d < b and c < d):
            count += 1
    return count


def _longest_constant_run(signal):
    changes = np.flatnonzero(np.diff(signal) != 0)
    edges = np.concatenate([[-1], changes, [signal.size - 1]])
    return int(np.max(np.diff(edges)))


@pytest.fixture(scope='module')
def signal():
    return identification_excitation(60.0, sample_rate=RATE, seed=7)


def test_starts_at_rest_and_stays_in_range(signal):
    t, i = signal
    assert t.shape == i.shape == (60001,)
    assert t[0] == 0.0 and t[-1] == pytest.approx(60.0)
    assert i[0] == 0.0
    after_ramp = i[t >= 1.0]
    assert after_ramp.min() >= 0.2 and after_ramp.max() <= 1.8
    assert after_ramp.min() < 0.25 and after_ramp.max() > 1.75  # the major loop is visited
    ramp = i[t < 1.0]
    assert np.all(np.diff(ramp) >= 0) and ramp.max() <= 1.0


def test_custom_bias_and_amplitude():
    t, i = identification_excitation(30.0, sample_rate=500.0, bias=0.0, amplitude=2.0, seed=1,
                                     ramp_duration=0.5)
    assert np.all(np.abs(i) <= 2.0) and np.max(np.abs(i)) > 1.9


def test_deterministic_given_the_seed(signal):
    t, i = identification_excitation(60.0, sample_rate=RATE, seed=7)
    np.testing.assert_array_equal(i, signal[1])
    _, other = identification_excitation(60.0, sample_rate=RATE, seed=8)
    assert not np.array_equal(other, signal[1])


def test_contains_nested_minor_loops_and_decays(signal):
    t, i = signal
    times, values = _turning_points(i, t)
    assert values.size > 120  # 1 Hz major loops plus inner reversals and bursts
    assert _nested_minor_loops(values) >= 30
    early, late = i[(t > 1) & (t < 10)], i[t > 50]
    assert np.ptp(late) < 0.5 * np.ptp(early)


def test_holds_expose_creep(signal):
    t, i = signal
    assert _longest_constant_run(i) >= 2.0 * RATE
    _, plain = identification_excitation(60.0, sample_rate=RATE, seed=7, holds=False)
    assert _longest_constant_run(plain) < 0.01 * RATE


def test_bursts_are_fast_and_main_loops_quasi_static(signal):
    t, i = signal
    gaps = np.diff(_turning_points(i, t)[0])
    burst_half_period = 0.5 / 10.0
    assert np.sum(np.abs(gaps - burst_half_period) < 0.005) >= 2 * 2 * 5 - 2  # 2 bursts in 60 s
    _, quiet = identification_excitation(60.0, sample_rate=RATE, seed=7, bursts=False)
    gaps = np.diff(_turning_points(quiet, t)[0])
    assert gaps.min() >= 0.25 - 2 / RATE  # at most 2 Hz per half-cycle pair


@pytest.mark.parametrize(('kwargs', 'match'), [
    ({'duration': 0.0}, r'duration must be > 0; found 0\.0'),
    ({'duration': float('nan')}, 'duration must be a finite number'),
    ({'sample_rate': 100.0}, r'sample_rate must be >= 200 Hz'),
    ({'amplitude': -1.0}, 'amplitude must be > 0'),
    ({'bias': float('inf')}, 'bias must be a finite number'),
    ({'final_amplitude': 2.0}, r'final_amplitude must be in \(0, 1\]'),
    ({'duration': 5.0}, 'too short for 1 hold'),
])
def test_identification_excitation_errors(kwargs, match):
    options = {'duration': 30.0, 'sample_rate': 500.0, 'seed': 0, **kwargs}
    duration = options.pop('duration')
    with pytest.raises(DataError, match=match):
        identification_excitation(duration, **options)


def test_tracking_trajectory_in_range_smooth_with_minor_loops():
    low, high = 5e-6, 35e-6
    t, d = tracking_trajectory(40.0, sample_rate=RATE, low=low, high=high)
    assert d[0] == low
    assert d.min() >= low and d.max() <= high
    assert d.max() > low + 0.8 * (high - low)
    # Smooth: the second difference is tiny compared with the range.
    assert np.max(np.abs(np.diff(d, 2))) < 1e-4 * (high - low)
    values = _turning_points(d, t)[1]
    assert values.size > 20 and _nested_minor_loops(values) >= 5
    np.testing.assert_array_equal(tracking_trajectory(40.0, sample_rate=RATE, low=low,
                                                      high=high)[1], d)


@pytest.mark.parametrize(('kwargs', 'match'), [
    ({'low': 2.0, 'high': 1.0}, r'low must be < high; found low=2\.0, high=1\.0'),
    ({'high': float('nan')}, 'high must be a finite number'),
    ({'frequencies': (1.0, 2.0), 'weights': (1.0,)}, 'equal length; found 2 and 1'),
    ({'frequencies': (0.0,), 'weights': (1.0,)}, r'frequencies must be finite and > 0'),
    ({'weights': (0.0, 0.0, 0.0)}, 'not all 0'),
    ({'sample_rate': 10.0}, r'sample_rate must be >= 29\.4 Hz'),
    ({'final_envelope': 1.5}, r'final_envelope must be in \(0, 1\]'),
])
def test_tracking_trajectory_errors(kwargs, match):
    options = {'sample_rate': 100.0, 'low': 0.0, 'high': 1.0, **kwargs}
    with pytest.raises(DataError, match=match):
        tracking_trajectory(10.0, **options)
