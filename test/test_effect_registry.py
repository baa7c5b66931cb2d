# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Effects are plug-ins: a toy effect registered here, in one place, works end to end.

The toy effect is a drive gain: the material sees ``k x`` instead of the commanded ``x``,
``s = Gamma[k x]`` (degenerate with Gamma itself, which is fine for a toy: the point is
that nothing outside this file is edited).  Registering it makes the parameter form, the
fit, the exact per-step inverse in the one compensator, the compensator nodes' parameters,
the diagnosis candidate with its row in the report's table, its signature plot with its
caption and what separates it from creep in a tie work, and, through its plant step (an
input-side gain, ``actuator.drive_gain``), the simulated actuator and the plant simulator
node, over DDS.
"""

from dataclasses import dataclass, replace
import re
import time
from typing import Any

from mpi_ros import MPIModel
from mpi_ros.compensation import Compensator
from mpi_ros.diagnosis import diagnose
from mpi_ros.diagnosis.report import markdown, write_report
from mpi_ros.errors import ModelError
from mpi_ros.extensions import (Effect, EffectParameter, EFFECTS, extended_model_from_params,
                                ExtendedModelBase, register_effect, unregister_effect)
from mpi_ros.extensions.effect import PlantEffect, PlantParameter, separating_measurement
from mpi_ros.extensions.fitting import fit_gamma, search_fit
from mpi_ros.node_parameters.compensator import axis_parameters, compensator_parameters
from mpi_ros.nodes.plant_simulator import PlantSimulatorNode
from mpi_ros.plant.actuator import ActuatorConfig, MagnetostrictiveActuator
from mpi_ros.plant.excitation import identification_excitation
from mpi_ros.recordings import Recording
import numpy as np
import pytest
import rclpy
from rclpy.executors import SingleThreadedExecutor
from rclpy.parameter import Parameter
from std_msgs.msg import Float64

from .core_models import random_model

GAIN = 'model.drive_gain.gain'


@dataclass(frozen=True, eq=False)
class DriveGainModel(ExtendedModelBase):

    model: MPIModel
    gain: float
    cause = 'drive_gain'

    @classmethod
    def from_params(cls, mapping):
        return cls(MPIModel.from_params(mapping), float(mapping[GAIN]))

    def to_params(self):
        return dict(self.model.to_params(), **{GAIN: self.gain})

    def simulate(self, time, current):
        return self.model.simulate(self.gain * np.asarray(current, dtype=float))

    def inverse_step(self):
        return DriveGainInverse(self.gain)


class DriveGainInverse:

    def __init__(self, gain):
        self.gain = gain
        self.state = np.zeros(0)

    def start(self, current):
        pass

    def carry(self, other):
        return False

    def prepare(self, previous, interval, started):
        pass

    def invert(self, v, previous, started, inverse):
        return inverse(v, 0.0) / self.gain           # the material must see Gamma^-1

    def advance(self, current, previous, started):
        return self.gain * current


def fit_drive_gain(time, current, displacement, *, order):
    def trial(gain: float) -> tuple[Any, float]:
        model, error = fit_gamma(gain * current, displacement, order, 1e-6)
        return DriveGainModel(model, gain), error
    _, model, _ = search_fit(trial, np.array([0.8, 1.0, 1.25]), refine=0)
    return model


def plot_drive_gain(ax, time, current, measured, baseline, extended, start):
    ax.plot(current[start:], measured[start:] - extended[start:], '.', ms=1, label='toy')
    ax.set_title('drive gain: residual against the input')


SEPARATION = 'a change of the drive amplifier separates a drive gain from creep'

TOY = Effect(name='drive_gain', formula='Gamma[k x]',
             parameters=(EffectParameter(GAIN, 'double', 0.0, 'Toy drive gain k'),),
             model_class=DriveGainModel, fit=fit_drive_gain, parameter_count=lambda p: 1,
             plot=plot_drive_gain, caption='Drive gain: the residual against the input.',
             separations={'creep': SEPARATION},
             plant=PlantEffect(
                 stage='input', label='drive gain',
                 parameters=(PlantParameter('drive_gain', 0.0, 'Toy drive gain k, 0 = off',
                                            '1', low=0.0, switch=True),),
                 start=lambda values: values['drive_gain'],
                 run=lambda gain, chunk, current: gain * current))


@pytest.fixture()
def toy():
    register_effect(TOY)
    try:
        yield TOY
    finally:
        unregister_effect(TOY.name)
    assert 'drive_gain' not in EFFECTS
    assert 'drive_gain' not in ActuatorConfig().to_mapping()
    assert GAIN not in {spec.name for spec in compensator_parameters()}


def test_toy_effect_parameter_form_and_exact_inverse(toy):
    rng = np.random.default_rng(4)
    gamma = random_model(rng, n=6, l=3).with_operating_point(input_offset=0.3,
                                                             output_offset=2e-5)
    params = dict(gamma.to_params(), **{GAIN: 1.7})
    model = extended_model_from_params(params)
    assert isinstance(model, DriveGainModel) and model.gain == 1.7
    comp = Compensator(model, output_min=-10.0, output_max=10.0)
    assert comp.kind == 'drive_gain' and comp.has_effect
    x = 0.3 + np.cumsum(rng.normal(0.0, 0.02, 400))
    desired = model.simulate(None, x)
    commands = np.array([comp.command(v) for v in desired])
    # The compensator's commands drive the toy model exactly to the desired values.
    np.testing.assert_allclose(model.simulate(None, commands)[50:], desired[50:], rtol=0,
                               atol=1e-12 * np.ptp(desired))
    comp.install(gamma)                                   # and back to plain, bumplessly
    assert comp.kind == 'none' and not comp.has_effect


def test_toy_effect_in_the_compensator_nodes_parameters(toy):
    """Both compensator nodes declare the toy's key from the registry (ROS-free specs)."""
    spec = next(s for s in compensator_parameters() if s.name == GAIN)
    assert spec.description == 'Toy drive gain k' and spec.default is None
    names = {s.name for s in axis_parameters(2)}
    assert {f'axis0.{GAIN}', f'axis1.{GAIN}'} <= names


