# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Issue 24: the identified model holds on a trajectory it was not fitted to.

Non-MPI plants (the built-in actuator's Preisach core, no effect; 32 seeds fixed before any
result was seen (see ``SEEDS``), each drawing the core's density and static map and a cut of
0-4 s off the start of its record), identified at (14, 7) from their excitation record,
compensated offline (:class:`~mpi_ros.compensation.Compensator`) on one sweep and then two
sines inside 15-85 % of the range.  On every seed the RMS tracking error after the sweep is
within 1.1x of the fit whose weights come only from the rows after the plays are determined
(the record's start only wipes out the memory), and never twice that of the start chosen
jointly with the weights (the procedure before cross-validation).
``benchmarks/eval_out_of_sample.py`` prints the table.
"""

import warnings

from mpi_ros import identify
from mpi_ros.compensation import Compensator
from mpi_ros.identification.fitter import fit_record
from mpi_ros.identification.qp import scaled_design
from mpi_ros.identification.record import prepare_record
from mpi_ros.identification.start_states import determined_from
from mpi_ros.plant.actuator import ActuatorConfig, MagnetostrictiveActuator
from mpi_ros.plant.excitation import identification_excitation
import numpy as np
import pytest

RATE = 200.0
LOW, HIGH = 0.2, 1.8
#: Seeds 0-11 were fixed before any result was seen; 500-519 too, later (2026-11-26): on 516
#: the tie-break of the time (the joint start) tracked at 1.16x the burn-in fit, which led to
#: the tie's mean (``'averaged'``); they stay as a regression set, no longer unseen.
SEEDS = tuple(range(12)) + tuple(range(500, 520))


def _plant(seed):
    rng = np.random.default_rng(seed)
    config = ActuatorConfig(
        noise_std_m=0.002 * 3.4e-5, sensor_zero_current_a=LOW, sensor_zero_peak_current_a=HIGH,
        coercive_current_a=float(rng.uniform(0.15, 0.45)),
        coercive_spread_a=float(rng.uniform(0.05, 0.2)),
        interaction_center_a=float(rng.uniform(0.8, 1.2)),
        interaction_spread_a=float(rng.uniform(0.3, 0.6)),
        reversible_fraction=float(rng.uniform(0.05, 0.2)),
        map_linear_fraction=float(rng.uniform(0.1, 0.4)),
        map_knee=float(rng.uniform(0.35, 0.7)))
    cut = int(rng.uniform(0.0, 4.0) * RATE)
    t, x = identification_excitation(30.0, sample_rate=RATE, seed=seed, holds=False,
                                     bursts=False)
    y = MagnetostrictiveActuator(config, seed=seed).simulate(t, x)
    return config, x[cut:], y[cut:]


def _tracking_error(model, config, seed, lo, hi):
    # RMS over the range after one sweep (2-98 %), on two sines inside 15-85 %.
    ramp = np.linspace(0.0, 1.0, int(2 * RATE))
    sweep = lo + (hi - lo) * (0.02 + 0.96 * np.concatenate([ramp, ramp[::-1]]))
    t = np.arange(int(20 * RATE)) / RATE
    sines = lo + (hi - lo) * (0.5 - 0.21 * np.cos(2 * np.pi * 0.31 * t)
                              - 0.14 * np.cos(2 * np.pi * 0.83 * t))
    desired = np.concatenate([sweep, sines])
    command = Compensator(model, output_min=LOW, output_max=HIGH).command_batch(desired)
    measured = MagnetostrictiveActuator(config, seed=seed + 500).simulate(
        np.arange(desired.size) / RATE, command)
    error = (measured - desired)[sweep.size:]
    return float(np.sqrt(np.mean(error ** 2)) / (hi - lo))


@pytest.mark.parametrize('seed', SEEDS)
def test_closed_loop_on_a_new_trajectory_within_the_burn_in_fit(seed):
    config, x, y = _plant(seed)
    lo, hi = float(np.min(y)), float(np.max(y))
    with warnings.catch_warnings():
        warnings.simplefilter('ignore')   # held-out warnings
        result = identify(x, y, n=14, l=7)
    record = prepare_record(x, y)
    design = scaled_design(x, y, 14, 7, sign=record.sign)
    split = determined_from(design.scaled_input(x), float(design.hysteresis_thresholds[-1]))
    burn_in = fit_record(record, 14, 7, burn_in=split, choose=False).model
    jointly = fit_record(record, 14, 7, memory_steps=True, rule='joint start').model
    error = _tracking_error(result.model, config, seed, lo, hi)
    assert error <= 1.1 * _tracking_error(burn_in, config, seed, lo, hi)
    assert error < 2.0 * _tracking_error(jointly, config, seed, lo, hi)
    # The held-out numbers are reported and the model beats the line on them.
    assert len(result.held_out_errors) == 5 and result.weights_from in (
        'determined', 'joint', 'joint start', 'averaged')
    assert result.held_out_error < result.line_held_out_error


def test_held_out_numbers_reported_against_the_line():
    # A hysteresis record: the model beats the straight line on every held-out fold, and the
    # JSON summary carries the per-fold numbers the refusal and the warnings use.
    config, x, y = _plant(3)
    result = identify(x, y, n=8, l=4)
    assert len(result.held_out_errors) == len(result.line_held_out_errors) == 5
    assert all(m < b for m, b in zip(result.held_out_errors, result.line_held_out_errors))
    held = result.summary()['held_out']
    assert held['rms_error'] == pytest.approx(result.held_out_error)
    assert held['weights_from'] == result.weights_from


@pytest.mark.parametrize('seed', range(1300, 1310))
def test_a_cut_record_predicts_its_rest_better_than_a_line(seed):
    # A record cut at a drawn share (30-90 %), identified on the part before the cut (order
    # auto, its time base): simulated on from the record's start, the model predicts the part
    # after, which no fit saw, at under half the error of a straight line fitted on the same
    # part.  Odd seeds: a discrete Preisach core of 2000 drawn relays instead of the built-in
    # one.  Seeds 1300-1309 chosen before any run (2026-11-27): 0.19-1.21 % of the range on
    # the rest against 3.3-10.7 % for the line; 40 seeds of the built-in core (1200-1239)
    # 0.23-0.93 % against 3.1-13 %.
    from mpi_ros.plant.preisach import random_preisach_core
    config, _, _ = _plant(seed)
    core = random_preisach_core(seed, relays=2000) if seed % 2 else None
    t, x = identification_excitation(30.0, sample_rate=RATE, seed=seed, holds=False,
                                     bursts=False)
    y = MagnetostrictiveActuator(config, seed=seed, core=core).simulate(t, x)
    cut = int(np.random.default_rng(seed + 7).uniform(0.3, 0.9) * x.size)
    with warnings.catch_warnings():
        warnings.simplefilter('ignore')   # held-out warnings
        result = identify(x[:cut], y[:cut], order='auto', time=t[:cut])
    span = float(np.ptp(y))
    rest = result.full_model.response(t, x)[cut:] - y[cut:]
    line = np.polyval(np.polyfit(x[:cut], y[:cut], 1), x[cut:]) - y[cut:]
    assert np.sqrt(np.mean(rest ** 2)) / span < 0.5 * np.sqrt(np.mean(line ** 2)) / span


@pytest.mark.parametrize('candidate, incumbent, better', [
    ([1.0, 1.0, 1.0, 1.0, 1.0], [1.0, 1.0, 1.0, 1.0, 1.00001], False),   # a tie within the floor
    ([0.5, 1.0, 1.0, 1.0, 1.0], [9.0, 1.0, 1.0, 1.0, 1.0], True),        # one fold, none worse
    ([0.5, 1.5, 1.0, 1.0, 1.0], [9.0, 1.0, 1.0, 1.0, 1.0], False),       # one fold, within noise
    ([0.9, 0.9, 0.9, 0.9, 0.9], [1.0, 1.0, 1.0, 1.0, 1.0], True),        # every fold
    ([0.9, 0.9, 0.9, 0.9, float('inf')], [1.0, 1.0, 1.0, 1.0, 1.0], False),   # cannot fit one
])
def test_a_rule_replaces_another_only_beyond_the_folds_noise(candidate, incumbent, better):
    from mpi_ros.identification.folds import better_on_folds, FoldErrors

    def errors(per_fold):
        values = np.array(per_fold) / 100.0
        return FoldErrors(float(np.sqrt(np.mean(values ** 2))), list(values))

    assert better_on_folds(errors(candidate), errors(incumbent)) is better
