#!/usr/bin/env python3
"""Writes the ROS 2 bag fixtures that `logs/tests/logs/bag_python.rs` reads,
with an encoder independent of leeway's: the `mcap` and `mcap-ros2-support`
packages (CDR from the ros2msg schema text, as Foxglove writes bags).

    python3 -m venv /tmp/venv
    /tmp/venv/bin/pip install mcap==1.6.0 mcap-ros2-support==0.6.0 lz4==4.4.5
    /tmp/venv/bin/python logs/tests/data/make_fixture.py logs/tests/data

It writes `python_zstd.mcap` (zstd chunks) and `python_lz4.mcap` (lz4
chunks), the same messages in each. Every value is a formula of the
message index `i` that the Rust test repeats (IEEE arithmetic gives the
same bits in both languages):

- `/nav/twist` geometry_msgs/msg/TwistStamped, 12 messages: stamp
  1_700_000_000 s + i·0.1 s + 3 ns, log time 2 ms later; linear.x =
  1.5 + i/8, linear.y = -0.1·i, angular.z = i·i/3.
- `/imu` sensor_msgs/msg/Imu, 8 messages: stamp as `/nav/twist`'s;
  heading h = -3 + 0.75·i as the quaternion (0, 0, sin(h/2), cos(h/2));
  angular_velocity.z = 0.01·i; orientation_covariance[k] = k.
- `/depth` std_msgs/msg/Float64 (no header), 5 messages: log time
  1_700_000_000 s + i s + 5 ns; data = 10 - i/4.
- `/scan` sensor_msgs/msg/LaserScan, 3 messages: ranges has 5 + i
  float32 elements, ranges[j] = j/2 + i; frame_id grows with i.
- `/counters` leeway_test/msg/Counters, 4 messages: a:int8 = -i,
  b:uint16 = 1000·i, c:int64 = -(2^40)·i, label:string = "x"·i,
  d:uint32 = 2^31 + i.
"""
import math
import sys
from pathlib import Path

from mcap.writer import CompressionType
from mcap_ros2.writer import Writer

SEP = "=" * 80 + "\n"
TIME = "MSG: builtin_interfaces/Time\nint32 sec\nuint32 nanosec\n"
HEADER = (
    "MSG: std_msgs/Header\n# Standard metadata\nbuiltin_interfaces/Time stamp\n"
    "string frame_id\n"
)
VECTOR3 = "MSG: geometry_msgs/Vector3\nfloat64 x\nfloat64 y\nfloat64 z\n"
QUATERNION = (
    "MSG: geometry_msgs/Quaternion\nfloat64 x 0\nfloat64 y 0\nfloat64 z 0\nfloat64 w 1\n"
)
TWIST_STAMPED = (
    "std_msgs/Header header\nTwist twist\n" + SEP + HEADER + SEP + TIME + SEP
    + "MSG: geometry_msgs/Twist\nVector3  linear\nVector3  angular\n" + SEP + VECTOR3
)
IMU = (
    "std_msgs/Header header\ngeometry_msgs/Quaternion orientation\n"
    "float64[9] orientation_covariance # Row major about x, y, z axes\n"
    "geometry_msgs/Vector3 angular_velocity\nfloat64[9] angular_velocity_covariance\n"
    "geometry_msgs/Vector3 linear_acceleration\nfloat64[9] linear_acceleration_covariance\n"
    + SEP + HEADER + SEP + TIME + SEP + QUATERNION + SEP + VECTOR3
)
FLOAT64 = "float64 data\n"
LASER_SCAN = (
    "std_msgs/Header header\nfloat32 angle_min\nfloat32 angle_max\n"
    "float32 angle_increment\nfloat32 time_increment\nfloat32 scan_time\n"
    "float32 range_min\nfloat32 range_max\nfloat32[] ranges\nfloat32[] intensities\n"
    + SEP + HEADER + SEP + TIME
)
COUNTERS = "int8 a\nuint16 b\nint64 c\nstring label\nuint32 d\nint32 LIMIT=5\n"

T0 = 1_700_000_000


def stamp(i):
    return {"sec": T0 + i // 10, "nanosec": (i % 10) * 100_000_000 + 3}


def ns(s):
    return s["sec"] * 1_000_000_000 + s["nanosec"]


def vector(x=0.0, y=0.0, z=0.0):
    return {"x": x, "y": y, "z": z}


def write(path, compression):
    with open(path, "wb") as f:
        w = Writer(f, compression=compression)
        twist = w.register_msgdef("geometry_msgs/msg/TwistStamped", TWIST_STAMPED)
        imu = w.register_msgdef("sensor_msgs/msg/Imu", IMU)
        depth = w.register_msgdef("std_msgs/msg/Float64", FLOAT64)
        scan = w.register_msgdef("sensor_msgs/msg/LaserScan", LASER_SCAN)
        counters = w.register_msgdef("leeway_test/msg/Counters", COUNTERS)
        for i in range(12):
            s = stamp(i)
            msg = {
                "header": {"stamp": s, "frame_id": "base_link"},
                "twist": {
                    "linear": vector(1.5 + i / 8, -0.1 * i),
                    "angular": vector(z=i * i / 3),
                },
            }
            w.write_message("/nav/twist", twist, msg, log_time=ns(s) + 2_000_000)
            if i < 8:
                h = -3 + 0.75 * i
                msg = {
                    "header": {"stamp": s, "frame_id": "imu"},
                    "orientation": {"x": 0.0, "y": 0.0, "z": math.sin(h / 2), "w": math.cos(h / 2)},
                    "orientation_covariance": [float(k) for k in range(9)],
                    "angular_velocity": vector(z=0.01 * i),
                    "angular_velocity_covariance": [0.0] * 9,
                    "linear_acceleration": vector(),
                    "linear_acceleration_covariance": [0.0] * 9,
                }
                w.write_message("/imu", imu, msg, log_time=ns(s))
            if i < 5:
                log = (T0 + i) * 1_000_000_000 + 5
                w.write_message("/depth", depth, {"data": 10 - i / 4}, log_time=log)
            if i < 3:
                msg = {
                    "header": {"stamp": s, "frame_id": "laser" * (i + 1)},
                    "angle_min": -1.0, "angle_max": 1.0, "angle_increment": 0.5,
                    "time_increment": 0.0, "scan_time": 0.1,
                    "range_min": 0.1, "range_max": 30.0,
                    "ranges": [j / 2 + i for j in range(5 + i)],
                    "intensities": [1.0] * i,
                }
                w.write_message("/scan", scan, msg, log_time=ns(s))
            if i < 4:
                msg = {"a": -i, "b": 1000 * i, "c": -(2**40) * i, "label": "x" * i, "d": 2**31 + i}
                w.write_message("/counters", counters, msg, log_time=ns(s))
        w.finish()


def main():
    out = Path(sys.argv[1] if len(sys.argv) > 1 else ".")
    write(out / "python_zstd.mcap", CompressionType.ZSTD)
    write(out / "python_lz4.mcap", CompressionType.LZ4)


if __name__ == "__main__":
    main()
