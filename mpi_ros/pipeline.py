# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
The one identification pipeline: recording + data options + order -> fitted model.

``mpi-ros identify``, the identifier node and the diagnosis' reading all go through
:func:`mpi_ros.recordings.read_recording` with one :class:`~mpi_ros.recordings.DataOptions`;
:func:`fit_recording` adds the fit with :func:`mpi_ros.model_fit.identify` (its design,
refusals and order selection), so a bag or CSV gives the same model whichever tool reads it.

:func:`fit_bag` is the identifier node's fit of one actuator (the model as parameters,
:class:`BagFit`); :func:`fit_bag_axes` fits every axis of a multi-axis bag, the axes in
parallel in a process pool.

Identification from a bag as the identifier node runs it (its parameters are
:mod:`mpi_ros.node_parameters.identifier`), one run (:func:`identify_bag`): read the bag,
fit one axis or N, report, write the parameter YAML if asked, and return the parameters
to push.
The push is the ROS side's (:mod:`mpi_ros.nodes.identifier`).
"""

from collections.abc import Callable, Mapping
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass, replace
import multiprocessing
import os
import signal
from typing import Any, Dict, List, Tuple

import numpy as np

from .errors import DataError, IdentificationError, MPIError
from .model_fit import IdentificationResult, identify
from .node_parameters import axis_key, LIMIT_KEYS
from .node_parameters.identifier import DATA_NAMES, parse_order
from .operators.model import MODEL_KEYS, OPERATING_POINT_KEYS, RECORD_START_STATES
from .order import format_order, Order
from .params import write_params_yaml
from .recordings import DataOptions, read_recording, Recording
from .stop_signals import STOP_SIGNALS
from .units import INPUT_QUANTITY_KEY

__all__ = ['BagFit', 'RecordingFit', 'diagnosed_parameters', 'fit_bag',
           'fit_bag_axes', 'LIMITS_COMMENT', 'fit_recording', 'identified_parameters',
           'identify_bag']

#: The comment a parameter file gets above the output limits :func:`identified_parameters` sets.
LIMITS_COMMENT = ('output.min / output.max: the input range the actuator was driven over '
                  'during identification\n(the model extrapolates outside it); narrow them to '
                  'the safe range of your actuator')


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
    result : mpi_ros.model_fit.IdentificationResult
        The fit: ``.model``, ``.order``, ``.nonlinearity_error`` (37), ``.rms_error``,
        ``.samples``, solver status.
    parameters : dict of str to list of float, float or int
        ``result.full_model.to_params()``: the four ``model.*`` arrays of Gamma, the three
        operating point keys, the keys of the dynamics the fit found (dead time, lag,
        output mode) and the record start ``record_start.*``, exactly the model ``mpi-ros
        identify`` writes.
    written : dict of str to value
        Everything ``mpi-ros identify`` writes for this record
        (:func:`identified_parameters`): `parameters` and the output limits; what the
        identifier pushes.
    warnings : tuple of str
        Scales of the record that look wrong (:func:`mpi_ros.units.scale_warnings`).
    diagnosis : str
        With ``diagnose``: what the diagnosis found and which model is delivered.

    """

    result: IdentificationResult
    parameters: dict[str, Any]
    written: dict[str, Any]
    warnings: tuple[str, ...] = ()
    diagnosis: str = ''

    def summary(self) -> str:
        """
        Describe the fit in one line.

        Returns
        -------
        str
            Orders, sample count and errors in percent.

        """
        n, l_s = self.result.order
        cause = getattr(self.result.full_model, 'cause', None)
        carried = f'; the model carries {cause}' if cause else ''
        return (f'fitted order n={n}, l={l_s} on {self.result.samples} samples: '
                f'nonlinearity error {100.0 * self.result.nonlinearity_error:.3f} %, '
                f'relative RMS error {100.0 * self.result.rms_error:.3f} %{carried}')


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
        See :func:`mpi_ros.model_fit.identify`.
    **identify_options
        Further keywords of :func:`~mpi_ros.model_fit.identify` (``epsilon``,
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
            options: DataOptions | None = None, diagnosed: bool = False) -> BagFit:
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
    diagnosed : bool
        Also run :func:`mpi_ros.diagnosis.diagnose` on the record (blocked validation:
        the first 60 % trains, the rest validates) and, when it names an effect with a
        clear gain (not weak, not tied), deliver its extended model instead of the
        identified one (:func:`diagnosed_parameters`).

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
    written = identified_parameters(result, fit.recording)
    diagnosis = ''
    if diagnosed:
        written, diagnosis = diagnosed_parameters(fit.recording, written, order=order)
    parameters = {key: value for key, value in written.items()
                  if key not in LIMIT_KEYS and key != INPUT_QUANTITY_KEY}
    missing = [key for key in MODEL_KEYS + OPERATING_POINT_KEYS + (RECORD_START_STATES,)
               if key not in parameters]
    if missing:
        msg = f'identify returned parameters {sorted(parameters)}; missing {missing}'
        raise IdentificationError(msg)
    return BagFit(result=result, parameters=parameters, written=written,
                  warnings=fit.recording.warnings, diagnosis=diagnosis)


