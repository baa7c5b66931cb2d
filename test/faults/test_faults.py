# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Faults over DDS: start order, missing target, killed and restarted nodes, a killed push.

Every node is a separate process on this module's own ``ROS_DOMAIN_ID`` (local-only
discovery); the test process drives the compensator in lock step and compares every
command with the core :class:`~mpi_ros.compensation.Compensator` (exactly, to
1e-12 A), so "unaffected" and "same model" are checked command by command.
"""

import time

from mpi_ros.nodes.identifier import push_model_parameters
from mpi_ros.operators.model import IDENTIFIED_INPUT_RANGE, MODEL_KEYS, MPIModel, \
    OPERATING_POINT_KEYS, RECORD_START_STATES
import numpy as np
import pytest
from std_msgs.msg import Float64

from .helpers import (
    commands_for, desired_values, first_command, get_parameters, LIMITS, log_text, mirror,
    wait_exit, wait_for_log,
)

EXACT = 1e-12        # [A] the node and the core run the same float64 code
ORDER = '6,3'
#: The keys of a plain model: Gamma, the operating point, the record start and the record's
#: input range (all pushed by the identifier).
KEYS = MODEL_KEYS + OPERATING_POINT_KEYS + (RECORD_START_STATES, IDENTIFIED_INPUT_RANGE)


def _assert_safe(commands):
    commands = np.asarray(commands)
    assert np.all(np.isfinite(commands))
    assert np.all((commands >= LIMITS[0]) & (commands <= LIMITS[1]))


def _identifier(nodes, bag, *ros_args):
    return nodes.start('identifier', '-p', f'bag:={bag}', '-p', f'order:={ORDER}', *ros_args)


def test_compensator_first_then_identifier_pushes_from_a_bag(nodes, driver, bags, tmp_path):
    bag_a, params_a, _ = bags['a']
    comp = nodes.compensator()
    wait_for_log(comp, 'no model given yet')
    driver.wait_for(lambda: driver.desired_pub.get_subscription_count() > 0, 'compensator',
                    60.0)
    # Unconfigured: nothing is published.
    driver.desired_pub.publish(Float64(data=1e-5))
    driver.spin_for(0.5)
    assert driver.commands == []
    # A corrupt bag: the identifier fails (status 1, names the problem), pushes nothing.
    broken = tmp_path / 'broken'
    broken.mkdir()
    for item in bag_a.iterdir():
        data = item.read_bytes()
        (broken / item.name).write_bytes(data if item.suffix == '.yaml' else data[:len(data) // 2])
    ident = _identifier(nodes, broken, '-p', 'service_timeout:=20.0')
    assert wait_exit(ident, 60.0) == 1
    assert 'error: identifier:' in log_text(ident)
    assert 'truncated or corrupt' in log_text(ident)
    driver.desired_pub.publish(Float64(data=1e-5))
    driver.spin_for(0.3)
    assert driver.commands == []
    # The real bag: fitted, pushed, accepted; the node then runs exactly that model.
    ident = _identifier(nodes, bag_a, '-p', 'service_timeout:=20.0')
    assert wait_exit(ident, 60.0) == 0, log_text(ident)
    assert '/compensator accepted the model' in log_text(ident)
    assert get_parameters(driver, KEYS) == params_a
    # The identifier pushes the identified input range as the limits too (issue 27).
    limits = get_parameters(driver, ('output.min', 'output.max'))
    core = mirror(params_a, (limits['output.min'], limits['output.max']))
    values = desired_values(params_a, 150, seed=1)
    assert first_command(driver, values[0]) == pytest.approx(core.command(values[0]), abs=EXACT)
    commands = commands_for(driver, values[1:])
    np.testing.assert_allclose(commands, [core.command(v) for v in values[1:]],
                               rtol=0, atol=EXACT)
    _assert_safe(commands)
    assert comp.running()


def test_identifier_without_compensator_fails_after_a_bounded_wait(nodes, bags):
    ident = _identifier(nodes, bags['a'][0], '-p', 'service_timeout:=3.0')
    wait_for_log(ident, 'fitted order')
    fitted = time.monotonic()
    status = wait_exit(ident, 30.0)
    waited = time.monotonic() - fitted
    assert status == 1
    assert ('error: identifier: no parameter service /compensator/set_parameters_atomically '
            'within 3 s' in log_text(ident))
    assert 'Nothing was pushed' in log_text(ident)
    assert waited >= 2.5                        # it did wait (wait_exit bounds it above)


def test_plant_killed_and_restarted_during_a_run(nodes, driver, bags):
    _, params_a, yaml_a = bags['a']
    comp = nodes.compensator('--params-file', str(yaml_a))
    plant = nodes.start('plant-simulator', '-p', 'seed:=3')
    core = mirror(params_a)
    values = desired_values(params_a, 500, seed=2)
    driver.wait_for(lambda: driver.current_pub.get_subscription_count() > 0, 'plant', 60.0)
    driver.wait_for(lambda: driver.desired_pub.get_subscription_count() > 0, 'compensator',
                    60.0)
    driver.handshake(driver.desired_pub, values[0])
    core.command(values[0])
    driver.commands.clear()
    # (1) closed loop
    before = [driver.exchange(driver.desired_pub, v) for v in values[1:150]]
    # (2) the plant dies: the compensator answers on, unaffected
    plant.kill()
    during = commands_for(driver, values[150:250])
    # (3) a new plant: the loop resumes (repeating the last value is state-neutral)
    nodes.start('plant-simulator', '-p', 'seed:=3')
    repeat = len(driver.commands)
    driver.handshake(driver.desired_pub, values[249])
    repeats = driver.commands[repeat:]
    after = [driver.exchange(driver.desired_pub, v) for v in values[250:]]

    expected = [core.command(v) for v in values[1:250]]
    np.testing.assert_allclose(driver.commands[:249], expected, rtol=0, atol=EXACT)
    np.testing.assert_allclose(during, expected[149:], rtol=0, atol=EXACT)
    np.testing.assert_allclose(repeats, expected[-1], rtol=0, atol=EXACT)
    tail = [core.command(v) for v in values[250:]]
    np.testing.assert_allclose(driver.commands[-len(tail):], tail, rtol=0, atol=EXACT)
    _assert_safe(driver.commands)
    assert np.all(np.isfinite(before)) and np.all(np.isfinite(after))
    assert comp.running()


def test_restarted_compensator_comes_back_with_its_configured_model(nodes, driver, bags):
    _, params_a, yaml_a = bags['a']
    _, params_b, _ = bags['b']
    values = desired_values(params_a, 150, seed=3)
    runs = []
    for run in range(2):
        comp = nodes.compensator('--params-file', str(yaml_a))
        first = first_command(driver, values[0])
        runs.append(np.concatenate([[first], commands_for(driver, values[1:])]))
        assert get_parameters(driver, KEYS) == params_a
        if run == 0:
            # A model pushed at run time is not persisted: after the crash the node
            # comes back with the model of its --params-file.
            with driver.detached():
                push_model_parameters(driver, '/compensator', params_b, timeout=20.0)
            assert get_parameters(driver, KEYS) == params_b
        comp.kill()                          # a crash, not a clean shutdown
    core = mirror(params_a)
    expected = [core.command(v) for v in values]
    np.testing.assert_allclose(runs[0], expected, rtol=0, atol=EXACT)
    np.testing.assert_allclose(runs[1], runs[0], rtol=0, atol=EXACT)
    _assert_safe(runs)


def test_identifier_killed_around_the_push_leaves_old_or_new_model(nodes, driver, bags):
    models = {name: bags[name][1] for name in 'ab'}
    nodes.compensator('--params-file', str(bags['a'][2]))
    core = mirror(models['a'])
    values = desired_values(models['a'], 400, seed=4)
    first_command(driver, values[0])
    core.command(values[0])
    rng = np.random.default_rng(5)
    # Kill moments: before the fit ends (surely old), after the push was accepted (surely
    # new), and random moments from the end of the fit, when the push starts.
    moments = [('identifying from', 0.0), ('accepted the model', 0.0)] + [
        ('fitted order', float(rng.uniform(0.0, 0.05))) for _ in range(4)]
    current, outcomes, k = 'a', [], 1
    for marker, delay in moments:
        target = 'b' if current == 'a' else 'a'
        ident = nodes.start('identifier', '-p', f'bag:={bags[target][0]}', '-p',
                            f'order:={ORDER}', '-p', 'service_timeout:=20.0')
        wait_for_log(ident, marker)
        time.sleep(delay)
        ident.kill()
        time.sleep(0.5)                      # a request already sent is served meanwhile
        held = get_parameters(driver, KEYS)
        assert held in (models[current], models[target]), 'a mix of two models'
        if held == models[target]:
            core.install(MPIModel.from_params(models[target]))
            current = target
            outcomes.append('new')
        else:
            outcomes.append('old')
        commands = commands_for(driver, values[k:k + 40])
        np.testing.assert_allclose(commands, [core.command(v) for v in values[k:k + 40]],
                                   rtol=0, atol=EXACT)
        _assert_safe(commands)
        k += 40
    print('outcomes of the kills:', outcomes)
    assert outcomes[:2] == ['old', 'new'], outcomes
