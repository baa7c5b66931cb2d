# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
The ``mpi-ros`` command: offline tools and the three nodes behind one console script.

Subcommands
-----------
``identify BAG|CSV``      fit a model, write a parameter YAML (and ``--json`` statistics)
``merge-axes A B ... -o F``  one identified file per axis -> a multi-axis parameter file
``simulate PARAMS``       forward model Gamma on a CSV column (warns about currents outside
                          the range the model was identified on)
``compensate PARAMS``     inverse model Gamma^-1 on a CSV column (offline feed-forward),
                          clamped as the compensator node clamps (``--no-clamp``: not)

                          Both start at rest after a sweep over the identified input range,
                          down to its lowest input
                          (``--start``: ``rest_low``, ``rest_high``, ``record`` to reproduce
                          the identification record, or explicit play states; see
                          :mod:`mpi_ros.operators.start`)
``diagnose DATA``         find what the model misses in measured data (see ``mpi_ros.diagnosis``)
``demo``                  the closed loop over DDS: record, identify, push, track, report
``compensator|identifier|plant-simulator [--ros-args ...]``  run a node, as ``ros2 run``

The command returns an exit code; errors are printed as ``error: ...`` on stderr, warnings
as ``warning: ...``.  Long work (``identify``, ``diagnose``, ``demo``) draws a progress line on
stderr when it is a terminal (:mod:`mpi_ros.progress`; ``--quiet``: none).
"""

import argparse
from collections.abc import Sequence
import hashlib
import json
import math
from pathlib import Path
import re
import sys

from typing import Any
import warnings

from ..errors import MPIError, MPIWarning

__all__ = ['main', 'order_table_lines']

_NODE_COMMANDS = ('compensator', 'identifier', 'plant-simulator', 'plant_simulator')


def _progress(text: str) -> None:
    print(text, file=sys.stderr, flush=True)


def _finite(value: Any) -> Any:
    # JSON has no NaN or Infinity: such values (an unstable order's error) become null.
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if isinstance(value, dict):
        return {key: _finite(v) for key, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_finite(v) for v in value]
    return value


def _check_output(path: str | None, option: str) -> None:
    """Fail before any work when an output file cannot be created."""
    if path is None:
        return
    target = Path(path)
    if not target.parent.is_dir():
        msg = (f'{option} {target}: directory {target.parent} does not exist; create it '
               'first (nothing was written)')
        raise MPIError(msg)
    if target.is_dir():
        msg = f'{option} {target} is a directory; give a file name (nothing was written)'
        raise MPIError(msg)


def _cmd_identify(args: argparse.Namespace) -> int:
    from .cli_options import data_options, order_option
    from ..order import format_order
    from .cli_options import check_outputs
    from ..params import params_yaml_text
    from ..pipeline import fit_recording, identified_parameters, LIMITS_COMMENT
    from ..progress import Progress
    from .ranges import range_header
    from ..recordings import atomic_writes, read_recording
    _check_output(args.output, '--output')
    _check_output(args.json, '--json')
    check_outputs([('DATA', args.data)], [('--output', args.output), ('--json', args.json)])
    options = data_options(args)             # refuse bad options before reading
    order = order_option(args)
    with Progress(quiet=args.quiet) as progress:
        progress('reading the record')
        recording = read_recording(args.data, options)
        for note in recording.notes:
            progress.say(f'note: {note}')
        if recording.units.found:
            progress.say(f'units: {recording.units.found} (stored in s, '
                         f'{recording.units.si_input} and m)')
        for warning in recording.warnings:
            progress.say(f'warning: {warning}')
        progress.say(f'identifying from {len(recording.time)} samples of {args.data} '
                     f'(order {format_order(order)}) ...')
        result = fit_recording(recording, order=order, anchor=args.anchor,
                               periodic=args.periodic, dynamics=args.dynamics,
                               progress=progress).result
    for line in order_table_lines(result.order_table):
        _progress(line)
    n, l = result.order  # noqa: E741
    model = result.model
    _progress(f'order n={n}, l={l}: nonlinearity error (37) '
              f'{100 * result.nonlinearity_error:.2f} % of the output range, RMS error '
              f'{100 * result.rms_error:.3f} % (straight line: '
              f'{100 * result.linear_rms_error:.3f} %); the whole record simulated from its '
              f'first sample: {100 * result.whole_record_rms_error:.3f} % '
              f'({result.solve_time:.2f} s)')
    _progress(f'operating point: input offset {model.input_offset:.6g}, output offset '
              f"{model.output_offset:.6g}, output sign {model.output_sign:+d}; the record's "
              'start (record_start.*, for simulate --start record; a new input starts at '
              'rest after a sweep down to the lowest identified input): '
              f"{result.start_state.get('description', 'n/a')}")
    record_range = range_header(recording.current, recording.displacement,
                                recording.units.input_quantity)
    _progress(f'{record_range} (written in the YAML header: simulate and compensate warn'
              ' outside it, compensate clamps to it)')
    if result.findings:
        _progress(f'found: {result.findings}')
    from ..diagnosis.time_base import implausible_dynamics, time_base_warning
    time_warning = time_base_warning(implausible_dynamics(result.dynamics_estimate),
                                     [('record', recording.time)], command='identify')
    if time_warning is not None:
        _progress(f'warning: {time_warning}')
    for note in result.notes:
        if not note.startswith('warning:'):     # the warnings were shown as they came
            _progress(f'note: {note}')
    summary = dict(result.summary(), source=str(args.data))
    text = params_yaml_text(
        identified_parameters(result, recording), node_name=args.node_name,
        header=(f'MPI model identified by mpi-ros identify from {args.data}\n'
                f'order n={n}, l={l}; nonlinearity error (37) '
                f'{100 * result.nonlinearity_error:.2f} %\n'
                f'{record_range}\n{LIMITS_COMMENT}'))
    # The pair: both are written to temporary files, then the YAML is renamed over
    # --output and the JSON over --json last. The JSON names the YAML it describes by its
    # SHA-256, so a crash between the two renames (a new YAML beside an old JSON) shows.
    summary['params_file'] = {'path': str(args.output),
                              'sha256': hashlib.sha256(text.encode('utf-8')).hexdigest()}
    paths = [args.output] + ([args.json] if args.json else [])
    try:
        with atomic_writes(paths) as handles:
            handles[0].write(text)
            if args.json:
                json.dump(_finite(summary), handles[1], indent=2, allow_nan=False)
    except OSError as err:
        msg = f'cannot write {" and ".join(paths)}: {err}'
        raise MPIError(msg) from err
    _progress(f'wrote {args.output}')
    if args.json:
        _progress(f'wrote {args.json}')
    return 0


def order_table_lines(table: list[dict[str, Any]]) -> list[str]:
    """
    Return the order selection's table as printed by ``identify`` (one line per order).

    Parameters
    ----------
    table : list of dict
        :attr:`mpi_ros.model_fit.IdentificationResult.order_table`.

    Returns
    -------
    list of str
        One line per order: its held-out errors, or ``held-out error unstable (not
        considered)`` for a row marked ``unstable`` (an absurd held-out error, such as a
        high order on a short record), never its absurd percentage.

    """
    lines = []
    for row in table:
        if row.get('unstable'):
            lines.append(f"  n={row['n']:2d} l={row['l']:2d}  held-out error unstable (not"
                         ' considered)')
            continue
        lines.append(f"  n={row['n']:2d} l={row['l']:2d}  held-out RMS error "
                     f"{100 * row['rms_error']:6.3f} %, nonlinearity error (37) "
                     f"{100 * row['nonlinearity_error']:6.2f} % of the output range")
    return lines


def _model_parameters(path: str, node_name: str | None) -> dict[str, Any]:
    """Read the model keys of `node_name` (None: the file's compensator or only entry)."""
    from ..params import load_params_document, read_params_yaml
    parameters = read_params_yaml(path) if node_name is None else read_params_yaml(
        path, node_name=node_name)
    if node_name is not None:
        # read_params_yaml falls back to a file's only entry whatever its name; an explicit
        # --node-name must name an entry that is there.
        document = load_params_document(path)
        entries = [str(key) for key, value in document.items()
                   if isinstance(value, dict) and 'ros__parameters' in value]
        if node_name.lstrip('/') not in {entry.lstrip('/') for entry in entries}:
            msg = (f'--node-name {node_name}: parameter file {path} has no entry for node '
                   f'{node_name!r}; entries found: {", ".join(entries)}; pass --node-name with '
                   'one of them, or leave it out')
            raise MPIError(msg)
    _refuse_unknown_keys(path, parameters)
    return parameters


def _refuse_unknown_keys(path: str, parameters: dict[str, Any]) -> None:
    # An error, not a warning: simulate and compensate read only the compensator's keys, so
    # a key they do not know is a typo (model.output_ofset) or a file for another node, and
    # either would silently give another result than the user meant.
    from ..node_parameters import RCLPY_PARAMETERS
    from ..node_parameters.compensator import compensator_parameters
    from ..params import closest_key, unknown_keys
    known = [spec.name for spec in compensator_parameters()] + list(RCLPY_PARAMETERS)
    unknown = unknown_keys(parameters, known, prefixes=('qos_overrides.',))
    if not unknown:
        return
    if any(re.match(r'axis[0-9]+\.', name) for name in unknown):
        msg = (f'parameter file {path} holds a multi-axis model (axis<k>.* keys); this command'
               ' takes the single-axis file of one axis, as mpi-ros identify writes it')
        raise MPIError(msg)
    hints = []
    for name in unknown[:5]:
        near = closest_key(name, known)
        hints.append(f'{name} (did you mean {near}?)' if near else name)
    more = f' and {len(unknown) - 5} more' if len(unknown) > 5 else ''
    msg = (f'parameter file {path} has parameters the compensator does not know: '
           f'{", ".join(hints)}{more}; correct or remove them (the known keys are the '
           "compensator node's, as `ros2 param describe` lists them)")
    raise MPIError(msg)


def _input_column(header: list[str], args: argparse.Namespace, *, inverse: bool,
                  numeric: list[bool] | None = None) -> tuple[str | None, str]:
    """
    Return the time column (None: none) and the input column of a --input table.

    Without ``--input-column`` the input is the one column besides the time whose values
    are numbers (``numeric``: per column, whether its first value is one); text columns
    (labels, notes) are ignored, as ``identify`` ignores them.

    """
    what = 'desired displacement' if inverse else 'current'
    time_column = args.time_column or None
    if time_column is not None and time_column not in header:
        if time_column != 'time':
            msg = (f'--time-column {time_column}: --input {args.input} has no such column; '
                   f'columns: {", ".join(header)}; pass one of them, or --time-column \'\' '
                   'if the file has no time column')
            raise MPIError(msg)
        time_column = None
    names = [name for name in header if name != time_column]
    if args.input_column is not None:
        if args.input_column not in names:
            msg = (f'--input-column {args.input_column}: --input {args.input} has no such '
                   f'column besides the time; columns: {", ".join(names) or "none"}; pass the '
                   f'column holding the {what}')
            raise MPIError(msg)
        return time_column, args.input_column
    if numeric is not None:
        names = [name for name in names if numeric[header.index(name)]]
    if len(names) != 1:
        listing = ', '.join(names) or 'none'
        msg = (f'--input {args.input} has {len(names)} columns besides the time ({listing}); '
               f'pass --input-column with the one holding the {what}')
        raise MPIError(msg)
    return time_column, names[0]


def _apply_model(args: argparse.Namespace, *, inverse: bool) -> int:
    from .cli_options import check_outputs
    check_outputs([('PARAMS', args.params), ('--input', args.input)],
                  [('--output', args.output)])
    parameters = _model_parameters(args.params, args.node_name)
    from ..extensions import extended_model_from_params
    from ..operators.start import StartState
    from .ranges import identified_range, outside, recorded_range
    from ..recordings import read_csv_table, write_csv_columns
    from ..units import INPUT_QUANTITY_KEY, input_unit_of, resolve_units
    start = StartState.parse(args.start, option='--start')
    described = extended_model_from_params(parameters)
    quantity = parameters.get(INPUT_QUANTITY_KEY) or 'current'
    unit = input_unit_of(quantity)
    used: list[str | None] = []

    def select(names: list[str], numeric: list[bool]) -> list[str]:
        used[:] = _input_column(names, args, inverse=inverse, numeric=numeric)
        return [name for name in used if name is not None]

    header, table = read_csv_table(args.input, select=select,
                                   nonfinite_hint='remove those rows or fill in the values')
    time_column, input_column = used[0], str(used[1])
    result_column = args.column_name or (quantity if inverse else 'displacement')
    if result_column in (input_column, time_column):
        msg = (f'--column-name {result_column}: the result column would replace the '
               f'{"input" if result_column == input_column else "time"} column of the same '
               'name; pass --column-name with another name')
        raise MPIError(msg)
    column = header.index(input_column)
    # The units rule of every command (mpi_ros.units): names and options, values to SI.
    units = resolve_units(time_column or '', '' if inverse else input_column,
                          input_column if inverse else '', time_unit=args.time_unit,
                          input_unit=None if inverse else args.input_unit,
                          output_unit=args.output_unit if inverse else None)
    values = table[:, column] * (units.output_factor if inverse else units.input_factor)
    if not inverse and units.si_input != unit and units.input != 'A':
        msg = (f'--input {args.input}: column {input_column!r} is in {units.input}, but '
               f'{args.params} holds a {quantity} model (input in {unit}); pass the column '
               f'in {unit} (or --input-unit)')
        raise MPIError(msg)
    time = None if time_column is None else (
        table[:, header.index(time_column)] * units.time_factor)
    if units.found:
        _progress(f'units: {units.found} (converted to SI)')
    # The range identify wrote in the file's header, else the one the model's thresholds tell.
    recorded = recorded_range(args.params)
    ranges = recorded or identified_range(described)
    if inverse:
        limits = _limits(args, parameters, ranges.current, unit)
        result = _compensate(described, time, time_column, values, args, limits, start,
                             ranges.current, unit,
                             recorded=recorded.current if recorded is not None else None)
    else:
        result = _simulate(_started(described, start, ranges.current, None, unit), time,
                           time_column, values, args)
        if ranges.current is None:
            _progress(f'note: {_UNKNOWN_RANGE.format(params=args.params)}: no range check')
        else:
            out = outside(values, *ranges.current)
            if out.count:
                _progress(f'warning: {out.describe(quantity + "s", ", " + _INPUT_RANGE, unit)};'
                          ' the model extrapolates there')
    columns = {}
    if time_column is not None:
        columns[time_column] = table[:, header.index(time_column)]
    columns[input_column] = table[:, column]
    columns[result_column] = result
    write_csv_columns(args.output, columns)
    _progress(f'wrote {len(result)} samples to {args.output} ({input_column} -> '
              f'{result_column})')
    return 0


#: What simulate and compensate say of the range a model was identified on.
_INPUT_RANGE = 'the input range the model was identified on'
_UNKNOWN_RANGE = ('the model in {params} does not tell the range it was identified on (the '
                  'thresholds of its superposition operator are not spaced as mpi-ros '
                  'identify spaces them: written by hand, or l = 0)')


def _limits(args: argparse.Namespace, parameters: dict[str, Any],
            identified: tuple[float, float] | None,
            unit: str = 'A') -> tuple[float, float, str] | None:
    """Return the clamp range [A or V] and where it comes from, as the node would have it."""
    ends: list[float] = []
    sources: list[str] = []
    for end, option, key in ((0, 'output_min', 'output.min'), (1, 'output_max', 'output.max')):
        given = getattr(args, option)
        if given is not None:
            ends.append(float(given))
            sources.append(f'--{option.replace("_", "-")}')
        elif isinstance(parameters.get(key), (int, float)):
            ends.append(float(parameters[key]))
            sources.append(f'{key} of {args.params}')
        elif identified is not None:
            ends.append(identified[end])
            sources.append(_INPUT_RANGE)
        else:
            return None
    lo, hi = ends
    if not (math.isfinite(lo) and math.isfinite(hi) and lo < hi):
        quantity = 'voltage' if unit == 'V' else 'current'
        msg = (f'the {quantity} range must be finite with its minimum below its maximum; found '
               f'{lo:g} ({sources[0]}) and {hi:g} ({sources[1]}); pass --output-min and '
               "--output-max with the actuator's safe range")
        raise MPIError(msg)
    source = sources[0] if sources[0] == sources[1] else ' and '.join(sources)
    return lo, hi, source


def _started(model: Any, start: Any, identified: tuple[float, float] | None,
             limits: tuple[float, float, str] | None, unit: str) -> Any:
    """Return the model starting where ``start`` says (a note tells where, in ``unit``)."""
    from ..extensions import start_model
    from ..operators.start import start_range
    allowed = start_range(identified, None if limits is None else limits[:2])
    started, _, words = start_model(model, start, allowed, unit)
    _progress(f'note: start: {words}')
    return started


def _compensate(model: Any, time: Any, time_column: str | None, values: Any,
                args: argparse.Namespace, limits: tuple[float, float, str] | None,
                start: Any, identified: tuple[float, float] | None,
                unit: str = 'A', *, recorded: tuple[float, float] | None = None) -> Any:
    # As the compensator node: the inverse of the model, its commands clamped to the safe
    # current range (the forward state follows the clamped command), unless --no-clamp.
    # With an effect (time column needed) the compensator's streaming inverse, as the node
    # with its defaults (a dead time predicted; an output mode: Gamma only, and a note).
    import numpy as np
    from ..compensation import operating_range
    from ..compensation.limits import limits_shortfall
    from ..compensation.updates import uncompensated
    from ..operators.start import start_range
    from .ranges import outside
    plain = not model.timed
    if model.timed:
        _check_time_column(model, time, time_column, args)
    left_out = uncompensated(model)
    if left_out is not None:
        _progress(f'note: {left_out}')
    if limits is None:
        _progress(f'note: {_UNKNOWN_RANGE.format(params=args.params)}: no range check and no'
                  ' clamping; pass --output-min and --output-max to clamp')
    else:
        lo, hi, source = limits
        # The node's rule (compensation.limits): limits that cut the identified range, the
        # one the header records where the file has it.
        shortfall = limits_shortfall(model, lo, hi, recorded)
        if shortfall is not None:
            _progress(f'warning: {shortfall.describe(unit=unit, names=source)}')
        reach = operating_range(model.gamma, lo, hi)
        out = outside(values, *reach)
        if out.count:
            inputs = 'voltages' if unit == 'V' else 'currents'
            where = (f', the range the model reaches with {inputs} from {lo:.4g} to {hi:.4g}'
                     f' {unit} (from {source})')
            _progress(f'warning: {out.describe("desired displacements", where, "m")}')
    if limits is None or args.no_clamp:
        if plain:
            result = _started(model, start, identified, limits,
                              unit).gamma.inverse().simulate(values)
        else:
            wide = 1e12 * (1.0 + float(np.max(np.abs(values))))
            allowed = start_range(identified, None if limits is None else limits[:2])
            unclamped = _streaming_compensator(model, time, -wide, wide, start=start,
                                               current_range=allowed, unit=unit)
            _progress(f'note: start: {unclamped.start_description}')
            result = unclamped.command_batch(values, time)
        if limits is not None:
            out = outside(result, limits[0], limits[1])
            if out.count:
                where = f' (from {limits[2]})'
                _progress(f'warning: {out.describe("commands", where, unit)}; not clamped'
                          ' (--no-clamp)')
        return result
    lo, hi, source = limits
    compensator = _streaming_compensator(model, time, lo, hi, start=start,
                                         current_range=identified, unit=unit)
    _progress(f'note: start: {compensator.start_description}')
    result = compensator.command_batch(values, None if plain else time)
    clamped = compensator.counters['clamped']
    if clamped:
        _progress(f'warning: {clamped} of {len(values)} commands clamped to {lo:.4g} to '
                  f'{hi:.4g} {unit} (from {source}), as the compensator node clamps; --no-clamp '
                  'writes the unclamped inverse')
    return result


def _streaming_compensator(model: Any, time: Any, lo: float, hi: float, *,
                           start: Any, current_range: tuple[float, float] | None = None,
                           unit: str = 'A') -> Any:
    import numpy as np
    from ..compensation import Compensator
    period = 1e-3 if time is None or len(time) < 2 else float(np.median(np.diff(time)))
    return Compensator(model, output_min=lo, output_max=hi, sample_period=period,
                       start=start, current_range=current_range, input_unit=unit)


def _check_time_column(model: Any, time: Any, time_column: str | None,
                       args: argparse.Namespace) -> None:
    # A model with an effect (dead time, lag, creep, ...) depends on time: the input needs
    # its time column, increasing.
    import numpy as np
    if time is None:
        msg = (f'{args.params} holds a model with {model.cause} (it depends on time):'
               f' --input {args.input} needs a time column [s]; pass --time-column with its'
               ' name')
        raise MPIError(msg)
    if not np.all(np.diff(time) > 0.0):
        msg = (f'--input {args.input}: the time column {time_column!r} must increase strictly'
               f' for a model with {model.cause}; sort or repair it')
        raise MPIError(msg)


def _simulate(model: Any, time: Any, time_column: str | None, values: Any,
              args: argparse.Namespace) -> Any:
    if model.timed:
        _check_time_column(model, time, time_column, args)
    return model.response(time, values)


def _cmd_simulate(args: argparse.Namespace) -> int:
    return _apply_model(args, inverse=False)


def _cmd_compensate(args: argparse.Namespace) -> int:
    return _apply_model(args, inverse=True)


def _cmd_merge_axes(args: argparse.Namespace) -> int:
    # One identified file per axis -> one multi-axis compensator file.
    from ..node_parameters.compensator import merge_axes
    from ..errors import ParameterRejected
    from ..params import write_params_yaml
    _check_output(args.output, '--output')
    per_axis = [_model_parameters(path, args.node_name) for path in args.params]
    try:
        merged = merge_axes(per_axis)
    except ParameterRejected as err:
        msg = f'{err} (files: {", ".join(args.params)})'
        raise MPIError(msg) from err
    if args.joints:
        joints = [name.strip() for name in args.joints.split(',')]
        if len(joints) != len(per_axis) or len(set(joints)) != len(joints) or not all(joints):
            msg = (f'--joints {args.joints}: give {len(per_axis)} different names, one per '
                   'file, in the order of the files')
            raise MPIError(msg)
        merged.update(joints=joints, output_layout='flat')
    header = [f'{len(per_axis)}-axis model merged by mpi-ros merge-axes']
    for axis, path in enumerate(args.params):
        header.append(f'axis {axis}: {path}')
        with Path(path).open(encoding='utf-8') as f:
            header += [f'  {line[1:].strip()}' for line in f
                       if line.startswith('#') and 'identified on' in line]
    if args.joints:
        header.append('joints and output_layout flat: ros2_control forward_command_controller'
                      ' layout (remap current_commands to /<controller>/commands)')
    try:
        write_params_yaml(args.output, merged, node_name=args.node_name or 'compensator',
                          header='\n'.join(header))
    except OSError as err:
        msg = f'cannot write --output {args.output}: {err}'
        raise MPIError(msg) from err
    _progress(f'wrote {args.output} ({len(per_axis)} axes)')
    return 0


def _cmd_diagnose(argv: list[str]) -> int:
    try:
        from .diagnose_cli import diagnose_main
    except ImportError as err:            # pragma: no cover - during development only
        msg = f'diagnosis is not available in this installation: {err}'
        raise MPIError(msg) from err
    return int(diagnose_main(argv))


def _cmd_demo(argv: list[str]) -> int:
    from .demo import demo_main
    return int(demo_main(argv))


def _parser() -> argparse.ArgumentParser:
    # Imported here: the node subcommands start without loading the recordings (rosbags).
    from .cli_options import add_data_options, add_order_option, ArgumentParser
    parser = ArgumentParser(
        prog='mpi-ros', description='Modified Prandtl-Ishlinskii hysteresis compensation.',
        epilog='Node subcommands (compensator, identifier, plant-simulator) take ROS '
               'arguments exactly like `ros2 run mpi_ros <node> --ros-args ...`. '
               'diagnose and demo have their own --help. Errors (usage errors too) exit '
               'with status 1.')
    sub = parser.add_subparsers(dest='command', metavar='COMMAND')
    p = sub.add_parser('identify', help='fit a model from a bag or CSV, write params YAML')
    p.add_argument('data', help='rosbag2 directory (sqlite3/mcap) or CSV file')
    add_order_option(p, default='14,7')
    p.add_argument('-o', '--output', required=True,
                   help='parameter YAML to write (written first; see --json)')
    p.add_argument('--json', help='fit statistics to write (order, errors, samples), written '
                                  'last, after --output: its params_file.sha256 is the '
                                  'SHA-256 of the YAML it belongs to (a crash between the '
                                  'two leaves a YAML whose digest differs)')
    p.add_argument('--node-name', default='compensator',
                   help='node the YAML is keyed by (default: compensator)')
    p.add_argument('--anchor', choices=('operating_point', 'origin'), default='operating_point',
                   help='operating_point (default): any sensor zero, bias, sign or start '
                        'state; origin: the design of the paper, for data that start at rest '
                        'at zero input and zero output')
    p.add_argument('--periodic', action='store_true',
                   help='the record is one period the actuator had been following (e.g. a '
                        'single measured loop that ends where it starts): its start state is '
                        'its end state instead of the one estimated (needs an explicit '
                        '--order)')
    p.add_argument('--dynamics', choices=('auto', 'off'), default='auto',
                   help="auto (default): with a time base, estimate the input's dead time "
                        'and lag and model them when they cut the held-out error clearly '
                        '(written as model.dead_time / model.rate_dependence.*), and a '
                        'lightly damped output mode when the output rings after steps '
                        '(model.resonance.*); off: the static model only')
    p.add_argument('--quiet', action='store_true',
                   help='no progress line on stderr (it is drawn only when stderr is a '
                        'terminal)')
    add_data_options(p)
    p.set_defaults(func=_cmd_identify)
    for name, func, what, column in (
            ('simulate', _cmd_simulate, 'forward model Gamma', 'current'),
            ('compensate', _cmd_compensate, 'inverse model Gamma^-1',
             'desired displacement')):
        p = sub.add_parser(name, help=f'apply the {what} to a CSV column')
        p.add_argument('params', help='parameter YAML (as written by mpi-ros identify)')
        p.add_argument('--input', required=True,
                       help=f'CSV with a header; its column of the {column}')
        p.add_argument('--output', required=True, help='CSV to write (time, input, result)')
        p.add_argument('--column-name', default=None, help='name of the result column')
        p.add_argument('--node-name', default=None,
                       help='node whose parameters to use (default: compensator, or the '
                            "file's only node)")
        p.add_argument('--start', default='rest_low', metavar='START',
                       help='where the actuator is before the first sample: rest_low '
                            '(default: at rest after a sweep up to the highest identified '
                            'input and down to the lowest, a mode at rest), rest_high (after '
                            'a sweep down and up to the highest), record (the identification '
                            "record's start: record_start.* of PARAMS, to reproduce that"
                            ' record), or the play states [A] separated by commas')
        if name == 'compensate':
            p.add_argument('--output-min', type=float, default=None, metavar='A',
                           help="lowest current command [A], as the node's output.min "
                                '(default: output.min of PARAMS if set, else the lower end of '
                                'the identified input range)')
            p.add_argument('--output-max', type=float, default=None, metavar='A',
                           help='highest current command [A], as output.max (default: '
                                'output.max of PARAMS if set, else the upper end of the '
                                'identified input range)')
            p.add_argument('--no-clamp', action='store_true',
                           help='write the unclamped inverse (commands outside the range '
                                'are counted and warned about, not limited)')
        unit_option = 'output_unit' if name == 'compensate' else 'input_unit'
        add_data_options(p, names=['time_column', 'input_column', 'time_unit', unit_option],
                         descriptions={
            'input_column': f'CSV column of the {column} (needed when the file has several '
                            'columns besides the time)',
            unit_option: f'unit of the {column} column (unset: from a suffix of its name, '
                         'e.g. _um, _V, else SI); converted to SI'})
        p.set_defaults(func=func)
    p = sub.add_parser('merge-axes', help='merge identified files (one per axis) into one '
                                          'multi-axis parameter file')
    p.add_argument('params', nargs='+', help='parameter YAMLs written by mpi-ros identify, '
                                             'one per axis, in axis order')
    p.add_argument('-o', '--output', required=True, help='multi-axis parameter YAML to write')
    p.add_argument('--node-name', default=None,
                   help='node the files are keyed by and the output is keyed by (default: '
                        "compensator, or each file's only node)")
    p.add_argument('--joints', default=None, metavar='J0,J1,...',
                   help='joint names in axis order: also writes joints and output_layout flat '
                        '(the ros2_control forward_command_controller layout)')
    p.set_defaults(func=_cmd_merge_axes)
    sub.add_parser('diagnose', help='find which effect the model misses (see diagnose -h)',
                   add_help=False)
    sub.add_parser('demo', help='closed-loop demo over DDS (see demo -h)', add_help=False)
    for name in ('compensator', 'identifier', 'plant-simulator'):
        sub.add_parser(name, help=f'run the {name} node (--ros-args ...)', add_help=False)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """
    Run the ``mpi-ros`` command.

    Parameters
    ----------
    argv : sequence of str, optional
        Arguments without the program name (default: ``sys.argv[1:]``).

    Returns
    -------
    int
        Exit status: 0 on success, 1 on any error (usage errors included), 130
        when interrupted.

    """
    args_list = list(sys.argv[1:] if argv is None else argv)
    if args_list and args_list[0] in _NODE_COMMANDS:
        from ..nodes.launcher import run_node
        return int(run_node(args_list[0], args_list[1:]))
    with warnings.catch_warnings():
        warnings.showwarning = show_warning
        return _run_command(args_list)


def show_warning(message: Warning | str, category: type[Warning], filename: str, lineno: int,
                 file: Any = None, line: str | None = None) -> None:
    """
    Print a warning as the commands print theirs: one line ``warning: ...`` on stderr.

    Python's default form names the source file and line of the call that warned, and
    repeats that line of code: noise to a user of the command.  The parameters are those of
    :func:`warnings.showwarning`.
    """
    text = ' '.join(str(message).split())
    if not issubclass(category, MPIWarning):
        text = f'{category.__name__}: {text}'
    if not text.startswith('warning:'):
        text = f'warning: {text}'
    print(text, file=sys.stderr if file is None else file)


def _run_command(args_list: list[str]) -> int:
    # The command, its errors as `error: ...` lines and its exit status.
    try:
        if args_list and args_list[0] == 'diagnose':
            return _cmd_diagnose(args_list[1:])
        if args_list and args_list[0] == 'demo':
            return _cmd_demo(args_list[1:])
        parser = _parser()
        args = parser.parse_args(args_list)
        if args.command is None:
            from .cli_options import UsageError
            parser.print_help()
            msg = 'give a COMMAND (see the list above)'
            raise UsageError(msg)
        return int(args.func(args))
    except MPIError as err:
        print(f'error: {err}', file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print('error: interrupted', file=sys.stderr)
        return 130


if __name__ == '__main__':  # pragma: no cover
    sys.exit(main())
