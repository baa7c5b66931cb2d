# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Recursive identification of the MPI operator: the QP (34)-(36) on forgetting Gram matrices.

The design of a running model is kept (its thresholds (28)-(31), scales and operating
point); the generalised error's Gram matrix of ``[H_rH[u], -S_r'S[v]]`` (34) is accumulated
sample by sample with exponential forgetting, and the QP is solved again under the same
invertibility constraints (8), (19), (36), pulled towards the running weights so that
directions the recent data do not excite keep their values.  A solution is a Gamma with the
same thresholds: the compensator's model swap (wiping-out property) takes it bumplessly.

Exponential forgetting rather than a sliding window: the Gram matrix stays one matrix (no
buffer of past rows to subtract), its memory has one time constant to state, and the old
data fade instead of dropping out at once.

A thermal drift (``h = H[x - x0] + w_T T``, ``tau_T dT/dt = x^2 - T``; the effect of
:mod:`mpi_ros.extensions.thermal_drift`) is one more column of the generalised error, the
thermal state ``T`` computed from the commands by the compensator's own recurrence
(:func:`heating`): its weight ``w_T`` is re-fitted with the others, any sign, and ``T``
follows the commands.  ``tau_T`` stays the model's (a time constant is not a linear
parameter of the QP).
"""

from dataclasses import dataclass
import math

import numba
import numpy as np
import numpy.typing as npt

from .qp import fit_generalized_error, ScaledDesign
from ..errors import ModelError
from ..operators.deadzone import dead_zone_step
from ..operators.inverse import invert_superposition
from ..operators.model import MPIModel
from ..operators.play import play_clamp

__all__ = ['heating', 'RecursiveFit', 'WeightPoint']

FloatArray = npt.NDArray[np.float64]

#: Strength of the pull towards the running weights, relative to the mean diagonal of
#: the covariance Gram matrix: small against an excited direction, decisive for one the
#: recent data leave flat.
PRIOR_STRENGTH = 1e-3

#: Weight of the running model's own covariance over its whole range against the recent
#: data's (:meth:`RecursiveFit.remember`).
MEMORY_WEIGHT = 1.0


@dataclass(frozen=True)
class WeightPoint:
    """
    One model of the recursive fit's design: weights, constant term and output shift.

    Attributes
    ----------
    weights : ndarray of float, shape (n+1+m,) or (n+2+m,)
        ``[w_H; w'_S]`` in the design's scaled units, satisfying (8), (19), (36); with a
        thermal column, its weight last (any sign).
    constant : float
        Constant term of the generalised error (an input offset, scaled units).
    output_shift : float
        Added to the design's output offset ``y0`` [m].

    """

    weights: FloatArray
    constant: float = 0.0
    output_shift: float = 0.0

    def toward(self, other: 'WeightPoint', fraction: float) -> 'WeightPoint':
        """
        Return the point ``fraction`` of the way to ``other``.

        The constraints (8), (19) and (36) are linear, so every point between two models
        that satisfy them satisfies them too.
        """
        a = float(fraction)
        return WeightPoint(self.weights + a * (other.weights - self.weights),
                           self.constant + a * (other.constant - self.constant),
                           self.output_shift + a * (other.output_shift - self.output_shift))


class RecursiveFit:
    """
    Forgetting Gram matrices of the generalised error (34) in the design of a model.

    Parameters
    ----------
    model : MPIModel
        The running forward model Gamma (n >= 1): its thresholds, scales and operating
        point fix the design; its weights are the starting point.
    forgetting : float
        Per-sample forgetting factor ``lambda`` in (0, 1]: the Gram matrix is
        ``sum_k lambda^(K-k) phi_k phi_k^T`` (memory ``1 / (1 - lambda)`` samples).
    offset_forgetting : float, optional
        A shorter memory for the regressors' means, which set the constant term (the
        operating point drifts faster than the shape changes); ``forgetting`` by default.
    thermal_time_constant : float, optional
        ``tau_T`` [s] of a thermal drift the model has (None: none): adds the thermal
        state's column.
    thermal_weight : float
        The model's ``w_T`` [1/A] (the starting point's thermal weight).
    sample_period : float
        Interval between samples [s], for the thermal state's recurrence.

    Raises
    ------
    ModelError
        For an inverse model, n = 0, a forgetting factor outside (0, 1], or a thermal
        time constant or sample period that is not finite and > 0.

    """

    def __init__(self, model: MPIModel, *, forgetting: float,
                 offset_forgetting: float | None = None,
                 thermal_time_constant: float | None = None, thermal_weight: float = 0.0,
                 sample_period: float = 1e-3) -> None:
        if model.is_inverse or model.n < 1:
            msg = ('the recursive fit needs a forward model Gamma with n >= 1 plays;'
                   f' found {"an inverse" if model.is_inverse else "n = 0"}')
            raise ModelError(msg)
        offset_forgetting = forgetting if offset_forgetting is None else offset_forgetting
        if not (0.0 < forgetting <= 1.0 and 0.0 < offset_forgetting <= 1.0):
            msg = f'forgetting must lie in (0, 1]; found {forgetting!r}'
            raise ModelError(msg)
        if thermal_time_constant is not None and not (
                math.isfinite(thermal_time_constant) and thermal_time_constant > 0.0
                and math.isfinite(sample_period) and sample_period > 0.0):
            msg = ('the thermal time constant and the sample period must be finite and > 0;'
                   f' found {thermal_time_constant!r} and {sample_period!r}')
            raise ModelError(msg)
        h = model.hysteresis
        n = model.n
        # (28): r_Hi = i/(n+1) ||x||_inf, so the design's input scale is (n+1) r_H1.
        x_scale = float(h.thresholds[1]) * (n + 1)
        s_inv = invert_superposition(model.superposition)
        y_scale = x_scale * float(np.mean(model.superposition.slopes))
        self.design = ScaledDesign(
            x_scale, y_scale, h.thresholds / x_scale, s_inv.thresholds / y_scale,
            s_inv.center, input_offset=model.input_offset,
            output_offset=model.output_offset, sign=model.output_sign, constant=True)
        self.forgetting = float(forgetting)
        self.offset_forgetting = float(offset_forgetting)
        w_h = np.asarray(h.weights, dtype=np.float64)
        w_s = np.asarray(s_inv.weights, dtype=np.float64) * (y_scale / x_scale)
        # (36) is a normalisation: H and S' scaled alike give the same Gamma.
        norm = float(np.dot(1.0 - self.design.hysteresis_thresholds, w_h))
        #: Lag coefficient ``a = exp(-h / tau_T)`` of the thermal state (None: no drift).
        self.heating_coefficient = (None if thermal_time_constant is None
                                    else math.exp(-sample_period / thermal_time_constant))
        # The thermal column is T / x_scale^2 (as the batch fit's), so w_T x_scale scaled.
        extra = ([] if thermal_time_constant is None else [thermal_weight * x_scale])
        self.start = WeightPoint(np.concatenate([w_h, w_s, extra]) / norm)
        nv = self.start.weights.size
        self._extras = len(extra)
        self._heat = np.full(2, math.nan)     # T and x of the last sample (scaled)
        self._gram = np.zeros((nv, nv))
        self._sums = np.zeros(nv)
        self._count = np.zeros(1)
        self._fast_sums = np.zeros(nv)
        self._fast_count = np.zeros(1)
        self._plays = np.zeros(n + 1)
        self._started = False
        self._memory = np.zeros((nv, nv))
        self.remember(self.start)

    def remember(self, point: WeightPoint) -> None:
        """
        Let ``point``'s model stand for the whole identified range in later solves.

        The model is driven over nested reversals across its whole input range (every
        play wiped out, every dead zone of S' reached) and its own output is taken as
        data: the covariance of those regressors is what the running model knows of the
        range.  :meth:`solve` adds it, weighted by ``memory``, to the recent data's, so a
        candidate changes where the recent data say so and keeps the model elsewhere.
        The generalised error of ``point`` on these data is 0, so the memory only resists
        a change, never moves the solution by itself.

        Parameters
        ----------
        point : WeightPoint
            The running model's point.

        """
        d = self.design
        levels = np.linspace(1.0, 0.1, 10)
        knots = np.ravel(np.column_stack([-levels, levels]))
        u = np.concatenate([np.linspace(a, b, 100, endpoint=False)
                            for a, b in zip(np.concatenate([[0.0], knots[:-1]]), knots)])
        x = d.input_offset + d.x_scale * u
        model = self.model(point)
        y = model.run(x, np.full(model.n + 1, -d.x_scale - model.input_offset))[0]
        nv = self._gram.shape[0]
        gram, sums, count = np.zeros((nv, nv)), np.zeros(nv), np.zeros(1)
        plays = np.full(d.hysteresis_thresholds.size, -1.0)
        # Gamma's own output, without drift: the thermal column is 0 here, so the memory
        # keeps Gamma's shape and leaves w_T to the recent data.
        _accumulate(d.scaled_input(x), d.scaled_output(y), np.ones(x.size, dtype=np.bool_),
                    np.zeros((x.size, self._extras)), d.hysteresis_thresholds,
                    d.inverse_superposition_thresholds, plays, 1.0,
                    gram, sums, count, 1.0, np.zeros(nv), np.zeros(1))
        mean = sums / count[0]
        self._memory = gram / count[0] - np.outer(mean, mean)

    @property
    def samples(self) -> float:
        """Return the forgotten count of samples in the Gram matrix (its memory)."""
        return float(self._count[0])

    def advance(self, current: npt.ArrayLike, displacement: npt.ArrayLike, *,
                use: npt.ArrayLike | None = None) -> None:
        """
        Run the plays over paired samples and add the used ones to the Gram matrix.

        Parameters
        ----------
        current : array_like of float, shape (K,)
            Commanded input [A].
        displacement : array_like of float, shape (K,)
            Measured output paired with each command [m].
        use : array_like of bool, shape (K,), optional
            Samples that enter the Gram matrix (default all); the others only advance
            the plays (e.g. garbage readings, or samples before the plays are determined).

        """
        x = np.ascontiguousarray(current, dtype=np.float64).reshape(-1)
        y = np.ascontiguousarray(displacement, dtype=np.float64).reshape(-1)
        mask = (np.ones(x.size, dtype=np.bool_) if use is None
                else np.ascontiguousarray(use, dtype=np.bool_).reshape(-1))
        d = self.design
        u = d.scaled_input(x)
        v = d.scaled_output(y)
        if not self._started and u.size:
            self._plays[:] = u[0]           # at rest at the first input: wiped out later
            self._started = True
        extra = np.zeros((x.size, self._extras))
        if self.heating_coefficient is not None and x.size:
            extra[:, 0], self._heat = heating(x / d.x_scale,
                                              coefficient=self.heating_coefficient,
                                              state=self._heat)
        _accumulate(u, v, mask, extra, d.hysteresis_thresholds,
                    d.inverse_superposition_thresholds,
                    self._plays, self.forgetting, self._gram, self._sums, self._count,
                    self.offset_forgetting, self._fast_sums, self._fast_count)

    def solve(self, prior: WeightPoint, *, strength: float = PRIOR_STRENGTH,
              memory: float = MEMORY_WEIGHT, hysteresis: bool = False) -> WeightPoint:
        """
        Solve the QP (34)-(36) on the current Gram matrix, pulled towards ``prior``.

        Minimises ``v^T C v + rho |v - v_prior|^2`` with ``C`` the covariance of the
        regressors (the constant term eliminated, as in the batch identification) and
        ``rho = strength * mean(diag C)``, under (8), (19) and (36).  With
        ``hysteresis=False`` the weights of H stay the prior's: H[u] is one known
        regressor, and only S' (the output map: gain, shape) and the constant (the
        operating point) are fitted, which closed-loop data inside the range determine
        far better than the weights of plays they never wipe out.

        Parameters
        ----------
        prior : WeightPoint
            The running model's point (also the QP's warm start).
        strength : float
            Relative strength of the pull.
        memory : float
            Weight of the remembered model's covariance (:meth:`remember`) against the
            recent data's, each normalised to a unit mean diagonal.
        hysteresis : bool
            Fit the weights of H too.

        Returns
        -------
        WeightPoint
            The new weights and constant term (output shift 0).

        Raises
        ------
        mpi_ros.errors.IdentificationError
            When the QP is not solved or its result violates a constraint.

        """
        count = max(self.samples, 1.0)
        mean = self._sums / count
        cov = self._gram / count - np.outer(mean, mean)
        scale = max(float(np.mean(np.diag(cov))), 1e-300)
        cov = cov / scale + memory * self._memory / max(
            float(np.mean(np.diag(self._memory))), 1e-300)
        d = self.design
        n1 = d.hysteresis_thresholds.size
        nv = cov.shape[0]
        k = self._extras
        m = nv - n1 - k
        if hysteresis:
            reduce = np.eye(nv)
            equality = 1.0 - d.hysteresis_thresholds
            start = prior.weights
        else:
            # [H[u]; -S'[v]; T] = R^T [plays; -S'[v]; T] with R = [w_H 0; 0 I]; (36) fixes
            # the one H weight at 1.
            reduce = np.zeros((nv, nv - n1 + 1))
            reduce[:n1, 0] = prior.weights[:n1]
            reduce[n1:, 1:] = np.eye(nv - n1)
            equality = np.ones(1)
            start = np.concatenate([[1.0], prior.weights[n1:]])
        cov = reduce.T @ cov @ reduce
        # The forgotten sums lose the covariance's positive semidefiniteness to round-off
        # when a column's mean dwarfs its spread: clip the eigenvalues at 0.
        values, vectors = np.linalg.eigh(0.5 * (cov + cov.T))
        cov = (vectors * np.maximum(values, 0.0)) @ vectors.T
        # Normalised to a unit mean diagonal: OSQP's infeasibility tests are absolute.
        cov /= max(float(np.mean(np.diag(cov))), 1e-300)
        rho = strength
        cov[np.diag_indices(cov.shape[0])] += rho
        # OSQP minimises 1/2 v^T P v + q^T v: with P = C + rho I, q = -rho v_prior is the
        # pull v^T C v + rho |v - v_prior|^2 (up to a factor 2 and a constant).
        w_h, w_s, w_x, _ = fit_generalized_error(
            cov, equality, n_hysteresis=equality.size, n_superposition=m,
            superposition_center=d.center, extra_lower=np.full(k, -np.inf),
            linear=-rho * start, warm_start=start)
        weights = (np.concatenate([w_h, w_s, w_x]) if hysteresis
                   else np.concatenate([prior.weights[:n1] * w_h[0], w_s, w_x]))
        recent = self._fast_sums / max(float(self._fast_count[0]), 1.0)
        return WeightPoint(weights, -float(recent @ weights))

    def model(self, point: WeightPoint) -> MPIModel:
        """
        Return Gamma in SI units for a point of this design.

        Parameters
        ----------
        point : WeightPoint
            Weights, constant and output shift.

        Returns
        -------
        MPIModel
            The model, its plays starting at 0 (a compensator carries its own memory over).

        """
        d = self.design
        n1 = d.hysteresis_thresholds.size
        m = point.weights.size - n1 - self._extras
        gamma = d.model(point.weights[:n1], point.weights[n1:n1 + m], point.constant)
        return gamma.with_operating_point(output_offset=d.output_offset + point.output_shift)

    def thermal_weight(self, point: WeightPoint) -> float:
        """
        Return ``w_T`` [1/A] of a point, for the Gamma :meth:`model` gives (0 without drift).

        Parameters
        ----------
        point : WeightPoint
            A point of this design.

        Returns
        -------
        float
            The weight of the thermal state ``T`` [A^2] in H's output [A].

        """
        if not self._extras:
            return 0.0
        return float(point.weights[-1]) / self.design.x_scale


def heating(current: npt.ArrayLike, *, coefficient: float,
            state: npt.ArrayLike) -> tuple[FloatArray, FloatArray]:
    """
    Return the thermal state ``T`` of a thermal drift over a chunk of currents, and the state.

    The compensator's recurrence (:class:`~mpi_ros.extensions.thermal_drift.ThermalDriftInverse`):
    ``T_k = a T_(k-1) + (1 - a) x_(k-1)^2``; at the first sample of all (a NaN state) ``T``
    starts in steady state, ``x_0^2``.

    Parameters
    ----------
    current : array_like of float, shape (K,)
        Current ``x`` (any unit; ``T`` comes out in its square).
    coefficient : float
        ``a = exp(-h / tau_T)`` for the sample interval ``h``.
    state : array_like of float, shape (2,)
        ``T`` and ``x`` of the sample before the chunk (NaN: none).

    Returns
    -------
    thermal_state : ndarray of float, shape (K,)
        ``T`` at each sample.
    state_end : ndarray of float, shape (2,)
        ``T`` and ``x`` of the last sample: pass it to continue in chunks.

    """
    x = np.ascontiguousarray(current, dtype=np.float64).reshape(-1)
    start = np.array(state, dtype=np.float64).reshape(2)
    if not x.size:
        return np.empty(0), start
    if not np.isfinite(start[0]):
        start = np.array([x[0] * x[0], x[0]])
    t = np.empty(x.size)
    _heat(x, float(coefficient), float(start[0]), float(start[1]), t)
    return t, np.array([t[-1], x[-1]])


@numba.njit(cache=True, nogil=True)
def _heat(x: FloatArray, a: float, t0: float, x0: float,
          out: FloatArray) -> None:  # pragma: no cover - compiled
    previous_t, previous_x = t0, x0
    for k in range(x.shape[0]):
        previous_t = a * previous_t + (1.0 - a) * previous_x * previous_x
        out[k] = previous_t
        previous_x = x[k]


@numba.njit(cache=True, nogil=True)
def _accumulate(u: FloatArray, v: FloatArray, use: npt.NDArray[np.bool_], extra: FloatArray,
                r_h: FloatArray, r_s: FloatArray, z: FloatArray, forgetting: float,
                gram: FloatArray, sums: FloatArray, count: FloatArray, fast_forgetting: float,
                fast_sums: FloatArray, fast_count: FloatArray) -> None:  # pragma: no cover
    # G <- lambda G + phi phi^T with phi = [plays (4), -dead zones (17), extras] per used
    # sample; the column sums twice: with lambda (the Gram matrix's) and with the
    # operating point's shorter memory.
    nh = r_h.shape[0]
    ns = r_s.shape[0]
    ne = extra.shape[1]
    nv = nh + ns + ne
    phi = np.empty(nv)
    dz = np.empty(ns)
    for k in range(u.shape[0]):
        x = u[k]
        for i in range(nh):
            z[i] = play_clamp(x, r_h[i], z[i])
        if not use[k]:
            continue
        for i in range(nh):
            phi[i] = z[i]
        dead_zone_step(v[k], r_s, dz)
        for j in range(ns):
            phi[nh + j] = -dz[j]
        for j in range(ne):
            phi[nh + ns + j] = extra[k, j]
        for a in range(nv):
            pa = phi[a]
            sums[a] = forgetting * sums[a] + pa
            fast_sums[a] = fast_forgetting * fast_sums[a] + pa
            for b in range(nv):
                gram[a, b] = forgetting * gram[a, b] + pa * phi[b]
        count[0] = forgetting * count[0] + 1.0
        fast_count[0] = fast_forgetting * fast_count[0] + 1.0
