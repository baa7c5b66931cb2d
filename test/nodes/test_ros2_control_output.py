# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
The multi-axis compensator wired to ros2_control's forward_command_controller.

The controller's contract (ros2_controllers, ``forward_command_controller``): it subscribes
``~/commands`` (``std_msgs/Float64MultiArray``, system-default QoS: with Fast DDS a
best-effort reader that keeps the newest message) and uses a message only when ``data``
holds exactly one value per joint of its ``joints`` parameter, in that order; the layout is
not read.  The node's
``output_layout: flat`` must publish exactly that: ``len(data) == len(joints)``, empty
``layout.dim``, ``layout.data_offset`` 0, ``data[k]`` the command of ``joints[k]``.  The
output is remapped to ``/<controller>/commands`` as the launch example does, and received
with the controller's QoS.  Inputs are ``sensor_msgs/JointState`` with the joints in
another order and extra joints, mapped by name; a message missing a joint is refused and
counted.  No timing is asserted; every wait is bounded.
"""

from diagnostic_msgs.msg import DiagnosticStatus
from mpi_ros.array_layout import encode_flat_float64_multiarray
from mpi_ros.compensation import Compensator
from mpi_ros.errors import ParameterRejected
from mpi_ros.nodes.compensator import make_node
from mpi_ros.nodes.multi_axis import axis_key, MultiAxisCompensatorNode
import numpy as np
import pytest
from rclpy.parameter import Parameter
from rclpy.qos import qos_profile_system_default
from rclpy.serialization import deserialize_message, serialize_message
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray

from .lifecycle_rig import LifecycleRig
from .test_multi_axis_node import _plain, desired_block, message, OUTPUT_MAX, OUTPUT_MIN

from ..core_models import random_model

#: The controller's joints, deliberately not in alphabetical order.
JOINTS = ['wrist', 'elbow', 'shoulder']
CONTROLLER = 'current_controller'
TOLERANCE = 1e-12


def joint_models(seed, count=len(JOINTS)):
    rng = np.random.default_rng(seed)
    return [random_model(rng, n=int(rng.integers(1, 6)), l=int(rng.integers(0, 3)),
                         initial_history=False) for _ in range(count)]


def overrides(models, joints=JOINTS, **options):
    result = [Parameter('axes', value=len(models)), Parameter('joints', value=list(joints)),
              Parameter('output.min', value=OUTPUT_MIN), Parameter('output.max', value=OUTPUT_MAX),
              Parameter('diagnostics_period', value=3600.0)]
    result += [Parameter(name, value=value) for name, value in options.items()]
    for axis, model in enumerate(models):
        result += [Parameter(axis_key(axis, key), value=value)
                   for key, value in _plain(model.to_params()).items()]
    return result


@pytest.fixture
def make_rig(ros_context):
    """Build the node (make_node, output remapped to the controller) and a client."""
    made = []

    def make(models, *, input_message='joint_state', joints=JOINTS):
        node = make_node(
            context=ros_context,
            parameter_overrides=overrides(models, joints, output_layout='flat',
                                          input_message=input_message),
            cli_args=['--ros-args', '-r', f'current_commands:=/{CONTROLLER}/commands'])
        rig = LifecycleRig(ros_context, node)
        rig.received = []
        # What forward_command_controller creates: ~/commands, system-default QoS.
        rig.client.create_subscription(Float64MultiArray, f'/{CONTROLLER}/commands',
                                       rig.received.append, qos_profile_system_default)
        if input_message == 'joint_state':
            rig.publisher = rig.client.create_publisher(JointState, 'desired_joint_states',
                                                        1000)
        else:
            rig.publisher = rig.client.create_publisher(Float64MultiArray,
                                                        'desired_displacements', 1000)
        assert rig.loop_matched(rig.publisher)
        made.append(rig)
        return rig

    yield make
    for rig in made:
        rig.close()
        rig.node.destroy_node()


def cores(models):
    return [Compensator(model, output_min=OUTPUT_MIN, output_max=OUTPUT_MAX)
            for model in models]


def assert_controller_contract(msg, joints):
    """Check what forward_command_controller accepts: one value per joint, no layout."""
    assert len(msg.data) == len(joints)
    assert list(msg.layout.dim) == []
    assert msg.layout.data_offset == 0


def test_joint_states_in_any_order_give_commands_in_joints_order(make_rig):
    models = joint_models(3)
    rig = make_rig(models)
    node = rig.node
    assert isinstance(node, MultiAxisCompensatorNode) and node.joints == tuple(JOINTS)
    desired = desired_block(models, 40, seed=6)         # column k: joint JOINTS[k]
    rng = np.random.default_rng(9)
    for count, row in enumerate(desired, start=1):
        names = JOINTS + ['gripper']                     # a joint the node does not serve
        values = list(row) + [0.5]
        order = rng.permutation(len(names))              # another order in every message
        rig.publisher.publish(JointState(name=[names[i] for i in order],
                                         position=[float(values[i]) for i in order]))
        # In lock step: the controller's queue keeps only the newest.
        assert rig.spin_until(lambda: len(rig.received) >= count)
    assert len(rig.received) == len(desired)
    for msg in rig.received:
        assert_controller_contract(msg, JOINTS)
    axis_cores = cores(models)
    expected = np.column_stack([[core.command(float(v)) for v in desired[:, k]]
                                for k, core in enumerate(axis_cores)])
    np.testing.assert_allclose(np.array([msg.data for msg in rig.received]), expected,
                               rtol=0, atol=TOLERANCE)
    # The axes really differ: a wrong order would not pass.
    assert np.max(np.abs(expected[:, 0] - expected[:, 1])) > 1e-3
    counters = node.counters
    assert counters['messages_in'] == counters['messages_out'] == len(desired)
    assert counters['missing_joints'] == counters['malformed'] == 0


def test_joint_states_missing_a_joint_are_refused_and_counted(make_rig):
    rig = make_rig(joint_models(4))
    node = rig.node
    node.diagnostics()
    rig.publisher.publish(JointState(name=['wrist', 'shoulder'], position=[1e-6, 2e-6]))
    rig.publisher.publish(JointState(name=['elbow', 'wrist', 'shoulder'], position=[1e-6]))
    assert rig.spin_until(lambda: node.counters['messages_in'] >= 2)
    rig.spin_for(0.3)
    assert rig.received == []
    counters = node.counters
    assert counters['missing_joints'] == 1 and counters['malformed'] == 1
    status = node.diagnostics().status[0]
    assert status.level == DiagnosticStatus.WARN
    assert '1 JointState messages missing a joint' in status.message
    assert 'without elbow' in status.message
    assert '3 names and 1 positions' in status.message


def test_array_chunks_give_one_message_per_sample_and_the_controller_the_newest(make_rig):
    models = joint_models(5)
    rig = make_rig(models, input_message='array')
    recorded = []                      # a deep reliable queue (a recorder) sees every one
    rig.client.create_subscription(Float64MultiArray, f'/{CONTROLLER}/commands',
                                   recorded.append, 100)
    assert rig.loop_matched(rig.publisher)
    desired = desired_block(models, 9, seed=7)
    axis_cores = cores(models)
    expected = np.column_stack([[core.command(float(v)) for v in desired[:, k]]
                                for k, core in enumerate(axis_cores)])
    rig.publisher.publish(message(desired[:5]))           # a chunk of 5 samples
    assert rig.spin_until(lambda: len(recorded) >= 5)
    rig.publisher.publish(message(desired[5:], layout=False))
    assert rig.spin_until(lambda: len(recorded) >= 9)
    assert rig.node.counters['messages_out'] == 9
    for msg in recorded:
        assert_controller_contract(msg, JOINTS)
    np.testing.assert_allclose(np.array([msg.data for msg in recorded]), expected, rtol=0,
                               atol=TOLERANCE)

    def newest_arrived():
        # The controller's queue (system default: Fast DDS keeps the newest) drops the
        # older messages of a burst: the last sample of each chunk reaches it.
        return bool(rig.received) and np.allclose(rig.received[-1].data, expected[-1],
                                                  rtol=0, atol=TOLERANCE)

    assert rig.spin_until(newest_arrived)
    for msg in rig.received:
        assert_controller_contract(msg, JOINTS)


def test_one_joint_is_the_multi_axis_node_with_one_value(make_rig):
    models = joint_models(6, count=1)
    rig = make_rig(models, joints=['gripper'])
    assert isinstance(rig.node, MultiAxisCompensatorNode) and rig.node.axes == 1
    rig.publisher.publish(JointState(name=['other', 'gripper'], position=[9.0, 1.0e-6]))
    assert rig.spin_until(lambda: len(rig.received) >= 1)
    assert_controller_contract(rig.received[0], ['gripper'])


def test_the_flat_bytes_are_the_message_rclpy_writes():
    for count in (1, 3, 8):
        values = np.linspace(-0.25, 1.75, count)
        mine = deserialize_message(encode_flat_float64_multiarray(values), Float64MultiArray)
        theirs = deserialize_message(serialize_message(Float64MultiArray(data=list(values))),
                                     Float64MultiArray)
        assert mine == theirs
        assert list(mine.layout.dim) == [] and mine.layout.data_offset == 0


@pytest.mark.parametrize('joints, options, needle', [
    (['a', 'b'], {}, 'joints names 2 joints (a, b) but axes is 3'),
    (['a', 'b', 'a'], {}, 'joints names a more than once'),
    (['a', ' ', 'c'], {}, 'the name of axis 1 is empty'),
    ([], {'input_message': 'joint_state'}, 'input_message joint_state needs the joints'),
])
def test_bad_wiring_refuses_to_start(ros_context, joints, options, needle):
    params = overrides(joint_models(8), joints, **options)
    if not joints:
        params = [p for p in params if p.name != 'joints']
    with pytest.raises(ParameterRejected, match=needle.replace('(', r'\(').replace(')', r'\)')):
        MultiAxisCompensatorNode(context=ros_context, parameter_overrides=params)
