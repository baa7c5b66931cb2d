# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Time constants that the record's time base makes implausible, as one warning.

A smart-material actuator shows dead times and rate lags of microseconds to milliseconds
(:data:`~mpi_ros.extensions.effect.FAST_TIME_LIMIT`) and creep and thermal time constants
of seconds to an hour or so (``SLOW_TIME_LIMIT`` there).  Every
time constant a diagnosis reports is measured in the record's time base, so a time
column written in ms (or us) and read as s inflates each of them a thousand (million)
times: a 20.6 ms dead time becomes "20.6 s", the creep lags of a 60 s record reach
"1.2e5 s".  Such values are not refused (a record can be slow, a fit can be wrong): the
diagnosis reports them in one warning that names them, gives the record's sample period
and duration, and says what to do (``--time-scale 1e-3``, or not to trust them).
"""

from collections.abc import Mapping, Sequence
import math
from typing import Any

import numpy as np
import numpy.typing as npt

from ..extensions import EFFECTS
from ..extensions.effect import FAST_TIME_LIMIT

__all__ = ['implausible_dynamics', 'implausible_time_constants', 'time_base_warning']

#: A reported time constant: (what it is, value [s], largest plausible value [s]).
TimeConstant = tuple[str, float, float]


def implausible_time_constants(candidates: Sequence[Mapping[str, Any]],
                               residual: Mapping[str, Any]) -> list[TimeConstant]:
    """
    Return the time constants of a diagnosis that exceed what an actuator shows.

    Parameters
    ----------
    candidates : sequence of Mapping
        The diagnosis' candidates (``cause`` and ``parameters``); each effect's parameters
        with a ``plausible_max`` (:class:`~mpi_ros.extensions.effect.EffectParameter`)
        are checked, a list by its largest element.
    residual : Mapping
        The diagnosis' residual structure: ``lag_of_best_correlation`` and the burst
        signature's ``delay`` and ``lag_time_constant`` are checked against
        :data:`~mpi_ros.extensions.effect.FAST_TIME_LIMIT`.

    Returns
    -------
    list of (str, float, float)
        What each implausible value is, the value [s] and its plausible maximum [s].

    """
    found: list[TimeConstant] = []
    for candidate in candidates:
        effect = EFFECTS.get(candidate.get('cause', ''))
        if effect is None:
            continue
        parameters = candidate.get('parameters', {})
        for parameter in effect.parameters:
            if parameter.plausible_max is None or parameter.unit != 's':
                continue
            values = np.atleast_1d(np.asarray(parameters.get(parameter.key, []), dtype=float))
            if values.size and float(np.max(values)) > parameter.plausible_max:
                largest = ' (largest)' if values.size > 1 else ''
                found.append((f'{parameter.key}{largest} of the {candidate["cause"]} candidate',
                              float(np.max(values)), parameter.plausible_max))
    lags = [('lag of the best rate correlation', residual.get('lag_of_best_correlation'))]
    bursts = residual.get('burst_signature') or {}
    lags += [('burst delay', bursts.get('delay')),
             ('burst lag time constant', bursts.get('lag_time_constant'))]
    for what, value in lags:
        if value is not None and math.isfinite(value) and abs(value) > FAST_TIME_LIMIT:
            found.append((what, abs(float(value)), FAST_TIME_LIMIT))
    return found


def implausible_dynamics(estimate: Any) -> list[TimeConstant]:
    """
    Return the dead time and lag of an identification that exceed what an actuator shows.

    Parameters
    ----------
    estimate : DynamicsEstimate
        :attr:`mpi_ros.model_fit.IdentificationResult.dynamics_estimate`: the best
        dead time and lag time constant of its trials (modelled or not) [s].

    Returns
    -------
    list of (str, float, float)
        What each implausible value is, the value [s] and its plausible maximum [s]
        (:data:`~mpi_ros.extensions.effect.FAST_TIME_LIMIT`).

    """
    found: list[TimeConstant] = []
    for what, value in (('dead time', getattr(estimate, 'dead_time', 0.0)),
                        ('lag time constant', getattr(estimate, 'lag_time_constant', 0.0))):
        if math.isfinite(value) and value > FAST_TIME_LIMIT:
            found.append((what, float(value), FAST_TIME_LIMIT))
    return found


def time_base_warning(found: Sequence[TimeConstant],
                      records: Sequence[tuple[str, npt.NDArray[np.float64]]], *,
                      command: str = 'diagnose') -> str | None:
    """
    Word one warning about implausible time constants and the time base behind them.

    Parameters
    ----------
    found : sequence of (str, float, float)
        From :func:`implausible_time_constants`.
    records : sequence of (str, ndarray of float, shape (N,))
        Name and sample times [s] of each record the values come from (training,
        validation).
    command : str
        The command to run again with ``--time-scale`` (``diagnose`` or ``identify``).

    Returns
    -------
    str or None
        The warning (one line), or None when nothing is implausible.

    Examples
    --------
    >>> import numpy as np
    >>> text = time_base_warning([('dead time', 20.6, 1.0)],
    ...                          [('training record', np.arange(60001.0))])
    >>> text.startswith('dead time 20.6 s (plausible: up to 1 s) is implausible')
    True

    """
    if not found:
        return None
    values = ', '.join(f'{what} {value:.3g} s (plausible: up to {limit:g} s)'
                       for what, value, limit in found)
    bases = []
    for name, time in records:
        if time.size >= 2:
            period = float(np.median(np.diff(time)))
            span = float(time[-1] - time[0])
            bases.append(f'the {name} has a sample period of {period:.3g} s and lasts'
                         f' {span:.3g} s ({time.size} samples)')
    base = '; '.join(bases) or 'the record is too short to tell its sample period'
    verb = 'is' if len(found) == 1 else 'are'
    return (f'{values} {verb} implausible for a smart-material actuator (dead times and rate'
            f' lags are us to ms, creep and thermal time constants at most about an hour);'
            f' {base}: a time column in ms (or us) read as s gives such values - if so,'
            f' pass --time-scale 1e-3 (us: 1e-6) and {command} again; if the time really is in'
            ' s, do not trust these time constants')
