# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Whether a valid parameter form is a *usable* model: Gamma (26) and Gamma^-1 (27) run.

:func:`~mpi_ros.operators.model.check_model_parameters` checks the form (lengths, order,
finiteness, the signs of (8) and (19)); a model can pass it and still be unusable in
floating point: subnormal weights make the inverse laws (13), (23), (25) divide by zero,
an offset of 1e308 turns every command into NaN.  :func:`check_usable` proves the model
works where it will be used, in a sandbox (any exception becomes a refusal):

1. **Scale** (relative to the thresholds and the current range; each refusal names the
   key): no subnormal weight or offset; H's and S's output at the initial states are
   finite; the input offset ``x0`` resolves the
   current range (its rounding step at most :data:`RESOLUTION` of the span), the output
   offset ``y0`` resolves the displacement span S gives over it; H's output over the
   range spans at least :data:`RESOLUTION` of the extent of S's thresholds (else the
   model is flat where it is used).
2. **Inverse**: H^-1 by (12)-(14) and S^-1 by (22)-(25) are built, with finite
   coefficients.
3. **Round trip**: Gamma runs over a sweep of the range (a major loop and nested minor
   loops) from the virgin state (the initial states only decide where the first command
   starts: a compensator derives its inverse state from the forward one at every step,
   (14)); every displacement is finite, and Gamma^-1 on them gives the currents back
   within :data:`ROUND_TRIP` of the span (so inside the range).

