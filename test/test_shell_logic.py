# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
The bookkeeping the compensator nodes hand to the core (issue 19), without ROS.

Loss counting (``compensation.loss``), the throttled fault warning and the diagnostics
period (``screening``, ``status``), the update rule across a node's models
(``updates.UpdateRule``, ``load_axes``), a multi-axis node's keys, models, inputs, chunk
times and counters (``parameters.AxisKeys``, ``multi_axis``), which node a compensator's
start-up values ask for, the type a pushed key is sent as, the steps of a grouped
``set_parameters`` request, the plant simulator's plants and excitation schedule
(``plant.simulator``), and the nodes' stop signals (``stop_signals``, in a child process).
"""

import subprocess
import sys

from mpi_ros.compensation import MultiAxisCompensator
from mpi_ros.compensation.loss import LOG_PERIOD_S, LossCounter
from mpi_ros.compensation.message_time import MessageClock
from mpi_ros.compensation.multi_axis import (
    AxisModels, InputCounts, joint_input, REPORTED_COUNTERS,
    reported_counters,
)
from mpi_ros.compensation.screening import FAULT_LOG_PERIOD_S, FaultLog
from mpi_ros.compensation.status import RateWindow, state_after
from mpi_ros.compensation.updates import (
    axis_key, LIMIT_KEYS, load_axes, model_keys, touches, UpdateRule,
)
from mpi_ros.errors import ParameterPushError, ParameterRejected
from mpi_ros.extensions import extended_model_from_params
from mpi_ros.node_parameters import request_steps, typed_value
from mpi_ros.node_parameters.compensator import AxisKeys, wants_multi_axis
from mpi_ros.node_parameters.plant_simulator import plant_parameters
from mpi_ros.operators.model import MPIModel
from mpi_ros.plant.simulator import build_truth, ExcitationRun, SimulatedPlants
import numpy as np
import pytest

from .core_models import hand_model

GAMMA = hand_model()
CREEP = {'model.creep.time_constants': [0.01, 0.1, 1.0],
         'model.creep.weights': [0.05, 0.05, 0.1]}
LIMITS = {'output.min': 0.0, 'output.max': 2.0}


def node_values(prefixes, models=None, **extra):
    """Return a multi-axis node's values: every key unset but the limits and ``models``."""
    values = {prefix + key: None for prefix in prefixes for key in model_keys()}
    values.update({prefix + key: None for prefix in prefixes for key in LIMIT_KEYS})
    values.update(LIMITS)
    for prefix, params in (models or {}).items():
        values.update({prefix + key: value for key, value in params.items()})
    values.update(extra)
    return values


def test_the_moved_logic_imports_no_ros():
    code = ('import sys, mpi_ros.compensation.loss, mpi_ros.compensation.multi_axis, '
            'mpi_ros.node_parameters.compensator, mpi_ros.compensation.updates, '
            'mpi_ros.node_parameters.plant_simulator, '
            'mpi_ros.plant.simulator, mpi_ros.stop_signals; '
            "sys.exit(any(m.split('.')[0] in ('rclpy', 'rcl_interfaces', 'std_msgs', "
            "'diagnostic_msgs') for m in sys.modules))")
    assert subprocess.run([sys.executable, '-c', code], check=False).returncode == 0


# -- loss counting ------------------------------------------------------------------------
def test_sequence_gaps_count_what_never_came_from_one_publisher():
    loss = LossCounter('desired_displacement', 'current_command', 'reliable')
    loss.delivered()             # the executor's message: no number
    loss.taken(10)               # the first number seen: nothing to compare
    loss.taken(11)
    loss.delivered()             # 12 handed over
    loss.taken(16)               # 13, 14, 15 lost
    assert loss.lost_sequence_gaps == 3
    loss.taken(2)                # a restarted publisher: numbers go back, nothing counted
    loss.taken(3)
    assert loss.counters() == {'messages_lost': 3, 'lost_sequence_gaps': 3,
                               'lost_dds_events': 0, 'incompatible_qos': 0}