def test_toy_effect_is_fitted_and_a_diagnosis_candidate(toy, tmp_path):
    t, x = identification_excitation(30.0, sample_rate=200.0, seed=2, holds=False,
                                     bursts=False)
    truth = DriveGainModel(random_model(np.random.default_rng(1), n=4, l=2,
                                        initial_history=False), 1.25)
    y = truth.simulate(t, x) + np.random.default_rng(3).normal(0.0, 1e-8, x.size)
    fitted = toy.fit(t, x, y, order=(4, 2))
    assert isinstance(fitted, DriveGainModel)
    report = diagnose(Recording(t, x, y, source='toy'), order=(4, 2),
                      causes=('creep', 'drive_gain'))
    names = [c.cause for c in report.candidates]
    assert names == ['creep', 'drive_gain']
    toy_row = report.candidates[1]
    assert toy_row.signature == 'unavailable' and toy_row.parameter_count == 1
    # Its fitted value with the unit its effect registers (none: k is a ratio).
    assert [(p.key, p.unit) for p in toy_row.fitted()] == [(GAIN, '')]
    # The report: a row in the table of models, its signature plot with its own caption.
    files = write_report(report, tmp_path)
    assert 'signature_drive_gain.png' in [f.name for f in files]
    summary = (tmp_path / 'summary.md').read_text(encoding='utf-8')
    assert re.search(r'^\| \d \| drive_gain( \(chosen\))? \| \S+ % \|', summary, re.MULTILINE)
    assert f'![signature_drive_gain.png](signature_drive_gain.png)\n\n*{TOY.caption}*' in summary
    # A tie with creep says what separates them, as the toy's module states it.
    assert separating_measurement(['creep', 'drive_gain']) == SEPARATION
    tied = replace(report, cause='creep', decision=replace(
        report.decision, ambiguous=True, tied_with=['drive_gain'],
        tie_reasons={'drive_gain': 'within the noise'}))
    assert f'5-40 Hz: {SEPARATION}.' in markdown(tied)


