# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""The multi-axis compensator's packed compiled loop against one compensator per axis."""

from hypothesis import given, settings, strategies as st
from mpi_ros.compensation import Compensator, MultiAxisCompensator
from mpi_ros.errors import DataError, ModelError
from mpi_ros.extensions import CreepModel, RateDependentModel
from mpi_ros.operators.memory import TurningPointMemory
import numpy as np
import pytest

from .core_models import random_model


def _reference_push(points, x, capacity):
    # The turning-point rule as it was written in Python before it was compiled.
    p = points
    if len(p) >= 2 and (p[-1] - p[-2]) * (x - p[-1]) >= 0.0:
        p[-1] = x
    elif len(p) >= 1 and x == p[-1]:
        return
    else:
        p.append(x)
    while len(p) >= 4:
        a, b, c, cur = p[-4], p[-3], p[-2], p[-1]
        if not ((c - a) * (b - c) >= 0.0 and (cur - b) * (b - c) >= 0.0):
            break
        del p[-3:-1]
    if len(p) > capacity:
        del p[1:3]


@settings(max_examples=200, deadline=None)
@given(st.lists(st.integers(-6, 6), min_size=0, max_size=120), st.integers(4, 12))
def test_compiled_memory_equals_the_reference_rule_with_overflow(steps, capacity):
    memory, reference = TurningPointMemory(capacity), []
    for x in np.cumsum(np.array(steps, dtype=float) * 0.5) * np.linspace(1.0, 3.0, len(steps)):
        memory.push(float(x))
        _reference_push(reference, float(x), capacity)
        assert memory.points.tolist() == reference
    assert len(memory) <= capacity


def _blocks(rng, ranges, count):
    lo, hi = ranges[:, 0], ranges[:, 1]
    path = np.cumsum(rng.normal(0.0, 0.12, (count, lo.size)), axis=0) % 1.5 - 0.25
    block = lo + (hi - lo) * path                  # some out of range and clamped
    block[rng.random(block.shape) < 0.02] = np.nan
    block[rng.random(block.shape) < 0.01] = -np.inf
    return block


def test_packed_axes_equal_single_compensators_exactly():
    rng = np.random.default_rng(3)
    models = [random_model(rng, n=n, l=l) for n, l in ((6, 3), (14, 7), (0, 0), (9, 2))]
    models[1] = CreepModel(models[1], np.array([0.05, 0.5]), np.array([0.1, 0.05]))
    highs = [1.5, 2.0, 2.5, 3.0]
    multi = MultiAxisCompensator(models, output_min=-1.0, output_max=highs)
    singles = [Compensator(m, output_min=-1.0, output_max=hi) for m, hi in zip(models, highs)]
    ranges = np.array([c.displacement_range for c in singles])
    block = _blocks(rng, ranges, 700)
    replacement = random_model(rng, n=11, l=4)
    changes = {
        1: lambda c, k: c.install(replacement) if k == 0 else None,
        2: lambda c, k: c.install(models[0]) if k == 3 else None,
        3: lambda c, k: c.set_limits(-0.5, 2.2),
        4: lambda c, k: setattr(c, 'enabled', False),
        5: lambda c, k: setattr(c, 'enabled', True),
    }
    parts = np.array_split(block, [1, 9, 200, 201, 450, 455])
    got, expected = [], []
    for step, part in enumerate(parts):
        if step in changes:
            if step == 1:
                multi.install(0, replacement)            # through the multi-axis compensator
            elif step == 3:
                multi.set_limits(-0.5, 2.2)
            elif step in (4, 5):
                multi.enabled = step == 5
            else:
                changes[step](multi.axes[3], 3)          # straight on an axis
            for k, single in enumerate(singles):
                changes[step](single, k)
        rows = [multi.command(row) for row in part] if step == 6 else [multi.command(part)]
        got.append(np.vstack(rows) if step == 6 else rows[0])
        expected.append([[c.command(v) for c, v in zip(singles, row)] for row in part])
    np.testing.assert_array_equal(np.vstack(got), np.vstack(expected))
    assert multi.counters == {key: sum(c.counters[key] for c in singles)
                              for key in singles[0].counters}
    for axis, single in zip(multi.axes, singles):
        assert axis.counters == single.counters
        assert axis.last_command == single.last_command
        np.testing.assert_array_equal(axis.state, single.state)
        np.testing.assert_array_equal(axis.memory.points, single.memory.points)
        np.testing.assert_array_equal(axis.slow_state, single.slow_state)
    counts = singles[0].counters
    assert counts['nonfinite_input'] and counts['out_of_range'] and counts['clamped']


