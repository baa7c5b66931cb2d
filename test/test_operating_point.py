# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Identification on a rig's operating point (issue 9): zero, bias, sign, scale, start state.

Data come from the built-in magnetostrictive-like actuator (not an MPI model) with its
sensor zeroed at the lowest current of the paper's range (0.2 A, after a 1.8 A peak), with
0.2 % sensor noise; models are validated on a second, different excitation.
"""

import functools

from hypothesis import given, HealthCheck, settings, strategies as st
from mpi_ros import IdentificationError, identify
from mpi_ros.compensation import Compensator
from mpi_ros.identification import burn_in, identify_weights
from mpi_ros.plant.actuator import ActuatorConfig, MagnetostrictiveActuator
from mpi_ros.plant.excitation import identification_excitation, tracking_trajectory
import numpy as np
import pytest

#: Sensor noise, fraction of the output range.
NOISE = 0.002
#: Issue 9: the validation error changes by less than 2 % (relative) under a transformation.
SAME_ERROR = 0.02
#: The paper's operating range, 1 A +- 0.8 A; the sensor is zeroed at its lowest current.
LOWEST, HIGHEST = 0.2, 1.8
RANGE_M = 3.4e-5       # about the displacement range of the default actuator on that range

ZEROED = {'sensor_zero_current_a': LOWEST, 'sensor_zero_peak_current_a': HIGHEST}

#: Three plants: the default shape and two others (narrower/wider loops, other static map).
PLANTS = (
    {},
    {'coercive_current_a': 0.22, 'interaction_center_a': 1.05, 'map_knee': 0.45},
    {'coercive_current_a': 0.38, 'coercive_spread_a': 0.14, 'map_linear_fraction': 0.3},
)


def _record(plant, seed, *, duration, rate, validation, repeats=1):
    config = ActuatorConfig(noise_std_m=NOISE * RANGE_M, **ZEROED, **PLANTS[plant])
    if validation:     # a different excitation: slower major loops, holds and bursts
        _, x = identification_excitation(duration, sample_rate=rate, seed=1000 + seed,
                                         main_frequency=0.5, holds=True, bursts=True)
    else:              # `repeats` decaying sweeps over the range, one after another
        sweeps = [identification_excitation(duration, sample_rate=rate, seed=seed + k,
                                            holds=False, bursts=False)
                  for k in range(repeats)]
        # Only the first starts with the ramp from rest (0 A) to the bias.
        x = np.concatenate([sweeps[0][1]] + [x[t >= 1.0] for t, x in sweeps[1:]])
    t = np.arange(x.size) / rate
    return x, MagnetostrictiveActuator(config, seed=seed).simulate(t, x)


@functools.lru_cache(maxsize=None)
def _small_records():
    """Training (three sweeps) and validation records small enough for property tests."""
    x, y = _record(0, 3, duration=12.0, rate=200.0, validation=False, repeats=3)
    ramp = 200             # the training record starts after the ramp from rest, at 1 A
    return ((x[ramp:], y[ramp:]),
            _record(0, 3, duration=30.0, rate=200.0, validation=True))


@functools.lru_cache(maxsize=None)
def _acceptance_records(plant):
    return (_record(plant, 10 + plant, duration=60.0, rate=200.0, validation=False),
            _record(plant, 10 + plant, duration=60.0, rate=200.0, validation=True))


def validation_error(model, x, y):
    """RMS error over the output range after the record's burn-in (start state unknown)."""
    start = burn_in(x, 0.99 * np.ptp(x), to_turning_point=True)
    error = model.simulate(x)[start:] - y[start:]
    return float(np.sqrt(np.mean(error * error)) / np.ptp(y))


def origin_with_constant(x, y, n, l):  # noqa: E741
    """Fit the paper's design (anchor='origin') with one constant term in the error."""
    design, w_h, w_s_inv, w_c, _, _ = identify_weights(
        x, y, n, l, anchor='origin', extra_columns=lambda _: np.ones((x.size, 1)),
        extra_lower=np.array([-np.inf]))
    return design.model(w_h, w_s_inv, float(w_c[0]))


