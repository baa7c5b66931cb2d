# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Issue 17's synthetic plants: dynamics and any start, identified whole.

Lag 0.5-5 ms at 1-10 kHz, dead time of 1-10 samples, 500-1000 Hz ringing after steps,
starts at rest, virgin and mid-history, rising-amplitude sines, one 300-sample loop: the
built-in actuator (not an MPI model) with 0.2 % noise, an arbitrary sensor zero and sign
(:mod:`mpi_ros.plant.synthetic`).  No record is refused; the lag or dead time is estimated within
20 %; the ringing records' output mode (:mod:`mpi_ros.extensions.resonance`) is found within
2 % (frequency) and 20 % (decay), modelled, and only there; the model simulated from the first
sample over the whole record (ringing included, for the ringing records) is within the noise
plus 0.5 points.
"""

from mpi_ros import identify
from mpi_ros.identification import fit_plain
from mpi_ros.plant.synthetic import SYNTHETIC_KINDS, synthetic_record
import numpy as np
import pytest


def _rms(sim, y):
    return float(np.sqrt(np.mean((sim - y) ** 2)) / np.ptp(y))


@pytest.mark.parametrize('seed', [1, 2, 3])
@pytest.mark.parametrize('kind', SYNTHETIC_KINDS)
def test_synthetic_plant_identified_whole(kind, seed):
    record = synthetic_record(kind, seed)
    t, x, y, truth = record.time, record.current, record.displacement, record.truth
    result = identify(x, y, order='auto', time=t)
    estimate = result.dynamics_estimate
    if truth['lag_time_constant']:
        assert estimate.lag_time_constant == pytest.approx(truth['lag_time_constant'],
                                                           rel=0.2)
    if truth['dead_time']:
        assert estimate.dead_time == pytest.approx(truth['dead_time'], rel=0.2)
    model = result.full_model
    sim = model.response(t, x)                  # the time base is ignored by a static model
    assert _rms(sim, y) == pytest.approx(result.whole_record_rms_error, rel=1e-9)
    bound = truth['noise'] * 0.034 / (np.ptp(y) / 1e-3) + 0.005     # noise + 0.5 points
    mode = result.resonance
    if truth['resonance_hz']:
        assert result.excluded > 0 and 'rings at about' in result.findings
        assert mode.modelled and model.cause == 'resonance'
        assert mode.frequency == pytest.approx(truth['resonance_hz'], rel=0.02)
        assert mode.decay == pytest.approx(truth['resonance_decay'], rel=0.2)
        assert f'rings at {mode.frequency:.4g} Hz' in result.findings
        assert result.whole_record_rms_error < _rms(fit_plain(x, y).simulate(x), y)
    else:
        assert not mode.modelled
    assert result.whole_record_rms_error <= bound
