# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
The :class:`Recording` type: paired actuator input/output samples.

An MPI model Γ = S∘H (26) is identified from pairs of samples of the actuator
input x (coil current [A]) and output s (displacement [m]); every reader of
:mod:`mpi_ros.recordings` returns them as a :class:`Recording`.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
import os
from typing import Union

import numpy as np
import numpy.typing as npt

from .options import DataOptions
from ..errors import DataError
from ..units import resolve_units, scale_warnings, SignalUnits

__all__ = ['MIN_SAMPLES', 'MAGNITUDE_LIMIT', 'Recording', 'join_recordings', 'PathLike',
           'FloatArray', 'check_magnitudes', 'in_si']

PathLike = Union[str, 'os.PathLike[str]']
FloatArray = npt.NDArray[np.float64]

#: Smallest number of paired samples a recording must hold to be usable.
MIN_SAMPLES = 10

#: Largest magnitude of a sample, and the inverse of the smallest non-zero span of a signal,
#: that the fit's arithmetic handles (in SI units after the scales): squares and sums of
#: squares of such values stay normal floats.  1e-12..1e12 (pm to Tm) is far inside.
MAGNITUDE_LIMIT = 1e100


@dataclass(frozen=True, eq=False)
class Recording:
    """
    Paired input/output samples of one actuator experiment.

    The arrays are converted to read-only ``float64`` copies on construction.

    Parameters
    ----------
    time : ndarray of float, shape (N,)
        Sample times [s]. Bags give times relative to the first paired sample;
        CSV files give the time column as written (times its scale).
    current : ndarray of float, shape (N,)
        Actuator input x at each sample [A] (for a generic actuator: its input,
        in the input's unit).
    displacement : ndarray of float, shape (N,)
        Actuator output s at each sample [m] (for a generic actuator: its
        output, in the output's unit).
    source : str
        Where the samples come from (the file or bag path).
    notes : tuple of str
        What the reader changed or noticed (dropped, sorted or duplicate
        samples), one sentence each; empty when the data was clean.
    timed : bool
        False when the record has no time base (a CSV file without a time column: ``time``
        is then the sample index); the identification then estimates no dynamics.
    units : SignalUnits
        The units the signals were recorded in (the arrays are in SI: s, A or V, m); its
        ``input_quantity`` is ``'current'`` or ``'voltage'``.
    warnings : tuple of str
        Scales that look wrong (:func:`mpi_ros.units.scale_warnings`), one sentence each.

    Raises
    ------
    DataError
        If the arrays are not one-dimensional numbers of equal length.

    Examples
    --------
    >>> rec = Recording([0.0, 0.1], [0.0, 0.5], [0.0, 1e-6], source='demo')
    >>> len(rec), rec.current.flags.writeable
    (2, False)

    """

    time: FloatArray
    current: FloatArray
    displacement: FloatArray
    source: str = ''
    notes: tuple[str, ...] = ()
    timed: bool = True
    units: SignalUnits = SignalUnits()
    warnings: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        """Validate and freeze the arrays."""
        lengths = {}
        for name in ('time', 'current', 'displacement'):
            try:
                arr = np.array(getattr(self, name), dtype=np.float64)
            except (TypeError, ValueError) as err:
                msg = f'Recording.{name} must be an array of numbers; {err}'
                raise DataError(msg) from err
            if arr.ndim != 1:
                msg = (f'Recording.{name} must be one-dimensional; found shape {arr.shape}; '
                       'pass one sample per element')
                raise DataError(msg)
            arr.flags.writeable = False
            object.__setattr__(self, name, arr)
            lengths[name] = arr.size
        if len(set(lengths.values())) != 1:
            msg = (f'Recording arrays must have equal lengths; found {lengths}; '
                   'pair the samples before building a Recording')
            raise DataError(msg)
        object.__setattr__(self, 'source', str(self.source))
        object.__setattr__(self, 'notes', tuple(str(note) for note in self.notes))
        object.__setattr__(self, 'timed', bool(self.timed))
        object.__setattr__(self, 'warnings', tuple(str(w) for w in self.warnings))

    def __len__(self) -> int:
        """Return the number of samples N."""
        return int(self.time.size)


