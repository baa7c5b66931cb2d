# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Plant simulator node: current command in, measured displacement out.

Topics (relative names, std_msgs/msg/Float64, SI units)
    ``current_command`` (subscribed) [A] and ``displacement`` (published) [m].

Timing
    Event-driven: every received command advances the plant by one sample and
    publishes one displacement, at once. The sample time is the steady clock at
    arrival, so the dynamic effects (creep, eddy-current lag, Joule heating, dead
    time) see the real command rate, and a test gets exactly one displacement per
    command. A non-finite command is not applied (a current source cannot output
    it); it is counted and logged, and no displacement is published for it.  The
    subscriptions are raw: a message that is not of the topic's type (too short, an
    unknown encapsulation, a bad array layout) is counted in ``counters['malformed']``,
    logged at most once a second, and dropped.

Truth (``truth``, read-only)
    ``builtin``: :class:`mpi_ros.plant.actuator.MagnetostrictiveActuator`, a Preisach-type
    actuator that is *not* an MPI model, configured by the ``actuator.*`` parameters
    (the fields of :class:`mpi_ros.plant.actuator.ActuatorConfig`: the hysteresis core's, the
    sensor's and those of every registered effect with a plant step, read from the effect
    registry when the node is built; every effect is off at 0).
    ``mpi``: the MPI model given by the four ``model.*`` parameters of Gamma (starting in
    its ``record_start.hysteresis.initial_states``, 0 when unset) and its
    operating point ``model.input_offset`` [A], ``model.output_offset`` [m],
    ``model.output_sign`` (+1/-1; defaults 0, 0, +1), the same keys as the compensator's:
    ``y = y0 + sign * S[H[x - x0]]`` (forward model, streamed). ``noise_std`` adds
    seeded Gaussian sensor noise to either truth.

Excitation mode (``excitation.enabled:=true``)
    The node drives itself with :func:`mpi_ros.plant.excitation.identification_excitation`
    (or, with ``excitation.signal:=diagnostic``, the validation record of the diagnosis,
    :func:`mpi_ros.plant.excitation.diagnostic_excitation`):
    it publishes each sample's current on ``current_command`` and the plant's answer on
    ``displacement``, on the schedule's own time base (so the data do not depend on
    timer jitter). It subscribes to ``current_command`` only afterwards, so neither its
    own commands nor anybody else's reach the plant meanwhile. When done it exits
    (``excitation.exit_when_done``) or continues as a normal plant.

