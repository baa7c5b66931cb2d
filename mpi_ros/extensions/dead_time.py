# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Dead-time extension: a pure delay between the command and the measured displacement.

``s(t) = Gamma[x](t - L)``; since Gamma is rate independent this equals
``Gamma[x(. - L)](t)``: the input is delayed (linearly interpolated, held at the first
sample before the record) and Gamma identified on it.  ``L`` is found by a 1-D search
(grid of lags, then bounded refinement), one QP identification per trial.  A compensator
cannot undo a dead time (it would need the future); it can only be told about it.

Parameter key (besides Gamma's ``model.*`` keys, operating point included):
``model.dead_time`` (``L`` [s], >= 0).
"""

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import numpy.typing as npt

from .effect import Effect, EffectParameter, ExtendedModelBase, FAST_TIME_LIMIT, PlantChunk, \
    PlantEffect, PlantParameter
from .fitting import AxisUnits, burst_evidence, burst_verdict, check_series, \
    fit_input_stage, Order, scalar_parameter
from .plant_steps import delay_state, delay_stream
from ..identification.finding import SEPARATE_LAG_AND_DEAD_TIME
from ..operators.filters import delay
from ..operators.model import MPIModel

__all__ = ['DeadTimeModel', 'fit_dead_time', 'DEAD_TIME']

FloatArray = npt.NDArray[np.float64]

DEAD_TIME = 'model.dead_time'


@dataclass(frozen=True, eq=False)
class DeadTimeModel(ExtendedModelBase):
    """
    MPI model behind a pure delay: ``s(t) = Gamma[x](t - L)``.

    Parameters
    ----------
    model : MPIModel
        Forward model Gamma.
    dead_time : float
        ``L`` [s], >= 0.
    not_identified : Mapping[str, str]
        Parameters the fit found at a bound of its search range (key -> why); see
        :func:`~mpi_ros.extensions.effect.unidentified_parameters`.

    """

    model: MPIModel
    dead_time: float
    not_identified: Mapping[str, str] = field(default_factory=dict)
    cause = 'dead_time'

    def __post_init__(self) -> None:
        """Validate ``L``."""
        object.__setattr__(self, 'dead_time', scalar_parameter(
            {DEAD_TIME: self.dead_time}, DEAD_TIME))

    @classmethod
    def from_params(cls, mapping: Mapping[str, Any]) -> 'DeadTimeModel':
        """Build from Gamma's keys plus ``model.dead_time``."""
        return cls(MPIModel.from_params(mapping), scalar_parameter(mapping, DEAD_TIME))

    def to_params(self) -> dict[str, Any]:
        """Return the flat parameter form."""
        params: dict[str, Any] = self.model.to_params()
        params[DEAD_TIME] = float(self.dead_time)
        return params

    def input_signal(self, time: npt.ArrayLike, current: npt.ArrayLike) -> FloatArray:
        """Return the current [A] the material sees (this input stage's output)."""
        t, x = check_series(time, current)
        return delay(t, x, self.dead_time)

    def simulate(self, time: npt.ArrayLike, current: npt.ArrayLike) -> FloatArray:
        """Return the displacement [m] for a current [A] sampled at ``time`` [s]."""
        t, x = check_series(time, current)
        return self.model.simulate(self.input_signal(t, x))


def fit_dead_time(time: npt.ArrayLike, current: npt.ArrayLike, displacement: npt.ArrayLike,
                  *, order: Order, epsilon: float = 1e-6) -> DeadTimeModel:
    """
    Identify Gamma and the dead time, chosen on held-out blocks.

    Trial lags: 0 (Gamma alone) and log-spaced from one sample interval to the smaller of 200
    intervals and 5 % of the record, chosen on held-out blocks and kept only when the
    delayed fit is better than Gamma alone on the record
    (:func:`~mpi_ros.extensions.fitting.fit_input_stage`; the samples scored start after
    the raw current's burn-in and the longest trial lag).  A best lag at the longest trial
    is reported as not identified (``not_identified``); one sample is a resolvable delay,
    not a bound (no delay competes below it).

    Parameters
    ----------
    time, current, displacement : array_like of float, shape (N,)
        The record: sample times [s], coil current [A], displacement [m].
    order : (int, int) or 'auto'
        ``(n, l)`` of Gamma; ``'auto'``: found by
        :func:`~mpi_ros.identification.select_order` on the record, then again on the
        delayed current (see :func:`~mpi_ros.extensions.fitting.resolve_order`).
    epsilon : float
        Bound of (8)/(19).

    Returns
    -------
    DeadTimeModel
        The identified model.

    """
    fit = fit_input_stage(time, current, displacement, delay, order=order, epsilon=epsilon,
                          lowest=1.0, settle=1.0)
    unidentified = {DEAD_TIME: fit.not_identified} if fit.not_identified else {}
    return DeadTimeModel(fit.model, fit.value, unidentified)


def _plot(ax: Any, time: FloatArray, current: FloatArray, measured: FloatArray,
          baseline: FloatArray, extended: FloatArray, start: int, *,
          units: AxisUnits | None = None, parameters: Mapping[str, Any] | None = None) -> None:
    # The dead-time model's residual against the delay d: its simulation is Gamma[x](t - L),
    # shifted by d - L it is Gamma[x](t - d).  The fitted L minimises the residual, so the
    # curve's minimum lies at L (the baseline's cross-correlation did not: the MPI loop
    # widens to absorb part of a delay, and its best shift fell short of L).
    units = units or AxisUnits()
    fitted = float((parameters or {}).get(DEAD_TIME, 0.0))
    t = time[start:]
    dt = float(np.median(np.diff(t)))
    longest = max(2.5 * fitted, 20.0 * dt)
    keep = (t >= t[0] + longest) & (t <= t[-1] - fitted)
    if int(keep.sum()) < 3:                  # too short for the window: the whole record
        keep = np.ones(t.size, dtype=bool)
    delays = np.linspace(0.0, longest, 241)
    rms = np.array([np.sqrt(np.mean((measured[start:][keep] - np.interp(
        t[keep] - (d - fitted), time, extended)) ** 2)) for d in delays]) * units.scale
    best = int(np.argmin(rms))
    ax.plot(delays * 1e3, rms, label='dead-time model, simulated with delay d')
    ax.plot(delays[best] * 1e3, rms[best], 'o', ms=3, color='tab:red',
            label=f'minimum at d = {1e3 * delays[best]:.3g} ms')
    ax.axvline(fitted * 1e3, color='0.4', lw=0.8, ls='--',
               label=f'fitted dead time L = {1e3 * fitted:.3g} ms')
    ax.set_xlabel('delay d of the simulated output [ms]')
    ax.set_ylabel(f'RMS residual [{units.displacement}]')
    # The title states what the curve shows, from the same two numbers as the legend.
    step = float(delays[1] - delays[0])
    where = ('at the fitted delay' if abs(delays[best] - fitted) <= step
             else 'not at the fitted delay')
    ax.set_title(f'dead time: fitted L = {1e3 * fitted:.3g} ms; the residual is smallest at'
                 f'\nd = {1e3 * delays[best]:.3g} ms ({where})', fontsize=10)


def _plant_start(values: Mapping[str, Any]) -> dict[str, Any]:
    return {'dead_time': values['dead_time_s'], 'history': delay_state()}


def _plant_run(state: dict[str, Any], chunk: PlantChunk, signal: FloatArray) -> FloatArray:
    return delay_stream(state['history'], chunk.time, signal, state['dead_time'])


#: Dead time in the simulated plant (output side, after the other output steps):
#: ``s_meas(t) = s(t - L)``, linearly interpolated on the sampled stream, 0 before the
#: first sample.
PLANT = PlantEffect(
    stage='output', label='dead time', start=_plant_start, run=_plant_run,
    parameters=(
        PlantParameter('dead_time_s', 0.0, 'dead time of the measurement, 0 = off', 's',
                       low=0.0, note='(0 switches it off)', switch=True),))

#: The dead-time effect, for the registry (:mod:`mpi_ros.extensions.effect`).  It has no
#: ``inverse_step``: a delay cannot be inverted causally.
EFFECT = Effect(
    name='dead_time', formula='Gamma[x](t - L)',
    parameters=(
        EffectParameter(DEAD_TIME, 'double', 0.0,
                        'Dead-time extension: delay L between command and displacement (not'
                        ' invertible: the compensator inverts Gamma only and warns); 0: no'
                        ' delay', 's', (0.0, 1.0e3), plausible_max=FAST_TIME_LIMIT),),
    model_class=DeadTimeModel, fit=fit_dead_time, parameter_count=lambda p: 1,
    signature=lambda residual, level: burst_verdict(residual, level, 'delay'),
    evidence=lambda residual: burst_evidence(residual, 'delay'), plot=_plot, stage='input',
    plant=PLANT, signature_test='burst', dynamics_finding='dead_time',
    separations={'rate_dependence': SEPARATE_LAG_AND_DEAD_TIME},
    caption="Dead time: the dead-time model's residual against the delay; the minimum should"
            ' sit on the fitted value.')
