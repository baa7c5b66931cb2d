# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Output limits that fit the model: the range a model was identified on, and what the limits cut.

A compensator clamps every command to ``[output.min, output.max]`` (the node's parameters,
``mpi-ros compensate``'s ``--output-min`` / ``--output-max`` or the file's keys).  A model
identified on inputs outside those limits cannot reach part of the displacement range it
was identified on: a piezo model identified on -90 to 90 V under the node's default 0 to
2 A limits answers desired -10, 0, 10 um with 0, 2, 2.  :func:`limits_shortfall` says how
much of the identified displacement range such limits leave unreachable; the compensator
nodes log it (WARN) at configure and at every accepted model or limits update and report it
on /diagnostics, ``mpi-ros compensate`` prints it.  ``mpi-ros identify`` writes
``output.min`` / ``output.max`` as the identified input range, so its files pushed as they
are never trigger it.

What a model knows of its identification record (:func:`identified_range`):

- **Displacement.** :func:`mpi_ros.model_fit.identify` places the thresholds of the
  inverse superposition operator S' over the record's output range, (29)-(31): the largest
  of ``l`` positive thresholds is ``(l - 1/2)/l`` of the output's extent above the operating
  point ``y0`` (and the same below), so the output range follows from them exactly.
- **Input.** The plays' thresholds give the input's extent, but the operating point ``x0``
  is shifted by the QP's constant term, so not where it lies.  The input range is
  therefore taken as the inputs at which the model's major loop reaches the two ends of
  its displacement range: after a descent to ``a`` every play is at ``a - x0 + r_i``, after
  an ascent to ``b`` at ``b - x0 - r_i``, so (with ``W = sum w_i`` and S' the inverse of S)
  ``a = x0 + (S'[v_lo] - sum w_i r_i) / W`` and ``b = x0 + (S'[v_hi] + sum w_i r_i) / W``.
- A model whose S' thresholds are not spaced as (29)-(31) space them (a model written by
  hand, or ``l = 0``) does not tell its range: None.