def join_recordings(recordings: Sequence[Recording], *, gap: float = 1.0) -> Recording:
    """
    Join separate experiments of one actuator into one record, a time gap between them.

    Each following record's clock is shifted to start ``gap`` seconds (at least 1000 of its
    sample intervals) after the previous record's last sample, so the identification sees a
    time gap and fits each experiment with its own start state (its segments).

    Parameters
    ----------
    recordings : sequence of Recording
        The experiments, in order; at least one.
    gap : float
        Time [s] between one record's last sample and the next one's first.

    Returns
    -------
    Recording
        The joined record (the first one itself when there is only one).

    Raises
    ------
    DataError
        Without recordings, or when one has no time base (its samples have no clock to
        separate the experiments with).

    """
    if not recordings:
        msg = 'join_recordings needs at least one recording'
        raise DataError(msg)
    if len(recordings) == 1:
        return recordings[0]
    untimed = [r.source for r in recordings if not r.timed]
    if untimed:
        msg = (f'{", ".join(untimed)}: no time column; experiments are joined on their clocks,'
               ' give each file its time column (--time-column)')
        raise DataError(msg)
    times = [recordings[0].time]
    for rec in recordings[1:]:
        steps = np.diff(rec.time)
        typical = float(np.median(steps)) if steps.size else 0.0
        start = float(times[-1][-1]) + max(gap, 1000.0 * typical)
        times.append(rec.time - float(rec.time[0]) + start)
    return Recording(np.concatenate(times),
                     np.concatenate([r.current for r in recordings]),
                     np.concatenate([r.displacement for r in recordings]),
                     source=' + '.join(r.source for r in recordings),
                     notes=tuple(n for r in recordings for n in r.notes),
                     units=recordings[0].units,
                     warnings=tuple(w for r in recordings for w in r.warnings))


def check_magnitudes(recording: Recording, options: DataOptions | None = None) -> Recording:
    """
    Refuse a recording whose values a fit cannot compute with; return it otherwise.

    Parameters
    ----------
    recording : Recording
        As read, after the scales.
    options : DataOptions, optional
        The scales, named in the message in ``options.spelling`` (default: the
        keyword spelling, scales 1).

    Returns
    -------
    Recording
        `recording` itself.

    Raises
    ------
    DataError
        If a sample exceeds :data:`MAGNITUDE_LIMIT` in magnitude (or is not finite: a
        scale made it overflow), or a signal that varies spans less than its inverse (its
        squared differences would overflow or underflow to 0, and every error measure with
        them).

    """
    options = DataOptions() if options is None else options
    for name, scale, unit in (('time', 'time_scale', 's'), ('current', 'input_scale', 'A'),
                              ('displacement', 'output_scale', 'm')):
        values = getattr(recording, name)
        if values.size == 0:
            continue
        largest = float(np.max(np.abs(values)))
        span = float(np.max(values) - np.min(values)) if largest <= MAGNITUDE_LIMIT else 0.0
        if not largest <= MAGNITUDE_LIMIT:              # NaN or Inf: the scale overflowed
            problem = f'reaches {largest:.3g} {unit}, too large'
        elif 0.0 < span < 1.0 / MAGNITUDE_LIMIT:
            problem = f'spans only {span:.3g} {unit}, too small'
        else:
            continue
        msg = (f'{recording.source}: the {name} {problem} to compute with (its squares leave '
               f'the floating-point range; magnitudes up to {MAGNITUDE_LIMIT:g} and spans '
               f'from {1.0 / MAGNITUDE_LIMIT:g} are handled); check the column or topic, or '
               f'rescale it to {unit} with {options.setting(scale, "<factor>")} (now '
               f'{getattr(options, scale):g})')
        raise DataError(msg)
    return recording


def in_si(recording: Recording, options: DataOptions, *, time_name: str = '',
          input_name: str = '', output_name: str = '') -> Recording:
    """
    Convert a recording read with the scales to SI by the units of :mod:`mpi_ros.units`.

    Parameters
    ----------
    recording : Recording
        As read, the scales applied.
    options : DataOptions
        The scales and the stated units.
    time_name, input_name, output_name : str
        The signals' names (CSV columns, or topics with their joints; '' for a bag's log
        time).

    Returns
    -------
    Recording
        The same samples in s, A or V, and m, with ``units`` and the ``warnings`` of scales
        that look wrong.

    """
    units = resolve_units(time_name, input_name, output_name, time_scale=options.time_scale,
                          input_scale=options.input_scale, output_scale=options.output_scale,
                          time_unit=options.time_unit if time_name else None,
                          input_unit=options.input_unit, output_unit=options.output_unit)
    time = recording.time * units.time_factor if recording.timed else recording.time
    displacement = recording.displacement * units.output_factor
    current = recording.current * units.input_factor
    warnings = scale_warnings(time, displacement, timed=recording.timed, units=units,
                              option={name: options.name(name)
                                      for name in ('output_unit', 'time_unit', 'input_unit')},
                              current=current)
    return Recording(time, current, displacement,
                     source=recording.source, notes=recording.notes, timed=recording.timed,
                     units=units, warnings=tuple(warnings))
