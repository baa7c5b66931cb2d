# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
The demo's closed loops over DDS: node processes, the loop driver, the parameter pushes.

``mpi-ros demo`` (:mod:`mpi_ros.app.demo`) parses its options and calls :func:`run_demo` or
:func:`run_effect_demo` with its report writer (:mod:`mpi_ros.app.demo_report`); everything
that needs rclpy is here, on the ROS side, which imports nothing from :mod:`mpi_ros.app`.
"""

import argparse
from collections.abc import Callable
import os
from pathlib import Path
import time
from typing import Any, TYPE_CHECKING

import numpy as np

from ..progress import Progress

if TYPE_CHECKING:
    from .processes import NodeProcess
    from ..extensions import EffectModel

__all__ = ['run_demo', 'run_effect_demo', 'ORDERS', 'EFFECTS']

#: The paper's table (section 5).
ORDERS = ((0, 0), (4, 2), (8, 4), (14, 7))

#: The option that sets each effect's strength in the plant (its argparse destination).
_STRENGTH_OPTIONS = {'creep': 'creep_gain', 'rate_dependence': 'eddy_time_constant'}

#: Effects ``--effect`` can switch on in the plant simulator.
EFFECTS = tuple(_STRENGTH_OPTIONS)
_REPLY_TIMEOUT = 5.0


class _DemoLoop:
    """Starts and stops the demo's node processes (by PID) around one driver."""

    def __init__(self, driver: Any, out: Path, processes: list['NodeProcess'],
                 plant_args: list[str], args: argparse.Namespace) -> None:
        self.driver, self.out, self.processes = driver, out, processes
        self.plant_args, self.args = plant_args, args

    def start_plant(self) -> Any:
        """Start a plant simulator process and wait until it subscribes."""
        from .processes import NodeProcess
        plant = NodeProcess('plant-simulator', self.plant_args,
                            self.out / 'plant_simulator.log')
        self.processes.append(plant)
        self.driver.wait_for(lambda: self.driver.current_pub.get_subscription_count() > 0,
                             'the plant simulator to start', 60.0)
        return plant

    def start_compensated(self, params: dict[str, Any], compensator_args: list[str],
                          first: float) -> tuple[Any, Any]:
        """
        Start a fresh plant and compensator, push ``params``, handshake with ``first``.

        A fresh plant is where the identification record started (the demo records from a
        fresh plant too), so the compensator starts from the record's start
        (``start_state:=record``), not at rest after a descent.
        """
        from .processes import NodeProcess
        from ..nodes.identifier import push_model_parameters
        plant = self.start_plant()
        comp = NodeProcess('compensator',
                           ['-p', f'output.min:={self.args.output_min!r}',
                            '-p', f'output.max:={self.args.output_max!r}',
                            '-p', 'start_state:=record', *compensator_args],
                           self.out / 'compensator.log')
        self.processes.append(comp)
        driver = self.driver
        with driver.detached():            # the push spins the node on its own executor
            push_model_parameters(driver, '/compensator', params, timeout=60.0)
        driver.wait_for(lambda: driver.desired_pub.get_subscription_count() > 0,
                        'the compensator to subscribe', 30.0)
        driver.handshake(driver.desired_pub, first)
        return comp, plant

    def stop(self, *started: Any) -> None:
        """Stop the given processes and forget them."""
        for proc in started:
            proc.stop()
            self.processes.remove(proc)


