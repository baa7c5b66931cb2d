# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Modified Prandtl-Ishlinskii operator Gamma = S o H (26) and its inverse (27).

``Gamma[x] = w_S^T S_rS[ w_H^T H_rH[x, z_H0] ]`` (26): a Prandtl-Ishlinskii
hysteresis operator H followed by a Prandtl-Ishlinskii superposition
operator S.  The inverse, obtained analytically by the laws in
:mod:`mpi_ros.inverse`, is ``Gamma^-1 = H' o S'`` (27): the same two kinds of
operator in the opposite order.  :class:`MPIModel` represents both; the flag
``is_inverse`` says which order applies.

Units: the forward model maps current (A) to displacement (m), H maps A to
A (its weights are dimensionless), S maps A to m.  The inverse maps m to A.
"""

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numba
import numpy as np
import numpy.typing as npt

from . import params as _params
from .deadzone import _dead_zone
from .hysteresis import PIHysteresisOperator
from .inverse import invert_hysteresis, invert_superposition
from .superposition import PISuperpositionOperator

__all__ = ['MPIModel', 'MPIStream']

FloatArray = npt.NDArray[np.float64]


@numba.njit(cache=True, nogil=True, inline='always')
def _hysteresis_step(x, r_h, w_h, z):  # pragma: no cover - compiled
    # Play operators (4) then the weighted sum (5).
    acc = 0.0
    for i in range(r_h.shape[0]):
        lo = x - r_h[i]
        hi = x + r_h[i]
        zi = z[i]
        if zi < lo:
            zi = lo
        elif zi > hi:
            zi = hi
        z[i] = zi
        acc += w_h[i] * zi
    return acc


@numba.njit(cache=True, nogil=True, inline='always')
def _superposition_value(x, r_s, w_s):  # pragma: no cover - compiled
    acc = 0.0
    for i in range(r_s.shape[0]):
        acc += w_s[i] * _dead_zone(x, r_s[i])              # (17)-(18)
    return acc


@numba.njit(cache=True, nogil=True)
def _mpi_step(x, r_h, w_h, z, r_s, w_s, inverse):  # pragma: no cover - compiled
    if inverse:                                             # (27): H' o S'
        return _hysteresis_step(_superposition_value(x, r_s, w_s), r_h, w_h, z)
    return _superposition_value(_hysteresis_step(x, r_h, w_h, z), r_s, w_s)   # (26)


@numba.njit(cache=True, nogil=True)
def _mpi_batch(x, r_h, w_h, z, r_s, w_s, inverse):  # pragma: no cover - compiled
    out = np.empty(x.shape[0])
    for k in range(x.shape[0]):
        out[k] = _mpi_step(x[k], r_h, w_h, z, r_s, w_s, inverse)
    return out


@dataclass(frozen=True, eq=False)
class MPIModel:
    """
    Modified Prandtl-Ishlinskii operator Gamma = S o H (26), or its inverse (27).

    Parameters
    ----------
    hysteresis : PIHysteresisOperator
        H (forward model) or H^-1 (inverse model).
    superposition : PISuperpositionOperator
        S (forward model) or S^-1 (inverse model).
    is_inverse : bool
        False: ``Gamma = S o H`` maps current [A] to displacement [m].
        True: ``Gamma^-1 = H^-1 o S^-1`` maps displacement [m] to current [A].

    Examples
    --------
    >>> model = MPIModel.from_params({
    ...     'model.hysteresis.thresholds': [0.0, 0.5],
    ...     'model.hysteresis.weights': [1.0, 0.5],
    ...     'model.hysteresis.initial_states': [0.0, 0.0],
    ...     'model.superposition.thresholds': [-0.5, 0.0, 0.5],
    ...     'model.superposition.weights': [0.5, 2e-5, -1e-5]})
    >>> x = [0.0, 1.0, 0.2, 0.8]
    >>> s = model.simulate(x)
    >>> bool(abs(model.inverse().simulate(s) - x).max() < 1e-12)
    True

    """

    hysteresis: PIHysteresisOperator
    superposition: PISuperpositionOperator
    is_inverse: bool = False

    # -- construction -------------------------------------------------------------------
    @classmethod
    def from_params(cls, mapping: Mapping[str, Any]) -> 'MPIModel':
        """
        Build a forward model from its parameter form, validating everything.

        Parameters
        ----------
        mapping : Mapping[str, sequence of float]
            The keys ``model.hysteresis.thresholds``, ``model.hysteresis.weights``,
            ``model.hysteresis.initial_states``, ``model.superposition.thresholds``
            and ``model.superposition.weights`` (SI units; extra keys ignored).

        Returns
        -------
        MPIModel
            The forward model Gamma.

        Raises
        ------
        ModelError
            Naming the offending key (lengths, ordering, finiteness, (8), (19)).

        """
        p = _params.check_model_parameters(mapping)
        return cls(PIHysteresisOperator(p[_params.HYSTERESIS_THRESHOLDS],
                                        p[_params.HYSTERESIS_WEIGHTS],
                                        p[_params.HYSTERESIS_INITIAL_STATES]),
                   PISuperpositionOperator(p[_params.SUPERPOSITION_THRESHOLDS],
                                           p[_params.SUPERPOSITION_WEIGHTS]))

    def to_params(self) -> dict[str, list[float]]:
        """
        Return the parameter form of the forward model (SI units).

        For an inverse model the forward model's parameters are returned, since
        parameter files always store Gamma.

        Returns
        -------
        dict[str, list of float]
            The five ``model.*`` keys.

        """
        forward = self.inverse() if self.is_inverse else self
        h, s = forward.hysteresis, forward.superposition
        return {
            _params.HYSTERESIS_THRESHOLDS: [float(v) for v in h.thresholds],
            _params.HYSTERESIS_WEIGHTS: [float(v) for v in h.weights],
            _params.HYSTERESIS_INITIAL_STATES: [float(v) for v in h.initial_states],
            _params.SUPERPOSITION_THRESHOLDS: [float(v) for v in s.thresholds],
            _params.SUPERPOSITION_WEIGHTS: [float(v) for v in s.weights],
        }

    # -- properties ---------------------------------------------------------------------
    @property
    def n(self) -> int:
        """Order ``n`` of the hysteresis operator (n+1 play operators)."""
        return self.hysteresis.order

    @property
    def l(self) -> int:  # noqa: E743 - the paper's symbol
        """Order ``l`` of the superposition operator (up to 2l+1 dead-zone operators)."""
        return self.superposition.order

    def inverse(self) -> 'MPIModel':
        """
        Return the analytic inverse by the transformation laws (12)-(14), (22)-(25).

        ``model.inverse().inverse()`` equals ``model`` up to rounding.

        Returns
        -------
        MPIModel
            Gamma^-1 (27) for a forward model, Gamma for an inverse model.

        """
        return MPIModel(invert_hysteresis(self.hysteresis),
                        invert_superposition(self.superposition),
                        not self.is_inverse)

    # -- evaluation ---------------------------------------------------------------------
    def _kernel_args(self) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
        h, s = self.hysteresis, self.superposition
        return (np.ascontiguousarray(h.thresholds), np.ascontiguousarray(h.weights),
                np.ascontiguousarray(s.thresholds), np.ascontiguousarray(s.weights))

    def run(self, x: npt.ArrayLike,
            state: npt.ArrayLike | None = None) -> tuple[FloatArray, FloatArray]:
        """
        Apply the operator to a sequence, starting from ``state``, return the end state.

        Parameters
        ----------
        x : array_like of float, shape (N,)
            Input: current [A] (forward) or desired displacement [m] (inverse).
        state : array_like of float, shape (n+1,), optional
            Play outputs before the first sample [A]; the model's initial states
            by default.

        Returns
        -------
        y : ndarray of float, shape (N,)
            Output: displacement [m] (forward) or current [A] (inverse).
        state_end : ndarray of float, shape (n+1,)
            Play outputs after the last sample; pass it to continue in chunks.

        """
        r_h, w_h, r_s, w_s = self._kernel_args()
        z = np.array(self.hysteresis.initial_states if state is None else state,
                     dtype=np.float64)
        x_arr = np.ascontiguousarray(x, dtype=np.float64).reshape(-1)
        y = _mpi_batch(x_arr, r_h, w_h, z, r_s, w_s, self.is_inverse)
        return y, z

    def simulate(self, x: npt.ArrayLike) -> FloatArray:
        """
        Apply the operator to a whole sequence from the model's initial states.

        Parameters
        ----------
        x : array_like of float, shape (N,)
            Current [A] for Gamma, desired displacement [m] for Gamma^-1.

        Returns
        -------
        ndarray of float, shape (N,)
            Displacement [m] for Gamma, current [A] for Gamma^-1.

        """
        return self.run(x)[0]

    def stream(self, state: npt.ArrayLike | None = None) -> 'MPIStream':
        """Return the streaming form (one sample at a time), see :class:`MPIStream`."""
        return MPIStream(self, state)


class MPIStream:
    """
    Streaming form of an :class:`MPIModel`: ``step(x)`` per sample, persistent state.

    Gives exactly the results of :meth:`MPIModel.run` on the joined samples.

    Parameters
    ----------
    model : MPIModel
        Forward or inverse model.
    state : array_like of float, shape (n+1,), optional
        Play outputs before the first sample [A]; the model's initial states
        by default.

    """

    def __init__(self, model: MPIModel, state: npt.ArrayLike | None = None) -> None:
        self.model = model
        self._args = model._kernel_args()
        self._inverse = model.is_inverse
        self._z = np.empty(model.hysteresis.thresholds.size)
        self.reset(state)

    @property
    def state(self) -> FloatArray:
        """Play outputs after the last step [A] (a read-only copy)."""
        z = self._z.copy()
        z.flags.writeable = False
        return z

    def reset(self, state: npt.ArrayLike | None = None) -> None:
        """Reset the play outputs to the initial states, or to ``state``."""
        self._z[:] = self.model.hysteresis.initial_states if state is None else np.asarray(
            state, dtype=np.float64)

    def step(self, x: float) -> float:
        """
        Advance by one sample.

        Parameters
        ----------
        x : float
            Current [A] (forward) or desired displacement [m] (inverse).

        Returns
        -------
        float
            Displacement [m] (forward) or current [A] (inverse).

        """
        r_h, w_h, r_s, w_s = self._args
        return float(_mpi_step(float(x), r_h, w_h, self._z, r_s, w_s, self._inverse))
