#!/usr/bin/python3
"""Convert a ROS 1 bag into an LCM log of rtfuse message types.

Supported ROS types and what they become:

    sensor_msgs/Imu                          -> rtfuse.imu_t
    nav_msgs/Odometry                        -> rtfuse.odometry_t
    sensor_msgs/NavSatFix                    -> rtfuse.navsat_fix_t
    geometry_msgs/PoseWithCovarianceStamped  -> rtfuse.pose_with_covariance_stamped_t
    geometry_msgs/TwistWithCovarianceStamped -> rtfuse.twist_with_covariance_stamped_t

The LCM channel is the topic name unchanged, so a robot_localization config
converted by rl_params_to_toml.py matches the log. header.stamp becomes
header.utime (microseconds, sub-microsecond part truncated); the event
timestamp is the bag's record time, which is what rtfuse-replay paces by.
Other topics are skipped and listed on stderr.

Needs Debian's python3-rosbag, hence /usr/bin/python3.
"""

import argparse
import os
import struct
import sys
from collections import OrderedDict
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from rtfuse_tools import lcm_log  # noqa: E402
from rtfuse_tools.lcmtypes_path import LcmTypesError, import_lcmtypes  # noqa: E402

EXIT_OK = 0
EXIT_ERROR = 2

SUPPORTED = OrderedDict([
    ("sensor_msgs/Imu", "imu_t"),
    ("nav_msgs/Odometry", "odometry_t"),
    ("sensor_msgs/NavSatFix", "navsat_fix_t"),
    ("geometry_msgs/PoseWithCovarianceStamped", "pose_with_covariance_stamped_t"),
    ("geometry_msgs/TwistWithCovarianceStamped", "twist_with_covariance_stamped_t"),
])


class ConversionError(Exception):
    pass


def time_to_utime(t) -> int:
    """rospy/genpy Time -> integer microseconds (floor, no float rounding)."""
    return int(t.secs) * 1_000_000 + int(t.nsecs) // 1000


def _wrap_signed(value: int, bits: int) -> int:
    # ROS uses unsigned fields (seq uint32, service uint16, covariance type
    # uint8) where LCM only has signed ones; keep the bit pattern so nothing
    # is lost and a reader can mask it back.
    value &= (1 << bits) - 1
    return value - (1 << bits) if value >= 1 << (bits - 1) else value


def _floats(seq, n, what):
    vals = [float(v) for v in seq]
    if len(vals) != n:
        raise ConversionError(f"{what}: expected {n} values, got {len(vals)}")
    return vals


