# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
The actuator built from the effect registry returns what the hard-coded one returned.

test/data/actuator_reference.npz holds the outputs of MagnetostrictiveActuator at commit
b9ad4fe, before issue 19 moved the plant effects (creep, eddy-current lag, thermal drift,
dead time) from its compiled kernel into the effect registry; it was written by
test/data/make_actuator_reference.py, which also stores the inputs and each case's config.
"""

import json
from pathlib import Path

from mpi_ros.plant.actuator import ActuatorConfig, MagnetostrictiveActuator
import numpy as np
import pytest

REFERENCE = np.load(Path(__file__).parent / 'data' / 'actuator_reference.npz')
CASES = json.loads(str(REFERENCE['cases']))
SEED = 5


@pytest.mark.parametrize('case', sorted(CASES))
def test_simulate_equals_the_pre_registry_actuator(case):
    act = MagnetostrictiveActuator(ActuatorConfig(**CASES[case]), seed=SEED)
    out = act.simulate(REFERENCE['time'], REFERENCE['current'])
    np.testing.assert_array_equal(out, REFERENCE[case])        # bit for bit


def test_chunked_run_equals_the_pre_registry_actuator():
    t, x, cuts = REFERENCE['time'], REFERENCE['current'], REFERENCE['cuts']
    act = MagnetostrictiveActuator(ActuatorConfig(**CASES['all']), seed=SEED)
    out = np.concatenate([act.advance(t[a:b], x[a:b]) for a, b in zip(cuts[:-1], cuts[1:])])
    np.testing.assert_array_equal(out, REFERENCE['all_streamed'])
    act.reset()
    single = [act.step(float(tk), float(xk)) for tk, xk in zip(t[:200], x[:200])]
    np.testing.assert_array_equal(single, REFERENCE['all'][:200])


def test_every_effect_changes_the_output():
    # Guards the reference itself: each effect's case differs from the plain actuator.
    for case in CASES:
        if case != 'plain':
            assert np.max(np.abs(REFERENCE[case] - REFERENCE['plain'])) > 1e-8, case