@pytest.mark.parametrize('axes', [1, 3, 16])
def test_one_sample_rows_equal_blocks(axes):
    rng = np.random.default_rng(axes)
    models = [random_model(rng, n=8, l=4) for _ in range(axes)]
    by_rows = MultiAxisCompensator(models, output_min=-1.0, output_max=2.0)
    by_block = MultiAxisCompensator(models, output_min=-1.0, output_max=2.0)
    ranges = np.array([c.displacement_range for c in by_rows.axes])
    block = _blocks(rng, ranges, 300)
    rows = np.vstack([by_rows.command(row) for row in block])
    np.testing.assert_array_equal(rows, by_block.command(block))
    assert by_rows.counters == by_block.counters


def test_one_compiled_variant_serves_every_block_layout():
    # Read-only views (as decoded from message bytes), strided and Fortran-ordered blocks
    # must not compile another variant of the loop in the middle of a stream.
    from mpi_ros.compensation.kernels import compensate_axes
    rng = np.random.default_rng(8)
    multi = MultiAxisCompensator([random_model(rng, n=5, l=2) for _ in range(3)],
                                 output_min=-1.0, output_max=2.0)
    variants = len(compensate_axes.signatures)
    ranges = np.array([c.displacement_range for c in multi.axes])
    block = _blocks(rng, ranges, 20)
    readonly = np.frombuffer(block.tobytes(), dtype=np.float64).reshape(block.shape)
    strided = np.hstack([block, block])[:, ::2]
    for layout in (readonly, strided, np.asfortranarray(block), block[0]):
        multi.command(layout)
    assert len(compensate_axes.signatures) == variants


def test_an_axis_used_alone_between_blocks_stays_exact():
    # A compensator taken from .axes and used on its own (its chunk loop packs it alone)
    # hands its state back and forth with the multi-axis pack.
    rng = np.random.default_rng(12)
    models = [random_model(rng, n=7, l=3) for _ in range(3)]
    multi = MultiAxisCompensator(models, output_min=-1.0, output_max=2.0)
    singles = [Compensator(m, output_min=-1.0, output_max=2.0) for m in models]
    ranges = np.array([c.displacement_range for c in singles])
    block = _blocks(rng, ranges, 90)
    first = multi.axes[1]
    got = [multi.command(block[:30])]
    alone = first.command_batch(block[30:40, 1])
    got.append(multi.command(block[40:60]))
    alone = np.concatenate([alone, first.command_batch(block[60:70, 1]),
                            [first.command(block[70, 1])]])
    got.append(multi.command(block[71:]))
    rows = np.r_[0:30, 40:60, 71:90]
    expected = np.array([[c.command(v) if (k == 1 or i in set(rows)) else np.nan
                          for k, (c, v) in enumerate(zip(singles, row))]
                         for i, row in enumerate(block)])
    np.testing.assert_array_equal(np.vstack(got), expected[rows])
    np.testing.assert_array_equal(alone, expected[np.r_[30:40, 60:71], 1])


