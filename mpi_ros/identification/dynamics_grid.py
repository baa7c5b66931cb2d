# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
The dynamics grid: dead time and lag of the input, each judged on held-out blocks.

With a time base, a grid over the dead time and the time constant of a first-order lag of
the input, one QP each (:func:`~.fitter.fit_record`), scored on held-out blocks by the
output's RMS error; the dynamics are kept when they beat the static model on them clearly
(:data:`DYNAMICS_GAIN`), and a dead time and a lag within the noise of the held-out blocks of
each other tie (:func:`~mpi_ros.identification.ties.compare_on_blocks`).
"""

from collections.abc import Callable
from dataclasses import dataclass, field, replace
import math
from typing import Any

import numpy as np
import numpy.typing as npt

from .dynamics import InputDynamics
from .fitter import fit_record, RecordFit
from .qp import FloatArray
from .record import PreparedRecord, Segment
from .ties import block_errors, BlockComparison, compare_on_blocks
from ..errors import DataError, IdentificationError

__all__ = ['DYNAMICS_GAIN', 'DynamicsEstimate', 'estimate_dynamics']


#: Dynamics are kept when they cut the held-out RMS output error by this fraction.
DYNAMICS_GAIN = 0.1


@dataclass(frozen=True)
class DynamicsEstimate:
    """
    The input's dynamics estimated from a record: both kinds, their errors, the choice.

    Attributes
    ----------
    modelled : InputDynamics
        What the model carries (zeros: the static model is as good on held-out data).
    dead_time : float
        Best dead time [s] of the dead-time-only trials (0 without a time base).
    lag_time_constant : float
        Best time constant [s] of the lag-only trials.
    static_error, dead_time_error, lag_error : float
        Held-out RMS output errors of the static model and of the best of each kind
        [fraction of the output range].
    tie : bool
        The dead time and the lag both beat the static model beyond the noise of the
        held-out blocks and are within it of each other
        (:func:`~mpi_ros.identification.ties.compare_on_blocks`): this record cannot tell
        them apart (a record with bursts at two rates can).
    trials : list of dict
        ``{'dead_time', 'lag_time_constant', 'held_error'}`` per trial.
    block_sizes : tuple of int
        Samples of each held-out block (empty when nothing was estimated).
    static_blocks, dead_time_blocks, lag_blocks : tuple of float
        Mean squared error per held-out block of the static model and of the best of each
        kind [fraction of the output range, squared].

    """

    modelled: InputDynamics = field(default_factory=InputDynamics)
    dead_time: float = 0.0
    lag_time_constant: float = 0.0
    static_error: float = math.nan
    dead_time_error: float = math.nan
    lag_error: float = math.nan
    tie: bool = False
    trials: list[dict[str, float]] = field(default_factory=list)
    block_sizes: tuple[int, ...] = ()
    static_blocks: tuple[float, ...] = ()
    dead_time_blocks: tuple[float, ...] = ()
    lag_blocks: tuple[float, ...] = ()

    def compare(self, first: str, second: str) -> BlockComparison:
        """
        Compare two of ``'static'``, ``'dead_time'``, ``'lag'`` on the held-out blocks.

        Parameters
        ----------
        first, second : str
            The models compared (first minus second).

        Returns
        -------
        BlockComparison
            The paired block test (:func:`~mpi_ros.identification.ties.compare_on_blocks`).

        """
        blocks = {'static': self.static_blocks, 'dead_time': self.dead_time_blocks,
                  'lag': self.lag_blocks}
        return compare_on_blocks(blocks[first], blocks[second], self.block_sizes)

    def to_json(self) -> dict[str, Any]:
        """Return the JSON form (no trials)."""
        return {'dead_time': self.dead_time, 'lag_time_constant': self.lag_time_constant,
                'static_held_out_error': _finite(self.static_error),
                'dead_time_held_out_error': _finite(self.dead_time_error),
                'lag_held_out_error': _finite(self.lag_error), 'tie': self.tie,
                'modelled': ('dead_time' if self.modelled.dead_time > 0.0 else
                             'lag' if self.modelled.lag_time_constant > 0.0 else 'none'),
                'modelled_dead_time': self.modelled.dead_time,
                'modelled_lag_time_constant': self.modelled.lag_time_constant}

    def describe(self) -> str:
        """Return what was found, in words (empty when nothing was estimated)."""
        nothing = self.dead_time == 0.0 and self.lag_time_constant == 0.0
        if not math.isfinite(self.static_error) or nothing:
            return ''
        both = (f'a dead time of {1e3 * self.dead_time:.3g} ms (held-out RMS'
                f' {100 * self.dead_time_error:.3g} %) or a first-order lag of'
                f' {1e3 * self.lag_time_constant:.3g} ms ({100 * self.lag_error:.3g} %),'
                f' against {100 * self.static_error:.3g} % for the static model')
        if not self.modelled.present:
            return (f'the output follows the input with {both}: not modelled (less than'
                    f' {100 * DYNAMICS_GAIN:.0f} % better); mpi-ros diagnose tests it on'
                    ' validation data')
        tie = (' they tie on this record (one rate): the lag is modelled, its inverse is'
               ' causal; bursts at two rates tell them apart (mpi-ros diagnose'
               ' --excitation)' if self.tie else '')
        return (f'the output follows the input with {both}; modelled:'
                f' {self.modelled.describe()}{";" if tie else ""}{tie}')


def _finite(value: float) -> float | None:
    return value if math.isfinite(value) else None


def estimate_dynamics(record: PreparedRecord, n: int, l: int,  # noqa: E741
                      held: npt.NDArray[np.bool_], starts: list[Segment],
                      burn_in: int = 0, *,
                      progress: Callable[[str], None] | None = None,
                      rule: str = 'joint') -> 'DynamicsEstimate':
    """
    Estimate the input's dead time and first-order lag: a grid, one QP each, held-out.

    Dead times from one sample interval and lag time constants from half a sample interval
    up to a quarter of the input's sweep time (and 200 intervals) are tried one kind at a
    time; the best of each kind is refined between its grid neighbours; each trial is
    scored by the RMS error of the model's output on the held-out blocks.  The better kind
    is modelled when it cuts the static model's held-out error by :data:`DYNAMICS_GAIN` or
    more, also at the highest order the record supports (up to (14, 7); a delay that only
    stands in for hysteresis a low order misses loses its gain there); when the two kinds
    are within the noise of each other on the held-out blocks (a paired test,
    :func:`~mpi_ros.identification.ties.compare_on_blocks`) the record cannot tell them
    apart (one rate), and the lag is modelled (its inverse is causal).

    Parameters
    ----------
    record : PreparedRecord
        The record, with a time base.
    n, l : int
        The order of the trial fits.
    held : ndarray of bool, shape (N,)
        Held-out rows.
    starts : list of Segment
        Start states (from the static fit).
    burn_in : int
        The static fit's burn-in (every trial is scored on the same rows).
    progress : callable, optional
        Called with a line of text before each trial fit (a progress display).
    rule : {'joint', 'determined'}
        Where each trial's weights come from (the static fit's rule, see :func:`fit_record`).

    Returns
    -------
    DynamicsEstimate
        The best dead time and lag, their held-out errors, whether they tie, and what is
        modelled (nothing when the static model is as good).

    """
    t = record.time
    trials: list[dict[str, float]] = []
    blocks: dict[InputDynamics, tuple[tuple[float, ...], tuple[int, ...]]] = {}
    if t is None:
        return DynamicsEstimate()
    dt = float(np.median(np.diff(t)))
    if not dt > 0.0:
        return DynamicsEstimate()
    limit = min(max(record.analysis.explain_limit, 4.0 * dt), 200.0 * dt,
                0.05 * float(t[-1] - t[0]))

    def score(dyn: InputDynamics) -> float:
        if progress is not None:
            progress(f'dynamics: trial fit {len(trials) + 1}, '
                     f'{dyn.describe() if dyn.present else "static"}')
        try:
            fit = fit_record(record, n, l, dynamics=dyn, held=held, starts=starts,
                             choose=False, burn_in=burn_in, rule=rule)
        except (IdentificationError, DataError):
            return math.inf
        difference = fit.simulate() - record.displacement     # one simulation per trial
        blocks[dyn] = block_errors(difference / np.ptp(record.displacement), held)
        error = _held_error(difference, record.displacement, held)
        trials.append({'dead_time': dyn.dead_time, 'lag_time_constant': dyn.lag_time_constant,
                       'held_error': error})
        return error

    delays = np.unique(np.round(np.geomspace(1.0, max(limit / dt, 1.0), 8))) * dt
    lags = np.geomspace(0.5 * dt, max(limit, dt), 8)
    static_error = score(InputDynamics())
    if not (math.isfinite(static_error) and static_error > 0.0):
        return DynamicsEstimate(static_error=static_error, trials=trials)
    best: dict[str, tuple[float, float]] = {}
    for kind, grid in (('dead_time', delays), ('lag_time_constant', lags)):
        # The best of each kind, refined between its grid neighbours (a lag and a dead time
        # look alike at one frequency, not over several: both are reported).
        errors = [score(InputDynamics(**{kind: float(v)})) for v in grid.tolist()]
        i = int(np.argmin(errors))
        error, dyn = _refine(score, (errors[i], InputDynamics(**{kind: float(grid[i])})), dt)
        best[kind] = (error, float(getattr(dyn, kind)))
    dead, lag = best['dead_time'], best['lag_time_constant']
    none: tuple[tuple[float, ...], tuple[int, ...]] = ((), ())
    sizes = blocks.get(InputDynamics(), none)[1]
    per_block = {kind: blocks.get(InputDynamics(**{kind: value}), none)[0]
                 for kind, value in (('dead_time', dead[1]), ('lag_time_constant', lag[1]))}
    static_blocks = blocks.get(InputDynamics(), none)[0]
    # Which kinds beat the static model beyond the noise of the blocks; a tie is two that do
    # and are within the noise of each other (the rule of the dynamics finding).
    beats = {kind: compare_on_blocks(per_block[kind], static_blocks, sizes).first_better
             for kind in per_block}
    tie = (beats['dead_time'] and beats['lag_time_constant'] and compare_on_blocks(
        per_block['dead_time'], per_block['lag_time_constant'], sizes).tie)
    # A tie models the lag: its inverse (a lead) is causal, a dead time's is not.
    kind = ('lag_time_constant' if tie else
            'dead_time' if beats['dead_time'] and not beats['lag_time_constant'] else
            'lag_time_constant' if beats['lag_time_constant'] and not beats['dead_time'] else
            'lag_time_constant' if lag[0] < dead[0] else 'dead_time')
    chosen = best[kind]
    modelled = (InputDynamics(**{kind: chosen[1]})
                if chosen[0] <= (1.0 - DYNAMICS_GAIN) * static_error else InputDynamics())
    if modelled.present and not _persists(record, modelled, held):
        modelled = InputDynamics()
    return DynamicsEstimate(modelled, dead_time=dead[1], lag_time_constant=lag[1],
                            static_error=static_error, dead_time_error=dead[0],
                            lag_error=lag[0], tie=tie, trials=trials, block_sizes=sizes,
                            static_blocks=static_blocks,
                            dead_time_blocks=per_block['dead_time'],
                            lag_blocks=per_block['lag_time_constant'])


def _persists(record: PreparedRecord, dynamics: InputDynamics,
              held: npt.NDArray[np.bool_]) -> bool:
    # The gain must persist at the highest order the record supports (up to (14, 7)): a
    # delay or lag that only stands in for hysteresis a lower order misses (one excitation
    # rate cannot tell them apart) loses its gain there; real dynamics keep it.
    size = int(np.count_nonzero(record.keep & ~held))
    orders = [order for order in ((14, 7), (12, 6), (10, 5))
              if size >= 10 * (order[0] + 2 * order[1] + 2)]
    if not orders:
        return True
    n, l = orders[0]  # noqa: E741
    try:
        static = fit_record(record, n, l, held=held)
        dynamic = fit_record(record, n, l, dynamics=dynamics, held=held,
                             starts=static.segments, choose=False, burn_in=static.burn_in)
    except (IdentificationError, DataError):
        return False
    before = _held_output_error(static, record.displacement, held)
    after = _held_output_error(dynamic, record.displacement, held)
    return bool(after <= (1.0 - DYNAMICS_GAIN) * before)


def _held_output_error(fit: RecordFit, displacement: FloatArray,
                       held: npt.NDArray[np.bool_]) -> float:
    # RMS error of the model's output on the held-out rows, over the output's range.
    return _held_error(fit.simulate() - displacement, displacement, held)


def _held_error(difference: FloatArray, displacement: FloatArray,
                held: npt.NDArray[np.bool_]) -> float:
    # The same from the model's output minus the measured output, already simulated.
    if not np.any(held):
        return math.nan
    error = difference[held]
    return float(np.sqrt(np.mean(error * error)) / np.ptp(displacement))


def _refine(score: Any, best: tuple[float, InputDynamics],
            dt: float) -> tuple[float, InputDynamics]:
    # A bounded search on the better kind, in log scale, between the grid's neighbours
    # (a factor 1.6 either side).
    from scipy.optimize import minimize_scalar
    error, dyn = best
    if not dyn.present:
        return best
    kind = 'dead_time' if dyn.dead_time > 0.0 else 'lag_time_constant'
    value = getattr(dyn, kind)

    def make(v: float) -> InputDynamics:
        return replace(dyn, **{kind: float(v)})

    res = minimize_scalar(lambda lv: score(make(math.exp(lv))),
                          bounds=(math.log(value / 1.6), math.log(value * 1.6)),
                          method='bounded', options={'maxiter': 8, 'xatol': 0.02})
    if float(res.fun) < error:
        error, dyn = float(res.fun), make(math.exp(float(res.x)))
    return error, dyn
