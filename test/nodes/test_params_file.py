# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
A node's ``--params-file`` is checked before rcl reads it (mpi_ros.nodes.spinning).

Every unusable file gives one line naming the file and the problem; a good one none.  The
node processes themselves (one ``error:`` line, exit status 1) are in
``test/faults/test_hostile_peers.py``.
"""

from mpi_ros.nodes.spinning import PARAMS_DEPTH, params_file_problem, params_files, run_node_main
from mpi_ros.params import write_params_yaml
import pytest


@pytest.mark.parametrize('content, words', [
    (b'\x89PNG\r\n\x1a\n\x00\x00garbage: [', 'not valid YAML'),
    (b'\xff\xfe\x00', 'not valid YAML'),
    (b'compensator:\n  ros__parameters: 5\n', 'compensator.ros__parameters must be a mapping'),
    (b'- a\n- b\n', 'expected a mapping of node names'),
    (b'', 'expected a mapping of node names'),
    (b'compensator: 3\n', 'compensator must be a mapping'),
    (b'compensator:\n  other: {}\n', 'no ros__parameters section'),
    (b'base: &a {ros__parameters: {x: 1}}\ncompensator: *a\n', 'aliases'),
    (b'a:\n' + b''.join(b' ' * (2 * i) + b'  k:\n' for i in range(PARAMS_DEPTH + 5)),
     f'nested deeper than {PARAMS_DEPTH}'),
    (b'[' * 10000, f'nested deeper than {PARAMS_DEPTH}'),
    (b'compensator:\n  ros__parameters:\n    output.max: [1.0, "a"]\n',
     'compensator.ros__parameters.output.max: a list must hold items of one type'),
    (b'compensator:\n  ros__parameters:\n    model: {w: [[1.0]]}\n',
     'model.w: a list must hold items of one type'),
])
def test_unusable_files_are_named(tmp_path, content, words):
    path = tmp_path / 'params.yaml'
    path.write_bytes(content)
    problem = params_file_problem(str(path))
    assert problem is not None and problem.startswith(str(path)) and words in problem, problem
    assert '\n' not in problem


def test_missing_and_directory(tmp_path):
    assert 'cannot read it' in params_file_problem(str(tmp_path / 'none.yaml'))
    assert 'cannot read it' in params_file_problem(str(tmp_path))


def test_a_written_params_file_passes(tmp_path):
    path = tmp_path / 'good.yaml'
    write_params_yaml(path, {'output.max': 1.8, 'model.hysteresis.weights': [1.0, 0.5],
                             'joints': ['a', 'b'], 'enabled': True})
    assert params_file_problem(str(path)) is None
    namespaced = tmp_path / 'ns.yaml'
    namespaced.write_text('/robot:\n  compensator:\n    ros__parameters:\n      axes: 2\n'
                          '/**:\n  ros__parameters:\n    use_sim_time: false\n')
    assert params_file_problem(str(namespaced)) is None


def test_params_files_are_found_in_ros_args_only():
    args = ['compensator', '--params-file', 'not-ros.yaml', '--ros-args', '-p', 'a:=1',
            '--params-file', 'one.yaml', '--', 'x', '--ros-args', '--params-file', 'two.yaml']
    assert list(params_files(args)) == ['one.yaml', 'two.yaml']


def test_the_main_path_refuses_before_rclpy_starts(tmp_path, capsys):
    path = tmp_path / 'bad.yaml'
    path.write_text('compensator: [1, 2]\n')

    def never():
        raise AssertionError('the node must not be built')

    status = run_node_main(never, 'compensator',
                           ['compensator', '--ros-args', '--params-file', str(path)])
    err = capsys.readouterr().err
    assert status == 1
    assert err.splitlines() == [f'error: compensator: --params-file {path}: compensator must '
                                'be a mapping (a mapping of node names to {ros__parameters: '
                                '{name: value}}); found list']
