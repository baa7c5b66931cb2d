# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Modified Prandtl-Ishlinskii operator Gamma = S o H (26) and its inverse (27).

``Gamma[x] = w_S^T S_rS[ w_H^T H_rH[x, z_H0] ]`` (26): a Prandtl-Ishlinskii
hysteresis operator H followed by a Prandtl-Ishlinskii superposition
operator S.  The inverse, obtained analytically by the laws in
:mod:`mpi_ros.operators.inverse`, is ``Gamma^-1 = H' o S'`` (27): the same two kinds of
operator in the opposite order.  :class:`MPIModel` represents both; the flag
``is_inverse`` says which order applies.

Units: the forward model maps current (A) to displacement (m), H maps A to
A (its weights are dimensionless), S maps A to m.  The inverse maps m to A.

Operating point (not in the paper, whose actuator rests at the origin): a rig's
sensor has an arbitrary zero ``y0``, its drive a bias ``x0``, and some sensors fall
as the actuator extends (``sign = -1``).  The model is

``y = y0 + sign * S[H[x - x0]]``  and its inverse  ``x = x0 + H'[S'[sign * (y - y0)]]``,

still exact and closed-form: the offsets and the sign are affine maps around the
operator pair.  H's plays and their initial states live in the shifted input
``x - x0``.