def test_limits_of_one_axis_change_that_axis_only():
    rng = np.random.default_rng(5)
    models = [random_model(rng, n=6, l=3) for _ in range(3)]
    multi = MultiAxisCompensator(models, output_min=-1.0, output_max=2.0)
    singles = [Compensator(m, output_min=-1.0, output_max=2.0) for m in models]
    ranges = np.array([c.displacement_range for c in singles])
    first, second = np.array_split(_blocks(rng, ranges, 400), 2)
    np.testing.assert_array_equal(
        multi.command(first), [[c.command(v) for c, v in zip(singles, row)] for row in first])
    multi.set_limits(-0.2, 0.9, axis=1)
    singles[1].set_limits(-0.2, 0.9)
    got = multi.command(second)
    np.testing.assert_array_equal(
        got, [[c.command(v) for c, v in zip(singles, row)] for row in second])
    assert [(c.output_min, c.output_max) for c in multi.axes] == [
        (-1.0, 2.0), (-0.2, 0.9), (-1.0, 2.0)]
    assert np.all((got[:, 1] >= -0.2) & (got[:, 1] <= 0.9))


@pytest.mark.parametrize('axis', [3, -1, 1.0])
def test_limits_of_a_missing_axis_are_refused(axis):
    rng = np.random.default_rng(6)
    multi = MultiAxisCompensator([random_model(rng, n=4, l=2) for _ in range(3)],
                                 output_min=-1.0, output_max=2.0)
    with pytest.raises(ModelError, match='axis must be an axis index from 0 to 2'):
        multi.set_limits(0.0, 1.0, axis=axis)
    with pytest.raises(ModelError, match='output.min must be finite and below output.max'):
        multi.set_limits(1.0, 0.5, axis=2)
    assert [(c.output_min, c.output_max) for c in multi.axes] == [(-1.0, 2.0)] * 3


def test_times_drive_the_lags_of_the_effect_axes_only():
    """Row times reach each effect axis's lags; the plain axes ignore them; a bad length fails."""
    rng = np.random.default_rng(21)
    gammas = [random_model(rng, n=5, l=2, initial_history=False) for _ in range(3)]
    models = [CreepModel(gammas[0], np.array([0.01, 0.2]), np.array([0.1, 0.05])), gammas[1],
              RateDependentModel(gammas[2], 0.004)]
    multi = MultiAxisCompensator(models, output_min=-1.0, output_max=2.0, sample_period=1e-3)
    singles = [Compensator(m, output_min=-1.0, output_max=2.0, sample_period=1e-3)
               for m in models]
    ranges = np.array([c.displacement_range for c in singles])
    block = _blocks(rng, ranges, 300)
    # Irregular, increasing times, one repeated (a bad time: counted, sample_period used).
    times = 5.0 + np.cumsum(rng.uniform(2e-4, 3e-3, block.shape[0]))
    times[150] = times[149]
    got = np.vstack([multi.command(part, part_times) for part, part_times in
                     zip(np.array_split(block, [1, 40, 41, 200]),
                         np.array_split(times, [1, 40, 41, 200]))])
    expected = np.column_stack([[c.command(float(v), time=float(t))
                                 for v, t in zip(block[:, a], times)]
                                for a, c in enumerate(singles)])
    assert np.array_equal(got, expected, equal_nan=True)
    nominal = np.column_stack([[c.command(float(v)) for v in block[:, a]]
                               for a, c in enumerate(
                                   Compensator(m, output_min=-1.0, output_max=2.0)
                                   for m in models)])
    assert np.array_equal(nominal[:, 1], expected[:, 1])     # the plain axis: no lag
    assert np.max(np.abs(nominal[:, 2] - expected[:, 2])) > 1e-6
    assert multi.counters['bad_time'] == 2                  # axes 0 and 2, once each
    with pytest.raises(DataError, match='times must give one time per sample'):
        multi.command(block[:4], times[:3])


def test_sample_period_is_set_on_every_axis_and_checked():
    rng = np.random.default_rng(2)
    multi = MultiAxisCompensator([random_model(rng, n=3, l=1) for _ in range(2)],
                                 output_min=-1.0, output_max=2.0, sample_period=2e-3)
    assert multi.sample_period == 2e-3
    multi.sample_period = 5e-4
    assert [axis.sample_period for axis in multi.axes] == [5e-4, 5e-4]
    with pytest.raises(ModelError, match='sample_period must be finite and > 0'):
        multi.sample_period = 0.0
