# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Write actuator signals to rosbag2 bags as ``std_msgs/msg/Float64`` topics.

:class:`BagRecorder` streams samples into a bag that appears at its path only
when closed; :func:`write_bag_signals` writes whole arrays so that
:func:`~mpi_ros.recordings.read_bag_signals` reads the same pairs back.
"""

from __future__ import annotations

import contextlib
import math
import os
from pathlib import Path
import shutil
import threading
import time
from typing import Any

import numpy as np
import numpy.typing as npt
from rosbags.rosbag2 import StoragePlugin, Writer

from .files import check_target, equal_length_arrays, install_directory, make_tmpdir, \
    write_target
from .messages import Float64Reader, typestore
from .options import show_value
from .recording import FloatArray, PathLike
from ..errors import DataError

__all__ = ['BagRecorder', 'write_bag_signals', 'STORAGES']

#: rosbag2 storage plugins by name.
STORAGES = {'sqlite3': StoragePlugin.SQLITE3, 'mcap': StoragePlugin.MCAP}

_FLOAT64 = Float64Reader.msgtype


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
    flush_period : float, optional
        Longest time [s] between two commits of what was written (sqlite3: a
        transaction commit; mcap: the pending chunk is finished, flushed and
        synced), checked at each write. A recorder killed mid-recording (``kill
        -9``, a power cut after the sync) loses at most the last `flush_period`
        seconds; 0 commits at every write (slow).

    Raises
    ------
    DataError
        If `storage` is unknown, the topics are empty or equal, or
        `flush_period` is negative or not finite.

    Notes
    -----
    A recorder that dies before :meth:`close` leaves the temporary bag,
    ``.<name>.<random>.tmp/<name>/`` beside `path`, without its
    ``metadata.yaml`` (written by :meth:`close`): ``mpi-ros identify`` and
    :func:`~mpi_ros.recordings.read_bag_signals` read that folder directly
    (an unfinished mcap up to its last finished chunk, with a note); move it
    where it belongs, or run ``ros2 bag reindex`` on it.

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
        flush_period: float = 1.0,
    ) -> None:
        self._path = write_target(Path(path))
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
        try:
            self._flush_period = float(flush_period)
        except (TypeError, ValueError):
            self._flush_period = math.nan
        if not (math.isfinite(self._flush_period) and self._flush_period >= 0.0):
            msg = (f'flush_period must be a finite time >= 0 s; found '
                   f'{show_value(flush_period)}')
            raise DataError(msg)
        self._flushed = time.monotonic()

    @property
    def path(self) -> Path:
        """Target bag directory."""
        return self._path

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
            check_target(self._path, overwrite=self._overwrite, kind='bag')
            tmpdir = make_tmpdir(self._path)
            writer: Writer | None = None
            try:
                writer = Writer(tmpdir / self._path.name, version=Writer.VERSION_LATEST,
                                storage_plugin=self._plugin)
                writer.open()
                for topic in self._topics:
                    self._connections[topic] = writer.add_connection(
                        topic, _FLOAT64, typestore=typestore())
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
        Record one output sample: actuator output s [m] at log time `t` [s].

        As :meth:`write_input`, on the output topic.
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
                install_directory(tmpdir / self._path.name, self._path, overwrite=self._overwrite)
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
            msg = f'value for topic {topic} must be a number; found {show_value(value)}'
            raise DataError(msg) from err
        store = typestore()
        data = store.serialize_cdr(store.types[_FLOAT64](data=number), _FLOAT64)
        with self._lock:
            if self._writer is None:
                msg = (f'BagRecorder for {self._path} is not open; call open() first '
                       'or use it as a context manager')
                raise DataError(msg)
            self._writer.write(self._connections[topic], stamp, data)
            self._counts[topic] += 1
            now = time.monotonic()
            if now - self._flushed >= self._flush_period:
                self._flushed = now
                _commit(self._writer)


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
    arrays = equal_length_arrays(
        {'time': time, 'current': current, 'displacement': displacement},
        what='write_bag_signals')
    stamps = _seconds_to_ns_array(arrays['time'])
    if stamps.size > 1 and np.any(np.diff(stamps) < 2):
        first = int(np.flatnonzero(np.diff(stamps) < 2)[0]) + 1
        msg = (f'write_bag_signals: time must increase by at least 2 ns per sample; '
               f'sample {first} is at {show_value(arrays["time"][first])} s after '
               f'{show_value(arrays["time"][first - 1])} s; sort the samples and remove '
               'duplicates')
        raise DataError(msg)
    recorder = BagRecorder(path, input_topic=input_topic, output_topic=output_topic,
                           storage=storage, overwrite=overwrite)
    with recorder:
        for stamp, x, s in zip(stamps.tolist(), arrays['current'].tolist(),
                               arrays['displacement'].tolist()):
            recorder._write(input_topic, stamp, x)
            recorder._write(output_topic, stamp + 1, s)


def _commit(writer: Writer) -> None:
    """Make what `writer` holds durable: commit sqlite3, finish and sync mcap's chunk."""
    storage = getattr(writer, 'storage', None)
    connection = getattr(storage, 'conn', None)
    if connection is not None:                       # rosbags' Sqlite3Writer
        connection.commit()
        return
    chunk, bio = getattr(storage, 'chunk', None), getattr(storage, 'bio', None)
    if storage is None or chunk is None or bio is None:   # pragma: no cover - other rosbags
        return
    if getattr(chunk, 'msgs', None):                 # rosbags' McapWriter: finish the chunk
        storage.close_chunk()
    bio.flush()
    os.fsync(bio.fileno())


def _storage_plugin(storage: str) -> StoragePlugin:
    try:
        return STORAGES[storage]
    except (KeyError, TypeError):
        msg = f'storage must be one of {sorted(STORAGES)}; found {storage!r}'
        raise DataError(msg) from None


def _check_topics(input_topic: str, output_topic: str) -> None:
    for option, topic in (('input_topic', input_topic), ('output_topic', output_topic)):
        if not isinstance(topic, str) or not topic.strip():
            msg = f'{option} must be a non-empty topic name; found {show_value(topic)}'
            raise DataError(msg)
    if input_topic == output_topic:
        msg = (f'input_topic and output_topic are both {input_topic!r}; '
               'the input and output must be on different topics')
        raise DataError(msg)


def _seconds_to_ns(t: float, *, what: str) -> int:
    try:
        seconds = float(t)
    except (TypeError, ValueError) as err:
        msg = f'{what} must be a time in seconds; found {show_value(t)}'
        raise DataError(msg) from err
    if not np.isfinite(seconds) or seconds < 0:
        msg = f'{what} must be a finite time >= 0 s; found {show_value(t)}'
        raise DataError(msg)
    return int(round(seconds * 1e9))


def _seconds_to_ns_array(time: FloatArray) -> npt.NDArray[np.int64]:
    bad = ~np.isfinite(time) | (time < 0) | (time > 9.2e9)
    if np.any(bad):
        first = int(np.flatnonzero(bad)[0])
        msg = (f'write_bag_signals: time must be finite and between 0 and 9.2e9 s; sample '
               f'{first} is {show_value(time[first])}; shift the times to start at 0')
        raise DataError(msg)
    return np.round(time * 1e9).astype(np.int64)
