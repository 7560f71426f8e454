#!/usr/bin/env python3
"""Python's ROS 2 bag readers on leeway's bags: the speed and memory
comparison of docs/data-files.md, and a check that Python decodes the bags
`leeway_logs::bag::write` writes.

    pip install mcap==1.6.0 mcap-ros2-support==0.6.0 rosbags==0.11.9
    target/release/bag write /tmp/big.mcap 10000000
    /usr/bin/time -v python3 bench/bag_python.py rosbags /tmp/big.mcap
    /usr/bin/time -v python3 bench/bag_python.py mcap_ros2 /tmp/big.mcap
    target/release/bag sample /tmp/sample.mcap
    python3 bench/bag_python.py check /tmp/sample.mcap

`rosbags` and `mcap_ros2` read the 6 fields `target/release/bag read`
reads (twist.linear.x and twist.angular.z of 3 topics) with their stamps
into arrays, and print the time, the messages and the same checksum.
`check` decodes the sample bag with both libraries and asserts every
value `bag sample` wrote (see `write_sample` in bench/src/bin/bag.rs).
"""
import math
import sys
import time
from array import array
from pathlib import Path

TOPICS = ["/nav/twist_body", "/dvl/twist", "/gps/twist"]


def stamp_ns(msg):
    return msg.header.stamp.sec * 1_000_000_000 + msg.header.stamp.nanosec


def read_rosbags(path):
    from rosbags.highlevel import AnyReader

    out = {t: (array("q"), array("d"), array("d")) for t in TOPICS}
    with AnyReader([Path(path)]) as reader:
        connections = [c for c in reader.connections if c.topic in TOPICS]
        for connection, _, raw in reader.messages(connections=connections):
            msg = reader.deserialize(raw, connection.msgtype)
            stamps, x, r = out[connection.topic]
            stamps.append(stamp_ns(msg))
            x.append(msg.twist.linear.x)
            r.append(msg.twist.angular.z)
    return out


def read_mcap_ros2(path):
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory

    out = {t: (array("q"), array("d"), array("d")) for t in TOPICS}
    with open(path, "rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        for _, channel, _, msg in reader.iter_decoded_messages(topics=TOPICS, log_time_order=False):
            stamps, x, r = out[channel.topic]
            stamps.append(stamp_ns(msg))
            x.append(msg.twist.linear.x)
            r.append(msg.twist.angular.z)
    return out


def check(path):
    """Both libraries decode the sample bag to the values `bag sample` wrote."""
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory
    from rosbags.highlevel import AnyReader

    topics = ["/twist", "/wrench", "/imu", "/depth"]

    def expected(k, i, c):
        return k + c / 8 + i / 4

    def verify(topic, i, msg):
        k = topics.index(topic)
        if topic == "/twist":
            got = [msg.twist.linear.x, msg.twist.linear.y, msg.twist.linear.z,
                   msg.twist.angular.x, msg.twist.angular.y, msg.twist.angular.z]
        elif topic == "/wrench":
            got = [msg.wrench.force.x, msg.wrench.force.y, msg.wrench.force.z,
                   msg.wrench.torque.x, msg.wrench.torque.y, msg.wrench.torque.z]
        elif topic == "/imu":
            q = msg.orientation
            yaw = math.atan2(2 * (q.w * q.z + q.x * q.y), 1 - 2 * (q.y * q.y + q.z * q.z))
            assert abs(yaw - (i / 2 - 1)) < 1e-12, (topic, i, yaw)
            assert list(msg.orientation_covariance) == [0.0] * 9
            got = [None, msg.angular_velocity.x, msg.angular_velocity.y, msg.angular_velocity.z,
                   msg.linear_acceleration.x, msg.linear_acceleration.y, msg.linear_acceleration.z]
        else:
            got = [msg.data]
        for c, value in enumerate(got):
            if value is not None:
                assert value == expected(k, i, c), (topic, i, c, value)
        if topic != "/depth":
            assert msg.header.frame_id == "base_link"
            assert stamp_ns(msg) == 1_700_000_000_000_000_000 + i * 100_000_000 + k * 1_000

    counts = {}
    with open(path, "rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        for _, channel, _, msg in reader.iter_decoded_messages(log_time_order=False):
            i = counts.get(("mcap_ros2", channel.topic), 0)
            verify(channel.topic, i, msg)
            counts[("mcap_ros2", channel.topic)] = i + 1
    with AnyReader([Path(path)]) as reader:
        for connection, _, raw in reader.messages():
            msg = reader.deserialize(raw, connection.msgtype)
            i = counts.get(("rosbags", connection.topic), 0)
            verify(connection.topic, i, msg)
            counts[("rosbags", connection.topic)] = i + 1
    assert sorted(counts.values()) == [5] * 8, counts
    print(f"check: mcap_ros2 and rosbags decode all 4 topics x 5 messages of {path} as written")


def main():
    mode, path = sys.argv[1], sys.argv[2]
    if mode == "check":
        check(path)
        return
    start = time.perf_counter()
    out = {"rosbags": read_rosbags, "mcap_ros2": read_mcap_ros2}[mode](path)
    seconds = time.perf_counter() - start
    messages = sum(len(s) for s, _, _ in out.values())
    checksum = sum(math.fsum(x) + math.fsum(r) for _, x, r in out.values())
    print(f"{mode}: {messages} messages, 6 fields, {seconds:.2f} s, checksum {checksum:.6f}")


if __name__ == "__main__":
    main()
