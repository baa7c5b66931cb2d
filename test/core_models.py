# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""Random valid MPI models, one hand-written model and signals shared by the tests."""

from mpi_ros.operators.hysteresis import PIHysteresisOperator
from mpi_ros.operators.model import MPIModel
from mpi_ros.operators.superposition import PISuperpositionOperator
import numpy as np


def hand_model():
    """
    Return the parameter form of the small hand-written Gamma many tests use, a new dict.

    Four plays (n = 3) and three dead zones, one negative weight (l = 2 split 0 + 2); its
    S thresholds are not spaced as (29)-(31), so it tells no identified range.

    """
    return {
        'model.hysteresis.thresholds': [0.0, 0.4, 0.8, 1.2],
        'model.hysteresis.weights': [1.0, 0.3, 0.2, 0.1],
        'model.hysteresis.initial_states': [0.0, 0.0, 0.0, 0.0],
        'model.superposition.thresholds': [0.0, 0.5, 1.0],
        'model.superposition.weights': [2e-5, -0.5e-5, 0.3e-5],
    }


def random_model(rng, *, n=None, l=None,  # noqa: E741 - the paper's symbol
                 initial_history=True, output_scale=1e-5):
    """
    Return a random forward MPI model satisfying (8) and (19).

    Asymmetric S (different negative/positive counts), optional non-zero
    (reachable) initial states produced by a random pre-history.

    """
    n = int(rng.integers(0, 21)) if n is None else n
    l = int(rng.integers(0, 11)) if l is None else l  # noqa: E741
    r_h = np.concatenate([[0.0], np.cumsum(rng.uniform(0.02, 0.3, n))])
    w_h = np.concatenate([[rng.uniform(0.2, 2.0)], rng.uniform(0.0, 1.0, n)])
    n_neg, n_pos = int(rng.integers(0, l + 1)), int(rng.integers(0, l + 1))
    r_s = np.concatenate([-np.cumsum(rng.uniform(0.05, 0.6, n_neg))[::-1], [0.0],
                          np.cumsum(rng.uniform(0.05, 0.6, n_pos))])
    slopes = rng.uniform(0.2, 3.0, r_s.size)
    w_s = np.empty_like(slopes)
    w_s[n_neg] = slopes[n_neg]
    w_s[n_neg + 1:] = np.diff(slopes[n_neg:])
    w_s[:n_neg] = -np.diff(slopes[:n_neg + 1])
    z0 = np.zeros(n + 1)
    if initial_history:
        _, z0 = PIHysteresisOperator(r_h, w_h).apply(rng.uniform(-2.0, 2.0, 25))
    return MPIModel(PIHysteresisOperator(r_h, w_h, z0),
                    PISuperpositionOperator(r_s, w_s * output_scale))


def random_walk(rng, size, scale=0.1, start=0.0):
    """Return a random-walk input that reverses often (rich minor loops)."""
    return start + np.cumsum(rng.normal(0.0, scale, size))
