# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
The one identification pipeline: recording + data options + order -> fitted model.

``mpi-ros identify``, the identifier node and the diagnosis' reading all go through
:func:`mpi_ros.recordings.read_recording` with one :class:`~mpi_ros.recordings.DataOptions`;
:func:`fit_recording` adds the fit with :func:`mpi_ros.identification.identify` (its design,
refusals and order selection), so a bag or CSV gives the same model whichever tool reads it.

:func:`fit_bag` is the identifier node's fit of one actuator (the model as parameters,
:class:`BagFit`); :func:`fit_bag_axes` fits every axis of a multi-axis bag, the axes in
parallel in a process pool.
"""

from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass, replace
import multiprocessing
import os
import signal
from typing import Any

from .errors import DataError, IdentificationError, MPIError, ParameterRejected
from .identification import IdentificationResult, identify
from .order import Order, parse_order as parse_order_text
from .params import MODEL_KEYS, OPERATING_POINT_KEYS
from .recordings import DataOptions, read_recording, Recording

__all__ = ['BagFit', 'RecordingFit', 'STOP_SIGNALS', 'fit_bag', 'fit_bag_axes',
           'fit_recording', 'parse_order']

#: The signals that stop a run (a node, or the workers of :func:`fit_bag_axes`).
STOP_SIGNALS = (signal.SIGINT, signal.SIGTERM)


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


@dataclass(frozen=True)
class BagFit:
    """
    A model fitted from a bag.

    Attributes
    ----------
    result : mpi_ros.identification.IdentificationResult
        The fit: ``.model``, ``.order``, ``.nonlinearity_error`` (37), ``.rms_error``,
        ``.samples``, solver status.
    parameters : dict of str to list of float, float or int
        ``result.model.to_params()``: the five ``model.*`` arrays of Gamma and the three
        operating point keys.

    """

    result: IdentificationResult
    parameters: dict[str, Any]

    def summary(self) -> str:
        """
        Describe the fit in one line.

        Returns
        -------
        str
            Orders, sample count and errors in percent.

        """
        n, l_s = self.result.order
        return (f'fitted order n={n}, l={l_s} on {self.result.samples} samples: '
                f'nonlinearity error {100.0 * self.result.nonlinearity_error:.3f} %, '
                f'relative RMS error {100.0 * self.result.rms_error:.3f} %')


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


def fit_bag(path: str, *, input_topic: str = '/current_command',
            output_topic: str = '/displacement', order: Order = 'auto',
            options: DataOptions | None = None) -> BagFit:
    """
    Read a bag, fit an MPI model and compute its errors on the same data.

    Parameters
    ----------
    path : str
        rosbag2 bag (directory or file), or a CSV file.
    input_topic, output_topic : str
        Topics of the current [A] and of the displacement [m] (used when
        `options` is None).
    order : 'auto' or tuple of (int, int)
        Model orders (n, l), or automatic selection.
    options : mpi_ros.recordings.DataOptions, optional
        Every data option (topics, joints, fields, indices, scales); default:
        the two topics with the other options at their defaults.

    Returns
    -------
    BagFit
        The model as parameters, with its errors.

    Raises
    ------
    mpi_ros.errors.DataError
        When the bag is unreadable or the topics are missing or unusable.
    mpi_ros.errors.IdentificationError
        When the fit fails or identify refuses the data (the message says why).

    """
    if options is None:
        options = DataOptions(input_topic=input_topic, output_topic=output_topic,
                              spelling='parameter')
    fit = fit_recording(path, options, order=order)          # the one pipeline (CLI too)
    result = fit.result
    parameters = result.model.to_params()
    expected = MODEL_KEYS + OPERATING_POINT_KEYS
    if set(parameters) != set(expected):
        msg = f'identify returned parameters {sorted(parameters)}; expected {list(expected)}'
        raise IdentificationError(msg)
    return BagFit(result=result, parameters=parameters)


def fit_bag_axes(path: str, axes: int, *, options: DataOptions | None = None,
                 order: Order = 'auto', workers: int = 0) -> list[BagFit]:
    """
    Fit one model per axis of a multi-axis bag (Float64MultiArray topics).

    Each message holds one sample of every axis, or a chunk of K samples x N axes
    (``layout.dim`` = samples x axes, as the multi-axis nodes publish it, or K x N values
    without ``dim``, as they also accept it); the chunk
    sizes of the input and output topics may differ.  How the samples of a chunk are
    timed: :func:`mpi_ros.recordings.read_bag_signals` (``options.sample_period``).

    Parameters
    ----------
    path : str
        rosbag2 bag.
    axes : int
        Number of axes; axis k is element (chunk column) k of the input and the output
        topic, and must be < N for chunked messages.
    options : mpi_ros.recordings.DataOptions, optional
        Topics, scales, ...; topics left at the single-axis defaults become
        ``/current_commands`` and ``/displacements``.  The indices are set per axis, and
        ``array_axes`` to `axes`: a message without ``layout.dim`` must hold K x `axes`
        values (K samples of every axis), as the multi-axis nodes read it.
    order : 'auto' or tuple of (int, int)
        Model orders, for every axis.
    workers : int
        Processes fitting axes in parallel: 0 = one per CPU (at most one per axis), 1 =
        in this process.

    Returns
    -------
    list of BagFit
        One fit per axis, in axis order.

    Raises
    ------
    mpi_ros.errors.DataError, mpi_ros.errors.IdentificationError
        As :func:`fit_bag`, the message prefixed with the axis.

    """
    options = options or DataOptions(spelling='parameter')
    defaults = DataOptions()
    if options.array_axes not in (None, axes):
        msg = (f'{options.name("array_axes")} is {options.array_axes} but axes is {axes}; '
               f'leave {options.name("array_axes")} unset (it follows axes) or make them equal')
        raise DataError(msg)
    changes: dict[str, Any] = {'array_axes': axes}
    if options.input_topic == defaults.input_topic:
        changes['input_topic'] = '/current_commands'
    if options.output_topic == defaults.output_topic:
        changes['output_topic'] = '/displacements'
    per_axis = [replace(options, input_index=axis, output_index=axis, **changes)
                for axis in range(axes)]
    count = min(axes, os.cpu_count() or 1) if workers == 0 else min(workers, axes)
    if count <= 1:
        return [_fit_axis(path, axis, opts, order) for axis, opts in enumerate(per_axis)]
    # spawn, not fork: this process runs DDS threads (a forked child could inherit a
    # lock held by one of them).  The workers ignore SIGINT/SIGTERM (Ctrl-C reaches the
    # whole process group): this process stops, cancels what has not started and waits
    # for the fits under way, so a stop leaves no traceback and no process behind.
    pool = ProcessPoolExecutor(max_workers=count, mp_context=multiprocessing.get_context(
        'spawn'), initializer=_ignore_stop_signals)
    try:
        futures = [pool.submit(_fit_axis, path, axis, opts, order)
                   for axis, opts in enumerate(per_axis)]
        return [future.result() for future in futures]
    finally:
        pool.shutdown(wait=True, cancel_futures=True)


def parse_order(text: str) -> Order:
    """
    Parse the ``order`` parameter with :func:`mpi_ros.order.parse_order`.

    Parameters
    ----------
    text : str
        ``auto``, ``N,L`` or ``N L``, with N >= 1 and L >= 1.

    Returns
    -------
    str or tuple of (int, int)
        ``'auto'`` or ``(n, l)``.

    Raises
    ------
    mpi_ros.errors.ParameterRejected
        For anything else; the message names ``order``.

    """
    try:
        return parse_order_text(text, option='order')
    except IdentificationError as err:
        raise ParameterRejected(str(err)) from err


def _ignore_stop_signals() -> None:
    for signum in STOP_SIGNALS:
        signal.signal(signum, signal.SIG_IGN)


def _fit_axis(path: str, axis: int, options: DataOptions, order: Order) -> BagFit:
    try:
        return fit_bag(path, options=options, order=order)
    except MPIError as err:
        msg = (f'axis {axis} (element or column {axis} of {options.input_topic}, '
               f'{options.output_topic}):')
        raise type(err)(f'{msg} {err}') from err