def test_a_gap_counts_only_while_one_publisher_feeds_the_topic():
    loss = LossCounter('in', 'out', 'reliable')
    loss.publisher_count = lambda: 2
    loss.taken(1)
    loss.taken(9)
    assert loss.lost_sequence_gaps == 0 and loss.publishers == 2
    loss.publisher_count = lambda: 1
    loss.taken(12)
    assert loss.lost_sequence_gaps == 2 and loss.publishers == 1


def test_restart_forgets_the_last_number():
    loss = LossCounter('in', 'out', 'reliable')
    loss.taken(5)
    loss.restart()
    loss.taken(50)               # a new subscription: not a gap of 44
    assert loss.lost_sequence_gaps == 0


def test_lost_is_the_larger_of_gaps_and_dds_events():
    loss = LossCounter('in', 'out', 'reliable')
    loss.taken(1)
    loss.taken(5)
    loss.message_lost(2)
    assert loss.lost == 3
    loss.message_lost(4)
    assert loss.lost == 6 and loss.counters()['messages_lost'] == 6


def test_incompatible_peers_are_counted_per_topic_and_worded():
    loss = LossCounter('desired_displacement', 'current_command', 'reliable')
    warning = loss.incompatible('desired_displacement', 1, 'RMW_QOS_POLICY_RELIABILITY')
    assert warning.startswith('desired_displacement: a peer with incompatible QoS '
                              '(RELIABILITY)')
    assert 'qos_reliability=reliable' in warning
    loss.incompatible('desired_displacement', 1, 'RELIABILITY')    # the same peer again
    loss.incompatible('current_command', 2, 'DURABILITY')
    assert loss.incompatible_qos == 3


def test_a_period_reports_its_backlog_and_restarts_it():
    loss = LossCounter('in', 'out', 'reliable')
    loss.served(3)
    loss.served(9)
    loss.served(4)
    counters = {'messages_lost': 0, 'incompatible_qos': 0}
    problems = loss.period(counters, {}, 10, 'desired displacements')
    assert loss.last_backlog == 9 and loss.max_backlog == 0
    assert problems == [
        'input queue more than half full (9 of qos_depth=10 messages waiting at once): the '
        'node is falling behind; messages are lost when it fills']
    assert loss.period(counters, {}, 10, 'desired displacements') == []
    assert loss.last_backlog == 0


def test_the_loss_warning_comes_at_most_every_period_and_only_for_new_losses():
    loss = LossCounter('in', 'out', 'reliable')
    assert loss.report(100.0, 'desired displacements') is None       # nothing lost
    loss.message_lost(4)
    assert loss.report(100.0, 'desired displacements').startswith(
        '4 desired displacements lost before this node could serve them (4 in all)')
    loss.message_lost(1)
    assert loss.report(100.0 + LOG_PERIOD_S - 0.1, 'desired displacements') is None
    assert loss.report(100.0 + LOG_PERIOD_S, 'x').startswith('1 x lost')
    assert loss.report(1000.0, 'x') is None                            # nothing new


# -- faults, diagnostics period, lifecycle --------------------------------------------------
def test_the_fault_warning_counts_since_the_last_one_at_most_every_period():
    log = FaultLog()
    assert log.report(0.0, {'nonfinite_input': 0, 'clamped': 0}) is None
    first = log.report(0.0, {'nonfinite_input': 1, 'out_of_range': 1})
    assert first.startswith('1 non-finite, 1 out-of-range inputs since the last report')
    assert 'clamped: command limited to [output.min, output.max]' in first
    counters = {'nonfinite_input': 101, 'out_of_range': 1}
    assert log.report(FAULT_LOG_PERIOD_S - 0.1, counters) is None
    assert log.report(FAULT_LOG_PERIOD_S + 0.1, counters).startswith('100 non-finite inputs')
    assert log.report(100.0, counters) is None