class Converter:
    """Builds rtfuse LCM messages from deserialised ROS messages."""

    def __init__(self, T):
        self.T = T
        self._by_type = {
            "sensor_msgs/Imu": self.imu,
            "nav_msgs/Odometry": self.odometry,
            "sensor_msgs/NavSatFix": self.navsat_fix,
            "geometry_msgs/PoseWithCovarianceStamped": self.pose_stamped,
            "geometry_msgs/TwistWithCovarianceStamped": self.twist_stamped,
        }

    def convert(self, ros_type, msg):
        return self._by_type[ros_type](msg)

    def header(self, h):
        out = self.T.header_t()
        out.utime = time_to_utime(h.stamp)
        out.seq = _wrap_signed(int(h.seq), 32)
        out.frame_id = h.frame_id
        return out

    def vector3(self, v):
        out = self.T.vector3_t()
        out.x, out.y, out.z = float(v.x), float(v.y), float(v.z)
        return out

    def quaternion(self, q):
        out = self.T.quaternion_t()
        out.x, out.y, out.z, out.w = float(q.x), float(q.y), float(q.z), float(q.w)
        return out

    def pose_with_covariance(self, p):
        out = self.T.pose_with_covariance_t()
        out.pose = self.T.pose_t()
        out.pose.position = self.vector3(p.pose.position)
        out.pose.orientation = self.quaternion(p.pose.orientation)
        out.covariance = _floats(p.covariance, 36, "pose covariance")
        return out

    def twist_with_covariance(self, t):
        out = self.T.twist_with_covariance_t()
        out.twist = self.T.twist_t()
        out.twist.linear = self.vector3(t.twist.linear)
        out.twist.angular = self.vector3(t.twist.angular)
        out.covariance = _floats(t.covariance, 36, "twist covariance")
        return out

    def imu(self, m):
        out = self.T.imu_t()
        out.header = self.header(m.header)
        out.orientation = self.quaternion(m.orientation)
        out.orientation_covariance = _floats(
            m.orientation_covariance, 9, "orientation_covariance")
        out.angular_velocity = self.vector3(m.angular_velocity)
        out.angular_velocity_covariance = _floats(
            m.angular_velocity_covariance, 9, "angular_velocity_covariance")
        out.linear_acceleration = self.vector3(m.linear_acceleration)
        out.linear_acceleration_covariance = _floats(
            m.linear_acceleration_covariance, 9, "linear_acceleration_covariance")
        return out

    def odometry(self, m):
        out = self.T.odometry_t()
        out.header = self.header(m.header)
        out.child_frame_id = m.child_frame_id
        out.pose = self.pose_with_covariance(m.pose)
        out.twist = self.twist_with_covariance(m.twist)
        return out

    def navsat_fix(self, m):
        out = self.T.navsat_fix_t()
        out.header = self.header(m.header)
        out.status = _wrap_signed(int(m.status.status), 8)
        out.service = _wrap_signed(int(m.status.service), 16)
        out.latitude = float(m.latitude)
        out.longitude = float(m.longitude)
        out.altitude = float(m.altitude)
        out.position_covariance = _floats(
            m.position_covariance, 9, "position_covariance")
        out.position_covariance_type = _wrap_signed(int(m.position_covariance_type), 8)
        return out

    def pose_stamped(self, m):
        out = self.T.pose_with_covariance_stamped_t()
        out.header = self.header(m.header)
        out.pose = self.pose_with_covariance(m.pose)
        return out

    def twist_stamped(self, m):
        out = self.T.twist_with_covariance_stamped_t()
        out.header = self.header(m.header)
        out.twist = self.twist_with_covariance(m.twist)
        return out


class Summary:
    def __init__(self):
        self.topics = OrderedDict()   # topic -> [ros_type, lcm_type, count]
        self.skipped = OrderedDict()  # topic -> (ros_type, count)
        self.first_utime = None
        self.last_utime = None
        self.events = 0

    @property
    def duration_s(self) -> float:
        if self.first_utime is None:
            return 0.0
        return (self.last_utime - self.first_utime) / 1e6