def diagnosed_parameters(recording: Recording, written: Mapping[str, Any], *,
                         order: Order = 'auto') -> Tuple[Dict[str, Any], str]:
    """
    Replace an identified model by the extended model a diagnosis names with a clear gain.

    Parameters
    ----------
    recording : Recording
        The record the model was identified on.
    written : mapping
        :func:`identified_parameters` of it.
    order : 'auto' or (int, int)
        The model orders.

    Returns
    -------
    parameters : dict
        `written` when the diagnosis names no effect, a weak one, a tie or data outside the
        invertible class; else the diagnosed model's keys (Gamma refitted on the training
        part with the extension, validated on the rest) with the limits and the input
        quantity of `written`.
    sentence : str
        What the diagnosis found and what is delivered.

    """
    from .diagnosis import diagnose
    report = diagnose(recording, order=order)
    decision = report.decision
    clear = (report.model is not None and report.cause not in ('none', 'outside_invertible_class')
             and decision.get('strength') == 'clear' and not decision.get('ambiguous'))
    if not clear:
        why = ('tied with ' + ', '.join(decision.get('tied_with', []))
               if decision.get('ambiguous') else str(decision.get('strength', 'none')))
        return dict(written), (f'diagnosis: {report.cause} ({why}, validation gain '
                               f'{report.gain:.3f}): the identified model is delivered')
    parameters = dict(report.parameters())
    parameters.update({key: value for key, value in written.items()
                       if key in LIMIT_KEYS or key == INPUT_QUANTITY_KEY})
    return parameters, (f'diagnosis: {report.cause}, clear (validation gain '
                        f'{report.gain:.3f}): its extended model is delivered')


def identified_parameters(result: IdentificationResult,
                          recording: Recording | None = None) -> dict[str, Any]:
    """
    Return every key ``mpi-ros identify`` writes and the identifier node pushes.

    One function for both, so that a key the identification learns to write (a new
    effect, a start-state policy) reaches the running compensator without a second edit.

    Parameters
    ----------
    result : IdentificationResult
        The fit.
    recording : Recording, optional
        The record it was fitted on; gives the output limits.

    Returns
    -------
    dict
        ``result.full_model.to_params()`` (Gamma, the operating point and the keys of the
        dynamics found: ``model.dead_time``, ``model.rate_dependence.*``,
        ``model.resonance.*``), and with a recording ``model.input_quantity`` (``current``
        or ``voltage``, from the input's unit, :mod:`mpi_ros.units`) and ``output.min`` /
        ``output.max``: the input range the actuator was driven over during
        identification [A or V], the range the model knows (a command outside it
        extrapolates the model).

    """
    parameters = dict(result.full_model.to_params())
    if recording is not None:
        parameters[INPUT_QUANTITY_KEY] = recording.units.input_quantity
    if recording is not None and len(recording):
        current = np.asarray(recording.current, dtype=np.float64)
        low, high = float(np.min(current)), float(np.max(current))
        if low < high:
            parameters['output.min'], parameters['output.max'] = low, high
    return parameters


