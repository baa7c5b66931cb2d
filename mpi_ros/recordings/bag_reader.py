# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Read the actuator input and output of a rosbag2 bag (sqlite3 or mcap) as paired samples.

Each topic's messages become samples through the reader registered for the
topic's type (:data:`mpi_ros.recordings.messages.MESSAGE_READERS`, one module per
message type): one sample per message, or the K samples of one axis of a chunked
``std_msgs/msg/Float64MultiArray`` (``layout.dim`` = samples x axes, the
multi-axis nodes' layout). Every sample gets a time (a message's log time
belongs to its last sample); each output sample is paired with the input held
at its time. The storage files are found and checked by
:mod:`mpi_ros.recordings.bag_storage`.
"""

from __future__ import annotations

import contextlib
from pathlib import Path

import numpy as np
import numpy.typing as npt
from rosbags.rosbag2 import Reader

from .bag_storage import check_message_counts, check_sqlite_file, corrupt_bag, \
    finish_unfinished_mcap, locate_bag
from .messages import MESSAGE_READERS, MessageReader, Selection, SelectionError, \
    supported_types, typestore
from .options import DataOptions
from .recording import check_magnitudes, FloatArray, in_si, MIN_SAMPLES, PathLike, Recording
from ..errors import DataError

__all__ = ['TIME_SOURCES', 'read_bag', 'read_bag_signals']

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
    of samples x axes), see :mod:`mpi_ros.recordings.messages`. Each output
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
    storage_path, notes = locate_bag(bag)
    with contextlib.ExitStack() as stack:
        if storage_path.suffix.lower() == '.mcap' and storage_path.is_file():
            # A recorder that was killed leaves an mcap without its summary and footer
            # (and no metadata.yaml): read the chunks it finished.
            repaired = finish_unfinished_mcap(bag, storage_path, stack)
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
        raise corrupt_bag(bag, err) from err
    try:
        files = [storage_path] if storage_path.is_file() else sorted(storage_path.iterdir())
        for path in files:
            if path.suffix.lower() == '.db3':
                check_sqlite_file(bag, path)
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
                if number == 0:
                    shape = readers[conn.topic].shape(decoded)
                    if shape is not None:
                        layouts[conn.topic] = shape
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
            raise corrupt_bag(bag, err) from err
        check_message_counts(bag, wanted, counts)
    finally:
        with contextlib.suppress(Exception):
            reader.close()
    _check_layouts(bag, selections, layouts, options)
    return {role: (np.array(stamps[role], dtype=np.int64),
                   np.concatenate(values[role]) if values[role] else np.empty(0),
                   np.array([chunk.size for chunk in values[role]], dtype=np.int64))
            for role in roles}


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