def convert(bag_path, out_path, topics=None, T=None, err=sys.stderr) -> Summary:
    """Convert bag_path to out_path; raises ConversionError on any failure.

    The output is written to a temporary file and renamed at the end, so a
    failed conversion never leaves a plausible-looking partial log behind.
    """
    import rosbag  # Debian python3-rosbag; imported late so --help works without it
    import genpy

    bag_path = Path(bag_path)
    out_path = Path(out_path)
    if not bag_path.is_file():
        raise ConversionError(f"{bag_path}: no such bag file")
    if T is None:
        try:
            T = import_lcmtypes()
        except LcmTypesError as e:
            raise ConversionError(str(e)) from None
    conv = Converter(T)
    summary = Summary()
    bag_errors = (rosbag.ROSBagException, genpy.DeserializationError,
                  struct.error, EOFError, ValueError, KeyError, OSError)

    try:
        bag = rosbag.Bag(str(bag_path), "r")
    except rosbag.ROSBagUnindexedException:
        raise ConversionError(
            f"{bag_path}: bag has no index (truncated, or the recorder did not "
            "close it); `rosbag reindex` may repair it") from None
    except bag_errors as e:
        raise ConversionError(f"{bag_path}: cannot read bag: {e}") from None

    tmp_path = out_path.with_name(f".{out_path.name}.{os.getpid()}.tmp")
    try:
        info = bag.get_type_and_topic_info().topics
        if topics:
            for t in topics:
                if t not in info:
                    raise ConversionError(
                        f"topic {t} is not in {bag_path} (topics: "
                        f"{', '.join(sorted(info)) or 'none'})")
                if info[t].msg_type not in SUPPORTED:
                    raise ConversionError(
                        f"topic {t} has unsupported type {info[t].msg_type} "
                        f"(supported: {', '.join(SUPPORTED)})")
            wanted = list(topics)
        else:
            wanted = [t for t in info if info[t].msg_type in SUPPORTED]
            for t in sorted(info):
                if info[t].msg_type not in SUPPORTED:
                    summary.skipped[t] = (info[t].msg_type, info[t].message_count)
        for t in sorted(wanted):
            summary.topics[t] = [info[t].msg_type, SUPPORTED[info[t].msg_type], 0]
        if summary.skipped:
            print("skipped unsupported topics:", file=err)
            for t, (ty, n) in summary.skipped.items():
                print(f"  {t} ({ty}): {n} message{'s' if n != 1 else ''}", file=err)
        if not wanted:
            raise ConversionError(f"{bag_path}: no topic of a supported type "
                                  f"({', '.join(SUPPORTED)})")

        with open(tmp_path, "wb") as f, lcm_log.LogWriter(f) as log:
            # read_messages merges connections by record time, i.e. bag order.
            for topic, msg, t in bag.read_messages(topics=wanted):
                ros_type = msg._type
                if ros_type not in SUPPORTED:  # a topic with mixed types
                    raise ConversionError(
                        f"{topic}: message of unsupported type {ros_type}")
                try:
                    lcm_msg = conv.convert(ros_type, msg)
                    data = lcm_msg.encode()
                except (ConversionError, struct.error, ValueError) as e:
                    raise ConversionError(
                        f"{topic}: message {summary.topics[topic][2]} "
                        f"(record time {t}): cannot convert: {e}") from None
                utime = time_to_utime(t)
                log.write(topic, data, utime)
                summary.topics[topic][2] += 1
                summary.events += 1
                if summary.first_utime is None:
                    summary.first_utime = utime
                summary.last_utime = utime
        os.replace(tmp_path, out_path)
    except bag_errors as e:
        raise ConversionError(f"{bag_path}: corrupt or unreadable bag: "
                              f"{type(e).__name__}: {e}") from None
    finally:
        bag.close()
        if tmp_path.exists():
            tmp_path.unlink()
    return summary


def print_summary(summary: Summary, out_path, out=sys.stdout) -> None:
    print(f"wrote {out_path}: {summary.events} events, "
          f"{summary.duration_s:.3f} s of record time", file=out)
    width = max(len(t) for t in summary.topics)
    for topic, (ros_type, lcm_type, n) in summary.topics.items():
        print(f"  {topic:<{width}}  {n:>7}  {ros_type} -> rtfuse.{lcm_type}", file=out)


def parse_args(argv):
    p = argparse.ArgumentParser(
        description="Convert a ROS 1 bag (Imu, Odometry, NavSatFix, "
                    "PoseWithCovarianceStamped, TwistWithCovarianceStamped) "
                    "into an LCM log of rtfuse types. Channel = topic name.",
        epilog="Exit status: 0 on success, 2 on any error.")
    p.add_argument("bag", metavar="IN.bag", help="ROS 1 bag file")
    p.add_argument("out", metavar="OUT.lcm", help="LCM log to write")
    p.add_argument("--topics", metavar="A,B",
                   help="comma-separated topics to convert (default: every "
                        "topic of a supported type)")
    return p.parse_args(argv)


def main(argv=None) -> int:
    args = parse_args(argv)
    topics = None
    if args.topics is not None:
        topics = [t.strip() for t in args.topics.split(",") if t.strip()]
        if not topics:
            print("rosbag_to_lcm: --topics is empty", file=sys.stderr)
            return EXIT_ERROR
    try:
        summary = convert(args.bag, args.out, topics)
    except ConversionError as e:
        print(f"rosbag_to_lcm: error: {e}", file=sys.stderr)
        return EXIT_ERROR
    except ImportError as e:
        print(f"rosbag_to_lcm: error: {e} (needs Debian's python3-rosbag; "
              "run with /usr/bin/python3)", file=sys.stderr)
        return EXIT_ERROR
    print_summary(summary, args.out)
    return EXIT_OK


if __name__ == "__main__":
    sys.exit(main())
