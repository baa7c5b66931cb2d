# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
The one identification pipeline: recording + data options + order -> fitted model.

``mpi-ros identify``, the identifier node and the diagnosis' reading all go through
:func:`mpi_ros.recordings.read_recording` with one :class:`~mpi_ros.recordings.DataOptions`;
:func:`fit_recording` adds the fit with :func:`mpi_ros.identification.identify` (its design,
refusals and order selection), so a bag or CSV gives the same model whichever tool reads it.
"""

from dataclasses import dataclass
import os
from typing import Any

from .identification import IdentificationResult, identify
from .order import Order
from .recordings import DataOptions, read_recording, Recording

__all__ = ['RecordingFit', 'fit_recording']


@dataclass(frozen=True)
class RecordingFit:
    """
    A recording and the model identified from it.

    Attributes
    ----------
    recording : Recording
        The data as read (time [s], current [A], displacement [m]).
    result : IdentificationResult
        The fit (model with its operating point, errors, order table).

    """

    recording: Recording
    result: IdentificationResult


def fit_recording(source: 'str | os.PathLike[str] | Recording',
                  options: DataOptions | None = None, *, order: Order = 'auto',
                  anchor: str = 'operating_point', **identify_options: Any) -> RecordingFit:
    """
    Read a bag or CSV (or take a recording) and identify the MPI model.

    Parameters
    ----------
    source : str, PathLike or Recording
        rosbag2 bag (directory or file), CSV file, or an already read recording.
    options : DataOptions, optional
        Topics, joints, fields, indices, columns, scales (defaults: ``/current_command``
        and ``/displacement``, Float64).
    order : 'auto' or (int, int)
        Model orders, or the automatic selection.
    anchor : {'operating_point', 'origin'}
        See :func:`mpi_ros.identification.identify`.
    **identify_options
        Further keywords of :func:`~mpi_ros.identification.identify` (``epsilon``,
        ``holdout``, ``dynamics``, ``periodic``; ``time`` defaults to the recording's).

    Returns
    -------
    RecordingFit
        The recording and the fit.

    Raises
    ------
    DataError
        Unreadable data or options that do not fit it.
    IdentificationError
        When the identification refuses the data (the message says why and what to do).

    """
    if isinstance(source, Recording):
        recording = source
    else:
        recording = read_recording(source, options if options is not None else DataOptions())
    # The record's time base lets the identification measure and model lag and dead time
    # (a CSV without a time column has none: its time is the sample index).
    identify_options.setdefault('time', recording.time if recording.timed else None)
    result = identify(recording.current, recording.displacement, order=order, anchor=anchor,
                      **identify_options)
    return RecordingFit(recording, result)