Several actuators (``axes`` > 1, read-only; default 1: the Float64 topics above)
    N independent plants of the same truth (the built-in actuator with seeds ``seed``,
    ``seed + 1``, ...; or the ``model.*`` MPI model for every axis), driven through
    ``current_commands`` [A] and answering on ``displacements`` [m], both
    ``std_msgs/msg/Float64MultiArray`` blocks of samples x axes as the multi-axis
    compensator publishes them (:mod:`mpi_ros.array_layout`): one displacement block of
    the same shape per command block.  The K samples of a chunk are taken
    ``sample_period`` apart, the last one at the block's arrival.  A non-finite current
    is not applied (the source holds the axis's last current) and is counted.  Excitation
    mode and recording are single-axis only.

Recording (``record.path``)
    Every applied command and displacement is written to a new rosbag2 bag through
    :class:`mpi_ros.recordings.BagRecorder`; the bag appears at ``record.path`` only
    when the node stops cleanly (written beside it and renamed).
"""

import math
import time
from typing import Any, List, Optional

import numpy as np
from rcl_interfaces.msg import SetParametersResult
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.task import Future
from std_msgs.msg import Float64, Float64MultiArray

from .parameters import (
    answer_request, check_parameters, declare_parameters, harden_parameter_services,
    parameter_values,
)
from .qos import loop_qos
from .spinning import run_node_main
from ..array_layout import ArrayLayoutError, block_of, encode_float64_multiarray, float64_of
from ..node_parameters import specs_by_name
from ..node_parameters.plant_simulator import plant_parameters
from ..plant.simulator import (
    describe_truth, excitation_schedule, ExcitationRun, SimulatedPlants,
)
from ..recordings import BagRecorder

__all__ = ['PlantSimulatorNode', 'plant_parameters', 'main']


def __getattr__(name: str) -> Any:
    """Return ``PARAMETERS``: every parameter, from the effect registry as it is now."""
    if name == 'PARAMETERS':
        return plant_parameters()
    msg = f'module {__name__!r} has no attribute {name!r}'
    raise AttributeError(msg)


#: Wall-clock period of the excitation timer; each tick publishes every due sample.
_EXCITATION_TICK_S = 0.005


class PlantSimulatorNode(Node):
    """
    Simulated actuator with a sensor; see the module docstring.

    Parameters
    ----------
    node_name : str
        Node name; ``plant_simulator`` unless remapped.
    **kwargs
        Passed on to :class:`rclpy.node.Node`.

    Raises
    ------
    mpi_ros.errors.MPIError
        When the truth cannot be built from the parameters.

    """

    def __init__(self, node_name: str = 'plant_simulator', **kwargs: Any) -> None:
        super().__init__(node_name, **kwargs)
        # The effects' actuator.* parameters as registered now, not at import.
        self._specs = specs_by_name(plant_parameters())
        self.add_on_set_parameters_callback(self._validate_parameters)
        declare_parameters(self, tuple(self._specs.values()))
        harden_parameter_services(self, specs=self._specs)
        values = parameter_values(self, list(self._specs))
        self._values = values
        self._plants = SimulatedPlants(values)
        self.axes = self._plants.axes
        self.finished = Future()
        self.counters = self._plants.counters
        self._t0 = time.monotonic()
        self._recorder: Optional[BagRecorder] = None
        if values['record.path']:
            self._recorder = BagRecorder(values['record.path'],
                                         storage=values['record.storage'])
            self._recorder.open()

        qos = loop_qos(values['qos_depth'], values['qos_reliability'])
        self._displacement = Float64()
        self._command = Float64()
        if self.axes > 1:
            self._publisher = self.create_publisher(Float64MultiArray, 'displacements', qos)
        else:
            self._publisher = self.create_publisher(Float64, 'displacement', qos)
        self._command_publisher: Optional[Any] = None
        self._excitation: Optional[ExcitationRun] = None
        if values['excitation.enabled']:
            self._command_publisher = self.create_publisher(Float64, 'current_command', qos)
            schedule_t, schedule_i = excitation_schedule(values)
            self._excitation = ExcitationRun(schedule_t, schedule_i)
            self._excitation_stamp = self._now()
            self._excitation_timer = self.create_timer(_EXCITATION_TICK_S, self._excite)
            self.get_logger().info(
                f'{values["excitation.signal"]} excitation: {len(schedule_t)} samples over '
                f'{schedule_t[-1] - schedule_t[0]:g} s')
        self._qos = qos
        self._subscription: Optional[Any] = None
        if self._excitation is None:
            self._subscribe()
        self.get_logger().info(
            f'simulating {describe_truth(values)}'
            + (f' x {self.axes} axes' if self.axes > 1 else '') + ': '
            f'{self.resolve_topic_name(self._input_topic)} [A] -> '
            f'{self._publisher.topic_name} [m]'
            + (' (excitation first)' if self._excitation is not None else '')
            + (f', recording into {values["record.path"]}' if values['record.path'] else ''))

    @property
    def exits_when_done(self) -> bool:
        """Tell whether the node stops by itself after the excitation."""
        return bool(self._values['excitation.enabled']
                    and self._values['excitation.exit_when_done'])

    @property
    def exciting(self) -> bool:
        """Tell whether the excitation is running."""
        return self._excitation is not None

    @property
    def _input_topic(self) -> str:
        return 'current_commands' if self.axes > 1 else 'current_command'

    def measure(self, t: float, current: float) -> float:
        """
        Advance the plant by one sample and return the measured displacement [m].

        ``t`` is the sample time [s], ``current`` the (finite) coil current [A]; see
        :meth:`mpi_ros.plant.simulator.SimulatedPlants.measure`.
        """
        return self._plants.measure(t, current)

    def measure_block(self, t: float, currents: Any) -> np.ndarray:
        """
        Advance every axis by the samples of a block; return the displacements [m].

        ``t`` is the time of the block's last sample [s], ``currents`` the K x axes coil
        currents [A]; see :meth:`mpi_ros.plant.simulator.SimulatedPlants.measure_block`.
        """
        return self._plants.measure_block(t, currents)

    def close(self) -> None:
        """Finish the recording (the bag appears at ``record.path``); idempotent."""
        recorder, self._recorder = self._recorder, None
        if recorder is not None:
            recorder.close()
            self.get_logger().info(f'recorded {recorder.counts} into {recorder.path}')

    def destroy_node(self) -> None:
        """Close the recording, then destroy the node."""
        self.close()
        super().destroy_node()

    # -- callbacks ---------------------------------------------------------------------
    def _subscribe(self) -> None:
        if self.axes > 1:
            self._subscription = self.create_subscription(
                Float64MultiArray, 'current_commands', self._on_current_commands, self._qos,
                raw=True)
            return
        self._subscription = self.create_subscription(
            Float64, 'current_command', self._on_current_command, self._qos, raw=True)

    def _malformed(self, topic: str, err: Exception) -> None:
        """Count and log (at most once a second) a message that is not of the topic's type."""
        self.counters['malformed'] = self.counters.get('malformed', 0) + 1
        self.get_logger().warning(f'ignoring {topic} message: {err}',
                                  throttle_duration_sec=1.0)

    def _on_current_commands(self, data: bytes) -> None:
        self.counters['commands'] += 1
        try:
            block = block_of(data, self.axes)
        except ArrayLayoutError as err:
            self._malformed('current_commands', err)
            return
        displacements = self.measure_block(time.monotonic() - self._t0, block)
        self._publisher.handle.publish_raw(encode_float64_multiarray(displacements))
        self.counters['published'] += 1

    def _on_current_command(self, data: bytes) -> None:
        # Raw: the bytes are checked before they are decoded (a peer may send anything).
        self.counters['commands'] += 1
        try:
            current = float64_of(data)
        except ArrayLayoutError as err:
            self._malformed('current_command', err)
            return
        if not math.isfinite(current):
            self.counters['nonfinite_commands'] += 1
            self.get_logger().warning(
                f'ignoring non-finite current command {current!r}',
                throttle_duration_sec=1.0)
            return
        t = self._plants.sample_time(time.monotonic() - self._t0)
        self._emit(t, self._now(), current, publish_command=False)

    def _excite(self) -> None:
        run = self._excitation
        if run is None:
            return
        for t, current in run.due(time.monotonic()):
            self._plants.last_t = t
            self._emit(t, self._excitation_stamp + t - run.times[0], current,
                       publish_command=True)
        if run.done:
            self.destroy_timer(self._excitation_timer)
            self._excitation = None
            self._t0 = time.monotonic() - self._plants.last_t
            self.get_logger().info(f'excitation done: {run.index} samples')
            if self.exits_when_done:
                self.close()
                self.finished.set_result(True)
            else:
                # Subscribing only now keeps the excitation's own commands (volatile
                # QoS, already sent) out of the plant.
                self._subscribe()

    def _emit(self, t: float, stamp: float, current: float, *, publish_command: bool) -> None:
        displacement = self.measure(t, current)
        if publish_command and self._command_publisher is not None:
            self._command.data = current
            self._command_publisher.publish(self._command)
        self._displacement.data = displacement
        self._publisher.publish(self._displacement)
        self.counters['published'] += 1
        if self._recorder is not None:
            self._recorder.write_input(stamp, current)
            self._recorder.write_output(stamp, displacement)

    def _now(self) -> float:
        return self.get_clock().now().nanoseconds * 1e-9

    # -- parameters --------------------------------------------------------------------
    def _validate_parameters(self, parameters: List[Parameter]) -> SetParametersResult:
        return answer_request(
            lambda: check_parameters(self._specs, parameters, allow_unset=True))


def main(args: Optional[List[str]] = None) -> int:
    """
    Run the plant simulator (``ros2 run mpi_ros plant_simulator --ros-args ...``).

    ``args`` is the command line for ``rclpy.init`` (program name first; ``sys.argv`` if
    None).  Returns the exit status: 0 on shutdown or after the excitation; 1 when the
    truth cannot be built.

    """
    return run_node_main(
        PlantSimulatorNode, 'plant_simulator', args,
        until=lambda node: node.finished if node.exits_when_done else None)