def fit_bag_axes(path: str, axes: int, *, options: DataOptions | None = None,
                 order: Order = 'auto', workers: int = 0,
                 diagnosed: bool = False) -> list[BagFit]:
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
    diagnosed : bool
        Diagnose each axis too (see :func:`fit_bag`).

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
        return [_fit_axis(path, axis, opts, order, diagnosed)
                for axis, opts in enumerate(per_axis)]
    # spawn, not fork: this process runs DDS threads (a forked child could inherit a
    # lock held by one of them).  The workers ignore SIGINT/SIGTERM (Ctrl-C reaches the
    # whole process group): this process stops, cancels what has not started and waits
    # for the fits under way, so a stop leaves no traceback and no process behind.
    pool = ProcessPoolExecutor(max_workers=count, mp_context=multiprocessing.get_context(
        'spawn'), initializer=_ignore_stop_signals)
    try:
        futures = [pool.submit(_fit_axis, path, axis, opts, order, diagnosed)
                   for axis, opts in enumerate(per_axis)]
        return [future.result() for future in futures]
    finally:
        pool.shutdown(wait=True, cancel_futures=True)


def _ignore_stop_signals() -> None:
    for signum in STOP_SIGNALS:
        signal.signal(signum, signal.SIG_IGN)


def _fit_axis(path: str, axis: int, options: DataOptions, order: Order,
              diagnosed: bool = False) -> BagFit:
    try:
        return fit_bag(path, options=options, order=order, diagnosed=diagnosed)
    except MPIError as err:
        msg = (f'axis {axis} (element or column {axis} of {options.input_topic}, '
               f'{options.output_topic}):')
        raise type(err)(f'{msg} {err}') from err


# --- the identifier node's run ---

def identify_bag(values: Mapping[str, Any], *, info: Callable[[str], Any],
                 error: Callable[[str], Any], warn: Callable[[str], Any] | None = None
                 ) -> Tuple['BagFit | List[BagFit]', Dict[str, Any]]:
    """
    Fit, report, and write the YAML if asked: one identifier run up to the push.

    Parameters
    ----------
    values : mapping
        The identifier's parameter values (:data:`PARAMETERS`).
    info, error : callable
        Log a line (the node's logger).
    warn : callable, optional
        Log a warning (scales that look wrong); default: `info`.

    Returns
    -------
    fitted : BagFit or list of BagFit
        The fit (one per axis when ``axes`` > 1).
    parameters : dict
        The model keys to push (``axis<k>.model.*`` when ``axes`` > 1).

    Raises
    ------
    mpi_ros.errors.MPIError
        ``DataError`` (no or unreadable bag), ``IdentificationError`` (fit refused,
        logged through ``error`` first).

    """
    bag = values['bag']
    if not bag:
        msg = 'no bag given; run with --ros-args -p bag:=PATH'
        raise DataError(msg)
    options = DataOptions.from_mapping({name: values[name] for name in DATA_NAMES},
                                       spelling='parameter')
    order = parse_order(values['order'])
    axes = values['axes']
    if axes > 1:
        info(f'identifying {axes} axes from {bag}, order {format_order(order)}')
    else:
        info(f'identifying from {bag} ({options.input_topic} -> '
             f'{options.output_topic}, order {format_order(order)})')
    try:
        fitted: 'BagFit | List[BagFit]' = (
            fit_bag_axes(bag, axes, options=options, order=order, workers=values['workers'],
                         diagnosed=values['diagnose'])
            if axes > 1 else fit_bag(bag, options=options, order=order,
                                     diagnosed=values['diagnose']))
    except IdentificationError as err:
        error(f'identification refused the data of {bag}: {err}; no model was '
              'written or pushed')
        raise
    for fit in fitted if isinstance(fitted, list) else [fitted]:
        for warning in fit.warnings:
            (warn or info)(warning)
        if fit.diagnosis:
            info(fit.diagnosis)
    if isinstance(fitted, list):
        parameters: Dict[str, Any] = {}
        for axis, fit in enumerate(fitted):
            info(f'axis {axis}: {fit.summary()}')
            parameters.update({axis_key(axis, key): v for key, v in fit.written.items()})
        written = dict(parameters, axes=axes)
        header = f'mpi_ros identifier: {axes} axes\nbag: {bag}\n{LIMITS_COMMENT}'
    else:
        info(fitted.summary())
        parameters = written = fitted.written
        header = f'mpi_ros identifier: {fitted.summary()}\nbag: {bag}\n{LIMITS_COMMENT}'
    params_file = values['params_file']
    if params_file:
        write_params_yaml(params_file, written, node_name='compensator', header=header)
        info(f'wrote {params_file}')
    return fitted, parameters
