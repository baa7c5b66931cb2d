# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Where a new input starts: the plays' initial states z_H0 (32) of an actuator model.

An actuator model (the ``model.*`` keys) does not say where the actuator is when a new input
begins; its identification record started somewhere of its own (``record_start.*``: the plays'
states at the record's first sample, a mode's deflection there), which reproduces that record
and nothing else.  A new input (``mpi-ros simulate``, ``mpi-ros compensate``, the compensator
and its nodes) starts from a :class:`StartState`:

``rest_low`` (the default)
    At rest after a sweep over the identified input range ``[a, b]``: up to the highest
    input ``b``, then down to the lowest ``a``.  Every play is at
    ``z_i = min(a - x0 + r_i, b - x0 - r_i)``: a play that the sweep wipes out (``2 r_i <=
    b - a``) at ``a - x0 + r_i``, where Gamma is at the end of its identified displacement
    range that the lowest input reaches (the low end for a rising sensor); a larger play,
    which no input inside the range moves again, where the ascent to ``b`` left it.  A mode
    at rest.
``rest_high``
    At rest after a sweep down to ``a`` and up to ``b``: ``z_i = max(b - x0 - r_i,
    a - x0 + r_i)``.
``record``
    The identification record's start (``record_start.*``; a file without it: the states it
    holds, ``model.hysteresis.initial_states`` of an older file, else 0, the paper's (32)).
explicit states
    ``z_H0`` given, one per play [A], relative to the input offset as
    ``record_start.hysteresis.initial_states``; a mode at rest.

