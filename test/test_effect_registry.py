# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Effects are plug-ins: a toy effect registered here, in one place, works end to end.

The toy effect is a drive gain: the material sees ``k x`` instead of the commanded ``x``,
``s = Gamma[k x]`` (degenerate with Gamma itself, which is fine for a toy: the point is
that nothing outside this file is edited).  Registering it makes the parameter form, the
fit, the exact per-step inverse in the one compensator and the diagnosis candidate work.
"""

from dataclasses import dataclass
from typing import Any

from mpi_ros import MPIModel
from mpi_ros.compensation import Compensator
from mpi_ros.diagnosis import diagnose
from mpi_ros.excitation import identification_excitation
from mpi_ros.extensions import (Effect, EffectParameter, EFFECTS, extended_model_from_params,
                                ExtendedModelBase, register_effect, unregister_effect)
from mpi_ros.extensions._common import fit_gamma, search_fit
from mpi_ros.recordings import Recording
import numpy as np
import pytest

from .core_models import random_model

GAIN = 'model.drive_gain.gain'


@dataclass(frozen=True, eq=False)
class DriveGainModel(ExtendedModelBase):

    model: MPIModel
    gain: float
    cause = 'drive_gain'

    @classmethod
    def from_params(cls, mapping):
        return cls(MPIModel.from_params(mapping), float(mapping[GAIN]))

    def to_params(self):
        return dict(self.model.to_params(), **{GAIN: self.gain})

    def simulate(self, time, current):
        return self.model.simulate(self.gain * np.asarray(current, dtype=float))

    def inverse_step(self):
        return DriveGainInverse(self.gain)


class DriveGainInverse:

    def __init__(self, gain):
        self.gain = gain
        self.state = np.zeros(0)

    def start(self, current):
        pass

    def carry(self, other):
        return False

    def prepare(self, previous, interval, started):
        pass

    def invert(self, v, previous, started, inverse):
        return inverse(v, 0.0) / self.gain           # the material must see Gamma^-1

    def advance(self, current, previous, started):
        return self.gain * current


def fit_drive_gain(time, current, displacement, *, order):
    def trial(gain: float) -> tuple[Any, float]:
        model, error = fit_gamma(gain * current, displacement, order, 1e-6)
        return DriveGainModel(model, gain), error
    _, model, _ = search_fit(trial, np.array([0.8, 1.0, 1.25]), refine=0)
    return model


TOY = Effect(name='drive_gain', formula='Gamma[k x]',
             parameters=(EffectParameter(GAIN, 'double', 0.0, 'Toy drive gain k'),),
             model_class=DriveGainModel, fit=fit_drive_gain, parameter_count=lambda p: 1)


@pytest.fixture()
def toy():
    register_effect(TOY)
    try:
        yield TOY
    finally:
        unregister_effect(TOY.name)
    assert 'drive_gain' not in EFFECTS


def test_toy_effect_parameter_form_and_exact_inverse(toy):
    rng = np.random.default_rng(4)
    gamma = random_model(rng, n=6, l=3).with_operating_point(input_offset=0.3,
                                                             output_offset=2e-5)
    params = dict(gamma.to_params(), **{GAIN: 1.7})
    model = extended_model_from_params(params)
    assert isinstance(model, DriveGainModel) and model.gain == 1.7
    comp = Compensator(model, output_min=-10.0, output_max=10.0)
    assert comp.kind == 'drive_gain' and comp.has_effect
    x = 0.3 + np.cumsum(rng.normal(0.0, 0.02, 400))
    desired = model.simulate(None, x)
    commands = np.array([comp.command(v) for v in desired])
    # The compensator's commands drive the toy model exactly to the desired values.
    np.testing.assert_allclose(model.simulate(None, commands)[50:], desired[50:], rtol=0,
                               atol=1e-12 * np.ptp(desired))
    comp.install(gamma)                                   # and back to plain, bumplessly
    assert comp.kind == 'none' and not comp.has_effect


def test_toy_effect_is_fitted_and_a_diagnosis_candidate(toy):
    t, x = identification_excitation(30.0, sample_rate=200.0, seed=2, holds=False,
                                     bursts=False)
    truth = DriveGainModel(random_model(np.random.default_rng(1), n=4, l=2,
                                        initial_history=False), 1.25)
    y = truth.simulate(t, x) + np.random.default_rng(3).normal(0.0, 1e-8, x.size)
    fitted = toy.fit(t, x, y, order=(4, 2))
    assert isinstance(fitted, DriveGainModel)
    report = diagnose(Recording(t, x, y, source='toy'), order=(4, 2),
                      causes=('creep', 'drive_gain'))
    names = [c['cause'] for c in report.candidates]
    assert names == ['creep', 'drive_gain']
    toy_row = report.candidates[1]
    assert toy_row['signature'] == 'unavailable' and toy_row['parameter_count'] == 1
