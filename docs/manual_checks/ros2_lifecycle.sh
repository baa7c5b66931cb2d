#!/usr/bin/env bash
# Manual check of the real jazzy `ros2 lifecycle` CLI against `mpi-ros compensator`
# (ros2cli's ros2lifecycle from source, in a scratch venv; never a dependency of mpi_ros).
# What it printed on the day: ros2_lifecycle.md beside this file.
set -u
export ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST ROS_DOMAIN_ID=${ROS_DOMAIN_ID:-78}
# CLI_VENV: a scratch venv outside the repo with this package (pip install -e .), psutil,
# netifaces, argcomplete, packaging, and, from their jazzy branches, pip install --no-deps:
# ros2cli, ros2node, ros2service, ros2param, ros2topic, ros2lifecycle (ros2cli 0.32.2) and
# rosidl_runtime_py 0.13.1 (ros2service imports it; it is not on the registries either).
V=${CLI_VENV:-/tmp/cli-venv-lc}/bin
mkdir -p "${WORKDIR:-/tmp/lifecyclecheck}" && cd "${WORKDIR:-/tmp/lifecyclecheck}"
ros2() { timeout 60 "$V/ros2" "$@" 2>&1; }
# A model file from identify.
$V/python - <<'PY'
from mpi_ros import identify
from mpi_ros.plant.actuator import MagnetostrictiveActuator
from mpi_ros.plant.excitation import identification_excitation
from mpi_ros.params import write_params_yaml
t, x = identification_excitation(20.0, sample_rate=200.0, seed=1, holds=False, bursts=False)
model = identify(x, MagnetostrictiveActuator().simulate(t, x), n=6, l=3).model
write_params_yaml('model.yaml', model.to_params())
with open('offset.txt', 'w') as f:          # the sensor zero moved by 0.1 um
    print(f'{model.output_offset + 1.0e-7!r}', file=f)
PY
# Count the commands the compensator answers to 50 desired displacements, from a client.
probe() {
  $V/python - "$1" <<'PY'
import sys, time
import rclpy
from std_msgs.msg import Float64
rclpy.init()
node = rclpy.create_node('lifecycle_probe')
got = []
node.create_subscription(Float64, '/current_command', lambda m: got.append(m.data), 100)
pub = node.create_publisher(Float64, '/desired_displacement', 100)
deadline = time.monotonic() + 10.0
while pub.get_subscription_count() == 0 and time.monotonic() < deadline:
    rclpy.spin_once(node, timeout_sec=0.1)
for k in range(50):
    pub.publish(Float64(data=1.0e-5 + 2.0e-7 * k))
    rclpy.spin_once(node, timeout_sec=0.01)
deadline = time.monotonic() + 2.0
while time.monotonic() < deadline:
    rclpy.spin_once(node, timeout_sec=0.05)
last = f', last {got[-1]:.6f} A' if got else ''
print(f'{sys.argv[1]}: subscribers of /desired_displacement '
      f'{pub.get_subscription_count()}, 50 desired sent, {len(got)} commands back{last}')
node.destroy_node()
rclpy.shutdown()
PY
}

echo '=== mpi-ros compensator (autostart: default true)'
$V/mpi-ros compensator --ros-args --params-file model.yaml \
    -p output.min:=0.2 -p output.max:=1.8 > comp.log 2>&1 &
PID=$!
sleep 8
echo '--- ros2 lifecycle nodes'; ros2 lifecycle nodes --no-daemon --spin-time 3
echo '--- ros2 lifecycle get /compensator'; ros2 lifecycle get --no-daemon --spin-time 3 /compensator
echo '--- ros2 lifecycle list /compensator'; ros2 lifecycle list --no-daemon --spin-time 3 /compensator
probe active
echo '--- ros2 lifecycle set /compensator deactivate'
ros2 lifecycle set --no-daemon --spin-time 3 /compensator deactivate
ros2 lifecycle get --no-daemon --spin-time 3 /compensator
probe inactive
echo '--- ros2 param set while inactive (valid, then invalid)'
ros2 param set --no-daemon --spin-time 3 /compensator model.output_offset "$(cat offset.txt)"
ros2 param set --no-daemon --spin-time 3 /compensator model.output_sign 0
echo '--- ros2 lifecycle set /compensator activate'
ros2 lifecycle set --no-daemon --spin-time 3 /compensator activate
probe active-again
echo '--- ros2 lifecycle set /compensator configure (not available while active)'
ros2 lifecycle set --no-daemon --spin-time 3 /compensator configure
echo '--- deactivate, cleanup'
ros2 lifecycle set --no-daemon --spin-time 3 /compensator deactivate
ros2 lifecycle set --no-daemon --spin-time 3 /compensator cleanup
ros2 lifecycle get --no-daemon --spin-time 3 /compensator
probe unconfigured
echo '--- ros2 lifecycle set /compensator shutdown'
ros2 lifecycle set --no-daemon --spin-time 3 /compensator shutdown
for _ in $(seq 100); do kill -0 $PID 2>/dev/null || break; sleep 0.1; done
if kill -0 $PID 2>/dev/null; then echo 'compensator still running'; kill -INT $PID; fi
wait $PID; echo "compensator exit $?"
echo '--- its log'; grep -v '^$' comp.log

echo '=== mpi-ros compensator -p autostart:=false'
$V/mpi-ros compensator --ros-args --params-file model.yaml -p autostart:=false \
    -r __node:=managed > comp2.log 2>&1 &
PID=$!
sleep 8
ros2 lifecycle get --no-daemon --spin-time 3 /managed
ros2 lifecycle set --no-daemon --spin-time 3 /managed activate
ros2 lifecycle set --no-daemon --spin-time 3 /managed configure
ros2 lifecycle set --no-daemon --spin-time 3 /managed activate
ros2 lifecycle get --no-daemon --spin-time 3 /managed
kill -INT $PID; wait $PID; echo "managed exit $?"
grep -i 'traceback\|error' comp.log comp2.log | head -5