def test_the_rate_window_gives_the_period_rate_and_its_start_counters():
    window = RateWindow(5.0)
    assert window.close(5.0, 10, {'a': 1}) == (0.0, {})          # no time passed
    assert window.close(7.0, 30, {'a': 2}) == (10.0, {'a': 1})
    assert window.close(8.0, 30, {'a': 3}) == (0.0, {'a': 2})


@pytest.mark.parametrize('transition, state', [
    ('configure', 'inactive'), ('activate', 'active'), ('deactivate', 'inactive'),
    ('cleanup', 'unconfigured'), ('shutdown', 'finalized'), ('error', 'unconfigured')])
def test_the_state_after_a_transition(transition, state):
    assert state_after(transition) == state


# -- the update rule across a node's models -------------------------------------------------
def test_the_rule_completes_every_prefix_and_keeps_unchanged_values_as_they_came():
    rule = UpdateRule(('axis0.', 'axis1.'))
    current = {prefix: node_values(rule.prefixes) for prefix in rule.prefixes}
    request = {axis_key(1, key): value for key, value in GAMMA.items()}
    request['enabled'] = False
    completed = rule.complete(current.__getitem__, request)
    for name, value in request.items():
        assert completed[name] is value
    assert completed[axis_key(1, 'model.output_sign')] == 1       # the whole axis-1 model
    assert completed[axis_key(1, 'model.input_offset')] == 0.0
    assert not any(name.startswith('axis0.') for name in completed)


def test_the_rule_keeps_what_it_prepared_for_one_take():
    rule = UpdateRule(('axis0.', 'axis1.'))
    values = node_values(rule.prefixes)
    request = {axis_key(0, key): value for key, value in GAMMA.items()}
    rule.prepare(lambda prefix: values, request, running=lambda prefix: False)
    prepared = rule.take()
    assert [update.prefix for update in prepared] == ['axis0.']   # axis 1 not touched
    assert isinstance(prepared[0].model, MPIModel) and prepared[0].inverse is not None
    assert rule.take() == []


def test_a_switch_touches_every_model_and_a_refusal_is_counted():
    rule = UpdateRule(('axis0.', 'axis1.'))
    values = node_values(rule.prefixes)
    rule.prepare(lambda prefix: values, {'enabled': False}, running=lambda prefix: False)
    assert [update.switches for update in rule.take()] == [{'enabled': False}] * 2
    request = {axis_key(1, 'model.hysteresis.weights'): [1.0]}
    with pytest.raises(ParameterRejected, match='axis 1 has no model yet'):
        rule.prepare(lambda prefix: values, request, running=lambda prefix: False)
    rule.refuse('axis 1 has no model yet')
    assert (rule.rejected, rule.last_rejection) == (1, 'axis 1 has no model yet')
    assert rule.take() == []


def test_touches_and_the_current_keys_of_a_prefix():
    assert touches({'axis0.model.dead_time': 0.0}, 'axis0.')
    assert not touches({'axis0.model.dead_time': 0.0}, 'axis1.')
    assert touches({'output.max': 1.0}, 'axis1.') and touches({'sample_period': 1.0}, '')
    keys = UpdateRule.current_keys('axis3.')
    assert keys[:len(model_keys())] == [axis_key(3, key) for key in model_keys()]
    assert keys[-4:] == ['axis3.output.min', 'axis3.output.max', 'output.min', 'output.max']
    assert UpdateRule.current_keys('')[-2:] == list(LIMIT_KEYS)


def test_load_axes_checks_every_range_first_and_returns_the_axes_with_a_model():
    prefixes = ('axis0.', 'axis1.', 'axis2.')
    values = node_values(prefixes, {'axis2.': GAMMA})
    models = load_axes(values, prefixes)
    assert list(models) == [2] and isinstance(models[2], MPIModel)
    bad = node_values(prefixes, {'axis2.': dict(GAMMA, **{'model.dead_time': 'x'})},
                      **{'axis1.output.min': 3.0})
    with pytest.raises(ParameterRejected, match='axis1.output.min must be below output.max'):
        load_axes(bad, prefixes)


