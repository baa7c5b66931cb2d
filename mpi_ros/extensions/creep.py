# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Creep extension: Kuhnen-style linear creep operators added to the hysteresis operator.

The extended operator is ``s = y0 + sign S[H[x - x0] + sum_j w_Cj C_j[x - x0]]`` (the
operating point ``x0``, ``y0``, ``sign`` is Gamma's) where each creep operator ``C_j`` is a
first-order lag ``tau_j dc_j/dt = x - c_j`` of the input (see
:mod:`mpi_ros.extensions._signals`) and the time constants ``tau_j`` are spaced
logarithmically over the record's time scales.  After a step of the input the lags
settle one after the other, which gives the ``log t``-like creep of the output.

The creep weights enter the generalised error (33) like the play weights,
``E = w_H^T H[x] + w_C^T C[x] - w'_S^T S'[y]``, so ``w_H``, ``w_C`` and ``w'_S`` are
found together in the convex QP (34)-(36) with ``w_C >= 0``.  With the lag states fixed,
the present input enters ``C_j`` with a positive gain ``b_j``, so the step map
``x -> H[x] + sum_j w_Cj b_j x + const`` is a PI operator whose first weight is
``w_H0 + sum_j w_Cj b_j > 0``: (8) holds and the inverse follows from the laws
(12)-(14) at every step (see :class:`mpi_ros.extensions.ExtendedCompensator`).

Parameter keys (besides Gamma's ``model.*`` keys):

- ``model.creep.time_constants``: ``tau_j`` [s], ascending, > 0;
- ``model.creep.weights``: ``w_Cj`` [1] (H-output per input unit, like ``w_H``), >= 0.
"""

from collections.abc import Callable, Mapping
from dataclasses import dataclass
import math
from typing import Any

import numpy as np
import numpy.typing as npt

from ._common import check_series, hold_evidence, residual_axes, vector_parameter
from ._signals import lag_bank, lag_coefficients
from .effect import Effect, EffectParameter, SLOW_TIME_LIMIT
from ..errors import ModelError
from ..identification import identify_weights
from ..model import MPIModel

__all__ = ['CreepModel', 'CreepInverse', 'creep_time_constants', 'fit_creep',
           'CREEP_TIME_CONSTANTS', 'CREEP_WEIGHTS']

FloatArray = npt.NDArray[np.float64]

CREEP_TIME_CONSTANTS = 'model.creep.time_constants'
CREEP_WEIGHTS = 'model.creep.weights'


@dataclass(frozen=True, eq=False)
class CreepModel:
    """
    MPI model with creep operators: ``s = y0 + sign S[H[u] + sum_j w_Cj C_j[u]]``, ``u = x - x0``.

    Parameters
    ----------
    model : MPIModel
        Forward model Gamma = S o H.
    time_constants : ndarray of float, shape (k,)
        ``tau_j`` [s] of the creep lags.
    weights : ndarray of float, shape (k,)
        ``w_Cj >= 0`` [1].

    """

    model: MPIModel
    time_constants: FloatArray
    weights: FloatArray
    cause = 'creep'

    def __post_init__(self) -> None:
        """Validate the creep parameters (ModelError names the key)."""
        params = {CREEP_TIME_CONSTANTS: list(self.time_constants),
                  CREEP_WEIGHTS: list(self.weights)}
        taus = vector_parameter(params, CREEP_TIME_CONSTANTS, strict=True)
        weights = vector_parameter(params, CREEP_WEIGHTS, unit='1')
        if taus.size != weights.size:
            msg = (f'{CREEP_WEIGHTS} must have one weight per time constant: expected'
                   f' {taus.size}, found {weights.size}')
            raise ModelError(msg)
        object.__setattr__(self, 'time_constants', taus)
        object.__setattr__(self, 'weights', weights)

    @classmethod
    def from_params(cls, mapping: Mapping[str, Any]) -> 'CreepModel':
        """
        Build from the parameter form (Gamma's ``model.*`` keys plus ``model.creep.*``).

        Parameters
        ----------
        mapping : Mapping[str, Any]
            Flat parameters.

        Returns
        -------
        CreepModel
            The validated model.

        """
        return cls(MPIModel.from_params(mapping),
                   vector_parameter(mapping, CREEP_TIME_CONSTANTS, strict=True),
                   vector_parameter(mapping, CREEP_WEIGHTS, unit='1'))

    def to_params(self) -> dict[str, Any]:
        """Return the flat parameter form (Gamma's keys plus ``model.creep.*``)."""
        params: dict[str, Any] = self.model.to_params()
        params[CREEP_TIME_CONSTANTS] = [float(v) for v in self.time_constants]
        params[CREEP_WEIGHTS] = [float(v) for v in self.weights]
        return params

    def creep_term(self, time: npt.ArrayLike, current: npt.ArrayLike) -> FloatArray:
        """Return ``sum_j w_Cj C_j[x - x0]`` [A]; the lags start settled at the first sample."""
        t, x = check_series(time, current)
        return lag_bank(t, x - self.model.input_offset, self.time_constants) @ self.weights

    def inverse_step(self) -> 'CreepInverse':
        """Return the exact per-step inverse a :class:`~mpi_ros.compensation.Compensator` uses."""
        return CreepInverse(self)

    def simulate(self, time: npt.ArrayLike, current: npt.ArrayLike) -> FloatArray:
        """
        Simulate the displacement for a current record.

        Parameters
        ----------
        time : array_like of float, shape (N,)
            Sample times [s].
        current : array_like of float, shape (N,)
            Coil current [A].

        Returns
        -------
        ndarray of float, shape (N,)
            Displacement [m].

        """
        t, x = check_series(time, current)
        h, _ = self.model.hysteresis_output(x)
        return self.model.output(h + self.creep_term(t, x))


class CreepInverse:
    """
    Per-step inverse of the creep operators (see :mod:`mpi_ros.compensation`).

    With the lag states fixed, ``c_j,k = p_j + b_j x_k``: the step map is H with the first
    weight ``w_H0 + sum_j w_Cj b_j`` plus a known offset, inverted by (12)-(14).  The lags
    hold absolute currents (a lag of the constant x0 is x0, so ``C[x - x0] = C[x] - x0``).

    Parameters
    ----------
    model : CreepModel
        The extended model.

    """

    def __init__(self, model: CreepModel) -> None:
        self.model = model
        self.state = np.zeros(model.time_constants.size)
        self._b = np.ones(self.state.size)
        self._p = np.zeros(self.state.size)

    def start(self, current: float) -> None:
        """Settle the lags at ``current`` [A]."""
        self.state = np.full(self.model.time_constants.size, float(current))

    def carry(self, other: object) -> bool:
        """Take over the lag states of another creep step with as many lags."""
        if isinstance(other, CreepInverse) and other.state.size == self.state.size:
            self.state = other.state.copy()
            return True
        return False

    def prepare(self, previous: float, interval: float, started: bool) -> None:
        """Fix the lag coefficients for this step (``previous`` command [A], ``interval`` [s])."""
        if started:
            coefficients = [lag_coefficients(interval, tau) for tau in self.model.time_constants]
            a = np.array([c[0] for c in coefficients])
            self._b = np.array([c[1] for c in coefficients])
            self._p = a * self.state + (1.0 - a) * previous - self._b * previous
        else:
            self._b = np.ones(self.state.size)
            self._p = np.zeros(self.state.size)

    def invert(self, v: float, previous: float, started: bool,
               inverse: Callable[[float, float], float]) -> float:
        """Return the current [A] whose step output is ``v`` (``inverse(v, beta)``)."""
        x0 = self.model.model.input_offset
        beta = float(np.dot(self.model.weights, self._b))
        offset = float(np.dot(self.model.weights, self._p - x0 * (1.0 - self._b)))
        return inverse(v - offset, beta)

    def advance(self, current: float, previous: float, started: bool) -> float:
        """Update the lags with the applied ``current`` [A]; return what the material sees."""
        self.state = self._p + self._b * current
        return current


def creep_time_constants(time: npt.ArrayLike, *, per_decade: float = 2.0,
                         maximum_count: int = 10) -> FloatArray:
    """
    Log-spaced creep time constants over a record's time scales.

    From ten sample intervals (at least 0.01 s) to twice the record length (slower creep
    looks like drift within the record), about ``per_decade`` per decade, between 2 and
    ``maximum_count`` of them.

    Parameters
    ----------
    time : array_like of float, shape (N,)
        Sample times [s].
    per_decade : float
        Density of the time constants.
    maximum_count : int
        Upper bound on their number.

    Returns
    -------
    ndarray of float, shape (k,)
        Ascending time constants [s].

    """
    t = np.asarray(time, dtype=np.float64)
    dt = float(np.median(np.diff(t)))
    lo = max(10.0 * dt, 0.01)
    hi = max(2.0 * float(t[-1] - t[0]), 2.0 * lo)
    count = int(min(max(round(per_decade * math.log10(hi / lo)) + 1, 2), maximum_count))
    return np.geomspace(lo, hi, count)


def fit_creep(time: npt.ArrayLike, current: npt.ArrayLike, displacement: npt.ArrayLike, *,
              order: tuple[int, int], time_constants: npt.ArrayLike | None = None,
              epsilon: float = 1e-6) -> CreepModel:
    """
    Identify an MPI model with creep operators jointly in the QP (34)-(36).

    Parameters
    ----------
    time : array_like of float, shape (N,)
        Sample times [s].
    current : array_like of float, shape (N,)
        Coil current [A].
    displacement : array_like of float, shape (N,)
        Displacement [m].
    order : (int, int)
        ``(n, l)`` of Gamma.
    time_constants : array_like of float, optional
        Creep time constants [s]; :func:`creep_time_constants` of ``time`` by default.
    epsilon : float
        Bound of (8)/(19), scaled units.

    Returns
    -------
    CreepModel
        The identified model.

    """
    t, x, y = check_series(time, current, displacement)
    taus = (creep_time_constants(t) if time_constants is None
            else np.asarray(time_constants, dtype=np.float64))
    n, l = order  # noqa: E741
    design, w_h, w_s_inv, w_c, constant, _ = identify_weights(
        x, y, n, l, epsilon=epsilon,
        extra_columns=lambda d: lag_bank(t, d.scaled_input(x), taus))
    # The lags shift with the input like the plays: the constant moves x0 by c / (sum w).
    return CreepModel(design.model(w_h, w_s_inv, constant, shift_weight=float(np.sum(w_c))),
                      taus, w_c)


def _signature(residual: Mapping[str, Any], level: float) -> str:
    holds = residual.get('hold_signature')
    if holds is None:
        return 'unavailable'
    return 'present' if holds['log_p'] < level else 'absent'


def _plot(ax: Any, time: FloatArray, current: FloatArray, measured: FloatArray,
          baseline: FloatArray, extended: FloatArray, start: int) -> None:
    ax2 = ax.twinx()
    ax2.plot(time[start:], current[start:], color='0.7', lw=0.6)
    ax2.set_ylabel('input [A]', color='0.5')
    residual_axes(ax, time, measured, baseline, extended, start, 'creep model')
    ax.set_xlabel('time [s]')
    ax.set_title('creep: residual keeps moving while the input holds')


#: The creep effect, for the registry (:mod:`mpi_ros.extensions.effect`).
EFFECT = Effect(
    name='creep', formula='S[H[x - x0] + sum_j w_Cj C_j[x - x0]]',
    parameters=(
        EffectParameter(CREEP_TIME_CONSTANTS, 'double_array', (),
                        'Creep extension: time constants tau_j of the creep lags, ascending,'
                        ' > 0; empty: no creep', 's', plausible_max=SLOW_TIME_LIMIT),
        EffectParameter(CREEP_WEIGHTS, 'double_array', (),
                        'Creep extension: weights w_Cj >= 0 of the creep lags (H output per'
                        ' input unit, like w_H), one per time constant; empty: no creep')),
    model_class=CreepModel, fit=fit_creep,
    parameter_count=lambda p: len(p[CREEP_WEIGHTS]),
    signature=_signature, evidence=hold_evidence, plot=_plot)
