# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Thermal-drift extension: a drift driven by a thermal state that integrates I^2.

``s = y0 + sign S[H[x - x0] + w_T T]`` with ``tau_T dT/dt = x^2 - T`` (Joule heating of the
coil, from the absolute current, not the one relative to the operating point ``x0``; ``T``
in A^2 starts in steady state at the first sample, ``x(t_0)^2``).  The drift enters before the
superposition operator S, in H's output unit (A), so that ``w_H``, ``w'_S`` and ``w_T``
(any sign) are found together in one convex QP (34)-(36) for each trial ``tau_T``: ``T``
is one more column of the generalised error (33).  Near an operating point the output
drift is ``k_T T`` with ``k_T = w_T dS/dv`` [m/A^2] (why not an output-additive drift:
docs/diagnosis.md, "Design choices of the effect models").  ``tau_T`` is found by a 1-D search
over slow time constants (a twentieth of the record to five records).  With the thermal
state fixed, the step map is Gamma shifted inside, so (8)/(19) and the inverse still hold.

Parameter keys (besides Gamma's ``model.*`` keys): ``model.thermal_drift.time_constant``
(``tau_T`` [s], > 0) and ``model.thermal_drift.weight`` (``w_T`` [1/A], any sign).
"""

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field, replace
import math
from typing import Any

import numpy as np
import numpy.typing as npt

from .effect import Effect, EffectParameter, ExtendedModelBase, PlantChunk, PlantEffect, \
    PlantParameter, SLOW_TIME_LIMIT
from .fitting import AxisUnits, bound_note, check_series, choose_out_of_sample, \
    fixed_held_out_error, fold_simulations, held_out_error, hold_evidence, Order, residual_axes, \
    resolve_order, scalar_parameter, with_record_start
from .plant_steps import lag_add, lag_state
from ..identification import identify_weights
from ..identification.folds import blocked_folds
from ..operators.filters import first_order_lag, lag_coefficients
from ..operators.model import MPIModel

__all__ = ['ThermalDriftModel', 'ThermalDriftInverse', 'fit_thermal_drift',
           'THERMAL_TIME_CONSTANT', 'THERMAL_WEIGHT']

FloatArray = npt.NDArray[np.float64]

THERMAL_TIME_CONSTANT = 'model.thermal_drift.time_constant'
THERMAL_WEIGHT = 'model.thermal_drift.weight'


@dataclass(frozen=True, eq=False)
class ThermalDriftModel(ExtendedModelBase):
    """
    MPI model with a thermal drift: ``s = y0 + sign S[H[x - x0] + w_T L_tau_T[x^2]]``.

    Parameters
    ----------
    model : MPIModel
        Forward model Gamma.
    time_constant : float
        ``tau_T`` [s], > 0.
    weight : float
        ``w_T`` [1/A] (H output per unit thermal state; 0 gives Gamma exactly).
    not_identified : Mapping[str, str]
        Parameters the fit found at a bound of its search range, or without meaning (the
        time constant of a zero weight): key -> why; see
        :func:`~mpi_ros.extensions.effect.unidentified_parameters`.

    """

    model: MPIModel
    time_constant: float
    weight: float
    not_identified: Mapping[str, str] = field(default_factory=dict)
    cause = 'thermal_drift'

    def __post_init__(self) -> None:
        """Validate the drift parameters."""
        object.__setattr__(self, 'time_constant', scalar_parameter(
            {THERMAL_TIME_CONSTANT: self.time_constant}, THERMAL_TIME_CONSTANT, strict=True))
        object.__setattr__(self, 'weight', scalar_parameter(
            {THERMAL_WEIGHT: self.weight}, THERMAL_WEIGHT, minimum=-math.inf, unit='1/A'))

    @classmethod
    def from_params(cls, mapping: Mapping[str, Any]) -> 'ThermalDriftModel':
        """Build from Gamma's keys plus ``model.thermal_drift.*``."""
        return cls(MPIModel.from_params(mapping),
                   scalar_parameter(mapping, THERMAL_TIME_CONSTANT, strict=True),
                   scalar_parameter(mapping, THERMAL_WEIGHT, minimum=-math.inf, unit='1/A'))

    def to_params(self) -> dict[str, Any]:
        """Return the flat parameter form."""
        params: dict[str, Any] = self.model.to_params()
        params[THERMAL_TIME_CONSTANT] = float(self.time_constant)
        params[THERMAL_WEIGHT] = float(self.weight)
        return params

    def thermal_state(self, time: npt.ArrayLike, current: npt.ArrayLike) -> FloatArray:
        """Return the thermal state ``T`` [A^2] for a current record."""
        t, x = check_series(time, current)
        return first_order_lag(t, x * x, self.time_constant)

    def inverse_step(self) -> 'ThermalDriftInverse':
        """Return the exact per-step inverse a :class:`~mpi_ros.compensation.Compensator` uses."""
        return ThermalDriftInverse(self)

    def simulate(self, time: npt.ArrayLike, current: npt.ArrayLike) -> FloatArray:
        """Return the displacement [m] for a current [A] sampled at ``time`` [s]."""
        t, x = check_series(time, current)
        if self.weight == 0.0:              # no drift: Gamma exactly (the nested baseline)
            return self.model.simulate(x)
        h, _ = self.model.hysteresis_output(x)
        return self.model.output(h + self.weight * self.thermal_state(t, x))


class ThermalDriftInverse:
    """
    Per-step inverse of the thermal drift: the predicted thermal term is subtracted.

    ``T_k = a T_(k-1) + (1 - a) x_(k-1)^2`` (the first-order-hold term, ``~ h / tau_T``, is
    dropped), then H' by (12)-(14).  The first sample, where the state starts at ``x_0^2``,
    takes a few fixed-point sweeps.  The heating follows the absolute current.

    Parameters
    ----------
    model : ThermalDriftModel
        The extended model.

    """

    def __init__(self, model: ThermalDriftModel) -> None:
        self.model = model
        self.state = np.zeros(1)          # the thermal state T [A^2]
        self._thermal: float | None = None

    def start(self, current: float) -> None:
        """Settle the thermal state at ``current`` [A]."""
        self.state = np.array([float(current) ** 2])

    def carry(self, other: object) -> bool:
        """Take over the thermal state of another thermal-drift step."""
        if isinstance(other, ThermalDriftInverse):
            self.state = other.state.copy()
            return True
        return False

    def prepare(self, previous: float, interval: float, started: bool) -> None:
        """Predict the thermal state of this step."""
        if started:
            a, _ = lag_coefficients(interval, self.model.time_constant)
            self._thermal = a * float(self.state[0]) + (1.0 - a) * previous ** 2
        else:
            self._thermal = None

    def invert(self, v: float, previous: float, started: bool,
               inverse: Callable[[float, float], float]) -> float:
        """Return the current [A] whose output, drift included, is ``v``."""
        weight = self.model.weight
        if self._thermal is not None:
            return inverse(v - weight * self._thermal, 0.0)
        # First sample: the state starts at x_0^2 (steady state); a few fixed-point sweeps
        # x <- H'[v - w_T x^2] (a contraction for the small w_T a drift has) settle it.
        raw = previous
        for _ in range(8):
            raw = inverse(v - weight * raw * raw, 0.0)
        return raw

    def advance(self, current: float, previous: float, started: bool) -> float:
        """Store the thermal state; the material sees the applied ``current``."""
        self.state[0] = self._thermal if self._thermal is not None else current ** 2
        return current


def _fit_at(t: FloatArray, x: FloatArray, y: FloatArray, n: int, l: int,  # noqa: E741
            tau: float | None, epsilon: float,
            rows: npt.NDArray[np.bool_] | None = None) -> tuple[ThermalDriftModel, float, int]:
    # One joint QP at a trial tau (None: no thermal column, Gamma alone with w_T = 0) on
    # ``rows`` (default every sample after the burn-in); the MSE after the burn-in, and the
    # burn-in.  The
    # heating follows the absolute current (I^2), not the offset one.
    if tau is None:
        design, w_h, w_s_inv, _, constant, _ = identify_weights(x, y, n, l, epsilon=epsilon,
                                                                rows=rows)
        model = ThermalDriftModel(design.model(w_h, w_s_inv, constant), float(t[-1] - t[0]),
                                  0.0)
    else:
        design, w_h, w_s_inv, w_t, constant, _ = identify_weights(
            x, y, n, l, epsilon=epsilon,
            extra_columns=lambda d: first_order_lag(t, (x / d.x_scale) ** 2, tau)[:, None],
            extra_lower=np.array([-np.inf]), rows=rows)
        model = ThermalDriftModel(design.model(w_h, w_s_inv, constant), tau,
                                  float(w_t[0]) / design.x_scale)
    # Scored like the fit, after the burn-in (the same samples for every trial: the
    # design depends on the current and the displacement only).
    keep = slice(design.burn_in, None)
    error = float(np.mean((model.simulate(t, x)[keep] - y[keep]) ** 2))
    return model, error, design.burn_in


def fit_thermal_drift(time: npt.ArrayLike, current: npt.ArrayLike,
                      displacement: npt.ArrayLike, *, order: Order,
                      epsilon: float = 1e-6) -> ThermalDriftModel:
    """
    Identify Gamma, ``tau_T`` and ``w_T``: ``tau_T`` chosen on held-out blocks.

    Trials: ``tau_T`` log-spaced from a twentieth of the record to five records (one joint
    QP per trial and fold), and no drift at all (``w_T = 0``: Gamma exactly).  Each is judged
    out of sample, on contiguous blocks of the record each predicted by the fit on the
    others (:func:`~mpi_ros.identification.folds.blocked_folds`): on the fitted samples a
    free ``tau_T`` trades against Gamma's weights and wins on a drift it does not predict
    (on unseen plants it chose 9.3 s for a drift over 20-50 s and lost 6 % against the
    baseline on validation).  The chosen ``tau_T`` is fitted on the whole record and kept
    only when it fits the record better than no drift.  A best ``tau_T`` at either end of
    the range is reported as not identified (``not_identified``), as is the time constant
    of a zero weight.

    Parameters
    ----------
    time, current, displacement : array_like of float, shape (N,)
        The record: sample times [s], coil current [A], displacement [m].
    order : (int, int) or 'auto'
        ``(n, l)`` of Gamma; ``'auto'``: found by
        :func:`~mpi_ros.identification.select_order` on the record (the drift enters
        inside S, so there is no drift-free signal to select it on again).
    epsilon : float
        Bound of (8)/(19).

    Returns
    -------
    ThermalDriftModel
        The identified model (the trial with the smallest output error).

    """
    t, x, y = check_series(time, current, displacement)
    (n, l), _ = resolve_order(x, y, order)  # noqa: E741
    duration = float(t[-1] - t[0])
    off, off_error, start = _fit_at(t, x, y, n, l, None, epsilon)
    scored = np.arange(t.size) >= start
    folds = blocked_folds(t.size, start=start)

    def fold_fit(tau: float | None, held: npt.NDArray[np.bool_]) -> FloatArray:
        return _fit_at(t, x, y, n, l, tau, epsilon, rows=~held)[0].simulate(t, x)
    baseline = fold_simulations(lambda held: fold_fit(None, held), folds)
    choice = choose_out_of_sample(
        lambda tau: held_out_error(lambda held: fold_fit(tau, held), y, folds, scored,
                                   nested=baseline),
        np.geomspace(duration / 20.0, 5.0 * duration, 7), refine=2,
        off_error=fixed_held_out_error(baseline, y, folds, scored))
    unknown = {THERMAL_TIME_CONSTANT: 'not identified: no drift (weight 0), no time constant'}
    if choice.value is not None:
        model, error, _ = _fit_at(t, x, y, n, l, choice.value, epsilon)
        if error < off_error:
            started: ThermalDriftModel = with_record_start(model, t, x, y)
            if choice.bound:
                return replace(started,
                               not_identified={THERMAL_TIME_CONSTANT: bound_note(choice)})
            return started
    rest: ThermalDriftModel = with_record_start(off, t, x, y)
    return replace(rest, not_identified=unknown)


def _signature(residual: Mapping[str, Any], level: float) -> str:
    holds = residual.get('hold_signature')
    if holds is None:
        return 'unavailable'
    drift = holds['drift_p'] < level and not holds['log_p'] < level
    return 'present' if drift else 'absent'


def _evidence(residual: Mapping[str, Any]) -> str | None:
    detail = hold_evidence(residual)
    if detail is None:
        return None
    return detail + ': a smooth drift without the log(t) shape of creep'


def _plot(ax: Any, time: FloatArray, current: FloatArray, measured: FloatArray,
          baseline: FloatArray, extended: FloatArray, start: int, *,
          units: AxisUnits | None = None, parameters: Mapping[str, Any] | None = None) -> None:
    # The abscissa is the thermal state of the fit: x^2 through its lag tau_T (record / 3
    # when no fitted value is given).
    units = units or AxisUnits()
    tau = float((parameters or {}).get(THERMAL_TIME_CONSTANT, 0.0))
    which = f'tau_T = {tau:.3g} s, fitted' if tau > 0.0 else 'tau_T = record / 3'
    if not tau > 0.0:
        tau = float(time[-1] - time[0]) / 3.0
    power = first_order_lag(time, current * current, tau)[start:]
    residual_axes(ax, time, measured, baseline, extended, start, 'thermal model',
                  against=power, units=units)
    ax.set_xlabel(f'lagged input power x^2 [{units.current}^2] ({which})')
    ax.set_title('thermal drift shows as a baseline residual that follows the lagged power;'
                 "\nthe thermal model's should not", fontsize=10)


def _plant_start(values: Mapping[str, Any]) -> dict[str, Any]:
    return {'gain': values['thermal_gain_m_per_a2'], 'tau': values['thermal_time_constant_s'],
            'lag': lag_state()}


def _plant_run(state: dict[str, Any], chunk: PlantChunk, signal: FloatArray) -> FloatArray:
    result: FloatArray = lag_add(chunk.time, chunk.current * chunk.current, state['tau'],
                                 state['gain'], state['lag'], signal)
    return result


#: Thermal drift in the simulated plant (output side): Joule heating of the coil,
#: ``tau_T dT/dt = i^2 - T`` (``T`` in A^2, steady state the mean of ``i^2``), expands the
#: rod by ``k_T T``.
PLANT = PlantEffect(
    stage='output', label='thermal drift', start=_plant_start, run=_plant_run,
    parameters=(
        PlantParameter('thermal_gain_m_per_a2', 0.0,
                       'thermal drift per unit state, 0 = off', 'm/A^2', switch=True),
        PlantParameter('thermal_time_constant_s', 30.0, 'thermal time constant', 's',
                       low=0.0, low_open=True)))

#: The thermal-drift effect, for the registry (:mod:`mpi_ros.extensions.effect`).
EFFECT = Effect(
    name='thermal_drift', formula='S[H[x - x0] + w_T L_tau_T[x^2]]',
    parameters=(
        EffectParameter(THERMAL_TIME_CONSTANT, 'double', 0.0,
                        'Thermal-drift extension: time constant tau_T of the thermal state'
                        ' (I^2 lag), > 0; 0 together with a 0 weight: no drift', 's',
                        (0.0, 1.0e6), plausible_max=SLOW_TIME_LIMIT),
        EffectParameter(THERMAL_WEIGHT, 'double', 0.0,
                        'Thermal-drift extension: weight w_T of the thermal state (H output'
                        ' per A^2, any sign); 0: no drift', '1/A', (-1.0e6, 1.0e6))),
    model_class=ThermalDriftModel, fit=fit_thermal_drift,
    parameter_count=lambda p: 2, signature=_signature, evidence=_evidence, plot=_plot,
    plant=PLANT, signature_test='hold',
    caption='Thermal drift: residual against the lagged input power.',
    separations={'creep': 'holds after steps up and down: creep follows log t in the'
                          ' direction of the step, thermal drift follows the input power'
                          ' whatever the step'})
