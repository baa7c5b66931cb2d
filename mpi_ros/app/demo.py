# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
``mpi-ros demo``: the whole product in one run, over DDS, with separate processes.

(The two demo paths, plain and with an effect, share one process harness here; the report
and its plots are :mod:`mpi_ros.app.demo_report`.)

1. Start the plant simulator (built-in magnetostrictive-like actuator, not an MPI
   model, with sensor noise) as its own process.
2. Drive it with the identification excitation and record ``current_command`` and
   ``displacement`` into a rosbag2 bag.
3. Identify MPI models of the paper's orders (0,0), (4,2), (8,4), (14,7) from the bag.
4. For each model: start a compensator process, push the model through its
   ``set_parameters_atomically`` service, track a smooth desired trajectory with minor
   loops, and measure the control error (38).  The uncompensated baseline is the
   compensator with ``enabled:=false`` (the best linear map).
5. Print and save ``report.md`` and PNG plots (loops, tracking error) in the output folder
   (:mod:`mpi_ros.app.demo_report`).

While it works, a progress line on stderr says which phase runs, with the time since the
start (only on a terminal; ``--quiet``: none).

With ``--effect creep`` or ``--effect rate_dependence`` the plant simulator runs with that
effect switched on (``actuator.creep_gain``, ``actuator.eddy_time_constant_s``; see
``--creep-gain``, ``--eddy-time-constant``) and the demo compares two compensators of
order (14, 7): the plain MPI model and the extended model fitted by the extension's fit
function (:mod:`mpi_ros.extensions`), each pushed into a fresh compensator in front of a
fresh plant, tracking the same trajectory.  The identification excitation then has holds
and bursts.  Both effects depend on time: the plant takes a command's time from its steady
clock at its arrival, the compensator the stream's (``sample_period`` apart, its
``message_time`` default), so the driver sends sample ``k``
at ``t[k]`` in real time (:meth:`~mpi_ros.harness.driver.LoopDriver.exchange_paced`), still
waiting for each answer; the bag's time stamps are the real send times.

