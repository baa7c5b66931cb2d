#!/usr/bin/env bash
# Manual check of the real jazzy ros2 CLI (ros2cli/ros2param from source, scratch venv).
set -u
export ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST ROS_DOMAIN_ID=77
# CLI_VENV: a scratch venv outside the repo with this package (pip install -e .), psutil,
# netifaces, and ros2cli, ros2node, ros2pkg, ros2param from the jazzy sources (pip install --no-deps).
V=${CLI_VENV:-/tmp/cli-venv}/bin
mkdir -p "${WORKDIR:-/tmp/clicheck}" && cd "${WORKDIR:-/tmp/clicheck}"
# A model file from identify (operating point included), and a broken one.
$V/python - <<'PY'
import numpy as np
from mpi_ros import identify
from mpi_ros.plant.actuator import MagnetostrictiveActuator
from mpi_ros.plant.excitation import identification_excitation
from mpi_ros.params import write_params_yaml
t, x = identification_excitation(20.0, sample_rate=200.0, seed=1, holds=False, bursts=False)
y = 3e-4 - MagnetostrictiveActuator().simulate(t, x)          # sensor with its own zero, falling
m = identify(x, y, n=6, l=3).model
write_params_yaml('model.yaml', m.to_params())
p = m.to_params(); p['model.hysteresis.weights'] = [-1.0] + p['model.hysteresis.weights'][1:]
write_params_yaml('broken.yaml', p)
print('model: x0 %.4g y0 %.4g sign %d' % (m.input_offset, m.output_offset, m.output_sign))
PY
$V/compensator --ros-args -p output.min:=0.2 -p output.max:=1.8 > comp.log 2>&1 &
PID=$!
sleep 6
echo '--- ros2 param load (valid)'; timeout 60 $V/ros2 param load --no-daemon --spin-time 3 /compensator model.yaml | tail -3
echo '--- ros2 param get model.output_sign'; timeout 60 $V/ros2 param get --no-daemon --spin-time 3 /compensator model.output_sign
echo '--- ros2 param load (broken)'; timeout 60 $V/ros2 param load --no-daemon --spin-time 3 /compensator broken.yaml 2>&1 | tail -3
echo '--- ros2 param set model.output_offset (valid)'; timeout 60 $V/ros2 param set --no-daemon --spin-time 3 /compensator model.output_offset 0.00031
echo '--- ros2 param set model.output_sign 0 (invalid)'; timeout 60 $V/ros2 param set --no-daemon --spin-time 3 /compensator model.output_sign 0
echo '--- ros2 param dump'; timeout 60 $V/ros2 param dump --no-daemon --spin-time 3 /compensator > dump.yaml; head -5 dump.yaml
kill -INT $PID; sleep 0.05; kill -INT $PID; wait $PID; echo "compensator exit $?"
echo '--- restart from the dump'
$V/compensator --ros-args --params-file dump.yaml -p qos_depth:=1000 > comp2.log 2>&1 &
PID=$!
sleep 6
timeout 60 $V/ros2 param get --no-daemon --spin-time 3 /compensator model.output_offset
kill -INT $PID; wait $PID; echo "compensator2 exit $?"
grep -i "error\|traceback" comp.log comp2.log | head -5
tail -3 comp.log
