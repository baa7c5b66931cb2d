# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""Analytic inverse: transformation laws (12)-(14), (22)-(25) and Gamma^-1 (27)."""

from mpi_ros.operators.hysteresis import PIHysteresisOperator
from mpi_ros.operators.inverse import (invert_hysteresis, invert_hysteresis_initial_states,
                                       invert_hysteresis_thresholds, invert_hysteresis_weights,
                                       invert_superposition)
from mpi_ros.operators.superposition import PISuperpositionOperator
import numpy as np
import pytest

from .core_models import random_model, random_walk

#: Acceptance bound of the core issue: relative round-trip error.
ROUND_TRIP_TOL = 1e-9


def _relative(a, b):
    return float(np.max(np.abs(a - b)) / np.max(np.abs(b)))


@pytest.mark.parametrize('seed', range(40))
def test_inverse_of_forward_is_identity(seed):
    rng = np.random.default_rng(seed)
    model = random_model(rng)                    # n <= 20, l <= 10, non-zero initial states
    x = random_walk(rng, 3000, start=float(rng.uniform(-1, 1)))
    y = model.simulate(x)
    assert _relative(model.inverse().simulate(y), x) <= ROUND_TRIP_TOL


@pytest.mark.parametrize('seed', range(40))
def test_forward_of_inverse_is_identity(seed):
    rng = np.random.default_rng(100 + seed)
    model = random_model(rng)
    y0 = model.simulate(random_walk(rng, 200))
    desired = rng.uniform(y0.min(), y0.max(), 3000)
    inverse = model.inverse()
    assert _relative(model.simulate(inverse.simulate(desired)), desired) <= ROUND_TRIP_TOL


def test_largest_orders_with_initial_states():
    rng = np.random.default_rng(5)
    model = random_model(rng, n=20, l=10)
    assert np.any(model.hysteresis.initial_states != 0.0)
    x = random_walk(rng, 5000)
    assert _relative(model.inverse().simulate(model.simulate(x)), x) <= ROUND_TRIP_TOL


def test_inverse_is_an_involution():
    rng = np.random.default_rng(9)
    model = random_model(rng, n=12, l=6)
    back = model.inverse().inverse()
    assert not back.is_inverse and model.inverse().is_inverse
    for a, b in [(back.hysteresis.thresholds, model.hysteresis.thresholds),
                 (back.hysteresis.weights, model.hysteresis.weights),
                 (back.hysteresis.initial_states, model.hysteresis.initial_states),
                 (back.superposition.thresholds, model.superposition.thresholds),
                 (back.superposition.weights, model.superposition.weights)]:
        np.testing.assert_allclose(a, b, rtol=1e-12, atol=1e-12 * np.max(np.abs(b)))


def test_threshold_law_maps_thresholds_through_generator_function():
    h = PIHysteresisOperator([0.0, 0.2, 0.5, 1.1], [0.8, 0.3, 0.6, 0.1])
    r_inv = invert_hysteresis_thresholds(h.thresholds, h.weights)          # (12)
    np.testing.assert_allclose(r_inv, h.generator_function(h.thresholds))


def test_weight_law_inverts_slopes():
    w = np.array([0.8, 0.3, 0.6, 0.1])
    w_inv = invert_hysteresis_weights(w)                                     # (13)
    np.testing.assert_allclose(np.cumsum(w_inv), 1.0 / np.cumsum(w))
    assert w_inv[0] == pytest.approx(1.0 / 0.8)
    assert np.all(w_inv[1:] <= 0.0)


def test_initial_state_law_matches_inverse_play_outputs():
    # The inverse plays, driven by H[x], must run through the states (14) gives.
    rng = np.random.default_rng(3)
    h = PIHysteresisOperator([0.0, 0.2, 0.5, 1.1], [0.8, 0.3, 0.6, 0.1])
    x = random_walk(rng, 300)
    z, _ = h.play_outputs(x)
    y = z @ h.weights
    h_inv = invert_hysteresis(h)
    z_inv, _ = h_inv.play_outputs(y)
    for k in range(0, x.size, 37):
        np.testing.assert_allclose(z_inv[k], invert_hysteresis_initial_states(z[k], h.weights),
                                   atol=1e-12)                               # (14)


def test_superposition_inverse_both_branches():
    s = PISuperpositionOperator([-1.0, -0.4, 0.0, 0.3, 0.9], [0.5, 0.7, 1.0, -0.4, 0.9])
    s_inv = invert_superposition(s)
    x = np.linspace(-3.0, 3.0, 601)
    np.testing.assert_allclose(s_inv.apply(s.apply(x)), x, atol=1e-12)
    np.testing.assert_allclose(s_inv.thresholds, s.apply(s.thresholds), atol=1e-15)  # (22),(24)
    np.testing.assert_allclose(s_inv.slopes, 1.0 / s.slopes)                          # (23),(25)