The identified range ``[a, b]`` is the record's current range (``model.identified_input_range``,
which ``identify`` writes, or the header it writes into a parameter file,
:mod:`mpi_ros.app.ranges`), else the closed form of the model's thresholds
(:func:`identified_ranges`); a compensator raises ``a`` to its lowest command and
lowers ``b`` to its highest: the sweep is the one its own commands can make.  (A start after a
descent from above every threshold, ``z_i = a - x0 + r_i`` for every play, is a state no input
inside the range reaches when ``2 r_i > b - a``: the largest play of a model identified on
0-1.8 A and driven within 0.2-1.8 A.  Its state stays for as long as the input stays inside
the range, an offset of ``w_i (a + 2 r_i - b)`` in H; in the wide sweep's offline loop, after
the sweep every plant gets, it made the plain compensator of a creep + lag plant track at
2.3-2.9 % of the range at orders 12-16 against 0.8-0.9 % from the sweep's state,
docs/diagnosis.md.)  A model that tells no range (hand-written thresholds, ``l = 0``) and has
no such limits starts at its record start.
"""

from dataclasses import dataclass
import math
from typing import Any

import numpy as np
import numpy.typing as npt

from ..errors import ModelError

__all__ = ['START_CHOICES', 'StartState', 'identified_ranges', 'rest_states', 'start_range']

FloatArray = npt.NDArray[np.float64]

#: The named starts (besides explicit states).
START_CHOICES = ('rest_low', 'rest_high', 'record')


def rest_states(gamma: Any, current: float, *, descent: bool = True,
                turn: float | None = None) -> FloatArray:
    """
    Return the play states at rest after a descent (or an ascent) to ``current``.

    Parameters
    ----------
    gamma : MPIModel
        The forward model (its thresholds and input offset).
    current : float
        The input reached [A].
    descent : bool
        True: coming down to ``current``; False: up to it.
    turn : float, optional
        Where the input turned before [A]: a descent from ``turn`` after an ascent to it
        (``z_i = min(u + r_i, t - r_i)``, ``t = turn - x0``), an ascent from ``turn`` after a
        descent (``z_i = max(u - r_i, t + r_i)``).  None: from beyond every threshold
        (``z_i = u + r_i`` or ``u - r_i``), with ``u = current - x0``.

    Returns
    -------
    ndarray of float, shape (n+1,)
        ``z_H0`` [A], relative to the input offset.

    Examples
    --------
    >>> from mpi_ros import MPIModel
    >>> gamma = MPIModel.from_params({
    ...     'model.hysteresis.thresholds': [0.0, 1.0], 'model.hysteresis.weights': [1.0, 0.5],
    ...     'model.superposition.thresholds': [0.0], 'model.superposition.weights': [1.0],
    ...     'model.input_offset': 2.0})
    >>> rest_states(gamma, 0.0).tolist(), rest_states(gamma, 4.0, descent=False).tolist()
    ([-2.0, -1.0], [2.0, 1.0])
    >>> rest_states(gamma, 0.0, turn=3.0).tolist()   # the play of r = 1 after 0 -> 3 -> 0 A
    ([-2.0, -1.0])
    >>> rest_states(gamma, 0.0, turn=1.5).tolist()   # ... after 1.5 -> 0 A: never wiped out
    ([-2.0, -1.5])

    """
    r = np.asarray(gamma.hysteresis.thresholds, dtype=np.float64)
    u = float(current) - float(gamma.input_offset)
    if turn is None:
        return np.asarray(u + r if descent else u - r, dtype=np.float64)
    t = float(turn) - float(gamma.input_offset)
    if descent:
        return np.asarray(np.minimum(u + r, t - r), dtype=np.float64)
    return np.asarray(np.maximum(u - r, t + r), dtype=np.float64)


def identified_ranges(gamma: Any, inverse: Any = None) -> tuple[
        tuple[float, float], tuple[float, float]] | None:
    """
    Return the current and displacement ranges a model was fitted on.

    A model that holds its record's input range (``model.identified_input_range``, which
    ``identify`` writes) gives it, and the displacement range its major loop over it reaches
    (so that commands clamped to the input range reach every displacement inside; a record
    whose output overshoots, ringing after steps, widens S' beyond it).  Otherwise the
    thresholds tell both.  ``identify`` spaces the thresholds of S' over the record's output
    range (29)-(31): the
    ``k`` thresholds of a branch end at ``(k - 1/2)/k`` of its extent.  The current range is
    where the major loop reaches the two ends: after a descent to ``a`` every play is at
    ``a - x0 + r_i``, after an ascent to ``b`` at ``b - x0 - r_i``, so with ``W = sum w_i``
    ``a = x0 + (S'[v_lo] - sum w_i r_i) / W`` and ``b = x0 + (S'[v_hi] + sum w_i r_i) / W``.

    Parameters
    ----------
    gamma : MPIModel
        The forward model.
    inverse : MPIModel, optional
        Its inverse, when already built (None: built here).

    Returns
    -------
    ((float, float), (float, float)) or None
        ``(a, b)`` [A] and the displacement range [m]; None when the model holds no range
        and the thresholds of S' are not spaced as (29)-(31) space them (written by hand, or
        ``l = 0``) or give no proper range.

    """
    known = getattr(gamma, 'identified_input_range', None)
    if known is not None:
        return _major_loop_reach(gamma, known)
    s_inv = (gamma.inverse() if inverse is None else inverse).superposition
    r = np.asarray(s_inv.thresholds, dtype=np.float64)
    positive, negative = r[r > 0.0], -r[r < 0.0][::-1]
    if not (positive.size or negative.size) or not all(
            _spaced_as_identified(branch) for branch in (positive, negative)):
        return None
    v_hi = float(positive[-1]) * positive.size / (positive.size - 0.5) if positive.size else 0.0
    v_lo = -float(negative[-1]) * negative.size / (negative.size - 0.5) if negative.size else 0.0
    h = gamma.hysteresis
    w = np.asarray(h.weights, dtype=np.float64)
    total, spread = float(np.sum(w)), float(np.sum(w * np.asarray(h.thresholds)))
    h_lo, h_hi = (float(v) for v in s_inv.apply(np.array([v_lo, v_hi])))
    a = gamma.input_offset + (h_lo - spread) / total
    b = gamma.input_offset + (h_hi + spread) / total
    ends = sorted(gamma.output_offset + gamma.output_sign * v for v in (v_lo, v_hi))
    if not (np.isfinite(a) and np.isfinite(b) and a < b and ends[0] < ends[1]):
        return None
    return (float(a), float(b)), (float(ends[0]), float(ends[1]))


def _major_loop_reach(gamma: Any, inputs: tuple[float, float]) -> tuple[
        tuple[float, float], tuple[float, float]] | None:
    # The input range and the displacements the major loop over it reaches: H at its two
    # ends (a play wider than the range keeps where the other end left it), then S.
    a, b = (float(v) for v in inputs)
    r = np.asarray(gamma.hysteresis.thresholds, dtype=np.float64)
    w = np.asarray(gamma.hysteresis.weights, dtype=np.float64)
    u_a, u_b = a - gamma.input_offset, b - gamma.input_offset
    v = np.array([float(np.dot(w, np.minimum(u_a + r, u_b - r))),
                  float(np.dot(w, np.maximum(u_b - r, u_a + r)))])
    reach = sorted(float(y) for y in gamma.output(v))
    return ((a, b), (reach[0], reach[1])) if reach[0] < reach[1] else None


def start_range(identified: tuple[float, float] | None,
                limits: tuple[float, float] | None = None) -> tuple[float, float] | None:
    """
    Return the currents a rest start may rest at: the identified range within the limits.

    Parameters
    ----------
    identified : (float, float) or None
        The identified current range [A]; None: unknown.
    limits : (float, float), optional
        The lowest and highest command allowed [A] (a compensator's ``output.min`` /
        ``output.max``).

    Returns
    -------
    (float, float) or None
        ``identified`` with each end moved inside ``limits``; None when unknown.

    Examples
    --------
    >>> start_range((-0.2, 2.5), (0.0, 2.0))
    (0.0, 2.0)

    """
    if identified is None:
        return None
    if limits is None:
        return float(identified[0]), float(identified[1])
    lo, hi = float(limits[0]), float(limits[1])
    return (min(max(float(identified[0]), lo), hi), min(max(float(identified[1]), lo), hi))


@dataclass(frozen=True)
class StartState:
    """
    Where a new input starts: a named start or explicit play states.

    Attributes
    ----------
    name : str
        ``'rest_low'``, ``'rest_high'``, ``'record'`` or ``'explicit'``.
    states : tuple of float
        The explicit ``z_H0`` [A] (empty for a named start).

    """

    name: str = 'rest_low'
    states: tuple[float, ...] = ()

    @classmethod
    def parse(cls, value: Any, *, option: str = 'start_state') -> 'StartState':
        """
        Read a start as the user writes it: a name, or play states.

        Parameters
        ----------
        value : str, sequence of float or StartState
            ``'rest_low'``, ``'rest_high'``, ``'record'``, or the explicit states as a
            sequence or as a text of numbers separated by commas (``'-1.5, -0.5, 0.5'``).
        option : str
            How the user names it, for the message (``--start``, ``start_state``).

        Returns
        -------
        StartState
            The start.

        Raises
        ------
        ModelError
            Neither a name nor finite numbers.

        Examples
        --------
        >>> StartState.parse('rest_high')
        StartState(name='rest_high', states=())
        >>> StartState.parse('-1, 0.5').states
        (-1.0, 0.5)

        """
        if isinstance(value, StartState):
            return value
        if isinstance(value, str):
            text = value.strip()
            if text in START_CHOICES:
                return cls(text)
            items: list[Any] = [part for part in text.replace(',', ' ').split() if part]
        else:
            items = list(value) if hasattr(value, '__iter__') else [value]
        try:
            states = tuple(float(item) for item in items if not isinstance(item, bool))
        except (TypeError, ValueError):
            states = ()
        if not items or len(states) != len(items) or not all(map(math.isfinite, states)):
            msg = (f'{option} must be one of {", ".join(START_CHOICES)} or the play states'
                   f' z_H0 [A] as numbers separated by commas (one per threshold of H);'
                   f' found {value!r}')
            raise ModelError(msg)
        return cls('explicit', states)

    @property
    def text(self) -> str:
        """Return the start as the user writes it (``rest_low``, or the numbers)."""
        if self.name != 'explicit':
            return self.name
        return ', '.join(repr(v) for v in self.states)

    def plays(self, gamma: Any, current_range: tuple[float, float] | None, *,
              strict: bool = True, unit: str = 'A') -> tuple[FloatArray, float | None, str]:
        """
        Return the play states of this start for a model, the current, and a description.

        Parameters
        ----------
        gamma : MPIModel
            The forward model; its ``hysteresis.initial_states`` is its record start.
        current_range : (float, float) or None
            The identified current range ``(a, b)`` [A] (already limited to the commands
            allowed); None: unknown (a rest start then falls back to the record start).
        strict : bool
            True: explicit states of another number of plays are refused; False: the record
            start is used instead, and the description says so (a running compensator's
            model arrives after its start was chosen).
        unit : str
            The input's unit in the description (``'A'``, or ``'V'`` for a voltage-driven
            actuator: ``model.input_quantity``); the numbers are the model's either way.

        Returns
        -------
        states : ndarray of float, shape (n+1,)
            ``z_H0`` [A].
        current : float or None
            The current of a rest start [A]; None for the record or explicit states.
        description : str
            The start in words, for a note or a log line.

        Raises
        ------
        ModelError
            Explicit states whose number differs from the model's plays (``strict``).

        """
        record = np.array(gamma.hysteresis.initial_states, dtype=np.float64)
        if self.name == 'explicit':
            msg = (f'start_state gives {len(self.states)} play states; the model has'
                   f' {record.size} plays (thresholds of H): give one state per play,'
                   f' or rest_low, rest_high or record')
            if len(self.states) == record.size:
                return np.array(self.states), None, f'explicit play states [{self.text}] {unit}'
            if strict:
                raise ModelError(msg)
            return record, None, f"record: the model's record start ({msg})"
        if self.name == 'record' or current_range is None:
            why = ('' if self.name == 'record' else
                   f' ({self.name} asked, but the model tells no identified input range)')
            return record, None, f"record: the model's record start{why}"
        low = self.name == 'rest_low'
        current = float(current_range[0] if low else current_range[1])
        turn = float(current_range[1] if low else current_range[0])
        words = ((f'up to the highest identified input, {turn:.6g} {unit}, and down to the'
                  f' lowest, {current:.6g} {unit}') if low else
                 (f'down to the lowest identified input, {turn:.6g} {unit}, and up to the'
                  f' highest, {current:.6g} {unit}'))
        return (rest_states(gamma, current, descent=low, turn=turn), current,
                f'{self.name}: at rest after a sweep {words}')


def _spaced_as_identified(branch: FloatArray) -> bool:
    # (30)-(31): the k thresholds of a branch, ascending, are (i - 1/2)/k of its extent,
    # i.e. 1, 3, 5, ... times the first (an empty branch: the output never went there).
    if not branch.size:
        return True
    odd = 2.0 * np.arange(branch.size) + 1.0
    return bool(np.allclose(branch, odd * branch[0], rtol=1e-6, atol=0.0))