def run_demo(args: argparse.Namespace, progress: Progress,
             write_report: Callable[..., object]) -> dict[str, Any]:
    """
    Run the demo's closed loop (plant, compensator, identification) and its report.

    ``write_report`` writes the report (:func:`mpi_ros.app.demo_report.write_report`).
    """
    os.environ['ROS_AUTOMATIC_DISCOVERY_RANGE'] = 'LOCALHOST'
    os.environ['ROS_DOMAIN_ID'] = str(args.domain_id)      # the nodes it starts inherit it
    import rclpy

    from ..plant.excitation import identification_excitation
    from ..model_fit import identify
    from .driver import LoopDriver
    from .processes import NodeProcess
    from ..metrics import control_error
    from ..recordings import BagRecorder, read_bag_signals

    out = Path(args.output)
    out.mkdir(parents=True, exist_ok=True)
    started = time.monotonic()
    rclpy.init(args=['mpi_ros_demo'])
    processes: list[NodeProcess] = []
    results: dict[str, Any] = {'domain_id': args.domain_id, 'tracking': []}
    try:
        driver = LoopDriver('mpi_ros_demo')
        plant_args = ['-p', f'noise_std:={args.noise_std!r}', '-p', f'seed:={args.seed}']

        loop = _DemoLoop(driver, out, processes, plant_args, args)

        # 1-2: record the identification bag.
        progress.say(f'[demo] ROS_DOMAIN_ID={args.domain_id}, output in {out}')
        progress('starting the plant simulator')
        plant = loop.start_plant()
        t, current = identification_excitation(args.duration, sample_rate=args.sample_rate,
                                               seed=args.seed, holds=False, bursts=False)
        bag = out / 'identification_bag'
        progress.say(f'[demo] recording {t.size} excitation samples into {bag} ...')
        driver.handshake(driver.current_pub, current[0])
        with BagRecorder(bag, overwrite=True) as recorder:
            # Real time stamps: the wall clock at the start of the recording plus the
            # excitation's own time (the samples are exchanged in lock step).
            wall_start = time.time() - float(t[0])
            for k in range(t.size):
                progress.update(f'recording the excitation: sample {k + 1} of {t.size}')
                s = driver.exchange(driver.current_pub, current[k])
                recorder.write_input(wall_start + float(t[k]), float(current[k]))
                recorder.write_output(wall_start + float(t[k]) + 1e-6, s)
        plant.stop()
        processes.remove(plant)
        # 3: identify.
        data = read_bag_signals(bag)
        results['samples'] = int(data.time.size)
        models = {}
        results['identification'] = []
        for n, l in ORDERS:  # noqa: E741
            fit = identify(data.current, data.displacement, n=n, l=l,
                           progress=_phase(progress, f'identifying n={n}, l={l}: '))
            models[(n, l)] = fit.model
            results['identification'].append({'n': n, 'l': l,
                                              'nonlinearity_error': fit.nonlinearity_error,
                                              'rms_error': fit.rms_error})
            progress.say(f'[demo] identified n={n:2d} l={l}: nonlinearity error (37) '
                         f'{100 * fit.nonlinearity_error:5.2f} %')
        # 4: track with each compensator.
        final = models[ORDERS[-1]]
        t_track, desired, lead = _desired_trajectory(final, args)
        desired_all = np.concatenate([lead, desired])
        runs = [('linear map (enabled:=false)', final, False)] + [
            (f'MPI n={n}, l={l}', models[(n, l)], True) for n, l in ORDERS[1:]]
        traces = {}
        for label, model, enabled in runs:
            progress(f'{label}: starting a plant and a compensator, pushing the model')
            started_here = loop.start_compensated(
                model.to_params(), ['-p', f'enabled:={str(enabled).lower()}'], desired_all[0])
            measured = np.empty(desired_all.size)
            for k, value in enumerate(desired_all):
                progress.update(f'{label}: tracking, sample {k + 1} of {desired_all.size}')
                measured[k] = driver.exchange(driver.desired_pub, value)
            progress(f'{label}: stopping its processes')
            loop.stop(*started_here)
            tracked = slice(lead.size, None)
            err = control_error(desired_all[tracked], measured[tracked])
            traces[label] = measured
            results['tracking'].append({'controller': label, 'control_error': err})
            progress.say(f'[demo] {label:28s} control error (38) {100 * err:5.2f} %')
        results['elapsed_s'] = time.monotonic() - started
        progress('writing the report and the plots')
        write_report(out, data, models, t_track, desired_all[lead.size:],
                     {k: v[lead.size:] for k, v in traces.items()}, results)
        driver.destroy_node()
    finally:
        for p in processes:
            p.stop()
        rclpy.try_shutdown()
    return results