def _transform(x, y, bias, offset, sign, x_scale, y_scale):
    return x_scale * x + bias, offset + sign * y_scale * y


def test_zeroed_actuator_reads_zero_at_its_lowest_current():
    t = np.linspace(0.0, 6.0, 601)
    x = np.interp(t, [0, 1, 2, 3, 4, 5, 6], [0, HIGHEST, LOWEST, 1.2, LOWEST, HIGHEST, LOWEST])
    plain = MagnetostrictiveActuator().simulate(t, x)
    zeroed = MagnetostrictiveActuator(ActuatorConfig(**ZEROED)).simulate(t, x)
    shifted = MagnetostrictiveActuator(ActuatorConfig(**ZEROED, sensor_offset_m=-2e-5))
    at_lowest = np.flatnonzero(np.isclose(x, LOWEST, rtol=0.0, atol=1e-12))
    np.testing.assert_allclose(zeroed[at_lowest], 0.0, atol=1e-12)  # wiping-out: each time
    assert plain[at_lowest[0]] > 0.1 * RANGE_M             # the plain actuator reads > 3 um
    np.testing.assert_allclose(zeroed - plain, -plain[at_lowest[0]], atol=1e-15)
    np.testing.assert_allclose(shifted.simulate(t, x), zeroed - 2e-5, atol=1e-15)
    config = ActuatorConfig(**ZEROED)
    assert ActuatorConfig.from_mapping(config.to_mapping(prefix='actuator.')) == config