# -- a multi-axis node's keys, models, inputs, times and counters -------------------------
def test_the_keys_of_the_axes_and_their_effective_limits():
    keys = AxisKeys.of(3)
    assert keys.prefixes == ('axis0.', 'axis1.', 'axis2.')
    assert keys.limits[1] == ('axis1.output.min', 'axis1.output.max')
    group = keys.group()
    assert len(group) == 3 * len(model_keys()) + 8
    assert axis_key(2, model_keys()[-1]) in group and 'output.min' in group
    values = dict.fromkeys(keys.all_limits)
    values.update({'output.min': 0.2, 'output.max': 1.8, 'axis1.output.max': 1.0,
                   'axis2.output.min': 0.5})
    assert keys.effective_limits(values) == ([0.2, 0.2, 0.5], [1.8, 1.0, 1.8])


def test_axis_models_count_versions_across_a_reset():
    models = AxisModels(3)
    gamma = MPIModel.from_params(GAMMA)
    creep = extended_model_from_params(dict(GAMMA, **CREEP))
    models.note(0, gamma)
    models.note(2, creep)
    assert models.missing == [1]
    assert models.applied({0: gamma, 2: creep}, running=False) == (
        'model applied to axis 0 (none), 2 (creep) (1 axes still without a model)')
    models.note(1, gamma)
    assert models.missing == [] and models.applied({1: gamma}, running=True) == (
        'model applied to axis 1 (none) (compensating)')
    models.inverses[0] = gamma.inverse()
    models.reset()
    assert models.missing == [0, 1, 2] and models.inverses == [None] * 3
    assert models.versions == [1, 1, 1]


def test_input_counts_tell_the_two_refusals_apart():
    inputs = InputCounts()
    inputs.samples += 4
    inputs.refuse('missing_joints', 'JointState without j2')
    inputs.refuse('malformed', 'JointState names a joint more than once')
    inputs.refuse('malformed', 'not a samples x axes block')
    assert inputs.counters(joints=False) == {'samples_in': 4, 'malformed': 2}
    assert inputs.counters(joints=True)['missing_joints'] == 1
    assert inputs.last_missing == 'JointState without j2'
    assert inputs.last_malformed == 'not a samples x axes block'


def test_message_clock_chains_the_chunks_on_the_stream():
    clock = MessageClock()
    stamps = [(10.0, 5), (10.002, 5), (10.05, 5), (10.0501, 2)]
    times = np.concatenate([clock.times(t, k, 0.001) for t, k in stamps])
    np.testing.assert_allclose(times, 9.996 + 0.001 * np.arange(17), rtol=0, atol=1e-12)
    clock.reset()
    np.testing.assert_allclose(clock.times(20.0, 2, 0.5), [19.5, 20.0])


def test_reported_counters_are_summed_over_the_axes():
    assert reported_counters(None) == dict.fromkeys(REPORTED_COUNTERS, 0)
    gamma = MPIModel.from_params(GAMMA)
    core = MultiAxisCompensator([gamma, gamma], output_min=0.0, output_max=2.0)
    core.command(np.array([[np.nan, 1e-5], [1e-5, np.inf]]))
    counters = reported_counters(core)
    assert list(counters) == list(REPORTED_COUNTERS)
    assert counters['nonfinite_input'] == 2 and counters['bad_time'] == 0


def test_slow_states_only_for_the_axes_with_an_effect():
    creep = extended_model_from_params(dict(GAMMA, **CREEP))
    core = MultiAxisCompensator([MPIModel.from_params(GAMMA), creep], output_min=0.0,
                                output_max=2.0)
    plain, lagged = core.slow_states
    assert plain is None and len(list(lagged)) == 3


