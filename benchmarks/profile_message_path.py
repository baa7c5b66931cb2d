#!/usr/bin/env python3
# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Where the compensator's CPU per Float64 message goes, stage by stage (run on demand).

One process holds the compensator node (the benchmark model n=14, l=7, default QoS) and a
source node; a sink process subscribes to ``current_command`` (reliable, so publishing
pays for a matched reader).  ``--count`` desired displacements are queued while nothing
is spun, then each stage is timed alone on the main thread (``time.thread_time``, CPU
time, not wall time) and the node's own callback drains the whole queue once.  What a
message costs beyond that callback (executor wake-up and dispatch, the DDS receive and
event threads) is the difference to ``bench_compensator_node.py``'s CPU per message.

Usage: ``python benchmarks/profile_message_path.py [--count 5000]``
"""

import argparse
import os
import random
import struct
import subprocess
import sys
import time

__all__ = ['main']

_SINK = """
import time, rclpy
from std_msgs.msg import Float64
from mpi_ros.nodes.qos import loop_qos
from mpi_ros.nodes.spinning import events_executor
rclpy.init()
node = rclpy.create_node('sink')
node.create_subscription(Float64, 'current_command', lambda data: None, loop_qos(), raw=True)
executor = events_executor()
executor.add_node(node)
end = time.monotonic() + 120.0
while time.monotonic() < end:
    executor.spin_once(timeout_sec=0.1)
"""


def main() -> None:
    """Time each stage of the message path and print a table [us per message]."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument('--count', type=int, default=5000)
    args = parser.parse_args()
    os.environ['ROS_AUTOMATIC_DISCOVERY_RANGE'] = 'LOCALHOST'
    os.environ.setdefault('ROS_DOMAIN_ID', str(random.randint(101, 199)))
    sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
    import numpy as np
    import rclpy
    from rclpy.parameter import Parameter
    from std_msgs.msg import Float64

    from bench_compensator_node import BENCH_MODEL
    from mpi_ros.nodes.compensator import CompensatorNode
    from mpi_ros.nodes.qos import loop_qos
    from mpi_ros.nodes.spinning import events_executor

    sink = subprocess.Popen([sys.executable, '-c', _SINK])
    rclpy.init()
    node = CompensatorNode(parameter_overrides=[
        Parameter(key, value=[float(v) for v in value]) for key, value in BENCH_MODEL.items()])
    source = rclpy.create_node('source')
    publisher = source.create_publisher(Float64, 'desired_displacement', loop_qos())
    executor = events_executor()
    executor.add_node(node)
    rows = []
    try:
        deadline = time.monotonic() + 60.0
        while ((publisher.get_subscription_count() < 1
                or node.count_subscribers('current_command') < 2)
               and time.monotonic() < deadline):
            executor.spin_once(timeout_sec=0.05)
        time.sleep(1.0)
        n = args.count
        desired = (5e-6 + 2.5e-5 * (0.5 + 0.4 * np.sin(np.arange(n) / 50.0))).tolist()
        take = node._subscription.handle.take_message
        out = node._publisher.handle.publish_raw
        little = struct.Struct('<d').unpack_from
        pack = struct.Struct('<H2xd').pack
        compensator = node.compensator

        def fill() -> None:
            for value in desired:
                publisher.publish(Float64(data=value))
            time.sleep(0.5)                     # let DDS deliver them all

        def timed(label: str, work) -> None:
            start = time.thread_time()
            done = work()
            rows.append((label, (time.thread_time() - start) / max(done, 1) * 1e6, done))

        def take_all() -> int:
            k = 0
            while take(Float64, True) is not None:
                k += 1
            return k

        fill()
        timed('take_message (raw bytes + info dict)', take_all)
        fill()
        timed('take_message (deserialised Float64)',
              lambda: sum(1 for _ in iter(lambda: take(Float64, False), None)))
        data = pack(0x0100, desired[0])
        timed('decode: struct unpack of the CDR double',
              lambda: sum(1 for _ in range(n) if little(data, 4)[0] or True))
        timed('core: Compensator.command (numba step, counters)',
              lambda: sum(1 for value in desired if compensator.command(value) or True))
        time.sleep(0.5)
        timed('encode + publish_raw (reliable, 1 matched reader)',
              lambda: sum(1 for value in desired if out(pack(0x0100, value)) or True))
        time.sleep(0.5)
        timed('publish of a Float64 object (for comparison)',
              lambda: sum(1 for value in desired if publisher.publish(Float64(data=value))
                          or True))
        time.sleep(0.5)
        fill()
        first = take(Float64, True)[0]
        before = node.counters['messages_in']
        timed('the node callback draining its queue (all of the above)',
              lambda: node._on_desired_displacement(first)
              or node.counters['messages_in'] - before)
    finally:
        executor.shutdown()
        source.destroy_node()
        node.destroy_node()
        rclpy.try_shutdown()
        sink.kill()
        sink.wait()
    print(f'load average {" ".join(f"{v:.2f}" for v in os.getloadavg())}')
    for label, micros, done in rows:
        print(f'{micros:7.2f} us  {label} ({done} messages)')


if __name__ == '__main__':
    main()