Parameter form (the keys the compensator node reads; ``to_params`` / ``from_params``): the
actuator, in SI units (A, m), under ``model.hysteresis.thresholds`` (r_H, ascending from
0, A), ``model.hysteresis.weights`` (w_H, dimensionless), ``model.superposition.thresholds``
(r_S, ascending with exactly one 0, A), ``model.superposition.weights`` (w_S, m/A), and the
optional operating point ``model.input_offset`` (x0, A, default 0.0),
``model.output_offset`` (y0, m, default 0.0), ``model.output_sign`` (+1 or -1, default +1);
apart from it the identification record's own start,
``record_start.hysteresis.initial_states`` (z_H0, A, optional: default 0, the paper's (32)).
An :class:`MPIModel` keeps that start as ``hysteresis.initial_states`` (its ``simulate``
reproduces the record); a new input starts where :mod:`mpi_ros.operators.start` says.
``model.hysteresis.initial_states``, the key older files hold the record start under, is read
as the record start.  :func:`check_model_parameters` validates such a mapping completely
(lengths, ordering, finiteness, the constraints (8) and (19)) and names the offending key;
:mod:`mpi_ros.params` reads and writes it as a ROS 2 parameter file.
"""

from collections.abc import Mapping
from dataclasses import dataclass, replace
import math
from typing import Any, ClassVar, Protocol

import numba
import numpy as np
import numpy.typing as npt

from .deadzone import dead_zone
from .hysteresis import PIHysteresisOperator
from .inverse import invert_hysteresis, invert_superposition
from .play import play_clamp
from .superposition import PISuperpositionOperator
from .usability import check_usable
from ..errors import ModelError

__all__ = ['hysteresis_step', 'superposition_value', 'ActuatorModel', 'HYSTERESIS_INITIAL_STATES',
           'HYSTERESIS_THRESHOLDS', 'IDENTIFIED_INPUT_RANGE', 'RECORD_START_STATES',
           'HYSTERESIS_WEIGHTS', 'INPUT_OFFSET', 'MODEL_KEYS', 'MPIModel', 'MPIStream',
           'OPERATING_POINT_DEFAULTS', 'OPERATING_POINT_KEYS', 'OUTPUT_OFFSET', 'OUTPUT_SIGN',
           'SUPERPOSITION_THRESHOLDS', 'SUPERPOSITION_WEIGHTS', 'check_identified_input_range',
           'check_model_parameters', 'check_operating_point']

FloatArray = npt.NDArray[np.float64]


# -- the parameter form: the keys the compensator node reads, and their checks --

HYSTERESIS_THRESHOLDS = 'model.hysteresis.thresholds'
HYSTERESIS_WEIGHTS = 'model.hysteresis.weights'
SUPERPOSITION_THRESHOLDS = 'model.superposition.thresholds'
SUPERPOSITION_WEIGHTS = 'model.superposition.weights'
#: Gamma's four arrays, the actuator (the nodes and every tool use this one definition).
MODEL_KEYS = (HYSTERESIS_THRESHOLDS, HYSTERESIS_WEIGHTS, SUPERPOSITION_THRESHOLDS,
              SUPERPOSITION_WEIGHTS)
#: The identification record's start: the plays' states at its first sample (optional).
RECORD_START_STATES = 'record_start.hysteresis.initial_states'
#: Where files written before the split hold the record start (read as it; never written).
HYSTERESIS_INITIAL_STATES = 'model.hysteresis.initial_states'
#: The lowest and highest input of the identification record [A] (optional; ``identify``
#: writes it): where a rest start's sweep turns and what the limits are judged against.
IDENTIFIED_INPUT_RANGE = 'model.identified_input_range'
INPUT_OFFSET = 'model.input_offset'
OUTPUT_OFFSET = 'model.output_offset'
OUTPUT_SIGN = 'model.output_sign'
#: The operating point: optional keys, these defaults when absent (the paper's origin).
OPERATING_POINT_KEYS = (INPUT_OFFSET, OUTPUT_OFFSET, OUTPUT_SIGN)
OPERATING_POINT_DEFAULTS: dict[str, float | int] = {INPUT_OFFSET: 0.0, OUTPUT_OFFSET: 0.0,
                                                    OUTPUT_SIGN: 1}


def _vector(mapping: Mapping[str, Any], key: str) -> FloatArray:
    if key not in mapping:
        msg = f'{key} is missing; a model needs all of: {", ".join(MODEL_KEYS)}'
        raise ModelError(msg)
    value = mapping[key]
    if isinstance(value, (str, bytes)) or not hasattr(value, '__len__'):
        msg = f'{key} must be a list of floats; found {type(value).__name__} {value!r}'
        raise ModelError(msg)
    items = list(value)
    for i, item in enumerate(items):
        number = isinstance(item, (int, float, np.floating, np.integer))
        if isinstance(item, bool) or not number:
            msg = (f'{key} must be a list of floats; item {i} is'
                   f' {type(item).__name__} {item!r}')
            raise ModelError(msg)
    arr = np.array(items, dtype=np.float64)
    if arr.size == 0:
        msg = f'{key} must not be empty'
        raise ModelError(msg)
    bad = np.flatnonzero(~np.isfinite(arr))
    if bad.size:
        msg = f'{key} must be finite; item {bad[0]} is {arr[bad[0]]}'
        raise ModelError(msg)
    return arr


def _strictly_ascending(arr: FloatArray, key: str) -> None:
    steps = np.diff(arr)
    if np.any(steps <= 0.0):
        i = int(np.flatnonzero(steps <= 0.0)[0])
        kind = 'duplicate' if steps[i] == 0.0 else 'unsorted'
        msg = (f'{key} must be strictly ascending; found {kind} values {float(arr[i])!r} and'
               f' {float(arr[i + 1])!r} at items {i} and {i + 1}')
        raise ModelError(msg)


def _scalar(mapping: Mapping[str, Any], key: str) -> float:
    value = mapping.get(key)
    if value is None:
        return float(OPERATING_POINT_DEFAULTS[key])
    number = isinstance(value, (int, float, np.floating, np.integer))
    if isinstance(value, bool) or not number:
        msg = f'{key} must be a number; found {type(value).__name__} {value!r}'
        raise ModelError(msg)
    if not math.isfinite(float(value)):
        msg = f'{key} must be finite; found {float(value)}'
        raise ModelError(msg)
    return float(value)


def check_operating_point(mapping: Mapping[str, Any]) -> tuple[float, float, int]:
    """
    Validate the operating point keys (absent or None: the defaults).

    Parameters
    ----------
    mapping : Mapping[str, Any]
        Flat parameters; ``model.input_offset`` [A], ``model.output_offset`` [m] and
        ``model.output_sign`` (+1 or -1) are read, other keys ignored.

    Returns
    -------
    (float, float, int)
        ``(x0, y0, sign)``.

    Raises
    ------
    ModelError
        Naming the key.

    """
    x0 = _scalar(mapping, INPUT_OFFSET)
    y0 = _scalar(mapping, OUTPUT_OFFSET)
    sign = _scalar(mapping, OUTPUT_SIGN)
    if sign not in (1.0, -1.0):
        msg = (f'{OUTPUT_SIGN} must be 1 (the sensor rises as the actuator extends) or -1'
               f' (it falls); found {sign:g}')
        raise ModelError(msg)
    return x0, y0, int(sign)


def check_identified_input_range(value: Any) -> tuple[float, float] | None:
    """
    Validate the identified input range (``model.identified_input_range``).

    Parameters
    ----------
    value : sequence of two float, empty sequence or None
        ``[lowest, highest]`` recorded input [A]; empty or None: not known.

    Returns
    -------
    (float, float) or None
        The range; None when not known.

    Raises
    ------
    ModelError
        Not two finite numbers, the first below the second (naming the key).

    Examples
    --------
    >>> check_identified_input_range([0.0, 1.8]), check_identified_input_range([])
    ((0.0, 1.8), None)

    """
    if value is None or (hasattr(value, '__len__') and not isinstance(value, (str, bytes))
                         and len(value) == 0):
        return None
    values = _vector({IDENTIFIED_INPUT_RANGE: value}, IDENTIFIED_INPUT_RANGE)
    if values.size != 2:
        msg = (f'{IDENTIFIED_INPUT_RANGE} must be the lowest and the highest input of the '
               f'identification record [A], or empty (not known); found {values.size} values')
        raise ModelError(msg)
    _strictly_ascending(values, IDENTIFIED_INPUT_RANGE)
    return float(values[0]), float(values[1])


def check_model_parameters(mapping: Mapping[str, Any]) -> dict[str, FloatArray]:
    """
    Validate the parameter form of a forward MPI model and return its arrays.

    The operating point keys are checked by :func:`check_operating_point`.

    Parameters
    ----------
    mapping : Mapping[str, sequence of float]
        The four ``model.*`` arrays of Gamma and, optionally, the record start
        ``record_start.hysteresis.initial_states`` (or, in a file written before the split,
        ``model.hysteresis.initial_states``; the former wins when both are given); extra
        keys are ignored.

    Returns
    -------
    dict[str, ndarray of float]
        The four arrays keyed as in ``MODEL_KEYS``, and the record start under
        ``RECORD_START_STATES`` (zeros, the paper's (32), when not given).

    Raises
    ------
    ModelError
        Naming the key, what was expected, what was found and what to do.

    """
    r_h = _vector(mapping, HYSTERESIS_THRESHOLDS)
    w_h = _vector(mapping, HYSTERESIS_WEIGHTS)
    # An unset (None) or empty record start is no record start.
    start = next((key for key in (RECORD_START_STATES, HYSTERESIS_INITIAL_STATES)
                  if mapping.get(key) is not None and not (
                      hasattr(mapping[key], '__len__') and len(mapping[key]) == 0)), None)
    z_h0 = np.zeros_like(r_h) if start is None else _vector(mapping, start)
    r_s = _vector(mapping, SUPERPOSITION_THRESHOLDS)
    w_s = _vector(mapping, SUPERPOSITION_WEIGHTS)
    if w_h.size != r_h.size:
        msg = (f'{HYSTERESIS_WEIGHTS} must have one weight per threshold in'
               f' {HYSTERESIS_THRESHOLDS}: expected {r_h.size}, found {w_h.size}')
        raise ModelError(msg)
    if z_h0.size != r_h.size:
        msg = (f'{start} must have one state per threshold in'
               f' {HYSTERESIS_THRESHOLDS}: expected {r_h.size}, found {z_h0.size}')
        raise ModelError(msg)
    if w_s.size != r_s.size:
        msg = (f'{SUPERPOSITION_WEIGHTS} must have one weight per threshold in'
               f' {SUPERPOSITION_THRESHOLDS}: expected {r_s.size}, found {w_s.size}')
        raise ModelError(msg)
    if r_h[0] != 0.0:
        msg = (f'{HYSTERESIS_THRESHOLDS} must start at exactly 0.0 (r_H0 = 0);'
               f' found {float(r_h[0])!r}; re-run identify or prepend 0.0')
        raise ModelError(msg)
    _strictly_ascending(r_h, HYSTERESIS_THRESHOLDS)
    zeros = int(np.count_nonzero(r_s == 0.0))
    if zeros != 1:
        found = 'none' if zeros == 0 else f'{zeros} zeros'
        msg = (f'{SUPERPOSITION_THRESHOLDS} must contain exactly one 0; found {found};'
               ' re-run identify or add 0.0')
        raise ModelError(msg)
    _strictly_ascending(r_s, SUPERPOSITION_THRESHOLDS)
    if not w_h[0] > 0.0:
        msg = (f'{HYSTERESIS_WEIGHTS} violates (8): the first weight w_H0 must be positive;'
               f' found {float(w_h[0])!r}')
        raise ModelError(msg)
    negative = np.flatnonzero(w_h[1:] < 0.0)
    if negative.size:
        i = int(negative[0]) + 1
        msg = (f'{HYSTERESIS_WEIGHTS} violates (8): weights after the first must be >= 0;'
               f' item {i} is {float(w_h[i])!r} ({negative.size} negative)')
        raise ModelError(msg)
    c = int(np.flatnonzero(r_s == 0.0)[0])
    slopes = np.empty_like(w_s)
    slopes[c:] = np.cumsum(w_s[c:])
    slopes[:c + 1] = np.cumsum(w_s[:c + 1][::-1])[::-1]
    bad = np.flatnonzero(slopes <= 0.0)
    if bad.size:
        i = int(bad[0])
        msg = (f'{SUPERPOSITION_WEIGHTS} violates (19): the static map must be strictly'
               f' increasing, but the piece at threshold {float(r_s[i])!r} (item {i}) has slope'
               f' {float(slopes[i])!r}')
        raise ModelError(msg)
    return {HYSTERESIS_THRESHOLDS: r_h, HYSTERESIS_WEIGHTS: w_h,
            RECORD_START_STATES: z_h0, SUPERPOSITION_THRESHOLDS: r_s,
            SUPERPOSITION_WEIGHTS: w_s}


@numba.njit(cache=True, nogil=True, inline='always')
def hysteresis_step(x: float, r_h: FloatArray, w_h: FloatArray,
                    z: FloatArray) -> float:  # pragma: no cover - compiled
    """
    Advance H by one sample: play operators (4), then the weighted sum (5); compiled.

    Parameters
    ----------
    x : float
        Input sample, relative to the input offset [A].
    r_h, w_h : ndarray of float, shape (n+1,)
        Play thresholds [A] and weights.
    z : ndarray of float, shape (n+1,)
        Play states [A], advanced in place.

    Returns
    -------
    float
        ``H[x]`` [A].

    """
    acc = 0.0
    for i in range(r_h.shape[0]):
        z[i] = play_clamp(x, r_h[i], z[i])
        acc += w_h[i] * z[i]
    return acc


@numba.njit(cache=True, nogil=True, inline='always')
def superposition_value(x: float, r_s: FloatArray,
                        w_s: FloatArray) -> float:  # pragma: no cover - compiled
    """
    Return S at one value: the weighted sum of dead-zone operators (17)-(18); compiled.

    Parameters
    ----------
    x : float
        S's input (H's output, or a displacement for S').
    r_s, w_s : ndarray of float, shape (l,)
        Dead-zone thresholds and weights.

    Returns
    -------
    float
        ``S[x]``.

    """
    acc = 0.0
    for i in range(r_s.shape[0]):
        acc += w_s[i] * dead_zone(x, r_s[i])              # (17)-(18)
    return acc


@numba.njit(cache=True, nogil=True)
def _mpi_step(x: float, r_h: FloatArray, w_h: FloatArray, z: FloatArray, r_s: FloatArray,
              w_s: FloatArray, inverse: bool,
              affine: FloatArray) -> float:  # pragma: no cover - compiled
    # affine = (a, b, c, d): the operators see a + b x, the output is c + d * result.
    u = affine[0] + affine[1] * x
    if inverse:                                             # (27): H' o S'
        out = hysteresis_step(superposition_value(u, r_s, w_s), r_h, w_h, z)
    else:
        out = superposition_value(hysteresis_step(u, r_h, w_h, z), r_s, w_s)   # (26)
    result: float = affine[2] + affine[3] * out
    return result


@numba.njit(cache=True, nogil=True)
def _mpi_batch(x: FloatArray, r_h: FloatArray, w_h: FloatArray, z: FloatArray,
               r_s: FloatArray, w_s: FloatArray, inverse: bool,
               affine: FloatArray) -> FloatArray:  # pragma: no cover - compiled
    # _mpi_step's arithmetic, with the direction and the affine map taken out of the loop:
    # the compiler then keeps the loop tight (four times faster on 1e6 samples).
    out = np.empty(x.shape[0])
    a, b, c, d = affine[0], affine[1], affine[2], affine[3]
    if inverse:                                             # (27): H' o S'
        for k in range(x.shape[0]):
            out[k] = c + d * hysteresis_step(superposition_value(a + b * x[k], r_s, w_s),
                                             r_h, w_h, z)
    else:                                                   # (26)
        for k in range(x.shape[0]):
            out[k] = c + d * superposition_value(hysteresis_step(a + b * x[k], r_h, w_h, z),
                                                 r_s, w_s)
    return out


class ActuatorModel(Protocol):
    """
    What every model of the actuator offers: Gamma alone or Gamma with effects.

    :class:`MPIModel` (the paper's Gamma) and the extended models of
    :mod:`mpi_ros.extensions` (one effect, or a composite of several) implement it, so a
    caller never asks which kind of model it holds (the style of python-control's
    ``InputOutputSystem``).

    Attributes
    ----------
    cause : str
        ``'none'`` for Gamma alone, else the effect's name (``'creep + rate_dependence'``
        for a composite).
    timed : bool
        Whether the response needs the sample times (an effect with dynamics).

    """

    cause: str
    timed: bool

    @property
    def gamma(self) -> 'MPIModel':
        """Return the forward Gamma (operating point and start state included)."""

    def response(self, time: npt.ArrayLike, current: npt.ArrayLike) -> FloatArray:
        """Return the displacement [m] for a current [A] sampled at ``time`` [s]."""

    def inverse_step(self) -> Any:
        """Return the exact per-step inverse of the effects, or None (Gamma's own suffices)."""

    def to_params(self) -> dict[str, Any]:
        """Return the flat parameter form (``from_params`` of its class reads it)."""

    def with_gamma(self, gamma: 'MPIModel') -> 'ActuatorModel':
        """Return the same model around another Gamma (e.g. another start state)."""


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
    input_offset : float
        ``x0`` [A]: the plays see ``x - x0`` (``model.input_offset``).
    output_offset : float
        ``y0`` [m]: added to the output of S (``model.output_offset``).
    output_sign : int
        +1, or -1 for a sensor that falls as the actuator extends (``model.output_sign``).
        The forward model is ``y0 + sign * S[H[x - x0]]``; an inverse model keeps the
        forward model's operating point and computes ``x0 + H'[S'[sign * (y - y0)]]``.
    identified_input_range : (float, float) or None
        The lowest and highest input of the identification record [A]
        (``model.identified_input_range``, written by ``identify``); None: not known, the
        thresholds tell it (:func:`~mpi_ros.operators.start.identified_ranges`).

    Examples
    --------
    >>> model = MPIModel.from_params({
    ...     'model.hysteresis.thresholds': [0.0, 0.5],
    ...     'model.hysteresis.weights': [1.0, 0.5],
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
    input_offset: float = 0.0
    output_offset: float = 0.0
    output_sign: int = 1
    identified_input_range: tuple[float, float] | None = None
    #: :class:`ActuatorModel`: Gamma alone has no effect and needs no time base.
    cause: ClassVar[str] = 'none'
    timed: ClassVar[bool] = False

    def __post_init__(self) -> None:
        """Check the operating point (finite offsets, sign +1 or -1)."""
        x0, y0, sign = check_operating_point({
            INPUT_OFFSET: self.input_offset, OUTPUT_OFFSET: self.output_offset,
            OUTPUT_SIGN: self.output_sign})
        object.__setattr__(self, 'input_offset', x0)
        object.__setattr__(self, 'output_offset', y0)
        object.__setattr__(self, 'output_sign', sign)
        object.__setattr__(self, 'identified_input_range',
                           check_identified_input_range(self.identified_input_range))

    # -- construction -------------------------------------------------------------------
    @classmethod
    def from_params(cls, mapping: Mapping[str, Any]) -> 'MPIModel':
        """
        Build a forward model from its parameter form, validating everything.

        Parameters
        ----------
        mapping : Mapping[str, sequence of float]
            The keys ``model.hysteresis.thresholds``, ``model.hysteresis.weights``,
            ``model.superposition.thresholds`` and ``model.superposition.weights`` (SI
            units; extra keys ignored), and optionally the operating point
            ``model.input_offset`` [A], ``model.output_offset`` [m], ``model.output_sign``
            (default 0, 0, +1), the record start
            ``record_start.hysteresis.initial_states`` [A] (default 0; an older file's
            ``model.hysteresis.initial_states`` is read as it) and the identified input
            range ``model.identified_input_range`` [A] (default: not known).

        Returns
        -------
        MPIModel
            The forward model Gamma, its ``hysteresis.initial_states`` the record start.

        Raises
        ------
        ModelError
            Naming the offending key (lengths, ordering, finiteness, (8), (19)), or the
            key that makes the model unusable in floating point
            (:func:`mpi_ros.operators.usability.check_usable`: subnormal or overflowing
            weights and offsets; Gamma and Gamma^-1 are run over the range the model
            covers and must give the currents back).

        """
        p = check_model_parameters(mapping)
        x0, y0, sign = check_operating_point(mapping)
        known = check_identified_input_range(mapping.get(IDENTIFIED_INPUT_RANGE))
        hysteresis = PIHysteresisOperator(p[HYSTERESIS_THRESHOLDS], p[HYSTERESIS_WEIGHTS],
                                          p[RECORD_START_STATES])
        superposition = PISuperpositionOperator(p[SUPERPOSITION_THRESHOLDS],
                                                p[SUPERPOSITION_WEIGHTS])
        check_usable(hysteresis, superposition, input_offset=x0, output_offset=y0,
                     output_sign=sign)
        return cls(hysteresis, superposition, input_offset=x0, output_offset=y0,
                   output_sign=sign, identified_input_range=known)

    def to_params(self) -> dict[str, Any]:
        """
        Return the parameter form of the forward model (SI units).

        For an inverse model the forward model's parameters are returned, since
        parameter files always store Gamma.

        Returns
        -------
        dict[str, list of float or float or int]
            The four ``model.*`` arrays of Gamma, the three operating point keys, the
            record start ``record_start.hysteresis.initial_states`` (the plays' states the
            model holds) and, where known, ``model.identified_input_range``.

        """
        forward = self.inverse() if self.is_inverse else self
        h, s = forward.hysteresis, forward.superposition
        known = ({} if self.identified_input_range is None else
                 {IDENTIFIED_INPUT_RANGE: [float(v) for v in self.identified_input_range]})
        return {
            HYSTERESIS_THRESHOLDS: [float(v) for v in h.thresholds],
            HYSTERESIS_WEIGHTS: [float(v) for v in h.weights],
            SUPERPOSITION_THRESHOLDS: [float(v) for v in s.thresholds],
            SUPERPOSITION_WEIGHTS: [float(v) for v in s.weights],
            INPUT_OFFSET: float(self.input_offset),
            OUTPUT_OFFSET: float(self.output_offset),
            OUTPUT_SIGN: int(self.output_sign),
            RECORD_START_STATES: [float(v) for v in h.initial_states],
            **known,
        }

    def with_operating_point(self, *, input_offset: float | None = None,
                             output_offset: float | None = None,
                             output_sign: int | None = None) -> 'MPIModel':
        """
        Return the same operators at another operating point (unchanged where not given).

        Parameters
        ----------
        input_offset : float, optional
            ``x0`` [A].
        output_offset : float, optional
            ``y0`` [m] (e.g. a validation run's own sensor zero).
        output_sign : int, optional
            +1 or -1.

        Returns
        -------
        MPIModel
            A new model; ``self`` is unchanged.

        """
        return replace(self,
                       input_offset=self.input_offset if input_offset is None else input_offset,
                       output_offset=(self.output_offset if output_offset is None
                                      else output_offset),
                       output_sign=self.output_sign if output_sign is None else output_sign)

    def with_initial_states(self, states: npt.ArrayLike) -> 'MPIModel':
        """
        Return the same model whose plays start in ``states`` (e.g. another start state).

        Parameters
        ----------
        states : array_like of float, shape (n+1,)
            The plays' states [A] (of H, or of H' for an inverse model).

        Returns
        -------
        MPIModel
            A new model; ``self`` is unchanged.

        """
        h = self.hysteresis
        return replace(self, hysteresis=PIHysteresisOperator(h.thresholds, h.weights, states))

    # -- properties ---------------------------------------------------------------------
    @property
    def n(self) -> int:
        """Order ``n`` of the hysteresis operator (n+1 play operators)."""
        return self.hysteresis.order

    @property
    def l(self) -> int:  # noqa: E743 - the paper's symbol
        """Order ``l`` of the superposition operator (up to 2l+1 dead-zone operators)."""
        return self.superposition.order

    # -- ActuatorModel --------------------------------------------------------------------
    @property
    def gamma(self) -> 'MPIModel':
        """Return the forward Gamma: this model, or the forward model of an inverse one."""
        return self.inverse() if self.is_inverse else self

    def response(self, time: npt.ArrayLike, current: npt.ArrayLike) -> FloatArray:
        """Return :meth:`simulate` of ``current`` (Gamma is rate independent: no time)."""
        return self.simulate(current)

    def inverse_step(self) -> None:
        """Return None: Gamma's inverse is the compensator's own (laws (12)-(14))."""
        return None

    def with_gamma(self, gamma: 'MPIModel') -> 'MPIModel':
        """Return ``gamma`` (Gamma alone is its Gamma)."""
        return gamma

    def inverse(self) -> 'MPIModel':
        """
        Return the analytic inverse by the transformation laws (12)-(14), (22)-(25).

        ``model.inverse().inverse()`` equals ``model`` up to rounding.

        Returns
        -------
        MPIModel
            Gamma^-1 (27) for a forward model, Gamma for an inverse model.

        """
        return replace(self, hysteresis=invert_hysteresis(self.hysteresis),
                       superposition=invert_superposition(self.superposition),
                       is_inverse=not self.is_inverse)

    # -- operating point ------------------------------------------------------------------
    def hysteresis_output(self, current: npt.ArrayLike,
                          state: npt.ArrayLike | None = None) -> tuple[FloatArray, FloatArray]:
        """
        Return ``H[x - x0]`` [A] of a forward model and the end state of its plays.

        Parameters
        ----------
        current : array_like of float, shape (N,)
            Current ``x`` [A].
        state : array_like of float, shape (n+1,), optional
            Play outputs before the first sample (in ``x - x0``); initial states by default.

        Returns
        -------
        v : ndarray of float, shape (N,)
            H's output [A].
        state_end : ndarray of float, shape (n+1,)
            Play outputs after the last sample.

        """
        x = np.asarray(current, dtype=np.float64).reshape(-1)
        return self.hysteresis.apply(x - self.input_offset, state)

    def output(self, hysteresis_output: npt.ArrayLike) -> FloatArray:
        """
        Return ``y0 + sign * S[v]`` [m] of a forward model for H-output values ``v`` [A].

        Parameters
        ----------
        hysteresis_output : array_like of float, shape (N,)
            ``v``, e.g. from :meth:`hysteresis_output` (plus extension terms).

        Returns
        -------
        ndarray of float, shape (N,)
            Displacement [m].

        """
        return self.output_offset + self.output_sign * self.superposition.apply(
            hysteresis_output)

    # -- evaluation ---------------------------------------------------------------------
    def _affine(self) -> FloatArray:
        # (a, b, c, d): the operators see a + b * input, the result is c + d * output.
        x0, y0, sign = self.input_offset, self.output_offset, float(self.output_sign)
        if self.is_inverse:
            return np.array([-sign * y0, sign, x0, 1.0])
        return np.array([-x0, 1.0, y0, sign])

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
            Play outputs before the first sample [A] (in the shifted input ``x - x0``);
            the model's initial states by default.

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
        y = _mpi_batch(x_arr, r_h, w_h, z, r_s, w_s, self.is_inverse, self._affine())
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
        self._affine = model._affine()
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
        return float(_mpi_step(float(x), r_h, w_h, self._z, r_s, w_s, self._inverse,
                               self._affine))