def test_toy_effect_in_the_simulated_actuator(toy):
    t = np.arange(600) * 1e-3
    x = 1.0 + 0.7 * np.sin(2 * np.pi * 3 * t) * np.exp(-t)
    config = ActuatorConfig.from_mapping({'actuator.drive_gain': 1.25})
    assert ActuatorConfig.descriptions()['drive_gain'] == 'Toy drive gain k, 0 = off [1]'
    act = MagnetostrictiveActuator(config)
    out = act.simulate(t, x)
    # The hysteresis core sees k x: the plain actuator driven with 1.25 x, bit for bit.
    np.testing.assert_array_equal(out, MagnetostrictiveActuator().simulate(t, 1.25 * x))
    assert np.max(np.abs(out - MagnetostrictiveActuator().simulate(t, x))) > 1e-6
    chunks = [act.advance(t[a:b], x[a:b]) for a, b in ((0, 1), (1, 250), (250, 600))]
    np.testing.assert_array_equal(np.concatenate(chunks), out)
    with pytest.raises(ModelError, match=r'actuator\.drive_gain must be >= 0'):
        ActuatorConfig(drive_gain=-1.0)
    with pytest.raises(ModelError, match='belong to another effect'):
        register_effect(Effect(name='drive_gain_twin', formula='', parameters=(),
                               model_class=DriveGainModel, fit=fit_drive_gain,
                               parameter_count=lambda p: 0, plant=TOY.plant))


def test_toy_effect_in_the_plant_simulator_node(toy, ros_env):
    """The node declares actuator.drive_gain from the registry and applies it over DDS."""
    context = rclpy.Context()
    rclpy.init(context=context)
    nodes = []
    executor = SingleThreadedExecutor(context=context)
    try:
        plant = PlantSimulatorNode(context=context, parameter_overrides=[
            Parameter('actuator.drive_gain', value=1.25)])
        nodes.append(plant)
        descriptor = plant.describe_parameter('actuator.drive_gain')
        assert 'Toy drive gain k' in descriptor.description and descriptor.read_only
        driver = rclpy.create_node('toy_driver', context=context)
        nodes.append(driver)
        received = []
        publisher = driver.create_publisher(Float64, 'current_command', 100)
        driver.create_subscription(Float64, 'displacement',
                                   lambda msg: received.append(msg.data), 100)
        executor.add_node(plant)
        executor.add_node(driver)
        _spin_until(executor, lambda: publisher.get_subscription_count() > 0
                    and driver.count_publishers('displacement') > 0)
        commands = 1.0 + 0.6 * np.sin(np.linspace(0.0, 7.0, 40))
        for value in commands:                  # lock step: one command, one answer
            count = len(received)
            publisher.publish(Float64(data=float(value)))
            _spin_until(executor, lambda: len(received) > count)
    finally:
        executor.shutdown()
        for node in nodes:
            node.destroy_node()
        rclpy.try_shutdown(context=context)
    # Without time-dependent effects the actuator is rate independent: the node's own
    # sample times do not matter.  The material saw 1.25 x.
    expected = MagnetostrictiveActuator().simulate(np.arange(commands.size), 1.25 * commands)
    np.testing.assert_allclose(received, expected, rtol=0, atol=1e-15)
    plain = MagnetostrictiveActuator().simulate(np.arange(commands.size), commands)
    assert np.max(np.abs(np.asarray(received) - plain)) > 1e-6


def _spin_until(executor, condition, timeout=10.0):
    deadline = time.monotonic() + timeout
    while not condition():
        assert time.monotonic() < deadline, 'timed out'
        executor.spin_once(timeout_sec=0.05)
