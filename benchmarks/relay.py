# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
The cheapest relays rclpy allows: the measured floor under the compensator nodes.

``desired_displacement`` in, the same value out on ``current_command``, no arithmetic, so
``bench_compensator_node.py --node relay:MODE`` measures what rclpy and DDS alone cost
per message on this machine.  With ``--axes N`` (N > 1) the relay serves the multi-axis
node's array topics instead: ``Float64MultiArray`` on ``desired_displacements`` in, the
same message out on ``current_commands`` (the raw modes publish the bytes they took; no
decoding, no encoding), the floor under ``-p axes:=N``.  Modes:

``naive``
    What a tutorial writes: a ``Float64`` (``Float64MultiArray``) callback that publishes
    the message it got, spun by ``rclpy.spin`` (SingleThreadedExecutor).
``events``
    The EventsExecutor (``spin_once`` loop), a raw subscription whose callback serves
    every queued message (``take_message``) and publishes CDR bytes (``publish_raw``):
    the compensator node's message path without the compensator.
``waitset``
    No executor: one rclpy ``WaitSet`` holding the subscription, ``wait`` then drain.
``poll``
    No executor, no wait set: drain the queue, sleep ``--period`` s, again.
"""

import argparse
import struct
import time

__all__ = ['main', 'MODES']

MODES = ('naive', 'events', 'waitset', 'poll')


def main(argv: 'list[str] | None' = None) -> None:
    """Run one relay until SIGINT or ``--duration`` s."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument('--mode', choices=MODES, default='events')
    parser.add_argument('--qos-depth', type=int, default=10000)
    parser.add_argument('--reliability', default='reliable')
    parser.add_argument('--period', type=float, default=1e-4, help='poll period [s]')
    parser.add_argument('--duration', type=float, default=3600.0)
    parser.add_argument('--axes', type=int, default=1,
                        help='1: Float64 topics; N > 1: Float64MultiArray topics')
    args = parser.parse_args(argv)
    if args.axes < 1:
        parser.error(f'--axes must be a positive axis count; got {args.axes}: use 1 for '
                     'the Float64 topics, N > 1 for the array topics')

    import rclpy
    from rclpy.impl.implementation_singleton import rclpy_implementation as _rclpy
    from rclpy.signals import SignalHandlerOptions
    from std_msgs.msg import Float64, Float64MultiArray

    from mpi_ros.nodes.qos import loop_qos
    from mpi_ros.nodes.spinning import events_executor
    from mpi_ros.stop_signals import StopSignals
    qos = loop_qos(args.qos_depth, args.reliability)
    arrays = args.axes > 1
    message_type = Float64MultiArray if arrays else Float64
    topic_in, topic_out = (('desired_displacements', 'current_commands') if arrays
                           else ('desired_displacement', 'current_command'))
    with StopSignals() as stop:
        rclpy.init(signal_handler_options=SignalHandlerOptions.NO)
        node = rclpy.create_node('compensator')
        end = time.monotonic() + args.duration

        def running() -> bool:
            return not stop.requested and time.monotonic() < end

        if args.mode == 'naive':
            pub = node.create_publisher(message_type, topic_out, qos)
            node.create_subscription(message_type, topic_in,
                                     lambda msg: pub.publish(msg), qos)
            executor = rclpy.executors.SingleThreadedExecutor()
            executor.add_node(node)
            while running():
                executor.spin_once(timeout_sec=0.1)
        else:
            pub = node.create_publisher(message_type, topic_out, qos)
            publish = pub.handle.publish_raw
            raw = args.mode == 'events'
            sub = node.create_subscription(message_type, topic_in,
                                           lambda data: relay(data), qos, raw=raw)
            take = sub.handle.take_message
            pack = struct.Struct('<H2xd').pack
            unpack = struct.Struct('<d').unpack_from

            def relay_values(data: 'bytes | None') -> None:
                # Float64: the value decoded and packed again, as the compensator does.
                while data is not None:
                    publish(pack(0x0100, unpack(data, 4)[0]))
                    taken = take(Float64, True)
                    data = None if taken is None else taken[0]

            def relay_bytes(data: 'bytes | None') -> None:
                # Float64MultiArray: the bytes taken are the bytes published.
                while data is not None:
                    publish(data)
                    taken = take(Float64MultiArray, True)
                    data = None if taken is None else taken[0]

            relay = relay_bytes if arrays else relay_values

            if args.mode == 'events':
                executor = events_executor()
                executor.add_node(node)
                while running():
                    executor.spin_once(timeout_sec=0.1)
            elif args.mode == 'waitset':
                wait_set = _rclpy.WaitSet(1, 0, 0, 0, 0, 0, node.context.handle)
                with sub.handle, node.context.handle:
                    while running():
                        wait_set.clear_entities()
                        wait_set.add_subscription(sub.handle)
                        wait_set.wait(100_000_000)
                        relay(None if (t := take(message_type, True)) is None else t[0])
            else:
                while running():
                    relay(None if (t := take(message_type, True)) is None else t[0])
                    time.sleep(args.period)
        node.destroy_node()
        rclpy.try_shutdown()


if __name__ == '__main__':
    main()