The range is the one the model will be used on (a node's ``output.min`` to ``output.max``);
without one, :func:`model_range` derives it from the model.
"""

from collections.abc import Callable
import math
from typing import Any, TypeVar

import numpy as np
import numpy.typing as npt

from .hysteresis import PIHysteresisOperator
from .inverse import invert_hysteresis, invert_superposition
from .superposition import PISuperpositionOperator
from ..errors import ModelError

__all__ = ['RESOLUTION', 'ROUND_TRIP', 'check_usable', 'model_range', 'usability_sweep']

FloatArray = npt.NDArray[np.float64]
T = TypeVar('T')

#: Finest fraction of a span an offset must resolve, and that H's output must cover of
#: the extent of S's thresholds.
RESOLUTION = 1e-7
#: Largest round-trip error |Gamma^-1[Gamma[x]] - x| as a fraction of the current span.
ROUND_TRIP = 1e-6

_TINY = float(np.finfo(np.float64).tiny)
_KEYS = ('model.hysteresis.thresholds', 'model.hysteresis.weights',
         'record_start.hysteresis.initial_states', 'model.superposition.thresholds',
         'model.superposition.weights')
_R_H, _W_H, _Z_H0, _R_S, _W_S = _KEYS
_X0, _Y0 = 'model.input_offset', 'model.output_offset'


def usability_sweep(low: float, high: float, points: int = 24) -> FloatArray:
    """
    Return the currents the round trip runs: a major loop, then nested minor loops.

    Parameters
    ----------
    low, high : float
        Current range [A], ``low < high``.
    points : int
        Samples per half loop.

    Returns
    -------
    ndarray of float, shape (M,)
        From the middle up to ``high``, down to ``low``, then loops of half, a quarter and
        an eighth of the span around the middle, each ending at a turning point.

    """
    mid, half = 0.5 * (low + high), 0.5 * (high - low)
    turns = [mid, high, low, high]
    for fraction in (0.5, 0.25, 0.125):
        turns += [mid - fraction * half, mid + fraction * half]
    turns.append(mid)
    pieces = [np.linspace(a, b, points, endpoint=False) for a, b in zip(turns, turns[1:])]
    return np.concatenate(pieces + [np.array([turns[-1]])])


def model_range(hysteresis: PIHysteresisOperator, superposition: PISuperpositionOperator,
                input_offset: float) -> tuple[float, float]:
    """
    Return a current range a model covers when none is given [A].

    Around ``x0``: the widest play threshold plus the input that takes H's output to the
    outermost threshold of S (``max |r_S| / sum w_H``); 1 A either side for a model
    with one play and one dead zone (linear: any range shows it).

    Parameters
    ----------
    hysteresis : PIHysteresisOperator
        H of the forward model.
    superposition : PISuperpositionOperator
        S of the forward model.
    input_offset : float
        ``x0`` [A].

    Returns
    -------
    tuple of float
        ``(low, high)`` [A].

    Raises
    ------
    ModelError
        When the range does not fit in floating point (naming ``model.hysteresis.weights``).

    """
    gain = float(np.sum(hysteresis.weights))
    reach = float(np.max(np.abs(superposition.thresholds)))
    with np.errstate(all='ignore'):
        half = float(hysteresis.thresholds[-1]) + (reach / gain if reach > 0.0 else 0.0)
    if half == 0.0:
        half = 1.0
    if not math.isfinite(half):
        msg = (f'{_W_H} (sum {gain!r}) is too small for {_R_S} (up to {reach!r}): the '
               'input that reaches the outermost dead zone does not fit in floating point; '
               're-run identify')
        raise ModelError(msg)
    _resolves(_X0, input_offset, 2.0 * half,
              f'the span {2.0 * half:g} A its thresholds and weights cover', 'A')
    return input_offset - half, input_offset + half


def check_usable(hysteresis: PIHysteresisOperator, superposition: PISuperpositionOperator,
                 *, input_offset: float = 0.0, output_offset: float = 0.0,
                 output_sign: int = 1, current_range: tuple[float, float] | None = None,
                 ) -> tuple[PIHysteresisOperator, PISuperpositionOperator]:
    """
    Prove that the forward model ``y0 + sign * S[H[x - x0]]`` and its inverse run.

    Parameters
    ----------
    hysteresis : PIHysteresisOperator
        H (its initial states are where the sweep starts).
    superposition : PISuperpositionOperator
        S.
    input_offset, output_offset : float
        ``x0`` [A] and ``y0`` [m].
    output_sign : int
        +1 or -1.
    current_range : tuple of float, optional
        ``(low, high)`` [A] the model will be used on; None: :func:`model_range`.

    Returns
    -------
    tuple
        ``(H^-1, S^-1)``, built by (12)-(14) and (22)-(25).

    Raises
    ------
    ModelError
        Naming the key that makes the model unusable, what was found and what to do; also
        for any exception the operators raise on it (the sandbox).

    """
    _no_subnormal({_W_H: hysteresis.weights, _W_S: superposition.weights},
                  {_X0: input_offset, _Y0: output_offset})
    if current_range is None:
        low, high = model_range(hysteresis, superposition, input_offset)
    else:
        low, high = (float(v) for v in current_range)
    span = high - low
    if not (math.isfinite(low) and math.isfinite(high) and span > 0.0
            and math.isfinite(span)):
        msg = f'the current range {low!r} to {high!r} A must be finite and ascending'
        raise ModelError(msg)
    _resolves(_X0, input_offset, span, f'the current range {low:g} to {high:g} A', 'A')
    with np.errstate(all='ignore'):
        start = np.array([np.dot(hysteresis.weights, hysteresis.initial_states)])
        _finite(start, _Z_H0, "H's output at the initial states")
        _finite(superposition.apply(start), _Z_H0, "S of H's output at the initial states")
    # The round trip starts from the virgin state (every play at 0, which (14) maps to
    # 0): the initial states only decide where the first command starts, and a
    # compensator derives its inverse state from the forward one at every step (14).
    virgin = PIHysteresisOperator(hysteresis.thresholds, hysteresis.weights)
    x = usability_sweep(low, high)
    with np.errstate(all='ignore'):
        v = _sandboxed(lambda: virgin.apply(x - input_offset)[0], _W_H,
                       'H (5) over the range')
        _finite(v, _W_H, f'H[x - x0] for currents {low:g} to {high:g} A')
        s = _sandboxed(lambda: superposition.apply(v), _W_S, 'S (18) over the range')
        _finite(s, _W_S, 'S[H[x - x0]] over the range')
    _covers(v, superposition.thresholds, low, high)
    s_span = float(np.ptp(s))
    _resolves(_Y0, output_offset, s_span, f'the displacement span {s_span:g} m of the model',
              'm')
    with np.errstate(all='ignore'):
        y = output_offset + output_sign * s
        _finite(y, _Y0, 'the displacements over the range')
        h_inv = _sandboxed(lambda: invert_hysteresis(hysteresis), _W_H,
                           'H^-1 by the laws (12)-(14)')
        _finite(np.concatenate([h_inv.thresholds, h_inv.weights, h_inv.initial_states]),
                _W_H, 'H^-1 by (12)-(14)')
        s_inv = _sandboxed(lambda: invert_superposition(superposition), _W_S,
                           'S^-1 by the laws (22)-(25)')
        _finite(np.concatenate([s_inv.thresholds, s_inv.weights]), _W_S,
                'S^-1 by (22)-(25)')
        virgin_inv = PIHysteresisOperator(h_inv.thresholds, h_inv.weights)
        back = _sandboxed(
            lambda: input_offset + virgin_inv.apply(
                s_inv.apply(output_sign * (y - output_offset)))[0], _W_H,
            'Gamma^-1 (27) over the range')
    error = np.abs(back - x)
    worst = int(np.argmax(np.where(np.isfinite(error), error, np.inf)))
    if not error[worst] <= ROUND_TRIP * span:
        key = _culprit(x - input_offset, v, s, virgin_inv, s_inv)
        msg = (f'{key}: Gamma^-1[Gamma[x]] misses x by {float(error[worst])!r} A at '
               f'x = {float(x[worst]):g} A (more than {ROUND_TRIP:g} of the range {low:g} '
               f'to {high:g} A): the model is too ill-conditioned to invert in floating '
               'point; re-run identify')
        raise ModelError(msg)
    return h_inv, s_inv


def _culprit(shifted: FloatArray, v: FloatArray, s: FloatArray, h_inv: PIHysteresisOperator,
             s_inv: PISuperpositionOperator) -> str:
    """Name the weights of the operator whose own round trip is worse (relative)."""
    with np.errstate(all='ignore'):
        h_error = np.max(np.abs(h_inv.apply(v)[0] - shifted)) / max(np.ptp(shifted), _TINY)
        s_error = np.max(np.abs(s_inv.apply(s) - v)) / max(np.ptp(v), _TINY)
    return _W_S if not s_error <= h_error else _W_H


def _no_subnormal(arrays: dict[str, Any], offsets: dict[str, float]) -> None:
    for key, arr in list(arrays.items()) + [(k, np.array([v])) for k, v in offsets.items()]:
        values = np.asarray(arr, dtype=np.float64)
        bad = np.flatnonzero((values != 0.0) & (np.abs(values) < _TINY))
        if bad.size:
            i = int(bad[0])
            where = f' item {i}' if key in arrays else ''
            msg = (f'{key}{where} is {float(values[i])!r}: subnormal (nonzero but below '
                   f'{_TINY:.3g}, {bad.size} such), a rounding residue that the inverse laws '
                   'cannot divide by; write 0.0 or re-run identify')
            raise ModelError(msg)


def _resolves(key: str, offset: float, span: float, what: str, unit: str) -> None:
    step = float(np.spacing(abs(offset)))
    if span > 0.0 and not step <= RESOLUTION * span:
        msg = (f'{key} = {offset!r} {unit} cannot be resolved against {what}: its rounding '
               f'step {step:.3g} {unit} is more than {RESOLUTION:g} of the span, so the model '
               'would return the same value for every input; re-run identify or give the '
               'operating point')
        raise ModelError(msg)


def _covers(v: FloatArray, thresholds: FloatArray, low: float, high: float) -> None:
    reach = float(np.max(np.abs(thresholds)))
    v_span = float(np.ptp(v))
    if reach > 0.0 and not v_span >= RESOLUTION * reach:
        msg = (f'{_W_H}: H spans only {v_span!r} A over the currents {low:g} to {high:g} A, '
               f'less than {RESOLUTION:g} of the extent {reach:g} A of {_R_S}: the model '
               'is flat where it is used; re-run identify')
        raise ModelError(msg)


def _finite(values: FloatArray, key: str, what: str) -> None:
    bad = np.flatnonzero(~np.isfinite(values))
    if bad.size:
        msg = (f'{key}: {what} is not finite ({float(values[bad[0]])!r} at {bad.size} of '
               f'{values.size} samples): the weights and offsets overflow over this range; '
               're-run identify')
        raise ModelError(msg)


def _sandboxed(action: Callable[[], T], key: str, what: str) -> T:
    try:
        return action()
    except ModelError as err:
        msg = f'{key}: {what} cannot be built: {err}'
        raise ModelError(msg) from err
    except Exception as err:  # noqa: B902 - any failure of the operators is a refusal
        msg = (f'{key}: {what} failed ({type(err).__name__}: {err}); the model is not '
               'usable in floating point; re-run identify')
        raise ModelError(msg) from err
