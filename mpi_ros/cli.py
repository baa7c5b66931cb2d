# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
The ``mpi-ros`` command: offline tools and the three nodes behind one console script.

Subcommands
-----------
``identify BAG|CSV``      fit a model, write a parameter YAML (and ``--json`` statistics)
``simulate PARAMS``       forward model Gamma on a CSV column
``compensate PARAMS``     inverse model Gamma^-1 on a CSV column (offline feed-forward)
``diagnose DATA``         find what the model misses in measured data (see ``mpi_ros.diagnosis``)
``demo``                  the closed loop over DDS: record, identify, push, track, report
``compensator|identifier|plant-simulator [--ros-args ...]``  run a node, as ``ros2 run``

The command returns an exit code; errors are printed as ``error: ...`` on stderr.
"""

import argparse
from collections.abc import Sequence
import json
from pathlib import Path
import sys

from .errors import MPIError

__all__ = ['main']

_NODE_COMMANDS = ('compensator', 'identifier', 'plant-simulator', 'plant_simulator')


def _progress(text: str) -> None:
    print(text, file=sys.stderr, flush=True)


def _parse_order(values: list[str] | None) -> str | tuple[int, int]:
    if values is None:
        return (14, 7)
    if values == ['auto']:
        return 'auto'
    if len(values) == 2 and all(v.isdigit() for v in values):
        return int(values[0]), int(values[1])
    msg = f"--order takes 'auto' or two whole numbers N L; found {' '.join(values)!r}"
    raise MPIError(msg)


def _add_data_options(p: argparse.ArgumentParser) -> None:
    p.add_argument('--input-topic', default='/current_command',
                   help='bag topic of the input (std_msgs/Float64, A)')
    p.add_argument('--output-topic', default='/displacement',
                   help='bag topic of the output (std_msgs/Float64, m)')
    p.add_argument('--time-column', default='time', help='CSV time column [s]')
    p.add_argument('--input-column', default=None, help='CSV input column (default: first)')
    p.add_argument('--output-column', default=None, help='CSV output column (default: next)')
    p.add_argument('--input-scale', type=float, default=1.0, help='multiply the input by this')
    p.add_argument('--output-scale', type=float, default=1.0,
                   help='multiply the output by this (e.g. 1e-9 for nm -> m)')


def _read_data(path: str, args: argparse.Namespace):  # noqa: ANN202
    from .recordings import read_signals
    if Path(path).suffix.lower() == '.csv':
        return read_signals(path, time_column=args.time_column, input_column=args.input_column,
                            output_column=args.output_column, input_scale=args.input_scale,
                            output_scale=args.output_scale)
    return read_signals(path, input_topic=args.input_topic, output_topic=args.output_topic)


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
    from .identification import identify
    from .params import write_params_yaml
    from .recordings import atomic_write
    _check_output(args.output, '--output')
    _check_output(args.json, '--json')
    data = _read_data(args.data, args)
    order = _parse_order(args.order)
    _progress(f'identifying from {len(data.time)} samples of {args.data} '
              f'(order {order if isinstance(order, str) else "n=%d, l=%d" % order}) ...')
    result = identify(data.current, data.displacement, order=order)
    for row in result.order_table:
        _progress(f"  n={row['n']:2d} l={row['l']:2d}  held-out nonlinearity error "
                  f"{100 * row['nonlinearity_error']:6.2f} %")
    n, l = result.order  # noqa: E741
    _progress(f'order n={n}, l={l}: nonlinearity error (37) '
              f'{100 * result.nonlinearity_error:.2f} %, relative RMS error '
              f'{100 * result.rms_error:.3f} % ({result.solve_time:.2f} s)')
    summary = dict(result.summary(), source=str(args.data))
    # Both files appear only when both are complete: each is written to a temporary
    # file and renamed; a YAML this run created is removed again if the JSON fails.
    created = not Path(args.output).exists()
    try:
        write_params_yaml(args.output, result.model.to_params(), node_name=args.node_name,
                          header=(f'MPI model identified by mpi-ros identify from {args.data}\n'
                                  f'order n={n}, l={l}; nonlinearity error (37) '
                                  f'{100 * result.nonlinearity_error:.2f} %'))
    except OSError as err:
        msg = f'cannot write --output {args.output}: {err}'
        raise MPIError(msg) from err
    if args.json:
        try:
            with atomic_write(args.json) as f:
                json.dump(summary, f, indent=2)
        except BaseException:
            if created:
                Path(args.output).unlink(missing_ok=True)
            raise
    _progress(f'wrote {args.output}')
    if args.json:
        _progress(f'wrote {args.json}')
    return 0


def _apply_model(args: argparse.Namespace, *, inverse: bool) -> int:
    from .model import MPIModel
    from .params import read_params_yaml
    from .recordings import read_csv_table, write_csv_columns
    model = MPIModel.from_params(read_params_yaml(args.params, node_name=args.node_name))
    header, table = read_csv_table(args.input)
    names = [h for h in header if h != 'time']
    if not names:
        msg = f'{args.input} has no input column besides time; columns: {", ".join(header)}'
        raise MPIError(msg)
    column = header.index(names[0])
    operator = model.inverse() if inverse else model
    result = operator.simulate(table[:, column])
    columns = {}
    if 'time' in header:
        columns['time'] = table[:, header.index('time')]
    columns[names[0]] = table[:, column]
    columns[args.column_name or ('current' if inverse else 'displacement')] = result
    write_csv_columns(args.output, columns)
    _progress(f'wrote {len(result)} samples to {args.output}')
    return 0


def _cmd_simulate(args: argparse.Namespace) -> int:
    return _apply_model(args, inverse=False)


def _cmd_compensate(args: argparse.Namespace) -> int:
    return _apply_model(args, inverse=True)


def _cmd_diagnose(argv: list[str]) -> int:
    try:
        from .diagnosis.cli import diagnose_main
    except ImportError as err:            # pragma: no cover - during development only
        msg = f'diagnosis is not available in this installation: {err}'
        raise MPIError(msg) from err
    return int(diagnose_main(argv))


def _cmd_demo(argv: list[str]) -> int:
    from .demo import demo_main
    return int(demo_main(argv))


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog='mpi-ros', description='Modified Prandtl-Ishlinskii hysteresis compensation.',
        epilog='Node subcommands (compensator, identifier, plant-simulator) take ROS '
               'arguments exactly like `ros2 run mpi_ros <node> --ros-args ...`. '
               'diagnose and demo have their own --help.')
    sub = parser.add_subparsers(dest='command', metavar='COMMAND')
    p = sub.add_parser('identify', help='fit a model from a bag or CSV, write params YAML')
    p.add_argument('data', help='rosbag2 directory (sqlite3/mcap) or CSV file')
    p.add_argument('--order', nargs='+', metavar='N',
                   help="'auto' or N L (default 14 7, the paper's order)")
    p.add_argument('-o', '--output', required=True, help='parameter YAML to write')
    p.add_argument('--json', help='fit statistics to write (order, errors, samples)')
    p.add_argument('--node-name', default='compensator', help='node the YAML is keyed by')
    _add_data_options(p)
    p.set_defaults(func=_cmd_identify)
    for name, func, what in (('simulate', _cmd_simulate, 'forward model Gamma'),
                             ('compensate', _cmd_compensate, 'inverse model Gamma^-1')):
        p = sub.add_parser(name, help=f'apply the {what} to a CSV column')
        p.add_argument('params', help='parameter YAML (as written by mpi-ros identify)')
        p.add_argument('--input', required=True,
                       help='CSV with a header; the first non-time column is the input')
        p.add_argument('--output', required=True, help='CSV to write (time, input, result)')
        p.add_argument('--column-name', default=None, help='name of the result column')
        p.add_argument('--node-name', default='compensator', help='node key in the YAML')
        p.set_defaults(func=func)
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
        Exit status: 0 on success, 1 on a reported error, 2 on usage errors.

    """
    args_list = list(sys.argv[1:] if argv is None else argv)
    if args_list and args_list[0] in _NODE_COMMANDS:
        from .nodes.launcher import run_node
        return int(run_node(args_list[0], args_list[1:]))
    try:
        if args_list and args_list[0] == 'diagnose':
            return _cmd_diagnose(args_list[1:])
        if args_list and args_list[0] == 'demo':
            return _cmd_demo(args_list[1:])
        args = _parser().parse_args(args_list)
        if args.command is None:
            _parser().print_help()
            return 2
        return int(args.func(args))
    except MPIError as err:
        print(f'error: {err}', file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print('error: interrupted', file=sys.stderr)
        return 130


if __name__ == '__main__':  # pragma: no cover
    sys.exit(main())