def run_effect_demo(args: argparse.Namespace, progress: Progress,
                    write_report: Callable[..., object]) -> dict[str, Any]:
    """
    Run the demo on a plant with an effect: plain against extended compensator.

    ``write_report`` writes the report (:func:`mpi_ros.app.demo_report.write_effect_report`).
    """
    os.environ['ROS_AUTOMATIC_DISCOVERY_RANGE'] = 'LOCALHOST'
    os.environ['ROS_DOMAIN_ID'] = str(args.domain_id)      # the nodes it starts inherit it
    import rclpy

    from ..plant.excitation import identification_excitation
    from ..extensions import EFFECTS as REGISTRY
    from ..extensions.effect import plant_switch
    from ..model_fit import identify
    from .driver import LoopDriver
    from .processes import NodeProcess
    from ..metrics import control_error
    from ..recordings import BagRecorder, read_bag_signals

    n, l = ORDERS[-1]  # noqa: E741
    # The effect's fit and its plant switch (actuator.*) come from the registry; the value
    # from the effect's option (--creep-gain, --eddy-time-constant).
    fit: Callable[..., EffectModel] = REGISTRY[args.effect].fit
    strength = {f'actuator.{plant_switch(args.effect)}':
                getattr(args, _STRENGTH_OPTIONS[args.effect])}
    out = Path(args.output)
    out.mkdir(parents=True, exist_ok=True)
    started = time.monotonic()
    rclpy.init(args=['mpi_ros_demo'])
    processes: list[NodeProcess] = []
    results: dict[str, Any] = {'domain_id': args.domain_id, 'effect': args.effect,
                               'plant': strength, 'sample_rate': args.sample_rate,
                               'tracking': [], 'lateness_s': {}}
    try:
        driver = LoopDriver('mpi_ros_demo')
        plant_args = ['-p', f'noise_std:={args.noise_std!r}', '-p', f'seed:={args.seed}']
        for key, value in strength.items():
            plant_args += ['-p', f'{key}:={value!r}']

        loop = _DemoLoop(driver, out, processes, plant_args, args)

        def lateness(what: str, sent: np.ndarray, schedule: np.ndarray) -> None:
            late = sent - (schedule - schedule[0])
            results['lateness_s'][what] = {'max': float(late.max()),
                                           'p99': float(np.percentile(late, 99.0))}

        # Record the identification bag in real time.
        progress.say(f'[demo] ROS_DOMAIN_ID={args.domain_id}, effect {args.effect} '
                     f'({", ".join(f"{k}={v:g}" for k, v in strength.items())}), output in '
                     f'{out}')
        progress('starting the plant simulator')
        plant = loop.start_plant()
        t, current = identification_excitation(args.duration, sample_rate=args.sample_rate,
                                               seed=args.seed, holds=True, bursts=True)
        bag = out / 'identification_bag'
        progress.say(f'[demo] recording {t.size} excitation samples in real time '
                     f'({t[-1]:.0f} s) into {bag} ...')
        progress(f'recording {t.size} samples in real time ({t[-1]:.0f} s)')
        driver.handshake(driver.current_pub, current[0])
        wall_start = time.time()
        sent, measured = driver.exchange_paced(driver.current_pub, current, t,
                                               timeout=_REPLY_TIMEOUT)
        plant.stop()
        processes.remove(plant)
        lateness('identification', sent, t)
        with BagRecorder(bag, overwrite=True) as recorder:
            # Real time stamps: the wall clock at the start plus the real send times.
            for tk, ik, sk in zip(wall_start + sent, current, measured):
                recorder.write_input(float(tk), float(ik))
                recorder.write_output(float(tk) + 1e-6, float(sk))
        # Identify the plain and the extended model of the same order.
        data = read_bag_signals(bag)
        results['samples'] = int(data.time.size)
        plain = identify(data.current, data.displacement, n=n, l=l,
                         progress=_phase(progress, f'identifying the plain n={n}, l={l}: ')).model
        progress(f'fitting the model extended by {args.effect}')
        extended = fit(data.time, data.current, data.displacement, order=(n, l))
        params = extended.to_params()
        results['extension'] = {key: value for key, value in params.items()
                                if key.startswith(f'model.{args.effect}.')}
        results['identification'] = [
            _model_error(name, simulated, data)
            for name, simulated in (('plain', plain.simulate(data.current)),
                                    ('extended', extended.simulate(data.time, data.current)))]
        for row in results['identification']:
            progress.say(f'[demo] identified {row["model"]:8s} n={n} l={l}: nonlinearity '
                         f'error (37) {100 * row["nonlinearity_error"]:5.2f} %')
        # Track the same trajectory with each compensator, in real time.
        t_track, desired, lead = _desired_trajectory(plain, args)
        desired_all = np.concatenate([lead, desired])
        t_all = np.arange(desired_all.size) / args.sample_rate
        runs = [(f'plain MPI n={n}, l={l}', plain.to_params()),
                (f'extended MPI + {args.effect}', params)]
        traces = {}
        for label, model_params in runs:
            progress(f'{label}: starting a plant and a compensator, pushing the model')
            started_here = loop.start_compensated(
                model_params, ['-p', f'sample_period:={1.0 / args.sample_rate!r}'],
                desired_all[0])
            progress(f'{label}: tracking {desired_all.size} samples in real time '
                     f'({t_all[-1]:.0f} s)')
            sent, measured = driver.exchange_paced(driver.desired_pub, desired_all, t_all,
                                                   timeout=_REPLY_TIMEOUT)
            progress(f'{label}: stopping its processes')
            loop.stop(*started_here)
            lateness(label, sent, t_all)
            tracked = slice(lead.size, None)
            err = control_error(desired_all[tracked], measured[tracked])
            deviation = measured[tracked] - desired_all[tracked]
            rms = float(np.sqrt(np.mean(deviation ** 2)) / np.max(np.abs(desired)))
            traces[label] = measured[tracked]
            results['tracking'].append({'controller': label, 'control_error': err,
                                        'rms_error': rms})
            progress.say(f'[demo] {label:30s} control error (38) {100 * err:5.2f} % '
                         f'(RMS {100 * rms:.2f} %)')
        results['elapsed_s'] = time.monotonic() - started
        progress('writing the report and the plot')
        write_report(out, t_track, desired_all[lead.size:], traces, results)
        driver.destroy_node()
    finally:
        for p in processes:
            p.stop()
        rclpy.try_shutdown()
    return results


