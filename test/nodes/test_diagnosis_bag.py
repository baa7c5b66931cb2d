# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
End to end: plant_simulator nodes record bags with a hidden effect, diagnose names it.

Two plant_simulator nodes run in-process on a private context, both in excitation mode with
the same dead time switched on: one records the training bag (identification excitation),
the other the validation bag (``excitation.signal:=diagnostic``, the loops, holds and bursts
the diagnosis' signatures need).  They run side by side in real time (about 18 s).
"""

from mpi_ros.diagnosis import diagnose
from mpi_ros.nodes.plant_simulator import PlantSimulatorNode
from mpi_ros.recordings import read_bag_signals
import numpy as np
from rclpy.executors import SingleThreadedExecutor
from rclpy.parameter import Parameter

NOISE = 2e-8          # [m], 0.05 % of the 40 um stroke


def _plant(context, namespace, bag, dead_time, seed, **excitation):
    overrides = {
        'actuator.dead_time_s': dead_time, 'noise_std': NOISE, 'seed': seed,
        'excitation.enabled': True, 'excitation.sample_rate': 1000.0,
        'record.path': str(bag), **{f'excitation.{k}': v for k, v in excitation.items()}}
    return PlantSimulatorNode(
        context=context, namespace=namespace,
        parameter_overrides=[Parameter(k, value=v) for k, v in overrides.items()])


def test_diagnose_names_dead_time_in_bags_recorded_by_the_plant_node(ros_context, tmp_path):
    dead_time = float(np.random.default_rng(11).uniform(0.005, 0.015))    # realistic, seeded
    train = _plant(ros_context, 'train', tmp_path / 'train', dead_time, 1,
                   duration=18.0)
    validation = _plant(ros_context, 'validation', tmp_path / 'validation', dead_time, 2,
                        signal='diagnostic', repeats=1, hold_duration=1.5)
    executor = SingleThreadedExecutor(context=ros_context)
    for node in (train, validation):
        executor.add_node(node)
    try:
        for node in (train, validation):
            executor.spin_until_future_complete(node.finished, timeout_sec=40.0)
            assert node.finished.done()
    finally:
        executor.shutdown()
        published = [node.counters['published'] for node in (train, validation)]
        for node in (train, validation):
            node.destroy_node()          # closes the bag
    training_data = read_bag_signals(tmp_path / 'train')
    validation_data = read_bag_signals(tmp_path / 'validation')
    assert [len(training_data), len(validation_data)] == published
    assert validation_data.time[-1] - validation_data.time[0] > 15.0

    report = diagnose(training_data, validation=validation_data)
    assert report.cause == 'dead_time', report.decision['steps']
    assert report.gain > 0.05
    chosen = next(c for c in report.candidates if c.cause == 'dead_time')
    assert chosen.signature == 'present' and chosen.significant
    fitted = report.extended.parameters['model.dead_time']
    assert abs(fitted - dead_time) < 0.3 * dead_time, (fitted, dead_time)
