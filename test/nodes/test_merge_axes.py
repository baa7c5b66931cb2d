# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Issue 27: a two-axis parameter file made by the command line alone runs the multi-axis node.

Two actuators (the built-in one around two operating points) are recorded to CSV,
identified with ``mpi-ros identify`` one file per axis and merged with ``mpi-ros
merge-axes --joints``.  The merged file, given as ``--params-file``, starts the multi-axis
compensator (``make_node`` picks it from ``axes``) with ros2_control's layout: its output,
remapped to ``/<controller>/commands`` and received with the controller's QoS, holds one
command per joint, no layout, each the command of that axis's model clamped to the limits
identify wrote.  A single-axis file given to a two-axis node is refused, naming
``merge-axes``, instead of leaving both axes without a model.
"""

from mpi_ros.app.cli import main
from mpi_ros.compensation import Compensator
from mpi_ros.errors import ParameterRejected
from mpi_ros.extensions import extended_model_from_params
from mpi_ros.nodes.compensator import make_node
from mpi_ros.nodes.multi_axis import MultiAxisCompensatorNode
from mpi_ros.params import read_params_yaml
from mpi_ros.plant.actuator import MagnetostrictiveActuator
from mpi_ros.plant.excitation import identification_excitation
from mpi_ros.recordings import write_csv_columns
import numpy as np
import pytest
from rclpy.parameter import Parameter
from rclpy.qos import qos_profile_system_default
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray

from .lifecycle_rig import LifecycleRig
from .test_ros2_control_output import assert_controller_contract

JOINTS = ['elbow', 'wrist']
CONTROLLER = 'current_controller'


@pytest.fixture(scope='module')
def merged(tmp_path_factory):
    """Identify two actuators with the CLI and merge the files; return the paths."""
    tmp = tmp_path_factory.mktemp('merge')
    t, base = identification_excitation(8.0, sample_rate=500.0, seed=4)
    files = []
    for axis, current in enumerate((base, 0.8 * base + 0.3)):
        displacement = MagnetostrictiveActuator().simulate(t, current)
        write_csv_columns(tmp / f'axis{axis}.csv', {'time': t, 'current': current,
                                                    'displacement': displacement})
        assert main(['identify', str(tmp / f'axis{axis}.csv'), '--order', '6,3',
                     '--dynamics', 'off', '-o', str(tmp / f'axis{axis}.yaml')]) == 0
        files.append(tmp / f'axis{axis}.yaml')
    assert main(['merge-axes', *map(str, files), '--joints', ','.join(JOINTS),
                 '-o', str(tmp / 'axes.yaml')]) == 0
    return tmp / 'axes.yaml', files


def test_merge_axes_writes_every_axis_and_the_wiring(merged):
    path, files = merged
    written = read_params_yaml(path)
    assert written['axes'] == 2 and written['joints'] == JOINTS
    assert written['output_layout'] == 'flat'
    for axis, single in enumerate(files):
        for key, value in read_params_yaml(single).items():
            assert written[f'axis{axis}.{key}'] == value
    text = path.read_text()
    assert text.count('identified on current') == 2


def test_merge_axes_refuses_one_file_and_a_multi_axis_file(merged, tmp_path, capsys):
    path, files = merged
    assert main(['merge-axes', str(files[0]), '-o', str(tmp_path / 'x.yaml')]) == 1
    assert 'at least two parameter sets; found 1' in capsys.readouterr().err
    assert main(['merge-axes', str(path), str(files[0]), '-o', str(tmp_path / 'x.yaml')]) == 1
    assert 'holds a multi-axis model (axis<k>.* keys)' in capsys.readouterr().err
    assert not (tmp_path / 'x.yaml').exists()


def test_the_merged_file_runs_the_node_in_the_controller_layout(ros_context, merged):
    path, files = merged
    node = make_node(context=ros_context, cli_args=[
        '--ros-args', '--params-file', str(path), '-p', 'input_message:=joint_state',
        '-p', 'diagnostics_period:=3600.0', '-r', f'current_commands:=/{CONTROLLER}/commands'])
    rig = LifecycleRig(ros_context, node)
    try:
        assert isinstance(node, MultiAxisCompensatorNode) and node.joints == tuple(JOINTS)
        assert node.compensator is not None                         # both axes configured
        received = []
        rig.client.create_subscription(Float64MultiArray, f'/{CONTROLLER}/commands',
                                       received.append, qos_profile_system_default)
        publisher = rig.client.create_publisher(JointState, 'desired_joint_states', 1000)
        assert rig.loop_matched(publisher)
        singles = [read_params_yaml(single) for single in files]
        cores = [Compensator(extended_model_from_params(p), output_min=p['output.min'],
                             output_max=p['output.max']) for p in singles]
        reach = [core.displacement_range for core in cores]
        rng = np.random.default_rng(5)
        for count in range(1, 31):
            row = [lo + rng.uniform(-0.1, 1.1) * (hi - lo) for lo, hi in reach]
            publisher.publish(JointState(name=list(reversed(JOINTS)),
                                         position=[float(v) for v in reversed(row)]))
            assert rig.spin_until(lambda count=count: len(received) >= count)
            msg = received[-1]
            assert_controller_contract(msg, JOINTS)
            expected = [core.command(float(v)) for core, v in zip(cores, row)]
            np.testing.assert_allclose(msg.data, expected, rtol=0, atol=1e-12)
            for axis, value in enumerate(msg.data):
                assert singles[axis]['output.min'] <= value <= singles[axis]['output.max']
    finally:
        rig.close()
        node.destroy_node()


def test_a_single_axis_file_is_refused_by_a_two_axis_node(ros_context, merged):
    _, files = merged
    with pytest.raises(ParameterRejected, match=r'single-axis model keys given \(model\.'
                                                r'.*mpi-ros merge-axes'):
        make_node(context=ros_context, parameter_overrides=[Parameter('axes', value=2)],
                  cli_args=['--ros-args', '--params-file', str(files[0])])
