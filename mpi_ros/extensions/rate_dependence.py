# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Rate-dependence extension: a first-order input lag before the hysteresis operator.

``s = Gamma[x_e]`` with ``tau_e dx_e/dt = x - x_e``: the material sees a lagged current, as
with eddy currents in a magnetostrictive core; loops widen and round off as
``omega tau_e`` grows.  ``tau_e`` is found by a 1-D search (grid, then bounded refinement)
with a full QP identification of Gamma on the lagged current per trial.  The compensator
inverts the lag by a bounded lead filter, the proper inverse ``(1 + s tau_e) / (1 + s tau_e / G)``
(:class:`RateDependenceInverse`, ``G`` = :data:`LEAD_GAIN`).

Parameter key (besides Gamma's ``model.*`` keys, operating point included):
``model.rate_dependence.time_constant`` (``tau_e`` [s], >= 0).
"""

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
import math
from typing import Any

import numpy as np
import numpy.typing as npt

from .effect import Effect, EffectParameter, ExtendedModelBase, FAST_TIME_LIMIT, PlantChunk, \
    PlantEffect, PlantParameter
from .fitting import AxisUnits, burst_evidence, burst_verdict, check_series, \
    fit_input_stage, Order, scalar_parameter
from .plant_steps import lag_state, lag_stream
from ..errors import ModelError
from ..operators.filters import first_order_lag, lag_coefficients
from ..operators.model import MPIModel

__all__ = ['RateDependentModel', 'RateDependenceInverse', 'fit_rate_dependence',
           'LEAD_GAIN', 'RATE_TIME_CONSTANT']

FloatArray = npt.NDArray[np.float64]

RATE_TIME_CONSTANT = 'model.rate_dependence.time_constant'

#: The lead filter's high-frequency gain ``G = tau_e / tau_f`` (:class:`RateDependenceInverse`):
#: the command moves at most this many times as far as the lag-free target does.
LEAD_GAIN = 10.0


@dataclass(frozen=True, eq=False)
class RateDependentModel(ExtendedModelBase):
    """
    MPI model behind a first-order input lag: ``s = Gamma[L_tau[x]]``.

    Parameters
    ----------
    model : MPIModel
        Forward model Gamma.
    time_constant : float
        ``tau_e`` [s] of the input lag (0: no lag).
    not_identified : Mapping[str, str]
        Parameters the fit found at a bound of its search range (key -> why); see
        :func:`~mpi_ros.extensions.effect.unidentified_parameters`.

    """

    model: MPIModel
    time_constant: float
    not_identified: Mapping[str, str] = field(default_factory=dict)
    cause = 'rate_dependence'

    def __post_init__(self) -> None:
        """Validate ``tau_e``."""
        object.__setattr__(self, 'time_constant', scalar_parameter(
            {RATE_TIME_CONSTANT: self.time_constant}, RATE_TIME_CONSTANT))

    @classmethod
    def from_params(cls, mapping: Mapping[str, Any]) -> 'RateDependentModel':
        """Build from Gamma's keys plus ``model.rate_dependence.time_constant``."""
        return cls(MPIModel.from_params(mapping), scalar_parameter(mapping, RATE_TIME_CONSTANT))

    def to_params(self) -> dict[str, Any]:
        """Return the flat parameter form."""
        params: dict[str, Any] = self.model.to_params()
        params[RATE_TIME_CONSTANT] = float(self.time_constant)
        return params

    def inverse_step(self, *, lead_gain: float | None = None) -> 'RateDependenceInverse':
        """
        Return the per-step inverse a :class:`~mpi_ros.compensation.Compensator` uses.

        Parameters
        ----------
        lead_gain : float, optional
            High-frequency gain ``G`` of the lead filter (default :data:`LEAD_GAIN`);
            ``inf``: the exact, unbounded inverse of the lag.

        Returns
        -------
        RateDependenceInverse
            The step.

        """
        return RateDependenceInverse(self, lead_gain=LEAD_GAIN if lead_gain is None
                                     else lead_gain)

    def input_signal(self, time: npt.ArrayLike, current: npt.ArrayLike) -> FloatArray:
        """Return the current [A] the material sees (this input stage's output)."""
        t, x = check_series(time, current)
        return first_order_lag(t, x, self.time_constant)

    def simulate(self, time: npt.ArrayLike, current: npt.ArrayLike) -> FloatArray:
        """Return the displacement [m] for a current [A] sampled at ``time`` [s]."""
        t, x = check_series(time, current)
        return self.model.simulate(self.input_signal(t, x))


class RateDependenceInverse:
    """
    Per-step inverse of the input lag: a bounded lead filter.

    The exact inverse of the lag, ``x = x_e + tau_e dx_e/dt``, differentiates: solved per
    step for the present current it multiplies a change of the target by ``1 / b`` (about
    ``2 tau_e / h``), so a message ``h`` = 0.1 ms after the previous one in a 1 kHz stream
    swung the command by 100 times the target's step, and its first-order-hold form has a
    pole near -1 (the command rings at the Nyquist rate after every disturbance).  This step
    is the proper inverse ``(1 + s tau_e) / (1 + s tau_f)`` with ``tau_f = tau_e / G``
    (``G`` = :data:`LEAD_GAIN`): the target ``u = Gamma^-1[s_c]`` is filtered by the lag
    ``tau_f`` (``g``, first-order hold, exact for any interval), and

    ``x = g + G (u - g)``,

    whose lag ``tau_e`` is ``g`` exactly in continuous time (``tau_e dg/dt + g = G (u - g) +
    g``): the material follows the target ``tau_f`` behind instead of ``tau_e`` behind.

    The bound: ``g`` is a convex combination of the earlier targets (the lag's coefficients
    are positive), so ``|x - u| = (G - 1) |u - g|``, at most ``G - 1`` times how far the
    target moved within the last few ``tau_f``, whatever the intervals: a bunched message
    (``h`` -> 0) leaves ``g`` where it was and moves the command by at most ``G`` times the
    target's own change; a late one (``h`` >> ``tau_f``) settles ``g`` on ``u``, and the
    command on the target.  Bounded by the model: ``G`` is the high-frequency gain of the
    lead, ``tau_e / tau_f``.

    With ``lead_gain = inf`` it is the exact inverse of the lag, solved per step for the
    present current, ``x_k = x_(k-1) + (u_k - a x_e - (1 - a) x_(k-1)) / b`` (unbounded: for
    comparison, and for the round trip ``Gamma^-1[Gamma[x]] = x``).

    Parameters
    ----------
    model : RateDependentModel
        The extended model.
    lead_gain : float
        ``G`` >= 1; ``inf``: the exact inverse.

    """

    def __init__(self, model: RateDependentModel, *, lead_gain: float = LEAD_GAIN) -> None:
        if not lead_gain >= 1.0:
            msg = f'lead_gain must be >= 1 (or inf: the exact inverse); found {lead_gain!r}'
            raise ModelError(msg)
        self.model = model
        self.lead_gain = float(lead_gain)
        self.state = np.zeros(1)          # the lagged current x_e [A] (H's input)
        self._filtered = (0.0, 0.0)       # (u, g) of the last step [A]
        self._pending: tuple[float, float] | None = None
        self._a, self._b = 0.0, 1.0       # the lag tau_e
        self._af, self._bf = 0.0, 1.0     # the lead's filter tau_f

    def start(self, current: float) -> None:
        """Settle the lag and the lead's filter at ``current`` [A]."""
        self.state = np.array([float(current)])
        self._filtered = (float(current), float(current))

    def carry(self, other: object) -> bool:
        """Take over the lagged current and the lead's filter of another rate step."""
        if isinstance(other, RateDependenceInverse):
            self.state = other.state.copy()
            self._filtered = other._filtered
            return True
        return False

    def prepare(self, previous: float, interval: float, started: bool) -> None:
        """Fix the coefficients of the lag and of the lead's filter for this step."""
        tau = self.model.time_constant
        self._pending = None
        if started and tau > 0.0:
            self._a, self._b = lag_coefficients(interval, tau)
            self._af, self._bf = ((1.0, 0.0) if math.isinf(self.lead_gain) else
                                  lag_coefficients(interval, tau / self.lead_gain))
        else:
            self._a, self._b = 0.0, 1.0
            self._af, self._bf = 0.0, 1.0

    def invert(self, v: float, previous: float, started: bool,
               inverse: Callable[[float, float], float]) -> float:
        """Return the current [A] of the bounded lead for the target ``Gamma^-1`` of ``v``."""
        target = inverse(v, 0.0)
        if not started or self.model.time_constant <= 0.0:
            self._pending = (target, target)
            return target
        if math.isinf(self.lead_gain):
            self._pending = (target, target)
            a, b = self._a, self._b
            return previous + (target - a * float(self.state[0]) - (1.0 - a) * previous) / b
        u0, g0 = self._filtered
        g = self._af * g0 + (1.0 - self._af) * u0 + self._bf * (target - u0)
        self._pending = (target, g)
        return g + self.lead_gain * (target - g)

    def advance(self, current: float, previous: float, started: bool) -> float:
        """Update the lag with the applied ``current``; return the lagged current."""
        a, b = self._a, self._b
        material = (a * float(self.state[0]) + (1.0 - a) * previous + b * (current - previous)
                    if started else current)
        self.state[0] = material
        # Not inverted this step (the linear map, for comparison): the filter settles on
        # what the material sees.
        self._filtered = self._pending if self._pending is not None else (material, material)
        self._pending = None
        return material


def fit_rate_dependence(time: npt.ArrayLike, current: npt.ArrayLike,
                        displacement: npt.ArrayLike, *, order: Order,
                        epsilon: float = 1e-6) -> RateDependentModel:
    """
    Identify Gamma and the input-lag time constant, chosen on held-out blocks.

    The trial range is half a sample interval to the smaller of 200 intervals and 5 % of
    the record, log-spaced, and no lag at all competes with every trial; the lag is chosen
    on held-out blocks and kept only when the lagged fit is better than Gamma alone on the
    record (``tau_e = 0`` is Gamma; :func:`~mpi_ros.extensions.fitting.fit_input_stage`;
    the samples scored start after the raw current's burn-in and three of the longest trial
    lags).  A best lag at the longest trial is reported as not identified
    (``not_identified``); half a sample is no bound (no lag competes below it).

    Parameters
    ----------
    time, current, displacement : array_like of float, shape (N,)
        The record: sample times [s], coil current [A], displacement [m].
    order : (int, int) or 'auto'
        ``(n, l)`` of Gamma; ``'auto'``: found by
        :func:`~mpi_ros.identification.select_order` on the record, then again on the
        lagged current (see :func:`~mpi_ros.extensions.fitting.resolve_order`).
    epsilon : float
        Bound of (8)/(19).

    Returns
    -------
    RateDependentModel
        The identified model.

    """
    fit = fit_input_stage(time, current, displacement, first_order_lag, order=order,
                          epsilon=epsilon, lowest=0.5, settle=3.0)
    unidentified = {RATE_TIME_CONSTANT: fit.not_identified} if fit.not_identified else {}
    return RateDependentModel(fit.model, fit.value, unidentified)


def _plot(ax: Any, time: FloatArray, current: FloatArray, measured: FloatArray,
          baseline: FloatArray, extended: FloatArray, start: int, *,
          units: AxisUnits | None = None, parameters: Mapping[str, Any] | None = None) -> None:
    # RMS residual in speed classes (log-spaced, holds left out, classes of >= 20 samples):
    # a lag's error grows with the rate; the fitted lag flattens it.
    units = units or AxisUnits()
    tau = float((parameters or {}).get(RATE_TIME_CONSTANT, float('nan')))
    speed = np.abs(np.gradient(current[start:], time[start:]))
    top = float(np.max(speed))
    edges = np.geomspace(1e-2 * top, top, 13) if top > 0.0 else np.array([0.0, 1.0])
    which = np.digitize(speed, edges[1:-1])
    classes = [np.flatnonzero((which == k) & (speed >= edges[0])) for k in range(edges.size - 1)]
    classes = [c for c in classes if c.size >= 20] or [np.arange(speed.size)]
    centre = [float(np.median(speed[c])) for c in classes]
    for sim, label in ((baseline, 'baseline MPI'), (extended, 'rate model')):
        r = (measured - sim)[start:]
        ax.plot(centre, [units.scale * float(np.sqrt(np.mean(r[c] ** 2))) for c in classes],
                marker='o', ms=3, label=label)
    if top > 0.0 and min(centre) > 0.0:
        ax.set_xscale('log')
    ax.set_xlabel(f'input speed |dx/dt| [{units.current}/s] (classes, holds left out)')
    ax.set_ylabel(f'RMS residual [{units.displacement}]')
    fitted = f' (lag tau = {1e3 * tau:.3g} ms)' if np.isfinite(tau) else ''
    ax.set_title('rate dependence shows as a baseline error that grows with the input'
                 f' speed;\nthe rate model{fitted} should flatten it', fontsize=10)


def _plant_start(values: Mapping[str, Any]) -> dict[str, Any]:
    return {'tau': values['eddy_time_constant_s'], 'lag': lag_state()}


def _plant_run(state: dict[str, Any], chunk: PlantChunk, signal: FloatArray) -> FloatArray:
    lagged: FloatArray = lag_stream(chunk.time, signal, state['tau'], state['lag'])
    return lagged


#: Rate dependence in the simulated plant (input side): eddy currents delay the field in
#: the core, so the material sees ``i_e`` with ``tau_e di_e/dt = i - i_e``; loops widen as
#: ``omega tau_e`` grows.
PLANT = PlantEffect(
    stage='input', label='eddy-current lag', start=_plant_start, run=_plant_run,
    parameters=(
        PlantParameter('eddy_time_constant_s', 0.0,
                       'eddy-current lag time constant, 0 = off', 's', low=0.0,
                       note='(0 switches it off)', switch=True),))

#: The rate-dependence effect, for the registry (:mod:`mpi_ros.extensions.effect`).
EFFECT = Effect(
    name='rate_dependence', formula='Gamma[L_tau_e[x]]',
    parameters=(
        EffectParameter(RATE_TIME_CONSTANT, 'double', 0.0,
                        'Rate-dependence extension: time constant tau_e of the input'
                        ' (eddy-current) lag; 0: no lag', 's', (0.0, 1.0e3),
                        plausible_max=FAST_TIME_LIMIT),),
    model_class=RateDependentModel, fit=fit_rate_dependence,
    parameter_count=lambda p: 1,
    signature=lambda residual, level: burst_verdict(residual, level, 'lag'),
    evidence=lambda residual: burst_evidence(residual, 'lag'), plot=_plot, stage='input',
    plant=PLANT, signature_test='burst', dynamics_finding='lag',
    caption='Rate dependence: RMS residual against the input speed.')
