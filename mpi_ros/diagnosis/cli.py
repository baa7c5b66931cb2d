# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
``mpi-ros diagnose``: the command-line front of :func:`mpi_ros.diagnosis.diagnose`.

``mpi-ros diagnose DATA [--validate DATA2] [--input-topic T] [--output-topic T]
[--time-column C --input-column C --output-column C --input-scale F --output-scale F]
[--order auto|N L] --json report.json --report DIR [--params-out extended.yaml]``
"""

import argparse
import sys
from typing import Any, Sequence

from .diagnose import diagnose
from .report import write_extended_params, write_json, write_report
from ..errors import MPIError
from ..recordings import read_signals

__all__ = ['diagnose_main', 'build_parser']


def build_parser(prog: str = 'mpi-ros diagnose') -> argparse.ArgumentParser:
    """Return the argument parser of the diagnose command."""
    p = argparse.ArgumentParser(prog=prog, description=(
        'Diagnose what the MPI model misses in measured data, name the cause, fit the'
        ' extended model and measure the gain on validation data.'))
    p.add_argument('data', help='rosbag2 bag or CSV file (training data)')
    p.add_argument('--validate', help='separate validation recording (default: split DATA)')
    p.add_argument('--split', type=float, default=0.6,
                   help='training fraction when no --validate is given (default 0.6)')
    p.add_argument('--input-topic', help='bag topic of the current')
    p.add_argument('--output-topic', help='bag topic of the displacement')
    p.add_argument('--time-column', help='CSV column of the time [s]')
    p.add_argument('--input-column', help='CSV column of the input')
    p.add_argument('--output-column', help='CSV column of the output')
    p.add_argument('--input-scale', type=float, help='factor to A')
    p.add_argument('--output-scale', type=float, help='factor to m (e.g. 1e-9 for nm)')
    p.add_argument('--order', nargs='+', default=['auto'], metavar='auto|N L',
                   help="model order: 'auto' or two integers n l")
    p.add_argument('--json', required=True, help='report.json to write')
    p.add_argument('--report', required=True, help='directory for summary.md and plots')
    p.add_argument('--params-out', help='parameter YAML of the extended model')
    return p


def _read(path: str, args: argparse.Namespace) -> Any:
    options: dict[str, Any] = {}
    if str(path).lower().endswith('.csv'):
        for name in ('time_column', 'input_column', 'output_column', 'input_scale',
                     'output_scale'):
            if getattr(args, name) is not None:
                options[name] = getattr(args, name)
    else:
        for name in ('input_topic', 'output_topic'):
            if getattr(args, name) is not None:
                options[name] = getattr(args, name)
    return read_signals(path, **options)


def diagnose_main(argv: Sequence[str] | None = None) -> int:
    """
    Run the diagnose command; return the exit code (0 success, 1 error, 2 usage).

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
    args = parser.parse_args(argv)
    if args.order == ['auto']:
        order: Any = 'auto'
    elif len(args.order) == 2 and all(v.isdigit() for v in args.order):
        order = (int(args.order[0]), int(args.order[1]))
    else:
        parser.error(f"--order must be 'auto' or two integers N L; found {args.order}")

    def say(line: str) -> None:
        print(line, file=sys.stderr, flush=True)

    try:
        say(f'reading {args.data}')
        data = _read(args.data, args)
        validation = None
        if args.validate:
            say(f'reading {args.validate}')
            validation = _read(args.validate, args)
        report = diagnose(data, validation=validation, split=args.split, order=order,
                          progress=say)
        write_json(report, args.json)
        files = write_report(report, args.report)
        say(f'wrote {args.json} and {len(files)} file(s) in {args.report}')
        if args.params_out:
            if report.model is None:
                say('no model to write: the data are outside the invertible class')
            else:
                write_extended_params(report, args.params_out)
                say(f'wrote {args.params_out}')
    except (MPIError, OSError) as err:
        print(f'error: {err}', file=sys.stderr)
        return 1
    print(report.cause)
    return 0