@settings(max_examples=12, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(offset=st.floats(-0.5, 0.5), bias=st.floats(-1.0, 1.0), sign=st.sampled_from([1, -1]),
       log_x_scale=st.floats(-3.0, 3.0), log_y_scale=st.floats(-3.0, 3.0))
def test_invariant_to_zero_bias_sign_and_scale(offset, bias, sign, log_x_scale, log_y_scale):
    (x, y), (xv, yv) = _small_records()
    x_span, y_span = float(np.ptp(x)), float(np.ptp(y))
    x_scale, y_scale = 10.0 ** log_x_scale, 10.0 ** log_y_scale
    # Offsets of +-50 % of the output range, a bias of +-1 input range, in the new units.
    point = (bias * x_span * x_scale, offset * y_span * y_scale, sign, x_scale, y_scale)
    ref = identify(x, y, n=8, l=4)
    new = identify(*_transform(x, y, *point), n=8, l=4)
    ref_error = validation_error(ref.model, xv, yv)
    new_error = validation_error(new.model, *_transform(xv, yv, *point))
    assert ref_error < 0.01
    assert abs(new_error - ref_error) <= SAME_ERROR * ref_error
    assert new.model.output_sign == sign
    # The same model up to the operating point: simulations agree within the noise.
    sim = (new.model.simulate(_transform(xv, yv, *point)[0]) - point[1]) * sign / y_scale
    assert np.max(np.abs(sim - ref.model.simulate(xv))) <= NOISE * y_span
    # The same compensated trajectory: commands minus the bias agree within the noise
    # (commands in the input's units; the noise is the output's, through the mean slope).
    _, desired = tracking_trajectory(10.0, sample_rate=100.0, low=0.15 * np.ptp(yv),
                                     high=0.85 * np.ptp(yv))
    desired = desired + float(np.min(yv))
    plain = Compensator(ref.model, output_min=LOWEST, output_max=HIGHEST)
    moved = Compensator(new.model, output_min=LOWEST * x_scale + point[0],
                        output_max=HIGHEST * x_scale + point[0])
    commands = np.array([plain.command(d) for d in desired])
    moved_commands = np.array([moved.command(point[1] + sign * y_scale * d)
                               for d in desired])
    slack = NOISE * (HIGHEST - LOWEST)
    np.testing.assert_allclose((moved_commands - point[0]) / x_scale, commands, atol=slack)


@settings(max_examples=6, deadline=None, suppress_health_check=[HealthCheck.too_slow],
          derandomize=True)
@given(cut=st.floats(0.05, 0.3))
def test_record_starting_mid_history(cut):
    # Cut the start off: the record starts somewhere in the actuator's history (the later
    # sweeps still cover the whole range, so the data content stays comparable).  Its start
    # state is estimated (issue 17) and the model validates no worse than the whole
    # record's (which now fits the actuator's own initial loading curve from rest too, a
    # curve the PI model does not follow exactly: the cut record may do better).
    (x, y), (xv, yv) = _small_records()
    start = int(cut * x.size)
    ref = validation_error(identify(x, y, n=8, l=4).model, xv, yv)
    cut_fit = identify(x[start:], y[start:], n=8, l=4)
    new = validation_error(cut_fit.model, xv, yv)
    assert new <= 1.03 * ref
    assert cut_fit.burn_in == 0 and cut_fit.whole_record_rms_error < NOISE + 0.005


@pytest.mark.parametrize('start', [1005, 1035, 1155])
def test_record_starting_mid_descent_after_several_turning_points(start):
    # The cuts the randomised test above found (it is derandomised so that CI stays stable):
    # a descent after a history none of the start candidates covers, where the joint memory
    # estimate stopped while it moved one play at a time (validation 1.1-1.75x worse); it
    # moves steps between plays too now.
    (x, y), (xv, yv) = _small_records()
    ref = validation_error(identify(x, y, n=8, l=4).model, xv, yv)
    cut_fit = identify(x[start:], y[start:], n=8, l=4)
    assert validation_error(cut_fit.model, xv, yv) <= 1.03 * ref
    assert cut_fit.burn_in == 0 and cut_fit.whole_record_rms_error < NOISE + 0.005


@pytest.mark.parametrize('plant', range(len(PLANTS)))
@pytest.mark.parametrize('variant', ['zeroed', 'zero -20 um, bias +0.5 A'])
def test_builtin_actuator_acceptance(plant, variant):
    # Issue 9 acceptance: (14, 7) on one excitation, validated on another, is no worse
    # than the plain QP with one constant term; order 'auto' chooses >= (8, 4), the
    # smallest order whose held-out RMS error is within 2 % of the best order's (issue 17:
    # RMS on 30 short held-out blocks; the peak error (37) of a held-out block is noisy).
    (x, y), (xv, yv) = _acceptance_records(plant)
    if variant != 'zeroed':
        x, y, xv, yv = x + 0.5, y - 2e-5, xv + 0.5, yv - 2e-5
    centred = validation_error(identify(x, y, n=14, l=7).model, xv, yv)
    baseline = validation_error(origin_with_constant(x, y, 14, 7), xv, yv)
    assert centred <= baseline
    assert centred < 2.0 * NOISE            # the noise is NOISE: the model error is below it
    auto = identify(x, y, order='auto')
    assert auto.order >= (8, 4)
    held_out = {(row['n'], row['l']): row['rms_error'] for row in auto.order_table}
    best = min(held_out.values())
    assert held_out[auto.order] <= 1.02 * best
    assert all(error > 1.02 * best for order, error in held_out.items() if order < auto.order)
    assert validation_error(auto.model, xv, yv) <= baseline


def test_butterfly_refused_even_when_its_determined_part_is_monotone():
    # A ferroelectric butterfly loop, one bipolar cycle starting at 0 V: the part after
    # the burn-in (the last quarter) is monotone, the whole record is not.
    t = np.linspace(0.0, 1.0, 401)
    volts = 1400.0 * np.interp(t, [0.0, 0.25, 0.75, 1.0], [0.0, 1.0, -1.0, 0.0])
    falling = np.r_[True, np.diff(volts) < 0]
    switch = np.where(falling, -1000.0, 1000.0)
    strain = -(np.abs(volts - switch) - 0.6 * volts) * 1e-9
    assert abs(np.corrcoef(volts, strain)[0, 1]) > 0.3       # the correlation passes
    with pytest.raises(IdentificationError, match='butterfly loop'):
        identify(volts, strain, n=14, l=7)
