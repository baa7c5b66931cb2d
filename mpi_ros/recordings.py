# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Recorded actuator signals: rosbag2 bags and CSV files.

An MPI model Γ = S∘H (26) is identified from pairs of samples of the actuator
input x (coil current [A]) and output s (displacement [m]). This module reads
such pairs from rosbag2 bags (sqlite3 or mcap, through rosbags) and from CSV
files into a :class:`Recording`, writes them back, and provides the atomic
file writes every command-line output goes through.

The module is ROS-free: it uses the pure-Python ``rosbags`` library and never
imports ``rclpy``, so bags can be read and written on machines without ROS.

Every problem with a file or its content raises :class:`~mpi_ros.errors.DataError`
with a message naming the file, the topic or column, what was found and what to
do about it.
"""

from __future__ import annotations

import contextlib
import csv
from dataclasses import dataclass
import functools
import inspect
import numbers
import os
from pathlib import Path
import re
import shutil
import tempfile
import threading
from typing import Any, Callable, IO, Iterator, Mapping, Sequence, Union

import numpy as np
import numpy.typing as npt
from rosbags.rosbag2 import Reader, StoragePlugin, Writer
from rosbags.typesys import get_typestore, Stores

from .errors import DataError

__all__ = [
    'MIN_SAMPLES',
    'Recording',
    'BagRecorder',
    'read_signals',
    'read_bag_signals',
    'write_bag_signals',
    'read_csv_signals',
    'read_csv_table',
    'write_csv_columns',
    'atomic_write',
]

PathLike = Union[str, 'os.PathLike[str]']
FloatArray = npt.NDArray[np.float64]

#: Smallest number of paired samples a recording must hold to be usable.
MIN_SAMPLES = 10

_FLOAT64 = 'std_msgs/msg/Float64'
_STORAGES = {'sqlite3': StoragePlugin.SQLITE3, 'mcap': StoragePlugin.MCAP}
_BAG_SUFFIXES = ('.db3', '.mcap')
_TIME_SOURCES = ('receive',)
# A decimal number as written by numeric software; float() alone would also take
# '1_000', non-ASCII digits and surrounding whitespace.
_NUMBER = re.compile(
    r'[+-]?(?:(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?|nan|inf|infinity)', re.IGNORECASE)


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

    def __len__(self) -> int:
        """Return the number of samples N."""
        return int(self.time.size)


class BagRecorder:
    """
    Stream two ``std_msgs/msg/Float64`` topics into a new rosbag2 bag.

    Messages go into a temporary bag beside `path`; :meth:`close` moves the
    finished bag to `path` in one rename, :meth:`abort` (or an exception inside
    a ``with`` block) discards it. A crash therefore never leaves a
    half-written bag at `path`. The writes are serialised by a lock, so the
    recorder may be fed from several executor threads.

    Parameters
    ----------
    path : str or os.PathLike
        Bag directory to create.
    input_topic : str, optional
        Topic of the actuator input x (current [A]).
    output_topic : str, optional
        Topic of the actuator output s (displacement [m]).
    storage : {'sqlite3', 'mcap'}, optional
        rosbag2 storage plugin.
    overwrite : bool, optional
        Replace an existing bag at `path` on :meth:`close`; by default an
        existing `path` is an error.

    Raises
    ------
    DataError
        If `storage` is unknown or the topics are empty or equal.

    Notes
    -----
    Times are given in seconds and stored as integer nanoseconds, rounded. A
    float64 time since the Unix epoch resolves about 0.24 µs, which is far
    below the sample period of any actuator loop.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> bag = pathlib.Path(tempfile.mkdtemp()) / 'run'
    >>> with BagRecorder(bag) as rec:
    ...     rec.write_input(0.0, 0.5)
    ...     rec.write_output(0.001, 2e-6)
    >>> rec.counts
    {'/current_command': 1, '/displacement': 1}

    """

    def __init__(
        self,
        path: PathLike,
        *,
        input_topic: str = '/current_command',
        output_topic: str = '/displacement',
        storage: str = 'sqlite3',
        overwrite: bool = False,
    ) -> None:
        self._path = Path(path)
        self._plugin = _storage_plugin(storage)
        _check_topics(input_topic, output_topic)
        self._topics = (input_topic, output_topic)
        self._overwrite = bool(overwrite)
        self._lock = threading.Lock()
        self._writer: Writer | None = None
        self._tmpdir: Path | None = None
        self._connections: dict[str, Any] = {}
        self._counts = {input_topic: 0, output_topic: 0}
        self._finished = False

    @property
    def path(self) -> Path:
        """Target bag directory."""
        return self._path

    @property
    def is_open(self) -> bool:
        """Whether the recorder accepts messages."""
        return self._writer is not None

    @property
    def counts(self) -> dict[str, int]:
        """Messages written so far, per topic (a copy)."""
        return dict(self._counts)

    def open(self) -> None:  # noqa: A003 (the rosbags Writer/Reader verb)
        """
        Create the temporary bag and register both topics.

        Raises
        ------
        DataError
            If the recorder was opened before, the target's directory is
            missing, the target exists (without `overwrite`) or the bag cannot
            be created.

        """
        with self._lock:
            if self._writer is not None or self._finished:
                msg = (f'BagRecorder for {self._path} was already opened; '
                       'create a new BagRecorder for each bag')
                raise DataError(msg)
            _check_target(self._path, overwrite=self._overwrite, kind='bag')
            tmpdir = _make_tmpdir(self._path)
            writer: Writer | None = None
            try:
                writer = Writer(tmpdir / self._path.name, version=Writer.VERSION_LATEST,
                                storage_plugin=self._plugin)
                writer.open()
                for topic in self._topics:
                    self._connections[topic] = writer.add_connection(
                        topic, _FLOAT64, typestore=_typestore())
            except Exception as err:  # rosbags, sqlite3 and OS errors alike
                if writer is not None:
                    with contextlib.suppress(Exception):
                        writer.abort()
                shutil.rmtree(tmpdir, ignore_errors=True)
                msg = f'cannot create bag {self._path}: {type(err).__name__}: {err}'
                raise DataError(msg) from err
            self._writer = writer
            self._tmpdir = tmpdir

    def write_input(self, t: float, value: float) -> None:
        """
        Record one input sample.

        Parameters
        ----------
        t : float
            Log (receive) time [s], at least 0.
        value : float
            Actuator input x [A].

        Raises
        ------
        DataError
            If the recorder is not open or `t` is negative or not finite.

        """
        self._write(self._topics[0], _seconds_to_ns(t, what='write_input time t'), value)

    def write_output(self, t: float, value: float) -> None:
        """
        Record one output sample.

        Parameters
        ----------
        t : float
            Log (receive) time [s], at least 0.
        value : float
            Actuator output s [m].

        Raises
        ------
        DataError
            If the recorder is not open or `t` is negative or not finite.

        """
        self._write(self._topics[1], _seconds_to_ns(t, what='write_output time t'), value)

    def close(self) -> None:
        """
        Finish the bag and move it to the target path.

        Closing a recorder that is not open does nothing.

        Raises
        ------
        DataError
            If the bag cannot be finished or moved; nothing is left at the
            target path then (an existing bag there is kept).

        """
        with self._lock:
            writer, tmpdir = self._writer, self._tmpdir
            if writer is None or tmpdir is None:
                return
            self._writer, self._tmpdir, self._finished = None, None, True
            try:
                try:
                    writer.close()
                except Exception as err:  # rosbags, sqlite3 and OS errors alike
                    with contextlib.suppress(Exception):
                        writer.abort()
                    msg = f'cannot finish bag {self._path}: {type(err).__name__}: {err}'
                    raise DataError(msg) from err
                _install(tmpdir / self._path.name, self._path, overwrite=self._overwrite)
            finally:
                shutil.rmtree(tmpdir, ignore_errors=True)

    def abort(self) -> None:
        """Discard everything written; the target path is left untouched."""
        with self._lock:
            writer, tmpdir = self._writer, self._tmpdir
            self._writer, self._tmpdir, self._finished = None, None, True
            if writer is not None:
                with contextlib.suppress(Exception):
                    writer.abort()
            if tmpdir is not None:
                shutil.rmtree(tmpdir, ignore_errors=True)

    def __enter__(self) -> BagRecorder:
        """Open the recorder."""
        self.open()
        return self

    def __exit__(self, exc_type: Any, exc: Any, tb: Any) -> None:
        """Close the recorder, or abort it when the block raised."""
        if exc_type is None:
            self.close()
        else:
            self.abort()

    def _write(self, topic: str, stamp: int, value: float) -> None:
        try:
            number = float(value)
        except (TypeError, ValueError) as err:
            msg = f'value for topic {topic} must be a number; found {value!r}'
            raise DataError(msg) from err
        store = _typestore()
        data = store.serialize_cdr(store.types[_FLOAT64](data=number), _FLOAT64)
        with self._lock:
            if self._writer is None:
                msg = (f'BagRecorder for {self._path} is not open; call open() first '
                       'or use it as a context manager')
                raise DataError(msg)
            self._writer.write(self._connections[topic], stamp, data)
            self._counts[topic] += 1


def read_signals(path: PathLike, **options: Any) -> Recording:
    """
    Read a recording from a bag or a CSV file, chosen by the path.

    Parameters
    ----------
    path : str or os.PathLike
        A bag directory, a ``.db3``/``.mcap`` storage file or its
        ``metadata.yaml`` (read by :func:`read_bag_signals`), or a ``.csv``
        file (read by :func:`read_csv_signals`).
    **options
        Keyword options of the chosen reader; options of the other reader are
        rejected.

    Returns
    -------
    Recording
        The paired samples.

    Raises
    ------
    DataError
        If the path is missing, of an unknown kind, an option does not apply
        to that kind of file, or the reader rejects the data.

    """
    source = Path(path)
    if not source.exists():
        msg = f'{source} does not exist; check the path'
        raise DataError(msg)
    reader: Callable[..., Recording]
    is_bag = source.is_dir() or source.suffix.lower() in _BAG_SUFFIXES
    if is_bag or source.name == 'metadata.yaml':
        reader, kind = read_bag_signals, 'rosbag2 bag'
    elif source.suffix.lower() == '.csv':
        reader, kind = read_csv_signals, 'CSV file'
    else:
        msg = (f'{source}: unknown file type {source.suffix!r}; expected a rosbag2 bag '
               '(directory, .db3 or .mcap) or a .csv file')
        raise DataError(msg)
    accepted = [name for name, par in inspect.signature(reader).parameters.items()
                if par.kind is inspect.Parameter.KEYWORD_ONLY]
    unknown = sorted(set(options) - set(accepted))
    if unknown:
        msg = (f'option(s) {", ".join(unknown)} do not apply to {kind} {source}; '
               f'options for a {kind}: {", ".join(accepted)}')
        raise DataError(msg)
    return reader(source, **options)


def read_bag_signals(
    path: PathLike,
    *,
    input_topic: str = '/current_command',
    output_topic: str = '/displacement',
    time_source: str = 'receive',
    drop_nonfinite: bool = False,
) -> Recording:
    """
    Read the input and output topics of a rosbag2 bag as paired samples.

    Both topics must carry ``std_msgs/msg/Float64``. Each output message is
    paired with the most recent input message logged at or before it
    (zero-order hold): the displacement measured at time t responds to the
    last command sent before t. Output messages logged before the first input
    message have no command and are dropped.

    Parameters
    ----------
    path : str or os.PathLike
        Bag directory (with ``metadata.yaml``), its ``metadata.yaml``, or a
        single ``.db3``/``.mcap`` storage file. A directory without
        ``metadata.yaml`` but with exactly one storage file (a recording that
        was interrupted) is read from that file, with a note.
    input_topic : str, optional
        Topic of the actuator input x (current [A]).
    output_topic : str, optional
        Topic of the actuator output s (displacement [m]).
    time_source : {'receive'}, optional
        Which time stamps the samples: ``'receive'`` is the bag's log time.
        ``std_msgs/msg/Float64`` carries no header stamp, so it is the only
        source available.
    drop_nonfinite : bool, optional
        Drop NaN/Inf messages (with a note) instead of raising.

    Returns
    -------
    Recording
        ``time`` [s] relative to the first paired sample, ``current`` [A]
        (the held input), ``displacement`` [m], ``source`` = the path and
        ``notes`` on what was dropped, sorted or de-duplicated.

    Raises
    ------
    DataError
        If the path is missing or not a bag; the bag is truncated or corrupt;
        a topic is missing (the message lists the topics present), has the
        wrong type, no message or a single one; a topic holds NaN/Inf (without
        `drop_nonfinite`); or fewer than :data:`MIN_SAMPLES` samples pair up.

    Notes
    -----
    Log times t_k [ns] are sorted stably per topic; of several messages with
    the same time stamp the last one read is kept and the duplicates are
    counted in ``notes``. With input times τ_j and output times t_k the pairs
    are (x(τ_j*), s(t_k)) with j* = max{j : τ_j ≤ t_k}.

    """
    bag = Path(path)
    if time_source not in _TIME_SOURCES:
        msg = (f'time_source must be one of {_TIME_SOURCES}; found {time_source!r}; '
               f'{_FLOAT64} has no header stamp, so only the bag log time is available')
        raise DataError(msg)
    _check_topics(input_topic, output_topic)
    storage_path, notes = _locate_bag(bag)
    raw = _read_bag_topics(bag, storage_path, (input_topic, output_topic))
    t_in, x_in = _clean_topic(bag, input_topic, *raw[input_topic],
                              drop_nonfinite=drop_nonfinite, notes=notes)
    t_out, s_out = _clean_topic(bag, output_topic, *raw[output_topic],
                                drop_nonfinite=drop_nonfinite, notes=notes)
    held = np.searchsorted(t_in, t_out, side='right') - 1
    paired = held >= 0
    n_early = int(np.count_nonzero(~paired))
    if n_early:
        notes.append(f'dropped {n_early} {output_topic} message(s) logged before the first '
                     f'{input_topic} message')
    n_paired = int(np.count_nonzero(paired))
    if n_paired < MIN_SAMPLES:
        msg = (f'bag {bag}: only {n_paired} {output_topic} message(s) at or after the first '
               f'{input_topic} message (need at least {MIN_SAMPLES}); record longer, and start '
               'the recording before the actuator runs so both topics are captured')
        raise DataError(msg)
    t_out, s_out, x_held = t_out[paired], s_out[paired], x_in[held[paired]]
    time = (t_out - t_out[0]).astype(np.float64) * 1e-9
    return Recording(time, x_held, s_out, source=str(bag), notes=tuple(notes))


def write_bag_signals(
    path: PathLike,
    time: npt.ArrayLike,
    current: npt.ArrayLike,
    displacement: npt.ArrayLike,
    *,
    input_topic: str = '/current_command',
    output_topic: str = '/displacement',
    storage: str = 'sqlite3',
    overwrite: bool = False,
) -> None:
    """
    Write paired samples to a new rosbag2 bag that :func:`read_bag_signals` reads back.

    At each time t_k the input is logged at t_k and the output 1 ns later, so
    the zero-order-hold pairing of the reader restores the pairs exactly.

    Parameters
    ----------
    path : str or os.PathLike
        Bag directory to create (atomically, see :class:`BagRecorder`).
    time : array_like of float, shape (N,)
        Sample times [s], at least 0 and strictly increasing by at least 2 ns.
    current : array_like of float, shape (N,)
        Actuator input x [A].
    displacement : array_like of float, shape (N,)
        Actuator output s [m].
    input_topic : str, optional
        Topic for `current`.
    output_topic : str, optional
        Topic for `displacement`.
    storage : {'sqlite3', 'mcap'}, optional
        rosbag2 storage plugin.
    overwrite : bool, optional
        Replace an existing bag at `path`.

    Raises
    ------
    DataError
        If the arrays are not one-dimensional of equal length, the times are
        negative, not finite or not increasing by at least 2 ns, or the bag
        cannot be written. Nothing is left at `path` on failure.

    """
    arrays = _equal_length_arrays(
        {'time': time, 'current': current, 'displacement': displacement},
        what='write_bag_signals')
    stamps = _seconds_to_ns_array(arrays['time'])
    if stamps.size > 1 and np.any(np.diff(stamps) < 2):
        first = int(np.flatnonzero(np.diff(stamps) < 2)[0]) + 1
        msg = (f'write_bag_signals: time must increase by at least 2 ns per sample; '
               f'sample {first} is at {arrays["time"][first]!r} s after '
               f'{arrays["time"][first - 1]!r} s; sort the samples and remove duplicates')
        raise DataError(msg)
    recorder = BagRecorder(path, input_topic=input_topic, output_topic=output_topic,
                           storage=storage, overwrite=overwrite)
    with recorder:
        for stamp, x, s in zip(stamps.tolist(), arrays['current'].tolist(),
                               arrays['displacement'].tolist()):
            recorder._write(input_topic, stamp, x)
            recorder._write(output_topic, stamp + 1, s)


def read_csv_signals(
    path: PathLike,
    *,
    input_column: str | None = None,
    output_column: str | None = None,
    time_column: str | None = 'time',
    input_scale: float = 1.0,
    output_scale: float = 1.0,
    time_scale: float = 1.0,
    comment: str | None = '#',
    drop_nonfinite: bool = False,
) -> Recording:
    """
    Read input and output columns of a CSV file with a header row.

    Lines starting with `comment` (after leading blanks) and blank lines are
    skipped; the first other line is the header. Only the time, input and
    output columns must be numeric; other columns may hold text.

    Parameters
    ----------
    path : str or os.PathLike
        CSV file (UTF-8, comma-separated, optional quotes).
    input_column : str, optional
        Column of the actuator input; default: the first column that is not
        the time column.
    output_column : str, optional
        Column of the actuator output; default: the first column after the
        input column that is not the time column.
    time_column : str or None, optional
        Column of the sample times; None if the file has none, in which case
        ``time`` is the sample index 0, 1, 2, ... (a note says so).
    input_scale : float, optional
        Factor converting the input column to A (to the input's SI unit).
    output_scale : float, optional
        Factor converting the output column to m, e.g. 1e-9 for nm.
    time_scale : float, optional
        Factor converting the time column to s, e.g. 1e-3 for ms.
    comment : str or None, optional
        Prefix of comment lines; None to disable.
    drop_nonfinite : bool, optional
        Drop rows with NaN/Inf in the used columns (with a note) instead of
        raising.

    Returns
    -------
    Recording
        ``time`` [s] as written times `time_scale`, ``current`` [A],
        ``displacement`` [m], ``source`` = the path, ``notes``.

    Raises
    ------
    DataError
        If the file is missing, empty, not UTF-8 or has no header row; a named
        column is missing (the message lists those present); a used field is
        not a number (the message gives line and column); rows are ragged;
        fewer than :data:`MIN_SAMPLES` rows remain; or a used field is NaN/Inf
        (without `drop_nonfinite`).

    Examples
    --------
    The measured PZT files write time in s, voltage in V and displacement in nm::

        rec = read_csv_signals('SLOW_table03_TEST_800V.csv', time_column='Time_s',
                               input_column='Vplus_V', output_column='D1_nm',
                               output_scale=1e-9)

    """
    source = Path(path)
    scales = {'input_scale': input_scale, 'output_scale': output_scale,
              'time_scale': time_scale}
    for name, value in scales.items():
        number = isinstance(value, numbers.Real) and not isinstance(value, bool)
        if not number or not np.isfinite(value) or value == 0:
            msg = f'{name} must be a finite non-zero number; found {value!r}'
            raise DataError(msg)
    table = _read_csv_rows(source, comment=comment)
    if time_column is not None:
        _column_index(table, time_column, option='time_column')
    candidates = [name for name in table.header if name != time_column]
    if input_column is None:
        if not candidates:
            msg = (f'CSV file {source} has no column besides the time column {time_column!r}; '
                   'add input and output columns')
            raise DataError(msg)
        input_column = candidates[0]
    i_in = _column_index(table, input_column, option='input_column')
    if output_column is None:
        after = [name for name in table.header[i_in + 1:] if name != time_column]
        if not after:
            msg = (f'CSV file {source}: no column after the input column {input_column!r} to '
                   f'use as output; pass output_column= (available: {_names(table.header)})')
            raise DataError(msg)
        output_column = after[0]
    i_out = _column_index(table, output_column, option='output_column')
    if i_out == i_in:
        msg = (f'CSV file {source}: input_column and output_column are both '
               f'{input_column!r}; choose two different columns')
        raise DataError(msg)
    used = {'input': i_in, 'output': i_out}
    if time_column is not None:
        used['time'] = _column_index(table, time_column, option='time_column')
    _check_row_count(table, len(table.rows))
    values = {role: _parse_column(table, index) for role, index in used.items()}
    notes: list[str] = []
    keep = _nonfinite_rows(table, values, used, drop_nonfinite=drop_nonfinite, notes=notes)
    values = {role: column[keep] for role, column in values.items()}
    n_rows = int(np.count_nonzero(keep))
    _check_row_count(table, n_rows, after_drop=n_rows != len(table.rows))
    if time_column is None:
        time = np.arange(n_rows, dtype=np.float64)
        notes.append('no time column: time is the sample index 0, 1, 2, ...')
    else:
        time = values['time'] * time_scale
        steps = np.diff(time)
        if np.any(steps <= 0):
            first = int(np.flatnonzero(steps <= 0)[0]) + 1
            line = np.asarray(table.line_numbers)[keep][first]
            notes.append(f'time column {time_column!r} is not strictly increasing (first at '
                         f'line {line}); samples are kept in file order')
    return Recording(time, values['input'] * input_scale, values['output'] * output_scale,
                     source=str(source), notes=tuple(notes))


def read_csv_table(
    path: PathLike,
    *,
    comment: str | None = '#',
    drop_nonfinite: bool = False,
) -> tuple[list[str], FloatArray]:
    """
    Read a CSV file whose columns are all numeric.

    Used by the command line: the input signal is the first column not named
    ``time``; a ``time`` column passes through to the output file.

    Parameters
    ----------
    path : str or os.PathLike
        CSV file with a header row.
    comment : str or None, optional
        Prefix of comment lines; None to disable.
    drop_nonfinite : bool, optional
        Drop rows holding NaN/Inf (instead of raising).

    Returns
    -------
    header : list of str
        Column names, in file order.
    table : ndarray of float, shape (N, M)
        The values, one row per data line, in the units of the file.

    Raises
    ------
    DataError
        If the file is missing, empty or has no header; it has no column
        besides ``time``; a field is not a number (line and column named);
        rows are ragged; there is no data row; or a value is NaN/Inf (without
        `drop_nonfinite`).

    """
    source = Path(path)
    table = _read_csv_rows(source, comment=comment)
    if not [name for name in table.header if name != 'time']:
        msg = (f'CSV file {source} has no column besides the time column; add a column '
               'with the input signal')
        raise DataError(msg)
    if not table.rows:
        msg = f'CSV file {source} has a header but no data rows; add the samples'
        raise DataError(msg)
    columns = {name: _parse_column(table, index) for index, name in enumerate(table.header)}
    used = {name: index for index, name in enumerate(table.header)}
    notes: list[str] = []
    keep = _nonfinite_rows(table, columns, used, drop_nonfinite=drop_nonfinite, notes=notes)
    if not np.any(keep):
        msg = f'CSV file {source}: every row holds NaN/Inf; no data left'
        raise DataError(msg)
    data = np.column_stack([columns[name][keep] for name in table.header])
    return list(table.header), data.astype(np.float64)


def write_csv_columns(
    path: PathLike,
    columns: Mapping[str, npt.ArrayLike],
    *,
    comment: str | None = None,
) -> None:
    """
    Write equal-length columns to a CSV file atomically.

    Values are written with the shortest representation that reads back to
    the same float64 (``repr``), so a write/read round trip is exact.

    Parameters
    ----------
    path : str or os.PathLike
        CSV file to create or replace (see :func:`atomic_write`).
    columns : mapping of str to array_like of float, shape (N,)
        Column name → values, in column order. Names must be non-empty and
        hold no comma, quote or line break.
    comment : str, optional
        Text written first, each line prefixed with ``'# '`` (e.g. provenance).

    Raises
    ------
    DataError
        If there are no columns, a name is invalid, the columns differ in
        length or are not one-dimensional numbers, or the file cannot be
        written.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> out = pathlib.Path(tempfile.mkdtemp()) / 'out.csv'
    >>> write_csv_columns(out, {'time': [0.0, 0.5], 'current': [0.1, 0.2]})
    >>> print(out.read_text(), end='')
    time,current
    0.0,0.1
    0.5,0.2

    """
    target = Path(path)
    if not columns:
        msg = f'write_csv_columns({target}): no columns given; pass at least one column'
        raise DataError(msg)
    for name in columns:
        valid = isinstance(name, str) and bool(name) and name == name.strip()
        if not valid or any(char in name for char in ',"\r\n#'):
            msg = (f'write_csv_columns({target}): invalid column name {name!r}; use a '
                   'non-empty name without commas, quotes, line breaks or a leading #')
            raise DataError(msg)
    arrays = _equal_length_arrays(dict(columns), what=f'write_csv_columns({target})')
    rows = np.column_stack(list(arrays.values())).tolist() if arrays else []
    with atomic_write(target) as handle:
        if comment is not None:
            for line in str(comment).splitlines() or ['']:
                handle.write(f'# {line}'.rstrip() + '\n')
        handle.write(','.join(arrays) + '\n')
        handle.writelines(','.join(map(repr, row)) + '\n' for row in rows)


@contextlib.contextmanager
def atomic_write(path: PathLike, *, binary: bool = False) -> Iterator[IO[Any]]:
    """
    Open a file for writing that appears at `path` only when complete.

    The data goes to a temporary file in the same directory, which is
    flushed, synced and renamed over `path` (``os.replace``) when the block
    ends normally. If the block raises, the temporary file is removed and
    `path` is untouched.

    Parameters
    ----------
    path : str or os.PathLike
        File to create or replace.
    binary : bool, optional
        Yield a binary file instead of a UTF-8 text file (``newline=''``).

    Yields
    ------
    file object
        The open temporary file.

    Raises
    ------
    DataError
        If the directory of `path` does not exist, `path` is a directory, or
        the file cannot be created or renamed.

    """
    target = Path(path)
    _check_target(target, overwrite=True, kind='file')
    directory = target.parent
    try:
        fd, tmpname = tempfile.mkstemp(prefix=f'.{target.name}.', suffix='.tmp',
                                       dir=directory)
    except OSError as err:
        msg = f'cannot write {target}: {err}'
        raise DataError(msg) from err
    tmp = Path(tmpname)
    try:
        if binary:
            handle: IO[Any] = os.fdopen(fd, 'wb')
        else:
            handle = os.fdopen(fd, 'w', encoding='utf-8', newline='')
        with handle:
            yield handle
            handle.flush()
            os.fsync(handle.fileno())
        try:
            os.chmod(tmp, _new_file_mode(target))
            os.replace(tmp, target)
        except OSError as err:
            msg = f'cannot write {target}: {err}'
            raise DataError(msg) from err
    except BaseException:
        with contextlib.suppress(OSError):
            tmp.unlink()
        raise


# --------------------------------------------------------------------------- bags


@functools.lru_cache(maxsize=1)
def _typestore() -> Any:
    return get_typestore(Stores.ROS2_JAZZY)


def _storage_plugin(storage: str) -> StoragePlugin:
    try:
        return _STORAGES[storage]
    except (KeyError, TypeError):
        msg = f'storage must be one of {sorted(_STORAGES)}; found {storage!r}'
        raise DataError(msg) from None


def _check_topics(input_topic: str, output_topic: str) -> None:
    for option, topic in (('input_topic', input_topic), ('output_topic', output_topic)):
        if not isinstance(topic, str) or not topic.strip():
            msg = f'{option} must be a non-empty topic name; found {topic!r}'
            raise DataError(msg)
    if input_topic == output_topic:
        msg = (f'input_topic and output_topic are both {input_topic!r}; '
               'the input and output must be on different topics')
        raise DataError(msg)


def _seconds_to_ns(t: float, *, what: str) -> int:
    try:
        seconds = float(t)
    except (TypeError, ValueError) as err:
        msg = f'{what} must be a time in seconds; found {t!r}'
        raise DataError(msg) from err
    if not np.isfinite(seconds) or seconds < 0:
        msg = f'{what} must be a finite time >= 0 s; found {t!r}'
        raise DataError(msg)
    return int(round(seconds * 1e9))


def _seconds_to_ns_array(time: FloatArray) -> npt.NDArray[np.int64]:
    bad = ~np.isfinite(time) | (time < 0) | (time > 9.2e9)
    if np.any(bad):
        first = int(np.flatnonzero(bad)[0])
        msg = (f'write_bag_signals: time must be finite and between 0 and 9.2e9 s; sample '
               f'{first} is {time[first]!r}; shift the times to start at 0')
        raise DataError(msg)
    return np.round(time * 1e9).astype(np.int64)


def _locate_bag(bag: Path) -> tuple[Path, list[str]]:
    """Return the path to hand to rosbags' Reader and initial notes."""
    if not bag.exists():
        msg = (f'bag {bag} does not exist; check the path (a rosbag2 bag is a directory '
               'holding metadata.yaml and a .db3 or .mcap file)')
        raise DataError(msg)
    if bag.is_file() and bag.name == 'metadata.yaml':
        return bag.parent, []
    if bag.is_file():
        if bag.suffix.lower() in _BAG_SUFFIXES:
            return bag, []
        msg = (f'{bag} is not a rosbag2 bag: expected a bag directory or a .db3/.mcap file, '
               f'found a {bag.suffix or "suffix-less"} file; use read_csv_signals for CSV')
        raise DataError(msg)
    if (bag / 'metadata.yaml').is_file():
        return bag, []
    files = sorted(p for p in bag.iterdir() if p.suffix.lower() in _BAG_SUFFIXES)
    if len(files) == 1:
        note = (f'{bag} has no metadata.yaml (the recording was probably interrupted); '
                f'read the storage file {files[0].name} directly')
        return files[0], [note]
    if not files:
        msg = (f'{bag} is not a rosbag2 bag: it holds no metadata.yaml and no .db3/.mcap '
               'file; pass the bag directory that `ros2 bag record` created')
        raise DataError(msg)
    msg = (f'{bag} has no metadata.yaml and {len(files)} storage files; run '
           f'`ros2 bag reindex {bag}` or pass one of {[p.name for p in files]}')
    raise DataError(msg)


def _corrupt(bag: Path, err: BaseException) -> DataError:
    msg = (f'cannot read bag {bag}: {type(err).__name__}: {err}; the bag is truncated or '
           'corrupt (e.g. the recorder was killed); re-record it, or repair it '
           '(`sqlite3 in.db3 .recover | sqlite3 out.db3`, `mcap recover`) and retry')
    return DataError(msg)


def _read_bag_topics(
    bag: Path, storage_path: Path, topics: Sequence[str],
) -> dict[str, tuple[npt.NDArray[np.int64], FloatArray]]:
    """Return log times [ns] and values of each topic, in storage order."""
    # rosbags, apsw (sqlite), lz4/zstd and struct raise many types on damaged files;
    # the try blocks below hold only rosbags calls, so every failure there is the bag's.
    try:
        reader = Reader(storage_path)
        reader.open()
    except Exception as err:
        raise _corrupt(bag, err) from err
    try:
        connections = list(reader.connections)
        present = {conn.topic: conn.msgtype for conn in connections}
        for topic in topics:
            if topic not in present:
                listing = ', '.join(f'{name} ({kind})' for name, kind in sorted(present.items()))
                option = 'input_topic' if topic == topics[0] else 'output_topic'
                msg = (f'bag {bag} has no topic {topic}; topics in the bag: '
                       f'{listing or "none"}; pass {option}= with one of them')
                raise DataError(msg)
            kinds = sorted({conn.msgtype for conn in connections if conn.topic == topic})
            if kinds != [_FLOAT64]:
                msg = (f'topic {topic} in bag {bag} has type {", ".join(kinds)}; expected '
                       f'{_FLOAT64}; republish the signal as {_FLOAT64} and record again')
                raise DataError(msg)
        wanted = [conn for conn in connections if conn.topic in topics]
        stamps: dict[str, list[int]] = {topic: [] for topic in topics}
        values: dict[str, list[float]] = {topic: [] for topic in topics}
        store = _typestore()
        try:
            for conn, stamp, data in reader.messages(connections=wanted):
                try:
                    number = float(store.deserialize_cdr(data, _FLOAT64).data)
                except Exception as err:
                    msg = (f'message {len(stamps[conn.topic])} of topic {conn.topic} in bag '
                           f'{bag} cannot be decoded as {_FLOAT64} ({type(err).__name__}: '
                           f'{err}); the bag is corrupt; re-record it')
                    raise DataError(msg) from err
                stamps[conn.topic].append(stamp)
                values[conn.topic].append(number)
        except DataError:
            raise
        except Exception as err:
            raise _corrupt(bag, err) from err
    finally:
        with contextlib.suppress(Exception):
            reader.close()
    return {topic: (np.array(stamps[topic], dtype=np.int64),
                    np.array(values[topic], dtype=np.float64)) for topic in topics}


def _clean_topic(
    bag: Path,
    topic: str,
    stamps: npt.NDArray[np.int64],
    values: FloatArray,
    *,
    drop_nonfinite: bool,
    notes: list[str],
) -> tuple[npt.NDArray[np.int64], FloatArray]:
    """Check counts, sort stably, keep the last of duplicate stamps, handle NaN/Inf."""
    if stamps.size == 0:
        msg = (f'topic {topic} in bag {bag} has no messages; check that its publisher ran '
               f'during the recording (`ros2 bag info {bag}`)')
        raise DataError(msg)
    if stamps.size == 1:
        msg = (f'topic {topic} in bag {bag} has a single message; a recording needs at least '
               f'{MIN_SAMPLES} samples; record longer')
        raise DataError(msg)
    stamps, values, n_unsorted, n_duplicate = _sort_dedupe(stamps, values)
    if n_unsorted:
        notes.append(f'{topic}: {n_unsorted} message(s) out of time order; sorted stably '
                     'by log time')
    if n_duplicate:
        notes.append(f'{topic}: {n_duplicate} duplicate time stamp(s); kept the last '
                     'message of each')
    bad = ~np.isfinite(values)
    n_bad = int(np.count_nonzero(bad))
    if n_bad and not drop_nonfinite:
        first = int(np.flatnonzero(bad)[0])
        msg = (f'topic {topic} in bag {bag} has {n_bad} non-finite value(s) (NaN/Inf), the '
               f'first at message {first} ({(stamps[first] - stamps[0]) * 1e-9:.9g} s after '
               'the first message); fix the publisher or pass drop_nonfinite=True')
        raise DataError(msg)
    if n_bad:
        notes.append(f'{topic}: dropped {n_bad} non-finite value(s) (NaN/Inf)')
        stamps, values = stamps[~bad], values[~bad]
    return stamps, values


def _sort_dedupe(
    stamps: npt.NDArray[np.int64], values: FloatArray,
) -> tuple[npt.NDArray[np.int64], FloatArray, int, int]:
    """Sort stably by stamp and keep the last of equal stamps; return the counts."""
    n_unsorted = int(np.count_nonzero(np.diff(stamps) < 0))
    order = np.argsort(stamps, kind='stable')
    stamps, values = stamps[order], values[order]
    last = np.append(stamps[1:] != stamps[:-1], True)
    n_duplicate = int(np.count_nonzero(~last))
    return stamps[last], values[last], n_unsorted, n_duplicate


def _make_tmpdir(target: Path) -> Path:
    try:
        return Path(tempfile.mkdtemp(prefix=f'.{target.name}.', suffix='.tmp',
                                     dir=target.parent))
    except OSError as err:
        msg = f'cannot write {target}: {err}'
        raise DataError(msg) from err


def _check_target(target: Path, *, overwrite: bool, kind: str) -> None:
    parent = target.parent
    if not parent.is_dir():
        msg = f'cannot write {kind} {target}: directory {parent} does not exist; create it first'
        raise DataError(msg)
    if kind == 'file' and target.is_dir():
        msg = f'cannot write file {target}: it is a directory; choose a file name'
        raise DataError(msg)
    if not overwrite and (target.exists() or target.is_symlink()):
        msg = (f'cannot write {kind} {target}: it exists already; choose another path or '
               'pass overwrite=True')
        raise DataError(msg)


def _install(built: Path, target: Path, *, overwrite: bool) -> None:
    """Move the finished bag directory `built` to `target` (same file system)."""
    try:
        if not (target.exists() or target.is_symlink()):
            os.rename(built, target)
            return
        if not overwrite:
            msg = (f'cannot write bag {target}: it was created while recording; choose '
                   'another path or pass overwrite=True')
            raise DataError(msg)
        old = built.parent / f'{target.name}.replaced'
        os.rename(target, old)
        try:
            os.rename(built, target)
        except OSError:
            os.rename(old, target)
            raise
        if old.is_dir() and not old.is_symlink():
            shutil.rmtree(old, ignore_errors=True)
        else:
            old.unlink()
    except OSError as err:
        msg = f'cannot write bag {target}: {err}'
        raise DataError(msg) from err


# --------------------------------------------------------------------------- CSV


@dataclass(frozen=True)
class _Table:
    path: Path
    header: list[str]
    header_line: int
    rows: list[list[str]]
    line_numbers: list[int]


def _read_csv_rows(source: Path, *, comment: str | None) -> _Table:
    """Split a CSV file into header and rows of stripped strings, with line numbers."""
    if not source.exists():
        msg = f'CSV file {source} does not exist; check the path'
        raise DataError(msg)
    if source.is_dir():
        msg = f'{source} is a directory, not a CSV file; for a bag use read_bag_signals'
        raise DataError(msg)
    try:
        raw = source.read_bytes()
    except OSError as err:
        msg = f'cannot read CSV file {source}: {err}'
        raise DataError(msg) from err
    try:
        text = raw.decode('utf-8-sig')
    except UnicodeDecodeError as err:
        line = raw[:err.start].count(b'\n') + 1
        msg = (f'CSV file {source} line {line} is not UTF-8 text (byte {err.start}: '
               f'{err.reason}); save the file as UTF-8 CSV')
        raise DataError(msg) from err
    if not text.strip():
        msg = (f'CSV file {source} is empty; expected a header row (e.g. '
               'time,current,displacement) followed by data rows')
        raise DataError(msg)
    kept: list[int] = []

    def lines() -> Iterator[str]:
        for number, line in enumerate(text.split('\n'), start=1):
            stripped = line.strip()
            if not stripped or (comment and stripped.startswith(comment)):
                continue
            kept.append(number)
            yield line.rstrip('\r')

    header: list[str] | None = None
    header_line = 0
    rows: list[list[str]] = []
    line_numbers: list[int] = []
    reader = csv.reader(lines(), strict=True)
    while True:
        try:
            fields = next(reader)
        except StopIteration:
            break
        except csv.Error as err:
            line = kept[-1] if kept else 1
            msg = f'CSV file {source} line {line} is not valid CSV ({err}); fix the line'
            raise DataError(msg) from err
        line = kept[reader.line_num - 1]
        fields = [field.strip() for field in fields]
        if header is None:
            header, header_line = fields, line
        else:
            rows.append(fields)
            line_numbers.append(line)
    if header is None:
        msg = (f'CSV file {source} has only comments; expected a header row (e.g. '
               'time,current,displacement) followed by data rows')
        raise DataError(msg)
    if all(_NUMBER.fullmatch(name) for name in header):
        msg = (f'CSV file {source} has no header row: line {header_line} holds numbers; '
               'add a first line naming the columns, e.g. time,current,displacement')
        raise DataError(msg)
    for position, name in enumerate(header, start=1):
        if not name:
            msg = (f'CSV file {source} header (line {header_line}) has an empty name for '
                   f'column {position}; name every column')
            raise DataError(msg)
    duplicates = sorted({name for name in header if header.count(name) > 1})
    if duplicates:
        msg = (f'CSV file {source} header (line {header_line}) repeats column name(s) '
               f'{_names(duplicates)}; make the names unique')
        raise DataError(msg)
    for fields, line in zip(rows, line_numbers):
        if len(fields) != len(header):
            msg = (f'CSV file {source} line {line} has {len(fields)} field(s) but the header '
                   f'(line {header_line}) has {len(header)}; fix the row or the header')
            raise DataError(msg)
    return _Table(source, header, header_line, rows, line_numbers)


def _names(names: Sequence[str]) -> str:
    return ', '.join(repr(name) for name in names)


def _column_index(table: _Table, name: str, *, option: str) -> int:
    if name in table.header:
        return table.header.index(name)
    msg = (f'CSV file {table.path} has no column {name!r} ({option}); available columns: '
           f'{_names(table.header)}')
    if option == 'time_column':
        msg += '; pass time_column=<name>, or time_column=None if the file has no time column'
    raise DataError(msg)


def _parse_column(table: _Table, index: int) -> FloatArray:
    values = np.empty(len(table.rows), dtype=np.float64)
    for row, (fields, line) in enumerate(zip(table.rows, table.line_numbers)):
        field = fields[index]
        if not _NUMBER.fullmatch(field):
            found = 'an empty field' if not field else f'{field[:40]!r}'
            msg = (f'CSV file {table.path} line {line}, column {table.header[index]!r} '
                   f'(column {index + 1}): expected a number, found {found}; fix the value '
                   'or remove the row')
            raise DataError(msg)
        values[row] = float(field)
    return values


def _nonfinite_rows(
    table: _Table,
    values: Mapping[str, FloatArray],
    used: Mapping[str, int],
    *,
    drop_nonfinite: bool,
    notes: list[str],
) -> npt.NDArray[np.bool_]:
    """Return the mask of rows whose used values are all finite, or raise."""
    bad = np.zeros(len(table.rows), dtype=bool)
    for column in values.values():
        bad |= ~np.isfinite(column)
    n_bad = int(np.count_nonzero(bad))
    if n_bad and not drop_nonfinite:
        first = int(np.flatnonzero(bad)[0])
        role = next(role for role, column in values.items() if not np.isfinite(column[first]))
        name = table.header[used[role]]
        msg = (f'CSV file {table.path} has {n_bad} row(s) with non-finite values (NaN/Inf), '
               f'the first at line {table.line_numbers[first]}, column {name!r}; fix the data '
               'or pass drop_nonfinite=True to drop those rows')
        raise DataError(msg)
    if n_bad:
        notes.append(f'dropped {n_bad} row(s) with non-finite values (NaN/Inf)')
    return ~bad


def _check_row_count(table: _Table, n_rows: int, *, after_drop: bool = False) -> None:
    if n_rows < MIN_SAMPLES:
        extra = ' after dropping non-finite rows' if after_drop else ''
        msg = (f'CSV file {table.path} has only {n_rows} data row(s){extra}; a recording '
               f'needs at least {MIN_SAMPLES}; record longer')
        raise DataError(msg)


# --------------------------------------------------------------------------- arrays, files


def _equal_length_arrays(
    columns: Mapping[str, npt.ArrayLike], *, what: str,
) -> dict[str, FloatArray]:
    arrays: dict[str, FloatArray] = {}
    for name, column in columns.items():
        try:
            arr = np.asarray(column, dtype=np.float64)
        except (TypeError, ValueError) as err:
            msg = f'{what}: {name} must be an array of numbers; {err}'
            raise DataError(msg) from err
        if arr.ndim != 1:
            msg = f'{what}: {name} must be one-dimensional; found shape {arr.shape}'
            raise DataError(msg)
        arrays[name] = arr
    lengths = {name: arr.size for name, arr in arrays.items()}
    if len(set(lengths.values())) > 1:
        msg = f'{what}: the arrays must have equal lengths; found {lengths}'
        raise DataError(msg)
    return arrays


def _new_file_mode(target: Path) -> int:
    """Keep the mode of a file being replaced; else the usual 0o666 minus umask."""
    with contextlib.suppress(OSError):
        return target.stat().st_mode & 0o7777
    umask = os.umask(0o022)  # reading the umask requires setting it; restore at once
    os.umask(umask)
    return 0o666 & ~umask