def test_joint_state_input_needs_the_joints():
    assert not joint_input((), 'array')
    assert joint_input(('a', 'b'), 'joint_state')
    with pytest.raises(ParameterRejected, match='input_message joint_state needs the joints'):
        joint_input((), 'joint_state')


# -- which node, pushed types, grouped requests -----------------------------------------
@pytest.mark.parametrize('given, multi', [
    ({}, False), ({'axes': 1}, False), ({'axes': 2}, True), ({'axes': True}, False),
    ({'joints': []}, False), ({'joints': ['j0']}, True), ({'output_layout': 'flat'}, True),
    ({'output_layout': 'samples_by_axes'}, False), ({'input_message': 'joint_state'}, True)])
def test_which_compensator_the_start_up_values_ask_for(given, multi):
    assert wants_multi_axis(given) is multi


def test_a_pushed_value_is_sent_as_its_type():
    assert typed_value('model.output_sign', np.int64(-1)) == ('integer', -1)
    assert typed_value('model.dead_time', np.float64(0.5)) == ('double', 0.5)
    kind, value = typed_value('model.hysteresis.weights', np.array([1.0, 0.5]))
    assert kind == 'double_array' and value == [1.0, 0.5]
    assert all(type(v) is float for v in value)
    with pytest.raises(ParameterPushError, match='model.output_sign must be a number or a '
                                                 'list of numbers; found bool True'):
        typed_value('model.output_sign', True)


def test_a_grouped_request_is_set_in_steps():
    names = ['enabled', 'model.a', 'output.min', 'model.b', 'output.max', 'model.a']
    groups = [('model.a', 'model.b'), ('output.min', 'output.max', 'model.b')]
    assert request_steps(names, groups) == [[0], [1, 3, 5], [2, 4]]
    assert request_steps(names, groups, answered=[1]) == [[0], [2, 3, 4], [5]]
    assert request_steps(names, ()) == [[0], [1], [2], [3], [4], [5]]


# -- the plant simulator's plants and excitation ----------------------------------------
def plant_values(**given):
    """Return the plant simulator's default parameter values with ``given`` (``__``: ``.``)."""
    values = {spec.name: spec.default for spec in plant_parameters()}
    values.update({key.replace('__', '.'): value for key, value in given.items()})
    return values


def test_several_axes_are_refused_with_the_single_axis_modes():
    with pytest.raises(ParameterRejected, match='axes=2: excitation.enabled and record.path '
                                                'are single-axis only'):
        SimulatedPlants(plant_values(axes=2, excitation__enabled=True))
    with pytest.raises(ParameterRejected, match='axes=3'):
        SimulatedPlants(plant_values(axes=3, record__path='/tmp/bag'))


def test_each_axis_is_its_own_truth_with_seed_plus_k():
    values = plant_values(axes=3, seed=7)
    plants = SimulatedPlants(values)
    current = 1.0 + 0.5 * np.sin(np.arange(40) / 5.0)
    block = plants.measure_block(0.2, np.repeat(current[:, None], 3, axis=1))
    t = [0.2 - (39 - row) * values['sample_period'] for row in range(40)]  # last at 0.2
    for axis in range(3):
        truth = build_truth(values, seed=7 + axis)
        np.testing.assert_array_equal(block[:, axis], [truth.step(tk, ik)
                                                       for tk, ik in zip(t, current)])
    assert plants.last_t == 0.2


def test_a_non_finite_current_of_a_block_is_held_and_counted():
    mpi = {key.replace('.', '__'): value for key, value in GAMMA.items()}
    plants = SimulatedPlants(plant_values(truth='mpi', axes=2, **mpi))
    block = np.array([[0.5, 0.5], [np.nan, 0.9], [0.7, np.inf]])
    out = plants.measure_block(1.0, block)
    model = MPIModel.from_params(GAMMA)
    np.testing.assert_array_equal(out[:, 0], model.simulate(np.array([0.5, 0.5, 0.7])))
    np.testing.assert_array_equal(out[:, 1], model.simulate(np.array([0.5, 0.9, 0.9])))
    assert plants.counters['nonfinite_commands'] == 2


