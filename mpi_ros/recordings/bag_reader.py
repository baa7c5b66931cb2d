# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Read the actuator input and output of a rosbag2 bag (sqlite3 or mcap) as paired samples.

Each topic's messages become samples through the reader registered for the
topic's type (:data:`MESSAGE_READERS`, below): one sample per message, or the
K samples of one axis of a chunked ``std_msgs/msg/Float64MultiArray``
(``layout.dim`` = samples x axes, the multi-axis nodes' layout). Every sample
gets a time (a message's log time belongs to its last sample); each output
sample is paired with the input held at its time.

Message readers: the selected samples of each bag message, chosen by the topic's message
type.  A recording needs the samples of the actuator input x [A] or output s [m]
each message of a topic carries: one number for most types, a chunk of K
samples for a chunked ``std_msgs/msg/Float64MultiArray``. A
:class:`MessageReader` takes them from a decoded message; which number is
described by a :class:`Selection` (a joint and field of a
``sensor_msgs/msg/JointState``, an element or axis of a
``Float64MultiArray``). The bag reader picks the reader by the topic's type
as stored in the bag, through :data:`MESSAGE_READERS`.

Chunked arrays (the multi-axis nodes' layout, :mod:`mpi_ros.array_layout`)
    A ``Float64MultiArray`` whose ``layout.dim`` has two entries is a block of
    ``dim[0].size`` = K samples x ``dim[1].size`` = N axes, row-major from
    ``layout.data_offset`` with the row stride ``dim[1].stride`` (N when it is
    smaller). The selected index is the axis (column, < N); the reader returns
    the K samples of that column, oldest first. A message without ``dim``, or
    with one or more than two entries, is one sample whose elements are
    indexed as before (element k after ``data_offset``); so is a block with
    K = 1. With :attr:`Selection.axes` = N (the data option ``array_axes``,
    set by the identifier for ``axes`` > 1) such a message is read as the
    nodes read it: its values after ``data_offset`` are K x N samples x axes.
    When the samples were taken is the bag reader's business
    (:func:`mpi_ros.recordings.read_bag_signals`).

Adding a message type is one class and one registry line (the type must be in
rosbags' ROS 2 Jazzy typestore)::

    class PointXReader(MessageReader):
        msgtype = 'geometry_msgs/msg/Point'

        def value(self, msg, selection):
            return float(msg.x)

    MESSAGE_READERS = {..., PointXReader.msgtype: PointXReader()}

A type whose messages carry several samples also overrides :meth:`MessageReader.values`.
"""

from __future__ import annotations

import abc
import contextlib
import dataclasses
from dataclasses import dataclass
import functools
from pathlib import Path
from typing import Any, ClassVar, Mapping

import numpy as np
import numpy.typing as npt
from rosbags.rosbag2 import Reader
from rosbags.typesys import get_typestore, Stores

from .options import DataOptions
from .recording import check_magnitudes, FloatArray, in_si, MIN_SAMPLES, PathLike, Recording
from ..array_layout import chunk_layout, consecutive_layout
from ..errors import DataError

__all__ = ['BAG_SUFFIXES', 'Float64MultiArrayReader', 'Float64Reader', 'JointStateReader',
           'MESSAGE_READERS', 'MessageReader', 'Selection', 'SelectionError', 'TIME_SOURCES',
           'read_bag', 'read_bag_signals', 'supported_types', 'typestore']

#: Suffixes of rosbag2 storage files.
BAG_SUFFIXES = ('.db3', '.mcap')
#: Sources of the sample times: the bag's log (receive) time.
TIME_SOURCES = ('receive',)

_Stamped = tuple[npt.NDArray[np.int64], FloatArray]
#: Per message: log time [ns] and sample count; the samples of all messages in one array.
_Messages = tuple[npt.NDArray[np.int64], FloatArray, npt.NDArray[np.int64]]


def read_bag_signals(
    path: PathLike,
    *,
    input_topic: str = '/current_command',
    output_topic: str = '/displacement',
    input_joint: str | None = None,
    output_joint: str | None = None,
    input_field: str = 'position',
    output_field: str = 'position',
    input_index: int | None = None,
    output_index: int | None = None,
    array_axes: int | None = None,
    sample_period: float | None = None,
    time_source: str = 'receive',
    time_scale: float = 1.0,
    drop_nonfinite: bool = False,
) -> Recording:
    """
    Read the input and output topics of a rosbag2 bag as paired samples.

    Each topic may carry ``std_msgs/msg/Float64``, ``sensor_msgs/msg/JointState``
    (one joint's position, velocity or effort) or
    ``std_msgs/msg/Float64MultiArray`` (one element, or one axis of a chunk
    of samples x axes), see the message readers below. Each output
    sample is paired with the most recent input sample timed at or before it
    (zero-order hold): the displacement measured at time t responds to the
    last command sent before t. Output samples timed before the first input
    sample have no command and are dropped.

    Chunked messages (``layout.dim`` = [samples (K, K*N), axes (N, N)], as the
    multi-axis compensator and plant simulator publish them, or K*N values
    without ``dim`` when `array_axes` = N) give K samples each; input and
    output may use different chunk sizes, and messages without ``dim`` (unless
    `array_axes` is set) or with K = 1 are one sample as before. The log time of
    a message belongs to its **last** sample (a publisher sends a chunk when
    it is complete, and the plant simulator times a chunk's last sample at
    its arrival); the earlier ones are spaced by the sample period: the log
    time since the topic's previous message divided by K (so the chunks tile
    the time between messages and never overlap), for the first message the
    median of the others, or `sample_period` for every message when it is
    given.

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
        Topic of the actuator output s (displacement [m]). It may equal
        `input_topic` when the two select different joints, fields or
        elements of it.
    input_joint, output_joint : str, optional
        Joint of a ``JointState`` topic; by default the message's only joint.
    input_field, output_field : {'position', 'velocity', 'effort'}, optional
        Field of the joint in a ``JointState`` topic.
    input_index, output_index : int, optional
        Element of a ``Float64MultiArray`` topic (after ``layout.data_offset``),
        or the axis (column, < N) of a chunked one; by default the array's
        only element (the only axis).
    array_axes : int, optional
        Number of axes N of ``Float64MultiArray`` messages without
        ``layout.dim``: their K x N values are read as K samples x N axes
        (as the multi-axis nodes accept them). By default such a message is
        one sample (element `input_index`/`output_index`). Topics of other
        types ignore it.
    sample_period : float, optional
        Interval [s] between the samples of a chunked message (in s after
        `time_scale`); by default inferred from the log times (see above).
        Give it when the log times are bursty (a recorder on a loaded
        machine) and the rate is known;
        a sample that would fall at or before the previous message's last
        sample is moved 1 ns after it (as the plant simulator does), with a
        note.
    time_source : {'receive'}, optional
        Which time stamps the samples: ``'receive'`` is the bag's log time.
        ``std_msgs/msg/Float64`` carries no header stamp, so it is the only
        source for every type.
    time_scale : float, optional
        Factor from the log time [s] to the actuator's time [s], > 0: 1 for
        a live recording; e.g. 0.1 for a bag recorded while a record was
        replayed at a tenth of its speed.
    drop_nonfinite : bool, optional
        Drop NaN/Inf messages (with a note) instead of raising.

    Returns
    -------
    Recording
        ``time`` [s] relative to the first paired sample (log time times
        `time_scale`), ``current`` [A]
        (the held input), ``displacement`` [m], ``source`` = the path and
        ``notes`` on what was dropped, sorted or de-duplicated.

    Raises
    ------
    DataError
        If the path is missing or not a bag; the bag is truncated or corrupt;
        a topic is missing (the message lists the topics present), has an
        unsupported type (the message lists the supported ones), no message
        or a single one; a selected joint, field or element is missing (the
        message lists what the messages hold); a chunked message's layout does
        not fit its data, or its index is not an axis; a topic of chunks has a
        single message and no `sample_period`; a topic holds NaN/Inf (without
        `drop_nonfinite`); fewer than :data:`MIN_SAMPLES` samples pair up; or a
        signal is too large or spans too little to compute with
        (:func:`~mpi_ros.recordings.recording.check_magnitudes`).

    Notes
    -----
    Log times T_m [ns] are sorted stably per topic; of several messages with
    the same time stamp the last one read is kept and the duplicates are
    counted in ``notes``. Sample i = 0 ... K_m - 1 of message m is timed
    t = T_m - (K_m - 1 - i) p_m with p_m = (T_m - T_(m-1)) / K_m (rounded to
    ns), p_0 = median(p_m), or p_m = `sample_period`. With input times τ_j and
    output times t_k the pairs are (x(τ_j*), s(t_k)) with
    j* = max{j : τ_j ≤ t_k}.

    """
    options = DataOptions(input_topic=input_topic, output_topic=output_topic,
                          input_joint=input_joint, output_joint=output_joint,
                          input_field=input_field, output_field=output_field,
                          input_index=input_index, output_index=output_index,
                          array_axes=array_axes, sample_period=sample_period,
                          time_scale=time_scale, drop_nonfinite=drop_nonfinite)
    return read_bag(path, options, time_source=time_source)


def read_bag(path: PathLike, options: DataOptions, *, time_source: str = 'receive') -> Recording:
    """
    Read a bag with the bag options of `options` (see :func:`read_bag_signals`).

    The time, input and output are multiplied by ``options.time_scale``,
    ``options.input_scale`` and ``options.output_scale``; messages name the
    options in ``options.spelling``.

    Parameters
    ----------
    path : str or os.PathLike
        Bag directory, its ``metadata.yaml`` or a ``.db3``/``.mcap`` file.
    options : DataOptions
        Topics, selections, sample period, scales and `drop_nonfinite`.
    time_source : {'receive'}, optional
        See :func:`read_bag_signals`.

    Returns
    -------
    Recording
        As :func:`read_bag_signals`, scaled.

    Raises
    ------
    DataError
        As :func:`read_bag_signals`.

    """
    bag = Path(path)
    if time_source not in TIME_SOURCES:
        msg = (f'time_source must be one of {TIME_SOURCES}; found {time_source!r}; '
               'std_msgs/msg/Float64 has no header stamp, so only the bag log time is '
               'available')
        raise DataError(msg)
    selections = _selections(options)
    storage_path, notes = _locate_bag(bag)
    with contextlib.ExitStack() as stack:
        if storage_path.suffix.lower() == '.mcap' and storage_path.is_file():
            # A recorder that was killed leaves an mcap without its summary and footer
            # (and no metadata.yaml): read the chunks it finished.
            repaired = _finish_unfinished_mcap(bag, storage_path, stack)
            if repaired is not None:
                storage_path, note = repaired
                notes.append(note)
        raw = _read_bag_topics(bag, storage_path, selections, options)
    units = {role: 'message' if np.all(raw[role][2] == 1) else 'sample' for role in raw}
    (t_in, x_in), (t_out, s_out) = (
        _clean_topic(bag, selection, *raw[role], options=options, notes=notes)
        for role, selection in zip(('input', 'output'), selections))
    in_label, out_label = (selection.label for selection in selections)
    in_unit, out_unit = units['input'], units['output']
    held = np.searchsorted(t_in, t_out, side='right') - 1
    paired = held >= 0
    n_early = int(np.count_nonzero(~paired))
    if n_early:
        notes.append(f'dropped {n_early} {out_label} {out_unit}(s) logged before the first '
                     f'{in_label} {in_unit}')
    n_paired = int(np.count_nonzero(paired))
    if n_paired < MIN_SAMPLES:
        msg = (f'bag {bag}: only {n_paired} {out_label} {out_unit}(s) at or after the first '
               f'{in_label} {in_unit} (need at least {MIN_SAMPLES}); record longer, and start '
               'the recording before the actuator runs so both topics are captured')
        raise DataError(msg)
    t_out, s_out, x_held = t_out[paired], s_out[paired], x_in[held[paired]]
    time = (t_out - t_out[0]).astype(np.float64) * (1e-9 * options.time_scale)
    read = Recording(time, x_held * options.input_scale, s_out * options.output_scale,
                     source=str(bag), notes=tuple(notes))
    names = [f'{topic} {joint or ""}'.strip() for topic, joint in (
        (options.input_topic, options.input_joint), (options.output_topic, options.output_joint))]
    return check_magnitudes(in_si(read, options, input_name=names[0], output_name=names[1]),
                            options)


def _selections(options: DataOptions) -> tuple[Selection, Selection]:
    """Return the input and output selections; refuse two equal ones."""
    pair = tuple(
        Selection(getattr(options, f'{role}_topic'), joint=getattr(options, f'{role}_joint'),
                  joint_field=getattr(options, f'{role}_field'),
                  index=getattr(options, f'{role}_index'), axes=options.array_axes,
                  names={'topic': options.name(f'{role}_topic'),
                         'joint': options.name(f'{role}_joint'),
                         'joint_field': options.name(f'{role}_field'),
                         'index': options.name(f'{role}_index'),
                         'axes': options.name('array_axes')})
        for role in ('input', 'output'))
    if pair[0] == pair[1]:
        msg = (f'{options.name("input_topic")} and {options.name("output_topic")} are both '
               f'{options.input_topic!r} with the same joint, field and index; the input and '
               'output must be different topics, or different joints, fields or elements of '
               'one topic')
        raise DataError(msg)
    return pair[0], pair[1]


def _locate_bag(bag: Path) -> tuple[Path, list[str]]:
    """Return the path to hand to rosbags' Reader and initial notes."""
    if not bag.exists():
        msg = (f'bag {bag} does not exist; check the path (a rosbag2 bag is a directory '
               'holding metadata.yaml and a .db3 or .mcap file)')
        raise DataError(msg)
    if bag.is_file() and bag.name == 'metadata.yaml':
        return bag.parent, []
    if bag.is_file():
        if bag.suffix.lower() in BAG_SUFFIXES:
            return bag, []
        msg = (f'{bag} is not a rosbag2 bag: expected a bag directory or a .db3/.mcap file, '
               f'found a {bag.suffix or "suffix-less"} file; use read_csv_signals for CSV')
        raise DataError(msg)
    if (bag / 'metadata.yaml').is_file():
        return bag, []
    files = sorted(p for p in bag.iterdir() if p.suffix.lower() in BAG_SUFFIXES)
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


#: The magic that starts and ends an mcap file.
_MCAP_MAGIC = b'\x89MCAP0\r\n'


def _finish_unfinished_mcap(bag: Path, path: Path,
                            stack: contextlib.ExitStack) -> tuple[Path, str] | None:
    """
    Return a finished copy of an mcap a killed recorder left, and a note; None if finished.

    The copy ends after the last complete record (the chunks the recorder finished) with a
    data-end record and a footer without a summary, which the reader scans; each chunk's
    CRC is still checked as it is read.
    """
    import struct
    import tempfile
    try:
        data = path.read_bytes()
    except OSError as err:
        raise _corrupt(bag, err) from err
    if not data.startswith(_MCAP_MAGIC) or data.endswith(_MCAP_MAGIC):
        return None
    end = position = len(_MCAP_MAGIC)
    chunks = 0
    while position + 9 <= len(data):
        op, length = data[position], struct.unpack_from('<Q', data, position + 1)[0]
        if op == 0 or op > 0x10 or position + 9 + length > len(data):
            break                                   # zeros or a record cut short
        if op == 0x0F:                              # data end: the summary follows
            break
        position += 9 + length
        end = position
        chunks += op == 0x06
    footer = (b'\x0f' + struct.pack('<QI', 4, 0) + b'\x02' + struct.pack('<QQQI', 20, 0, 0, 0)
              + _MCAP_MAGIC)
    folder = Path(stack.enter_context(tempfile.TemporaryDirectory(prefix='mpi_ros_mcap_')))
    copy = folder / path.name
    copy.write_bytes(data[:end] + footer)
    note = (f'{path.name} was not finished (the recorder was killed or is still running): '
            f'read its {chunks} complete chunk(s), {len(data) - end} byte(s) after them '
            'dropped')
    return copy, note


def _check_sqlite_file(bag: Path, path: Path) -> None:
    """
    Refuse a sqlite3 storage file that is cut short or fails SQLite's ``quick_check``.

    SQLite reads the missing end of a truncated file as zeros, so a bag cut by one byte
    reads without an error and with a changed sample; its size is then no longer a whole
    number of pages, or smaller than the page count its header records.
    """
    import sqlite3
    try:
        size = path.stat().st_size
        with path.open('rb') as f:
            header = f.read(100)
    except OSError as err:
        raise _corrupt(bag, err) from err
    if len(header) < 100 or not header.startswith(b'SQLite format 3\x00'):
        raise _corrupt(bag, ValueError(f'{path.name} is not an SQLite database'))
    page_size = int.from_bytes(header[16:18], 'big')
    page_size = 65536 if page_size == 1 else page_size
    pages = int.from_bytes(header[28:32], 'big')
    header_valid = header[24:28] == header[92:96]       # the page count is kept up to date
    if page_size < 512 or size % page_size or (header_valid and pages * page_size > size):
        problem = (f'{path.name} holds {size} bytes, not the whole {page_size}-byte pages its '
                   f'header records ({pages} pages)')
        raise _corrupt(bag, ValueError(problem))
    try:
        connection = sqlite3.connect(f'{path.resolve().as_uri()}?mode=ro', uri=True)
        try:
            rows = connection.execute('PRAGMA quick_check').fetchmany(3)
        finally:
            connection.close()
    except sqlite3.Error as err:
        raise _corrupt(bag, err) from err
    if rows != [('ok',)]:
        found = '; '.join(str(row[0]) for row in rows)
        raise _corrupt(bag, ValueError(f'{path.name} fails the SQLite quick_check: {found}'))


def _check_counts(bag: Path, connections: list[Any], counts: dict[str, int]) -> None:
    """Refuse a bag with fewer messages on a topic than its metadata.yaml records."""
    for topic, count in counts.items():
        recorded = sum(int(getattr(conn, 'msgcount', 0) or 0) for conn in connections
                       if conn.topic == topic)
        if count < recorded:
            problem = (f'topic {topic} has {count} messages, its metadata.yaml records '
                       f'{recorded}')
            raise _corrupt(bag, ValueError(problem))


def _sort_dedupe(
    stamps: npt.NDArray[np.int64], values: FloatArray,
) -> tuple[npt.NDArray[np.int64], FloatArray, int, int]:
    """Sort stably by stamp and keep the last of equal stamps; return the counts."""
    kept, n_unsorted, n_duplicate = _message_order(stamps)
    return stamps[kept], values[kept], n_unsorted, n_duplicate


def _message_order(
    stamps: npt.NDArray[np.int64],
) -> tuple[npt.NDArray[np.intp], int, int]:
    """Return the messages sorted stably by stamp, the last of equal stamps kept; counts."""
    n_unsorted = int(np.count_nonzero(np.diff(stamps) < 0))
    order = np.argsort(stamps, kind='stable')
    ordered = stamps[order]
    last = np.append(ordered[1:] != ordered[:-1], True)
    n_duplicate = int(np.count_nonzero(~last))
    return order[last], n_unsorted, n_duplicate


def _sample_stamps(
    stamps: npt.NDArray[np.int64], counts: npt.NDArray[np.int64], period: float | None,
) -> tuple[npt.NDArray[np.int64], float, int]:
    """
    Time every sample of sorted, distinct messages; see :func:`read_bag_signals`, Notes.

    Returns the sample times [ns], the period of the first message [ns] and how many
    samples were moved to 1 ns after their predecessor (only with a fixed `period`).
    """
    if period is None:
        periods = np.diff(stamps).astype(np.float64) / counts[1:]
        first = float(np.median(periods))
        periods = np.concatenate([[first], periods])
    else:
        first = period * 1e9
        periods = np.full(stamps.size, first)
    ends = np.cumsum(counts) - 1                        # index of each message's last sample
    after = np.repeat(ends, counts) - np.arange(int(ends[-1]) + 1)
    times = np.repeat(stamps, counts) - np.rint(after * np.repeat(periods, counts)).astype(
        np.int64)
    # Strictly increasing: t_i >= t_(i-1) + 1 ns, i.e. a running maximum of t_i - i.
    rank = np.arange(times.size, dtype=np.int64)
    increasing = np.maximum.accumulate(times - rank) + rank
    return increasing, first, int(np.count_nonzero(increasing != times))


def _read_bag_topics(
    bag: Path, storage_path: Path, selections: tuple[Selection, Selection],
    options: DataOptions,
) -> dict[str, _Messages]:
    """Return log times [ns], selected samples and sample counts per message, in storage order."""
    # rosbags, apsw (sqlite), lz4/zstd and struct raise many types on damaged files;
    # the try blocks below hold only rosbags calls, so every failure there is the bag's.
    try:
        reader = Reader(storage_path)
        reader.open()
    except Exception as err:
        raise _corrupt(bag, err) from err
    try:
        files = [storage_path] if storage_path.is_file() else sorted(storage_path.iterdir())
        for path in files:
            if path.suffix.lower() == '.db3':
                _check_sqlite_file(bag, path)
        connections = list(reader.connections)
        present = {conn.topic: conn.msgtype for conn in connections}
        readers = {}
        for role, selection in zip(('input', 'output'), selections):
            topic = selection.topic
            if topic not in present:
                listing = ', '.join(f'{name} ({kind})' for name, kind in sorted(present.items()))
                option = options.setting(f'{role}_topic', '<topic>')
                msg = (f'bag {bag} has no topic {topic}; topics in the bag: '
                       f'{listing or "none"}; pass {option} with one of them')
                raise DataError(msg)
            kinds = sorted({conn.msgtype for conn in connections if conn.topic == topic})
            if len(kinds) != 1 or kinds[0] not in MESSAGE_READERS:
                msg = (f'topic {topic} in bag {bag} has type {", ".join(kinds)}; expected '
                       f'{supported_types()}; republish the signal as one of these types '
                       'and record again')
                raise DataError(msg)
            readers[topic] = MESSAGE_READERS[kinds[0]]
            _check_selectors(bag, selection, readers[topic])
        roles = {'input': selections[0], 'output': selections[1]}
        wanted = [conn for conn in connections if conn.topic in readers]
        stamps: dict[str, list[int]] = {role: [] for role in roles}
        values: dict[str, list[FloatArray]] = {role: [] for role in roles}
        counts = dict.fromkeys(readers, 0)
        layouts: dict[str, tuple[str, int]] = {}
        by_topic = {topic: [(role, selection) for role, selection in roles.items()
                            if selection.topic == topic] for topic in readers}
        store = typestore()
        try:
            for conn, stamp, data in reader.messages(connections=wanted):
                number = counts[conn.topic]
                counts[conn.topic] += 1
                try:
                    decoded = store.deserialize_cdr(data, conn.msgtype)
                except Exception as err:
                    msg = (f'message {number} of topic {conn.topic} in bag {bag} cannot be '
                           f'decoded as {conn.msgtype} ({type(err).__name__}: {err}); the bag '
                           'is corrupt; re-record it')
                    raise DataError(msg) from err
                if number == 0 and conn.msgtype == Float64MultiArrayReader.msgtype:
                    layouts[conn.topic] = _layout_of(decoded)
                for role, selection in by_topic[conn.topic]:
                    try:
                        samples = readers[conn.topic].values(decoded, selection)
                    except SelectionError as err:
                        msg = (f'message {number} of topic {conn.topic} ({conn.msgtype}) in '
                               f'bag {bag}: {err}')
                        raise DataError(msg) from err
                    stamps[role].append(stamp)
                    values[role].append(samples)
        except DataError:
            raise
        except Exception as err:
            raise _corrupt(bag, err) from err
        _check_counts(bag, wanted, counts)
    finally:
        with contextlib.suppress(Exception):
            reader.close()
    _check_layouts(bag, selections, layouts, options)
    return {role: (np.array(stamps[role], dtype=np.int64),
                   np.concatenate(values[role]) if values[role] else np.empty(0),
                   np.array([chunk.size for chunk in values[role]], dtype=np.int64))
            for role in roles}


def _layout_of(msg: Any) -> tuple[str, int]:
    """Return ('chunk', axes) for a samples x axes block, ('flat', values) without dim."""
    dims = msg.layout.dim
    if len(dims) == 2:
        return 'chunk', int(dims[1].size)
    if not dims:
        return 'flat', len(msg.data) - int(msg.layout.data_offset)
    return 'other', 0


def _check_layouts(bag: Path, selections: tuple[Selection, Selection],
                   layouts: dict[str, tuple[str, int]], options: DataOptions) -> None:
    """
    Refuse a dim-less array topic paired with chunks of N > 1 axes without `array_axes`.

    The multi-axis nodes read K x N values without ``layout.dim`` as K samples; without
    ``array_axes`` the reader would take one element per message and pair it with the
    other topic's K samples per message, a silently wrong recording.
    """
    if options.array_axes is not None:
        return
    shapes = {selection.topic: layouts.get(selection.topic) for selection in selections}
    chunks = [(topic, shape[1]) for topic, shape in shapes.items()
              if shape and shape[0] == 'chunk' and shape[1] > 1]
    flats = [(topic, shape[1]) for topic, shape in shapes.items()
             if shape and shape[0] == 'flat']
    for chunk_topic, axes in chunks:
        for flat_topic, size in flats:
            if size > axes and size % axes == 0:
                option = options.setting('array_axes', str(axes))
                msg = (f'bag {bag}: topic {flat_topic} holds {size} values per message '
                       f'without layout.dim while {chunk_topic} holds chunks of {axes} axes '
                       f'(layout.dim = samples x axes); its messages look like chunks of '
                       f'{size // axes} samples x {axes} axes, which would be read as one '
                       f'sample each; pass {option} to read them as the multi-axis nodes do, '
                       'or republish them with a layout.dim')
                raise DataError(msg)


def _check_selectors(bag: Path, selection: Selection, reader: MessageReader) -> None:
    """Refuse a joint, field or index set for a topic whose type does not have it."""
    selectors = reader.selectors
    given = [name for name, unset in (('joint', None), ('joint_field', 'position'),
                                      ('index', None))
             if getattr(selection, name) != unset and name not in selectors]
    if given:
        options = ', '.join(selection.name(name) for name in given)
        users = sorted(kind for kind, other in MESSAGE_READERS.items()
                       if set(given) <= set(other.selectors))
        msg = (f'{options} does not apply to topic {selection.topic} in bag {bag}: its type '
               f'{reader.msgtype} has no joints or elements to select '
               f'({options} applies to {", ".join(users) or "no supported type"}); remove '
               f'{options} or choose another topic')
        raise DataError(msg)


def _clean_topic(
    bag: Path,
    selection: Selection,
    stamps: npt.NDArray[np.int64],
    values: FloatArray,
    counts: npt.NDArray[np.int64],
    *,
    options: DataOptions,
    notes: list[str],
) -> _Stamped:
    """Check counts, sort stably, keep the last of duplicate stamps, time chunks, NaN/Inf."""
    topic = selection.label
    if stamps.size == 0:
        msg = (f'topic {topic} in bag {bag} has no messages; check that its publisher ran '
               f'during the recording (`ros2 bag info {bag}`)')
        raise DataError(msg)
    chunked = bool(np.any(counts != 1))
    if stamps.size == 1 and not chunked:
        msg = (f'topic {topic} in bag {bag} has a single message; a recording needs at least '
               f'{MIN_SAMPLES} samples; record longer')
        raise DataError(msg)
    if stamps.size == 1 and options.sample_period is None:
        msg = (f'topic {topic} in bag {bag} has a single message (a chunk of {counts[0]} '
               'samples): the interval between its samples cannot be inferred from one log '
               f'time; pass {options.setting("sample_period", "<seconds>")} or record longer')
        raise DataError(msg)
    kept, n_unsorted, n_duplicate = _message_order(stamps)
    if n_unsorted:
        notes.append(f'{topic}: {n_unsorted} message(s) out of time order; sorted stably '
                     'by log time')
    if n_duplicate:
        notes.append(f'{topic}: {n_duplicate} duplicate time stamp(s); kept the last '
                     'message of each')
    starts = np.cumsum(counts) - counts
    counts = counts[kept]
    # The kept messages' samples, message by message in time order.
    taken = np.repeat(starts[kept] - np.cumsum(counts) + counts, counts) + np.arange(
        int(counts.sum()))
    stamps, values = stamps[kept], values[taken]
    if chunked:
        # --sample-period is in the actuator's s, the log times before --time-scale.
        period = (None if options.sample_period is None
                  else options.sample_period / options.time_scale)
        stamps, first, n_moved = _sample_stamps(stamps, counts, period)
        spacing = (f'{options.name("sample_period")} {options.sample_period:g} s apart'
                   if options.sample_period is not None else
                   'spaced by the log time since the previous message divided by its size '
                   f'(first message: {first * 1e-9 * options.time_scale:.6g} s, the median)')
        notes.append(f'{topic}: {values.size} samples in {counts.size} chunked message(s) '
                     f'of {_sizes(counts)} samples, the last of each at its log time, the '
                     f'others {spacing}')
        if n_moved:
            name = options.name('sample_period')
            cause = (f'{name} longer than the log times allow; check {name}'
                     if options.sample_period is not None else
                     'messages logged fewer ns apart than they hold samples')
            notes.append(f'{topic}: {n_moved} sample(s) would fall at or before the last '
                         f'sample of the previous message ({cause}); moved to 1 ns after it')
    bad = ~np.isfinite(values)
    n_bad = int(np.count_nonzero(bad))
    if n_bad and not options.drop_nonfinite:
        first_bad = int(np.flatnonzero(bad)[0])
        where = f'message {first_bad}'
        if chunked:
            message = int(np.searchsorted(np.cumsum(counts), first_bad, side='right'))
            index = first_bad - int(np.cumsum(counts)[message] - counts[message])
            where = f'sample {index} of message {message}'
        msg = (f'topic {topic} in bag {bag} has {n_bad} non-finite value(s) (NaN/Inf), the '
               f'first at {where} ({(stamps[first_bad] - stamps[0]) * 1e-9:.9g} s after '
               f'the first {"sample" if chunked else "message"}); fix the publisher or pass '
               f'{options.setting("drop_nonfinite")}')
        raise DataError(msg)
    if n_bad:
        notes.append(f'{topic}: dropped {n_bad} non-finite value(s) (NaN/Inf)')
        stamps, values = stamps[~bad], values[~bad]
    return stamps, values


def _sizes(counts: npt.NDArray[np.int64]) -> str:
    low, high = int(counts.min()), int(counts.max())
    return f'{low}' if low == high else f'{low} to {high}'


class SelectionError(DataError):
    """A message does not hold the selected number (joint, field or index)."""


@dataclass(frozen=True)
class Selection:
    """
    Which number to take from each message of one topic.

    Attributes
    ----------
    topic : str
        Topic name in the bag.
    joint : str or None
        Joint name in a ``JointState``; None takes the message's only joint.
    joint_field : {'position', 'velocity', 'effort'}
        Field of the joint in a ``JointState``.
    index : int or None
        Element of a ``Float64MultiArray`` after ``layout.data_offset``, or
        the axis (column) of a chunked one (``layout.dim`` = samples x axes);
        None takes the array's only element (the only axis of a chunk).
    axes : int or None
        Number of axes N of a ``Float64MultiArray`` without ``layout.dim``:
        its values are then K x N samples x axes (row-major, K >= 1), as the
        multi-axis nodes accept them; None reads such a message as one
        sample (element `index`). A two-entry ``layout.dim`` must agree with
        it. Other types ignore it.
    names : Mapping[str, str]
        How the user writes the options behind ``topic``, ``joint``,
        ``joint_field``, ``index`` and ``axes`` (e.g. ``'--input-joint'``),
        for messages.

    """

    topic: str
    joint: str | None = None
    joint_field: str = 'position'
    index: int | None = None
    axes: int | None = None
    names: Mapping[str, str] = dataclasses.field(default_factory=dict, compare=False)

    def name(self, attribute: str) -> str:
        """Return how the user writes the option behind `attribute`."""
        return self.names.get(attribute, attribute)

    @property
    def label(self) -> str:
        """Topic, with the joint, field or index when one is selected."""
        parts = [part for part in (self.joint, None if self.joint is None else self.joint_field,
                                   None if self.index is None else f'[{self.index}]') if part]
        return f'{self.topic} {" ".join(parts)}' if parts else self.topic


class MessageReader(abc.ABC):
    """
    Take the selected number(s) from one decoded message of one type.

    Subclasses set :attr:`msgtype` and :attr:`selectors` and implement
    :meth:`value`; one line in :data:`MESSAGE_READERS` registers them. A type
    whose messages carry several samples of the signal (a chunk) also
    overrides :meth:`values`, which the bag reader calls.
    """

    #: Message type the reader decodes, as stored in the bag.
    msgtype: ClassVar[str]
    #: Attributes of :class:`Selection` the type uses (``joint``, ``joint_field``,
    #: ``index``); setting another one for a topic of this type is an error.
    selectors: ClassVar[tuple[str, ...]] = ()

    @abc.abstractmethod
    def value(self, msg: Any, selection: Selection) -> float:
        """
        Return the selected number of one message.

        Parameters
        ----------
        msg : object
            The message, decoded by rosbags.
        selection : Selection
            What to take from it.

        Returns
        -------
        float
            The number, in the unit it was published in.

        Raises
        ------
        SelectionError
            If the message does not hold it; the message says what it holds.

        """

    def values(self, msg: Any, selection: Selection) -> npt.NDArray[np.float64]:
        """
        Return the selected samples of one message, oldest first.

        Parameters
        ----------
        msg : object
            The message, decoded by rosbags.
        selection : Selection
            What to take from it.

        Returns
        -------
        ndarray of float, shape (K,)
            The K >= 1 samples, in the unit they were published in; by
            default the one number of :meth:`value`.

        Raises
        ------
        SelectionError
            If the message does not hold them; the message says what it holds.

        """
        return np.array([self.value(msg, selection)], dtype=np.float64)


class Float64Reader(MessageReader):
    """``std_msgs/msg/Float64``: the number is ``data``."""

    msgtype = 'std_msgs/msg/Float64'

    def value(self, msg: Any, selection: Selection) -> float:
        """Return ``msg.data``."""
        return float(msg.data)


class JointStateReader(MessageReader):
    """``sensor_msgs/msg/JointState``: one field (position, velocity, effort) of one joint."""

    msgtype = 'sensor_msgs/msg/JointState'
    selectors = ('joint', 'joint_field')

    def value(self, msg: Any, selection: Selection) -> float:
        """Return ``msg.<joint_field>[i]`` where ``msg.name[i]`` is the selected joint."""
        names = [str(name) for name in msg.name]
        joint_option = selection.name('joint')
        if selection.joint is None:
            if len(names) != 1:
                msg_text = (f'it holds {len(names)} joints ({_listing(names)}) and '
                            f'{joint_option} is not set; set {joint_option} to one of them')
                raise SelectionError(msg_text)
            position = 0
        elif selection.joint in names:
            position = names.index(selection.joint)
        else:
            msg_text = (f'it has no joint {selection.joint!r} ({joint_option}); joints found: '
                        f'{_listing(names)}; set {joint_option} to one of them')
            raise SelectionError(msg_text)
        values = getattr(msg, selection.joint_field)
        if position >= len(values):
            field_option = selection.name('joint_field')
            others = [name for name in ('position', 'velocity', 'effort')
                      if name != selection.joint_field and len(getattr(msg, name)) > position]
            msg_text = (f'it has no {selection.joint_field} for joint {names[position]!r}: '
                        f'{selection.joint_field} holds {len(values)} value(s) for '
                        f'{len(names)} joint(s) (its publisher does not fill it); set '
                        f'{field_option} to a filled field '
                        f'({", ".join(others) or "none is filled"})')
            raise SelectionError(msg_text)
        return float(values[position])


class Float64MultiArrayReader(MessageReader):
    """
    ``std_msgs/msg/Float64MultiArray``: one element of ``data``, or one axis of a chunk.

    A message whose ``layout.dim`` has two entries is a chunk of samples x axes
    (module docstring); any other message is one sample.
    """

    msgtype = 'std_msgs/msg/Float64MultiArray'
    selectors = ('index',)

    def value(self, msg: Any, selection: Selection) -> float:
        """Return ``msg.data[layout.data_offset + index]`` (a one-sample chunk's element)."""
        if len(msg.layout.dim) == 2 or selection.axes is not None:
            samples = self.values(msg, selection)
            if samples.size != 1:
                msg_text = (f'it holds a chunk of {samples.size} samples (samples x axes), '
                            'not one number; read it with values()')
                raise SelectionError(msg_text)
            return float(samples[0])
        return self._element(msg, selection)

    def values(self, msg: Any, selection: Selection) -> npt.NDArray[np.float64]:
        """Return the selected axis of a chunk (K samples), or ``[value]`` for one sample."""
        dims = msg.layout.dim
        offset = int(msg.layout.data_offset)
        size = len(msg.data)
        option = selection.name('index')
        axes_option = selection.name('axes')
        layout = chunk_layout([(int(d.size), int(d.stride)) for d in dims], offset)
        if layout is not None:
            samples, axes, row = layout.samples, layout.axes, layout.row
            stride = f', row stride {row}' if row != axes else ''
            shape = (f'{samples} sample(s) x {axes} axes (layout.dim = samples x axes{stride}'
                     f'{_offset_note(offset, ", ")})')
            if samples < 1 or axes < 1:
                msg_text = (f'its layout announces {shape}: a chunk needs at least one sample '
                            'and one axis; fix layout.dim in the publisher (dim[0] = samples, '
                            'dim[1] = axes) or leave dim empty for one sample per message')
                raise SelectionError(msg_text)
            if not layout.fits(size):
                msg_text = (f'its layout announces {shape}, which needs {layout.needed} values,'
                            f' but data holds {size}; fix layout.dim in the publisher (dim[0] = '
                            'samples, dim[1] = axes) to match the data')
                raise SelectionError(msg_text)
            if selection.axes is not None and axes != selection.axes:
                msg_text = (f'it holds chunks of {shape}, but {axes_option} is '
                            f'{selection.axes}; set {axes_option} to {axes} (one column per '
                            'axis) or record the topic of the other actuators')
                raise SelectionError(msg_text)
        elif selection.axes is not None:
            axes = selection.axes
            layout = consecutive_layout(size, offset, axes)
            if layout is None:
                msg_text = (f'it holds {max(size - offset, 0)} value(s){_offset_note(offset)}'
                            f' and no layout.dim, not whole samples of {axes_option} {axes}'
                            ' axes (samples x axes, row-major); publish K x N values or set '
                            f'layout.dim, or set {axes_option} to the number of axes')
                raise SelectionError(msg_text)
            samples = layout.samples
            shape = (f'{samples} sample(s) x {axes} axes ({axes_option} {axes}, no '
                     f'layout.dim{_offset_note(offset, ", ")})')
        else:
            return np.array([self._element(msg, selection)], dtype=np.float64)
        if selection.index is None:
            if axes != 1:
                msg_text = (f'it holds chunks of {shape} and {option} is not set; set '
                            f'{option} to the axis, one of 0 to {axes - 1}')
                raise SelectionError(msg_text)
            index = 0
        else:
            index = selection.index
        if index >= axes:
            msg_text = (f'{option} {index} is out of range: the message holds {shape}; set '
                        f'{option} to an axis, one of 0 to {axes - 1}')
            raise SelectionError(msg_text)
        return layout.column(msg.data, index)

    @staticmethod
    def _element(msg: Any, selection: Selection) -> float:
        """Return ``msg.data[layout.data_offset + index]`` of a one-sample message."""
        offset = int(msg.layout.data_offset)
        size = len(msg.data) - offset
        option = selection.name('index')
        if selection.index is None:
            if size != 1:
                msg_text = (f'it holds {size} elements and {option} is not set; set {option} '
                            f'to one of 0 to {size - 1}')
                raise SelectionError(msg_text)
            index = 0
        else:
            index = selection.index
        if not 0 <= index < size:
            fix = (f'set {option} to one of 0 to {size - 1}' if size > 0
                   else 'record a topic whose arrays hold the signal')
            msg_text = (f'{option} {index} is out of range: the array holds {max(size, 0)} '
                        f'element(s){_offset_note(offset)}; {fix}')
            raise SelectionError(msg_text)
        return float(msg.data[offset + index])


#: Message type -> reader. A new type is one class above and one line here.
MESSAGE_READERS: dict[str, MessageReader] = {
    Float64Reader.msgtype: Float64Reader(),
    JointStateReader.msgtype: JointStateReader(),
    Float64MultiArrayReader.msgtype: Float64MultiArrayReader(),
}


def supported_types() -> str:
    """
    List the message types :data:`MESSAGE_READERS` reads, for messages.

    Returns
    -------
    str
        E.g. ``'std_msgs/msg/Float64, sensor_msgs/msg/JointState or ...'``.

    """
    names = list(MESSAGE_READERS)
    return names[0] if len(names) == 1 else f'{", ".join(names[:-1])} or {names[-1]}'


@functools.lru_cache(maxsize=1)
def typestore() -> Any:
    """Build rosbags' ROS 2 Jazzy typestore once and return it."""
    return get_typestore(Stores.ROS2_JAZZY)


def _listing(names: list[str]) -> str:
    return ', '.join(repr(name) for name in names) or 'none'


def _offset_note(offset: int, lead: str = ' after ') -> str:
    return f'{lead}layout.data_offset {offset}' if offset else ''