"""

from dataclasses import dataclass
from typing import Any


from .compensator import gamma_of
from .screening import operating_range
from ..operators.start import identified_ranges

__all__ = ['IdentifiedRange', 'LimitsShortfall', 'UNREACHABLE_TOLERANCE', 'identified_range',
           'limits_shortfall']

#: Smallest unreachable fraction of the identified displacement range that is reported: the
#: identified input range is the recorded one to about 1 % of its span at orders (8, 4) and
#: up, 4 % at (2, 1) (synthetic records, docs/benchmarks.md), so smaller cuts are not news.
UNREACHABLE_TOLERANCE = 0.05


@dataclass(frozen=True)
class IdentifiedRange:
    """
    The current and displacement ranges a model was identified on (None: unknown).

    Attributes
    ----------
    current : (float, float) or None
        Lowest and highest current [A].
    displacement : (float, float) or None
        Lowest and highest displacement [m].

    """

    current: tuple[float, float] | None = None
    displacement: tuple[float, float] | None = None


@dataclass(frozen=True)
class LimitsShortfall:
    """
    Output limits that do not contain the input range a model was identified on.

    Attributes
    ----------
    identified : (float, float)
        The input range the model was identified on [A, or V for a voltage-driven actuator].
    limits : (float, float)
        ``output.min`` and ``output.max``.
    displacement : (float, float)
        The displacement range the model was identified on [m].
    reachable : (float, float)
        The displacement range the model reaches inside the limits [m].
    unreachable : float
        Fraction of the identified displacement range outside ``reachable`` (0 to 1).

    """

    identified: tuple[float, float]
    limits: tuple[float, float]
    displacement: tuple[float, float]
    reachable: tuple[float, float]
    unreachable: float

    def describe(self, unit: str = 'A', names: str = 'output.min / output.max') -> str:
        """
        Say what the limits cut, and what to do.

        Parameters
        ----------
        unit : str
            Unit of the input (``'A'`` or ``'V'``).
        names : str
            How the limits are named (``'output.min / output.max'``, ``'--output-min /
            --output-max'``).

        Returns
        -------
        str
            One sentence.

        """
        (a, b), (lo, hi) = self.identified, self.limits
        (d_lo, d_hi), (r_lo, r_hi) = self.displacement, self.reachable
        return (f'the model was identified on inputs {a:.4g} to {b:.4g} {unit}, not inside '
                f'{names} {lo:.4g} to {hi:.4g} {unit}: {100.0 * self.unreachable:.3g} % of '
                f'its displacement range {d_lo:.4g} to {d_hi:.4g} m is unreachable (the '
                f'limits reach {r_lo:.4g} to {r_hi:.4g} m); set {names} to the safe range '
                'of the actuator (mpi-ros identify writes the identified range)')


def identified_range(model: Any) -> IdentifiedRange:
    """
    Return the current and displacement ranges a model's thresholds say it was fitted on.

    Parameters
    ----------
    model : MPIModel or extended model
        A forward model (an extended model's Gamma is used).

    Returns
    -------
    IdentifiedRange
        Both ranges, or None for both when the thresholds of S' are not spaced as
        (29)-(31) space them (a model written by hand, or ``l = 0``), or give no proper
        range (see the module docstring).

    """
    found = identified_ranges(gamma_of(model))
    return IdentifiedRange() if found is None else IdentifiedRange(*found)


def limits_shortfall(model: Any, output_min: float, output_max: float,
                     recorded: tuple[float, float] | None = None) -> LimitsShortfall | None:
    """
    Tell whether limits cut the range a model was identified on, and by how much.

    Parameters
    ----------
    model : MPIModel or extended model
        A forward model (an extended model's Gamma is used).
    output_min, output_max : float
        The command limits [A].
    recorded : (float, float), optional
        The input range the record held (``identify`` writes it in the parameter file's
        header): the identified input range, and the displacement range is what Gamma
        reaches over it.  By default both come from :func:`identified_range`: the model's
        own input range (``model.identified_input_range``) where it holds one.

    Returns
    -------
    LimitsShortfall or None
        None when the identified input range lies inside the limits, the limits leave less
        than :data:`UNREACHABLE_TOLERANCE` of the identified displacement range
        unreachable, or the model does not tell its range (:func:`identified_range`).

    Notes
    -----
    From the thresholds, the displacement range is the one S' spans, (29)-(31): a record
    whose output overshoots (a step at its start, ringing) widens it beyond what the
    recorded inputs reach through Gamma (TUM's 20 Hz capture: -143 to 90 V for a record
    of -90 to 90 V); such a cut is reported too, since desired displacements in it are
    clamped.  With the recorded range, only what the recorded inputs reach counts.

    Examples
    --------
    A model identified on 0 to 2 A under limits 0 to 1 A:

    >>> from mpi_ros.operators.model import MPIModel
    >>> model = MPIModel.from_params({
    ...     'model.hysteresis.thresholds': [0.0, 0.5], 'model.hysteresis.weights': [1.0, 0.2],
    ...     'model.hysteresis.initial_states': [0.0, 0.0],
    ...     'model.superposition.thresholds': [-0.75, -0.25, 0.0, 0.25, 0.75],
    ...     'model.superposition.weights': [0.0, 0.0, 1e-5, 0.0, 0.0]})
    >>> limits_shortfall(model, -10.0, 10.0) is None
    True
    >>> 0.0 < limits_shortfall(model, 0.0, 0.1).unreachable < 1.0
    True

    """
    if recorded is not None:
        a, b = float(recorded[0]), float(recorded[1])
        if not a < b:
            return None
        d_lo, d_hi = operating_range(gamma_of(model), a, b)
    else:
        known = identified_range(model)
        if known.current is None or known.displacement is None:
            return None
        (a, b), (d_lo, d_hi) = known.current, known.displacement
    tolerance = 1e-9 * (b - a)
    if output_min <= a + tolerance and b - tolerance <= output_max:
        return None
    if not d_lo < d_hi:
        return None
    r_lo, r_hi = operating_range(gamma_of(model), output_min, output_max)
    overlap = max(0.0, min(d_hi, r_hi) - max(d_lo, r_lo))
    unreachable = min(1.0, max(0.0, 1.0 - overlap / (d_hi - d_lo)))
    if unreachable < UNREACHABLE_TOLERANCE:
        return None
    return LimitsShortfall((a, b), (float(output_min), float(output_max)), (d_lo, d_hi),
                           (r_lo, r_hi), unreachable)