def _model_error(name: str, simulated: np.ndarray, data: Any) -> dict[str, Any]:
    # (37) over the whole record, over the displacement range (as identify reports it), and
    # where the largest error is (at the start: the model starts in another state).
    from ..metrics import range_error
    error = np.abs(simulated - data.displacement)
    return {'model': name, 'nonlinearity_error': range_error(simulated, data.displacement),
            'largest_error_at_s': float(data.time[int(np.argmax(error))] - data.time[0])}


def _desired_trajectory(model: Any, args: argparse.Namespace) -> tuple[
        np.ndarray, np.ndarray, np.ndarray]:
    """
    Return the tracking trajectory inside the model's operating range and its lead-in.

    Parameters
    ----------
    model : MPIModel
        Forward model whose displacement range (for the safe current range) is used.
    args : argparse.Namespace
        The demo options (``track_duration``, ``sample_rate``, ``output_min/max``).

    Returns
    -------
    t_track, desired, lead : ndarray of float
        Trajectory time [s] and desired displacement [m] (within the middle 80 % of the
        range), and a 1 s ramp from rest (0 m) to its first value.

    """
    from ..compensation import operating_range
    from ..plant.excitation import tracking_trajectory
    lo, hi = operating_range(model, args.output_min, args.output_max)
    span = hi - lo
    t_track, desired = tracking_trajectory(args.track_duration, sample_rate=args.sample_rate,
                                           low=lo + 0.1 * span, high=hi - 0.1 * span)
    return t_track, desired, np.linspace(0.0, desired[0], int(args.sample_rate))


def _phase(progress: Progress, prefix: str) -> Callable[[str], None]:
    # A progress callback for a library function: its lines under the demo's phase.
    def show(text: str) -> None:
        progress(prefix + text)
    return show