Samples are exchanged in lock step (each desired value waits for its measured
displacement), so the result does not depend on DDS timing.  DDS stays on this
machine (``ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST``) on the ``--domain-id`` given, else
the exported ``ROS_DOMAIN_ID``, else a random one; every process the demo starts is stopped
by the demo. The bag has real time stamps (the wall clock from the start of the recording).
"""

import os
import random

from .cli_options import ArgumentParser
from ..errors import MPIError
from ..harness.demo_runs import EFFECTS, ORDERS   # no rclpy at import (it loads when run)
from ..progress import Progress


__all__ = ['demo_domain_id', 'demo_main', 'ORDERS', 'EFFECTS']   # ORDERS, EFFECTS: the runs'

#: Excitation and tracking lengths [s] when not given: (plain demo, --effect demo).
_DURATIONS = {False: (40.0, 12.0), True: (60.0, 30.0)}


def demo_domain_id(given: int | None = None) -> int:
    """
    Return the ROS_DOMAIN_ID of the demo: ``--domain-id``, else the exported one, else random.

    Parameters
    ----------
    given : int, optional
        The ``--domain-id`` option.

    Returns
    -------
    int
        ``given`` if not None; else ``$ROS_DOMAIN_ID`` if set and not empty; else a
        random domain in 101-199 (so that two demos on one machine do not meet).

    Raises
    ------
    mpi_ros.errors.MPIError
        When the domain (given or exported) is not an integer in 0-232.

    """
    if given is None:
        exported = os.environ.get('ROS_DOMAIN_ID', '').strip()
        if not exported:
            return random.randint(101, 199)
        source = 'the exported ROS_DOMAIN_ID'
        try:
            given = int(exported)
        except ValueError:
            given = -1
    else:
        source = '--domain-id'
        exported = str(given)
    if not 0 <= given <= 232:
        msg = (f'{source} must be an integer from 0 to 232; found {exported!r}; '
               'pass --domain-id N or unset ROS_DOMAIN_ID')
        raise MPIError(msg)
    return given


def demo_main(argv: list[str]) -> int:
    """
    Run the demo; see the module docstring.

    Parameters
    ----------
    argv : list of str
        Command-line arguments after ``demo``.

    Returns
    -------
    int
        0 when the compensated control error is at most the goal (``--goal``), else 1;
        with ``--effect``: 0 when the extended compensator's control error is below the
        plain one's, else 1.

    """
    parser = ArgumentParser(prog='mpi-ros demo', description=__doc__.splitlines()[1])
    parser.add_argument('--output', default='mpi_ros_demo', help='folder for the report')
    parser.add_argument('--domain-id', type=int, default=None,
                        help='ROS_DOMAIN_ID to use (default: the exported ROS_DOMAIN_ID if '
                        'set, else a random one in 101-199)')
    parser.add_argument('--effect', choices=EFFECTS, default=None,
                        help='switch this effect on in the plant simulator and compare the '
                        'plain with the extended compensator (default: none, the plain '
                        'demo)')
    parser.add_argument('--creep-gain', type=float, default=0.06,
                        help='--effect creep: actuator.creep_gain of the plant [1]')
    parser.add_argument('--eddy-time-constant', type=float, default=0.005,
                        help='--effect rate_dependence: actuator.eddy_time_constant_s of '
                        'the plant [s]')
    parser.add_argument('--duration', type=float, default=None,
                        help='excitation length [s] (at --sample-rate; default 40, with '
                        '--effect 60)')
    parser.add_argument('--track-duration', type=float, default=None,
                        help='tracking trajectory length [s] (default 12, with --effect 30)')
    parser.add_argument('--sample-rate', type=float, default=200.0, help='samples per second')
    parser.add_argument('--noise-std', type=float, default=4e-8,
                        help='sensor noise of the plant [m]')
    parser.add_argument('--output-min', type=float, default=0.2, help='safe current min [A]')
    parser.add_argument('--output-max', type=float, default=1.8, help='safe current max [A]')
    parser.add_argument('--seed', type=int, default=1)
    parser.add_argument('--goal', type=float, default=0.03,
                        help='compensated control error (38) to reach (fraction)')
    parser.add_argument('--quiet', action='store_true',
                        help='no progress line on stderr (it is drawn only when stderr is a '
                        'terminal)')
    args = parser.parse_args(argv)
    args.domain_id = demo_domain_id(args.domain_id)
    duration, track_duration = _DURATIONS[args.effect is not None]
    args.duration = duration if args.duration is None else args.duration
    args.track_duration = track_duration if args.track_duration is None else args.track_duration
    from .demo_report import write_effect_report, write_report
    from ..harness.demo_runs import run_demo, run_effect_demo   # rclpy only when it runs
    with Progress(quiet=args.quiet, prefix='[demo] ') as progress:
        if args.effect is not None:
            results = run_effect_demo(args, progress, write_effect_report)
            plain, extended = (r['control_error'] for r in results['tracking'])
            progress.clear()
            progress.say(f'[demo] plant with {args.effect}: control error (38) plain MPI '
                         f'{100 * plain:.2f} %, extended {100 * extended:.2f} %; report in '
                         f'{args.output}/report.md ({results["elapsed_s"]:.0f} s)')
            return 0 if extended < plain else 1
        results = run_demo(args, progress, write_report)
        best = results['tracking'][-1]['control_error']
        linear = results['tracking'][0]['control_error']
        progress.clear()
        progress.say(f'[demo] control error (38): linear map {100 * linear:.2f} %, compensated '
                     f'(n=14, l=7) {100 * best:.2f} % (goal <= {100 * args.goal:.1f} %); report '
                     f'in {args.output}/report.md ({results["elapsed_s"]:.0f} s)')
        return 0 if best <= args.goal else 1