def test_sample_times_never_go_back():
    plants = SimulatedPlants(plant_values())
    assert plants.sample_time(2.0) == 2.0
    assert plants.sample_time(1.0) == pytest.approx(2.0 + 1e-9, abs=1e-15)
    plants.measure_block(0.5, np.ones((3, 1)))        # a block timed before the last sample
    assert plants.last_t == pytest.approx(2.0 + 4e-9, abs=1e-15)


def test_the_sensor_noise_is_seeded_and_added():
    values = plant_values(noise_std=1e-6, seed=3)
    first, second = SimulatedPlants(values), SimulatedPlants(values)
    quiet = SimulatedPlants(plant_values(seed=3))
    a = [first.measure(k * 1e-3, 1.0) for k in range(1, 20)]
    assert a == [second.measure(k * 1e-3, 1.0) for k in range(1, 20)]
    noise = np.subtract(a, [quiet.measure(k * 1e-3, 1.0) for k in range(1, 20)])
    assert 0.0 < np.std(noise) < 1e-5


def test_the_excitation_hands_each_sample_out_once_on_time():
    run = ExcitationRun([1.0, 1.001, 1.002, 1.5], [0.1, 0.2, 0.3, 0.4])
    assert run.due(100.0) == [(1.0, 0.1)]                 # the first one at once
    assert run.due(100.0015) == [(1.001, 0.2)]
    assert run.due(100.0015) == []
    assert not run.done
    assert run.due(100.6) == [(1.002, 0.3), (1.5, 0.4)]
    assert run.done and run.index == 4


# -- stop signals (in a child process: the handlers are the process's) -------------------
STOP_SCRIPT = """
import os, signal, sys
from mpi_ros.stop_signals import StopSignals
with StopSignals() as stop:
    os.kill(os.getpid(), signal.SIG{first})
    while not stop.requested:          # the handler runs at the next bytecode
        pass
    os.kill(os.getpid(), signal.SIG{second})      # ignored: no second request, no exit
    print(stop.name, stop.received == signal.SIG{first}, flush=True)
print(*(signal.getsignal(s) == signal.SIG_IGN for s in (signal.SIGINT, signal.SIGTERM)))
os.kill(os.getpid(), signal.SIGTERM)   # ignored after the context: the process goes on
with StopSignals(interrupt=True) as stop:
    try:
        os.kill(os.getpid(), signal.SIGINT)
        while True:
            pass
    except KeyboardInterrupt:
        print('interrupted', stop.name)
"""


@pytest.mark.parametrize('first, second', [('TERM', 'INT'), ('INT', 'TERM')])
def test_the_first_stop_signal_is_a_request_and_every_later_one_is_ignored(first, second):
    done = subprocess.run([sys.executable, '-c', STOP_SCRIPT.format(first=first, second=second)],
                          capture_output=True, text=True, timeout=60)
    assert done.returncode == 0, done.stderr
    assert done.stdout.splitlines() == [f'SIG{first} True', 'True True', 'interrupted SIGINT']


def test_without_a_signal_the_previous_handlers_come_back():
    code = ('import signal\nfrom mpi_ros.stop_signals import StopSignals\n'
            'before = [signal.getsignal(s) for s in (signal.SIGINT, signal.SIGTERM)]\n'
            'with StopSignals() as stop:\n'
            '    assert not stop.requested and stop.name == ""\n'
            'print([signal.getsignal(s) for s in (signal.SIGINT, signal.SIGTERM)] == before)\n')
    done = subprocess.run([sys.executable, '-c', code], capture_output=True, text=True,
                          timeout=60)
    assert done.stdout.strip() == 'True', done.stderr
