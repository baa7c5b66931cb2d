# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""Elementary operators (2)-(4), (16)-(17), H (5), S (18), Gamma (26): batch == streaming."""

from mpi_ros.errors import ModelError
from mpi_ros.operators.deadzone import dead_zone_operator
from mpi_ros.operators.hysteresis import PIHysteresisOperator
from mpi_ros.operators.play import play_end_state, play_operator, PlayOperatorStream
from mpi_ros.operators.superposition import PISuperpositionOperator
import numpy as np
import pytest

from .core_models import random_model, random_walk

TOL = 1e-12


def _reference_play(x, r, z0):
    z, out = z0, []
    for v in x:
        z = max(v - r, min(v + r, z))        # (4)
        out.append(z)
    return np.array(out)


def test_play_matches_definition_with_initial_state():
    rng = np.random.default_rng(1)
    x = random_walk(rng, 500)
    r = np.array([0.0, 0.1, 0.5, 2.0])
    z0 = np.array([0.3, -0.2, 1.0, 5.0])
    z, z_end = play_operator(x, r, z0)
    for i in range(r.size):
        np.testing.assert_allclose(z[:, i], _reference_play(x, r[i], z0[i]), atol=TOL)
    np.testing.assert_array_equal(z_end, z[-1])


def test_play_end_state_is_the_batch_end_state():
    # The plays run without their outputs end where the batch ends, bit for bit, and on the
    # definition (4) (the compiled clamp is written with selects).
    rng = np.random.default_rng(7)
    x = random_walk(rng, 2000, scale=0.3)
    r = np.array([0.0, 0.05, 0.4, 1.3])
    z0 = np.array([0.2, -0.1, 0.9, -2.0])
    z, z_end = play_operator(x, r, z0)
    np.testing.assert_array_equal(play_end_state(x, r, z0), z_end)
    np.testing.assert_array_equal(play_end_state(x, r), play_operator(x, r)[1])
    for i in range(r.size):
        np.testing.assert_array_equal(z[:, i], _reference_play(x, r[i], z0[i]))


def test_play_zero_threshold_is_identity():
    x = np.linspace(-1, 1, 11)
    z, _ = play_operator(x, [0.0], [7.0])
    np.testing.assert_array_equal(z[:, 0], x)


def test_play_streaming_equals_batch():
    rng = np.random.default_rng(2)
    x = random_walk(rng, 300)
    r = np.array([0.0, 0.2, 0.7])
    z0 = np.array([0.0, 0.1, -0.3])
    batch, _ = play_operator(x, r, z0)
    stream = PlayOperatorStream(r, z0)
    np.testing.assert_allclose(np.array([stream.step(v) for v in x]), batch, atol=0.0)
    stream.reset()
    np.testing.assert_array_equal(stream.state, z0)


def test_dead_zone_matches_definition():
    x = np.linspace(-3, 3, 61)
    out = dead_zone_operator(x, [-1.0, 0.0, 1.5])
    np.testing.assert_allclose(out[:, 0], np.minimum(x + 1.0, 0.0))     # (17), r < 0
    np.testing.assert_allclose(out[:, 1], x)                             # r = 0
    np.testing.assert_allclose(out[:, 2], np.maximum(x - 1.5, 0.0))     # r > 0


def test_generator_function_is_initial_loading_curve():
    h = PIHysteresisOperator([0.0, 0.3, 0.9], [1.0, 0.5, 0.25])
    x = np.linspace(0.0, 2.0, 201)
    y, _ = h.apply(x)
    np.testing.assert_allclose(y, h.generator_function(x), atol=TOL)   # (6)
    np.testing.assert_allclose(h.slopes, [1.0, 1.5, 1.75])              # (7)


@pytest.mark.parametrize('seed', range(5))
def test_model_chunked_run_equals_one_shot_and_stream(seed):
    rng = np.random.default_rng(seed)
    model = random_model(rng)
    x = random_walk(rng, 1000)
    full, end = model.run(x)
    cuts = np.sort(rng.choice(np.arange(1, x.size), size=4, replace=False))
    parts, state = [], None
    for chunk in np.split(x, cuts):
        y, state = model.run(chunk, state)
        parts.append(y)
    np.testing.assert_array_equal(np.concatenate(parts), full)
    np.testing.assert_array_equal(state, end)
    stream = model.stream()
    np.testing.assert_array_equal([stream.step(v) for v in x], full)
    np.testing.assert_array_equal(stream.state, end)


def test_model_is_composition_of_h_and_s():
    rng = np.random.default_rng(7)
    model = random_model(rng)
    x = random_walk(rng, 400)
    h, _ = model.hysteresis.apply(x)
    np.testing.assert_allclose(model.simulate(x), model.superposition.apply(h), rtol=1e-12,
                               atol=1e-18)                               # (26)


def test_superposition_slopes_and_constraints():
    s = PISuperpositionOperator([-1.0, 0.0, 1.0], [0.5, 1.0, -0.5])
    np.testing.assert_allclose(s.slopes, [1.5, 1.0, 0.5])
    assert s.satisfies_constraints(0.4) and not s.satisfies_constraints(0.6)


@pytest.mark.parametrize('args, match', [
    (([0.1, 0.5], [1.0, 1.0]), 'start at exactly 0'),
    (([0.0, 0.5, 0.5], [1.0, 1.0, 1.0]), 'strictly ascending'),
    (([0.0, 0.5], [1.0]), 'equal lengths'),
    (([0.0, 0.5], [1.0, -2.0]), 'cumulative sum positive'),
    (([0.0, np.nan], [1.0, 1.0]), 'must be finite'),
    (([], []), 'must not be empty'),
])
def test_hysteresis_rejects_invalid(args, match):
    with pytest.raises(ModelError, match=match):
        PIHysteresisOperator(*args)


@pytest.mark.parametrize('args, match', [
    (([-1.0, 1.0], [1.0, 1.0]), 'exactly one 0'),
    (([0.0, 0.0], [1.0, 1.0]), 'exactly one 0'),
    (([0.0, 1.0, 0.5], [1.0, 1.0, 1.0]), 'strictly ascending'),
    (([0.0, 1.0], [1.0, -1.0]), 'positive slope'),
    (([0.0, 1.0], [1.0]), 'equal lengths'),
])
def test_superposition_rejects_invalid(args, match):
    with pytest.raises(ModelError, match=match):
        PISuperpositionOperator(*args)
