# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
``mpi-ros diagnose``: the command-line front of :func:`mpi_ros.diagnosis.diagnose`.

``mpi-ros diagnose DATA [DATA ...] [--validate DATA2] [--window T0 T1] [data options]
[--order auto|N,L|N L] --json report.json --report DIR [--params-out extended.yaml]``

The data options (``--input-topic``, ``--input-joint``, ``--input-index``,
``--input-column``, ``--output-scale``, ...) are those of ``mpi-ros identify``
(:func:`mpi_ros.app.cli_options.add_data_options`); they apply to DATA and to
``--validate``.  The data are read in SI by the units rule of every command
(:mod:`mpi_ros.units`: unit suffixes of the column, topic or joint names, ``--input-unit`` /
``--output-unit`` / ``--time-unit``; ``volts`` -> V, ``D1_nm`` -> nm converted to m); the
report names the input A or V and the output m.

``mpi-ros diagnose --excitation OUT.csv [--excitation-rate HZ --excitation-bias A
--excitation-amplitude A --seed N]`` writes the diagnostic validation excitation (columns
``time`` [s], ``current`` [A]) to play on a rig; record the answer and pass it as
``--validate``.
"""

import argparse
import csv
from pathlib import Path
import sys
from typing import Any, Callable, Sequence

from .cli_options import (
    add_data_options, add_order_option, ArgumentParser, check_outputs, data_options,
    order_option)
from ..diagnosis.diagnose import diagnose
from ..diagnosis.report import data_units, report_facts, summary_lines, \
    write_extended_params, write_json, write_report
from ..errors import DataError, MPIError
from ..plant.excitation import diagnostic_excitation
from ..progress import Progress
from ..recordings import DataOptions, join_recordings, read_recording, Recording, \
    write_csv_columns
from ..recordings.reading import source_kind

__all__ = ['diagnose_main', 'build_parser']


def build_parser(prog: str = 'mpi-ros diagnose') -> argparse.ArgumentParser:
    """Return the argument parser of the diagnose command."""
    p = ArgumentParser(prog=prog, description=(
        'Diagnose what the MPI model misses in measured data, name the cause, fit the'
        ' extended model and measure the gain on validation data.'))
    p.add_argument('data', nargs='*', metavar='DATA',
                   help='rosbag2 bag or CSV file (training data); several: experiments of one'
                        ' actuator (e.g. at several rates), joined with a time gap, each'
                        ' with its own start state; optional with --excitation')
    p.add_argument('--validate', help='separate validation recording (default: split DATA)')
    p.add_argument('--window', nargs=2, type=float, metavar=('T0', 'T1'),
                   help='diagnose only DATA between T0 and T1 [s] after its first sample')
    p.add_argument('--split', type=float, default=0.6,
                   help='training fraction when no --validate is given (default 0.6)')
    add_order_option(p, default='auto')
    p.add_argument('--json', help='report.json to write (required with DATA); written last, '
                                  'after the --report folder')
    p.add_argument('--report', help='directory for summary.md and plots (required with DATA); '
                                    'each file is replaced atomically, summary.md last')
    p.add_argument('--params-out', help='parameter YAML of the extended model')
    p.add_argument('--excitation', metavar='OUT.csv',
                   help='write the diagnostic validation excitation (time [s], current [A])')
    p.add_argument('--excitation-rate', type=float, default=1000.0,
                   help='sample rate of --excitation [Hz] (default 1000; >= 800)')
    p.add_argument('--excitation-bias', type=float, default=1.0,
                   help='centre current of --excitation [A] (default 1.0)')
    p.add_argument('--excitation-amplitude', type=float, default=0.8,
                   help='half-width of --excitation [A] (default 0.8)')
    p.add_argument('--seed', type=int, default=0, help='seed of --excitation (default 0)')
    p.add_argument('--quiet', action='store_true',
                   help='no progress line on stderr (it is drawn only when stderr is a '
                        'terminal)')
    add_data_options(p)
    return p


def _window(recording: Recording, window: Sequence[float]) -> Recording:
    t0, t1 = window
    time = recording.time - recording.time[0]
    keep = (time >= t0) & (time <= t1)
    if not t0 < t1 or int(keep.sum()) < 2:
        msg = (f'--window {t0:g} {t1:g} must give T0 < T1 [s] after the first sample and'
               f' hold at least 2 samples; the data span 0 to {time[-1]:g} s')
        raise DataError(msg)
    return Recording(recording.time[keep], recording.current[keep],
                     recording.displacement[keep],
                     source=f'{recording.source} [{t0:g} s, {t1:g} s]',
                     notes=recording.notes)


def _check_output_folders(args: argparse.Namespace) -> None:
    # Fail before reading and fitting (minutes on a long record) when a file to write
    # cannot be created: its folder is missing, or the name is a folder (the report folder
    # itself is created, with its parents).
    for option, path in (('--json', args.json), ('--params-out', args.params_out),
                         ('--excitation', args.excitation)):
        if path is None:
            continue
        target = Path(path)
        if not target.parent.is_dir():
            msg = (f'{option} {target}: directory {target.parent} does not exist; create it'
                   ' first (nothing was computed or written)')
            raise DataError(msg)
        if target.is_dir():
            msg = (f'{option} {target} is a directory; give a file name (nothing was computed'
                   ' or written)')
            raise DataError(msg)
    if args.report is not None and Path(args.report).exists() and not Path(
            args.report).is_dir():
        msg = (f'--report {args.report} is a file; give a folder for summary.md and the plots'
               ' (nothing was computed or written)')
        raise DataError(msg)


def _write_excitation(args: argparse.Namespace) -> None:
    t, current = diagnostic_excitation(sample_rate=args.excitation_rate,
                                       bias=args.excitation_bias,
                                       amplitude=args.excitation_amplitude, seed=args.seed)
    write_csv_columns(args.excitation, {'time': t, 'current': current},
                      comment='diagnostic validation excitation of mpi-ros diagnose')


def _signal_names(path: str, options: DataOptions) -> tuple[str, str]:
    # The names the reader takes the input and output from: CSV columns (resolved as the
    # reader resolves unset ones) or bag topics with their joints.
    if source_kind(path) == 'bag':
        return (f'{options.input_topic} {options.input_joint or ""}'.strip(),
                f'{options.output_topic} {options.output_joint or ""}'.strip())
    header: list[str] = []
    with Path(path).open(encoding='utf-8', newline='') as f:
        for row in csv.reader(f):
            if row and row[0].strip() and not row[0].lstrip().startswith('#'):
                header = [name.strip() for name in row]
                break
    rest = [name for name in header if name != options.time_column]
    name_in = options.input_column or (rest[0] if rest else '')
    after = header[header.index(name_in) + 1:] if name_in in header else []
    name_out = options.output_column or next(
        (name for name in after if name != options.time_column), '')
    return name_in, name_out


def _check_outputs(args: argparse.Namespace) -> None:
    # No output may replace an input (or another output): the report folder's files too.
    inputs = [('DATA', path) for path in args.data] + [('--validate', args.validate)]
    outputs = [('--excitation', args.excitation), ('--params-out', args.params_out),
               ('--json', args.json)]
    if args.report:
        folder = Path(args.report)
        if folder.exists() and not folder.is_dir():
            msg = (f'--report {folder} is a file; give a folder for summary.md and the plots '
                   '(nothing was written)')
            raise DataError(msg)
        names = ['summary.md', 'loops.png', 'residual.png'] + [
            Path(path).name for _, path in inputs
            if path and Path(path).name.startswith('signature_')
            and Path(path).suffix == '.png']
        outputs += [('--report', str(folder / name)) for name in names]
    check_outputs(inputs, outputs)


def _units(args: argparse.Namespace) -> dict[str, str]:
    options = data_options(args)
    try:
        name_in, name_out = _signal_names(args.data[0], options)   # the first training file
    except (OSError, UnicodeDecodeError, csv.Error):
        name_in = name_out = ''
    return data_units(name_in, name_out, input_scale=options.input_scale,
                      output_scale=options.output_scale, input_unit=args.input_unit,
                      output_unit=args.output_unit)


def _read(path: str, args: argparse.Namespace, say: Callable[[str], None]) -> Any:
    say(f'reading {path}')
    recording = read_recording(path, data_options(args))
    for note in recording.notes:
        say(f'note: {note}')
    for warning in recording.warnings:
        say(f'warning: {warning}')
    return recording


def diagnose_main(argv: Sequence[str] | None = None) -> int:
    """
    Run the diagnose command; return the exit code (0 success, 1 error or usage error).

    Parameters
    ----------
    argv : sequence of str, optional
        Arguments after ``diagnose`` (``sys.argv[1:]`` style).

    Returns
    -------
    int
        Exit code.

    """
    parser = build_parser()
    progress = Progress(quiet=True)

    def say(line: str) -> None:
        # Each message on its own line; the progress line below it shows the phase running
        # and the time since the start (a terminal only).
        progress.say(line)
        progress(f'{line} ...')

    try:
        args = parser.parse_args(argv)
        progress = Progress(quiet=args.quiet)
        order = order_option(args)
        if not args.data and args.excitation is None:
            parser.error('give DATA to diagnose, or --excitation OUT.csv')
        if args.data and (args.json is None or args.report is None):
            parser.error('--json and --report are required with DATA')
        data_options(args)                   # refuse bad data options before any work
        _check_output_folders(args)          # outputs that cannot be written
        _check_outputs(args)                 # and outputs that would replace an input
        if args.excitation:
            _write_excitation(args)
            say(f'wrote {args.excitation}')
            if not args.data:
                return 0
        data = join_recordings([_read(path, args, say) for path in args.data])
        if len(args.data) > 1:
            say(f'{len(args.data)} experiments joined, a time gap between them: {len(data)}'
                ' samples')
        if args.window is not None:
            data = _window(data, args.window)
            say(f'window: {len(data)} samples')
        validation = None
        if args.validate:
            validation = _read(args.validate, args, say)
        report = diagnose(data, validation=validation, split=args.split, order=order,
                          progress=say)
        report.data['units'] = _units(args)
        # The JSON, the summary and summary.md are written from the report's typed fields.
        # The folder first, the JSON last: a JSON of this run means a complete folder.
        files = write_report(report, args.report)
        write_json(report_facts(report), args.json)
        for line in summary_lines(report):
            progress.say(line)
        say(f'wrote {args.json} and {len(files)} file(s) in {args.report}')
        if args.params_out:
            if report.model is None:
                say('no model to write: the data are outside the invertible class')
            else:
                write_extended_params(report, args.params_out)
                say(f'wrote {args.params_out}')
    except (MPIError, OSError) as err:
        progress.clear()
        print(f'error: {err}', file=sys.stderr)
        return 1
    finally:
        progress.close()
    print(report.cause)
    return 0
