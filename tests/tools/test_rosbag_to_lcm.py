"""Tests of tools/rosbag_to_lcm.py against a real bag and a bag made here."""

import os
import subprocess
import sys
import tempfile
import unittest
from collections import Counter
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
TOOL = REPO / "tools" / "rosbag_to_lcm.py"
sys.path.insert(0, str(REPO / "tools"))

from rtfuse_tools import lcm_log  # noqa: E402
from rtfuse_tools.lcmtypes_path import import_lcmtypes  # noqa: E402

try:
    import genpy
    import genpy.dynamic
    import rosbag
    HAVE_ROSBAG = True
except ImportError:  # pyenv's python3 cannot see Debian's python3-rosbag
    HAVE_ROSBAG = False


def shared_data():
    return Path(os.environ.get("RTFUSE_SHARED_DATA", REPO.parent / "shared" / "data"))


def run_tool(*args):
    return subprocess.run([sys.executable, str(TOOL)] + [str(a) for a in args],
                          capture_output=True, text=True)


def utime(t):
    return t.secs * 1_000_000 + t.nsecs // 1000


@unittest.skipUnless(HAVE_ROSBAG, "python3-rosbag missing (run with /usr/bin/python3)")
class RealBag(unittest.TestCase):
    """robot_localization's test2.bag (Clearpath Jackal)."""

    @classmethod
    def setUpClass(cls):
        cls.bag_path = shared_data() / "robot_localization" / "test2.bag"
        if not cls.bag_path.is_file():
            raise unittest.SkipTest(
                f"{cls.bag_path} absent (set RTFUSE_SHARED_DATA): real-bag tests skipped")
        cls.T = import_lcmtypes()
        cls.tmp = tempfile.TemporaryDirectory()
        cls.out = Path(cls.tmp.name) / "test2.lcm"
        cls.proc = run_tool(cls.bag_path, cls.out)
        cls.events = lcm_log.read_events(cls.out) if cls.out.exists() else []
        with rosbag.Bag(str(cls.bag_path)) as b:
            cls.ros = list(b.read_messages())

    @classmethod
    def tearDownClass(cls):
        cls.tmp.cleanup()

    def test_exit_and_summary(self):
        self.assertEqual(self.proc.returncode, 0, self.proc.stderr)
        self.assertIn("/imu/data", self.proc.stdout)
        self.assertIn("3061", self.proc.stdout)
        self.assertIn("61.201 s", self.proc.stdout)

    def test_counts(self):
        counts = Counter(e.channel for e in self.events)
        self.assertEqual(counts, {"/imu/data": 3061,
                                  "/jackal_velocity_controller/odom": 3060})

    def test_bag_order_and_record_time(self):
        self.assertEqual([(e.channel, e.timestamp) for e in self.events],
                         [(topic, utime(t)) for topic, _, t in self.ros])
        self.assertEqual([e.eventnum for e in self.events], list(range(len(self.events))))

    def test_utime_is_header_stamp(self):
        for ev, (topic, msg, _) in zip(self.events, self.ros):
            cls = self.T.imu_t if topic == "/imu/data" else self.T.odometry_t
            m = cls.decode(ev.data)
            self.assertEqual(m.header.utime, utime(msg.header.stamp))
            self.assertEqual(m.header.seq, msg.header.seq)
        # the stamps differ from the record times in this bag, so this is a real check
        self.assertNotEqual(
            [e.timestamp for e in self.events],
            [self.T.imu_t.decode(e.data).header.utime if e.channel == "/imu/data"
             else self.T.odometry_t.decode(e.data).header.utime for e in self.events])

    def test_first_imu_matches_rosbag(self):
        ev = next(e for e in self.events if e.channel == "/imu/data")
        ros = next(m for t, m, _ in self.ros if t == "/imu/data")
        m = self.T.imu_t.decode(ev.data)
        self.assertEqual(m.header.frame_id, ros.header.frame_id)
        self.assertEqual(m.header.seq, ros.header.seq)
        for a in "xyzw":
            self.assertEqual(getattr(m.orientation, a), getattr(ros.orientation, a))
        for f in ("angular_velocity", "linear_acceleration"):
            for a in "xyz":
                self.assertEqual(getattr(getattr(m, f), a), getattr(getattr(ros, f), a))
        for f in ("orientation_covariance", "angular_velocity_covariance",
                  "linear_acceleration_covariance"):
            self.assertEqual(list(getattr(m, f)), list(getattr(ros, f)))
        self.assertAlmostEqual(m.linear_acceleration.z, 9.703827518410009, places=12)

    def test_first_odometry_matches_rosbag(self):
        ev = next(e for e in self.events if e.channel == "/jackal_velocity_controller/odom")
        ros = next(m for t, m, _ in self.ros if t == "/jackal_velocity_controller/odom")
        m = self.T.odometry_t.decode(ev.data)
        self.assertEqual((m.header.frame_id, m.child_frame_id), ("odom", "base_link"))
        p, rp = m.pose.pose, ros.pose.pose
        self.assertEqual((p.position.x, p.position.y, p.position.z),
                         (rp.position.x, rp.position.y, rp.position.z))
        self.assertEqual((p.orientation.z, p.orientation.w),
                         (rp.orientation.z, rp.orientation.w))
        self.assertEqual(list(m.pose.covariance), list(ros.pose.covariance))
        self.assertEqual(m.pose.covariance[14], 1e6)
        tw, rtw = m.twist.twist, ros.twist.twist
        self.assertEqual((tw.linear.x, tw.angular.z), (rtw.linear.x, rtw.angular.z))
        self.assertEqual(list(m.twist.covariance), list(ros.twist.covariance))

    def test_topics_option(self):
        out = Path(self.tmp.name) / "imu_only.lcm"
        proc = run_tool(self.bag_path, out, "--topics", "/imu/data")
        self.assertEqual(proc.returncode, 0, proc.stderr)
        self.assertEqual(Counter(e.channel for e in lcm_log.read_events(out)),
                         {"/imu/data": 3061})

    def test_unknown_topic_is_an_error(self):
        out = Path(self.tmp.name) / "none.lcm"
        proc = run_tool(self.bag_path, out, "--topics", "/imu/dta")
        self.assertEqual(proc.returncode, 2)
        self.assertIn("/imu/dta", proc.stderr)
        self.assertIn("/imu/data", proc.stderr)  # lists what there is
        self.assertFalse(out.exists())

    def test_truncated_bag_is_an_error(self):
        bad = Path(self.tmp.name) / "cut.bag"
        bad.write_bytes(self.bag_path.read_bytes()[:200_000])
        out = Path(self.tmp.name) / "cut.lcm"
        proc = run_tool(bad, out)
        self.assertEqual(proc.returncode, 2, proc.stdout + proc.stderr)
        self.assertIn("cut.bag", proc.stderr)
        self.assertNotIn("Traceback", proc.stderr)
        self.assertFalse(out.exists())


# Message definitions (fields only) for building the classes rosbag's writer
# needs; Debian packages python3-std-msgs but not sensor/geometry msgs.
HEADER = "uint32 seq\ntime stamp\nstring frame_id\n"
DEFS = {
    "std_msgs/Header": HEADER,
    "sensor_msgs/NavSatStatus": "int8 status\nuint16 service\n",
    "sensor_msgs/NavSatFix": (
        "std_msgs/Header header\nsensor_msgs/NavSatStatus status\n"
        "float64 latitude\nfloat64 longitude\nfloat64 altitude\n"
        "float64[9] position_covariance\nuint8 position_covariance_type\n"),
    "geometry_msgs/Point": "float64 x\nfloat64 y\nfloat64 z\n",
    "geometry_msgs/Vector3": "float64 x\nfloat64 y\nfloat64 z\n",
    "geometry_msgs/Quaternion": "float64 x\nfloat64 y\nfloat64 z\nfloat64 w\n",
    "geometry_msgs/Pose": "geometry_msgs/Point position\ngeometry_msgs/Quaternion orientation\n",
    "geometry_msgs/PoseWithCovariance": "geometry_msgs/Pose pose\nfloat64[36] covariance\n",
    "geometry_msgs/PoseWithCovarianceStamped": (
        "std_msgs/Header header\ngeometry_msgs/PoseWithCovariance pose\n"),
    "geometry_msgs/Twist": "geometry_msgs/Vector3 linear\ngeometry_msgs/Vector3 angular\n",
    "geometry_msgs/TwistWithCovariance": "geometry_msgs/Twist twist\nfloat64[36] covariance\n",
    "geometry_msgs/TwistWithCovarianceStamped": (
        "std_msgs/Header header\ngeometry_msgs/TwistWithCovariance twist\n"),
}
DEPS = {
    "sensor_msgs/NavSatFix": ["std_msgs/Header", "sensor_msgs/NavSatStatus"],
    "geometry_msgs/PoseWithCovarianceStamped": [
        "std_msgs/Header", "geometry_msgs/PoseWithCovariance", "geometry_msgs/Pose",
        "geometry_msgs/Point", "geometry_msgs/Quaternion"],
    "geometry_msgs/TwistWithCovarianceStamped": [
        "std_msgs/Header", "geometry_msgs/TwistWithCovariance", "geometry_msgs/Twist",
        "geometry_msgs/Vector3"],
}


def msg_class(name):
    text = DEFS[name] + "".join(
        "\n" + "=" * 80 + f"\nMSG: {dep}\n" + DEFS[dep] for dep in DEPS[name])
    return genpy.dynamic.generate_dynamic(name, text)[name]


def cov(n, base):
    return [base + 0.5 * i for i in range(n)]


@unittest.skipUnless(HAVE_ROSBAG, "python3-rosbag missing (run with /usr/bin/python3)")
class SyntheticBag(unittest.TestCase):
    """A bag written here with one message of every other supported type."""

    @classmethod
    def setUpClass(cls):
        from std_msgs.msg import String
        cls.T = import_lcmtypes()
        cls.tmp = tempfile.TemporaryDirectory()
        cls.bag_path = Path(cls.tmp.name) / "synthetic.bag"
        NavSatFix = msg_class("sensor_msgs/NavSatFix")
        PoseCS = msg_class("geometry_msgs/PoseWithCovarianceStamped")
        TwistCS = msg_class("geometry_msgs/TwistWithCovarianceStamped")

        fix = NavSatFix()
        fix.header.seq = 3_000_000_000           # above int32: must wrap, not fail
        fix.header.stamp = genpy.Time(1_700_000_000, 123_456_789)
        fix.header.frame_id = "gps"
        fix.status.status = -1                   # STATUS_NO_FIX
        fix.status.service = 1 | 8               # GPS + GALILEO
        fix.latitude, fix.longitude, fix.altitude = 42.3601, -71.0942, 12.75
        fix.position_covariance = cov(9, 0.25)
        fix.position_covariance_type = 3
        cls.fix = fix

        pose = PoseCS()
        pose.header.seq = 7
        pose.header.stamp = genpy.Time(100, 999_999_999)
        pose.header.frame_id = "map"
        pose.pose.pose.position.x, pose.pose.pose.position.y = 1.5, -2.25
        pose.pose.pose.position.z = 0.125
        o = pose.pose.pose.orientation
        o.x, o.y, o.z, o.w = 0.1, -0.2, 0.3, 0.927361849549570
        pose.pose.covariance = cov(36, 1.0)
        cls.pose = pose

        twist = TwistCS()
        twist.header.seq = 8
        twist.header.stamp = genpy.Time(99, 1_000)  # older than the pose
        twist.header.frame_id = "base_link"
        tw = twist.twist.twist
        tw.linear.x, tw.linear.y, tw.linear.z = 0.5, 0.0, -0.01
        tw.angular.x, tw.angular.y, tw.angular.z = 0.001, 0.002, 0.3
        twist.twist.covariance = cov(36, 100.0)
        cls.twist = twist

        # Record times deliberately unlike the header stamps.
        cls.record = {"/gps/fix": genpy.Time(10, 0), "/chatter": genpy.Time(11, 0),
                      "/pose": genpy.Time(12, 500), "/twist": genpy.Time(13, 0)}
        with rosbag.Bag(str(cls.bag_path), "w") as b:
            b.write("/gps/fix", fix, cls.record["/gps/fix"])
            b.write("/chatter", String(data="hello"), cls.record["/chatter"])
            b.write("/pose", pose, cls.record["/pose"])
            b.write("/chatter", String(data="again"), genpy.Time(12, 0))
            b.write("/twist", twist, cls.record["/twist"])

        cls.out = Path(cls.tmp.name) / "synthetic.lcm"
        cls.proc = run_tool(cls.bag_path, cls.out)
        cls.events = lcm_log.read_events(cls.out) if cls.out.exists() else []

    @classmethod
    def tearDownClass(cls):
        cls.tmp.cleanup()

    def event(self, channel):
        return next(e for e in self.events if e.channel == channel)

    def test_exit_and_unsupported_listed(self):
        self.assertEqual(self.proc.returncode, 0, self.proc.stderr)
        self.assertRegex(self.proc.stderr, r"/chatter \(std_msgs/String\): 2 messages")

    def test_order_and_record_times(self):
        self.assertEqual([(e.channel, e.timestamp) for e in self.events],
                         [("/gps/fix", 10_000_000), ("/pose", 12_000_000),
                          ("/twist", 13_000_000)])

    def test_navsat_fix(self):
        m = self.T.navsat_fix_t.decode(self.event("/gps/fix").data)
        f = self.fix
        self.assertEqual(m.header.utime, 1_700_000_000_123_456)  # ns truncated to us
        self.assertEqual(m.header.seq & 0xFFFFFFFF, f.header.seq)
        self.assertEqual(m.header.frame_id, "gps")
        self.assertEqual(m.status, self.T.navsat_fix_t.STATUS_NO_FIX)
        self.assertEqual(m.service, self.T.navsat_fix_t.SERVICE_GPS
                         | self.T.navsat_fix_t.SERVICE_GALILEO)
        self.assertEqual((m.latitude, m.longitude, m.altitude),
                         (f.latitude, f.longitude, f.altitude))
        self.assertEqual(list(m.position_covariance), list(f.position_covariance))
        self.assertEqual(m.position_covariance_type,
                         self.T.navsat_fix_t.COVARIANCE_TYPE_KNOWN)

    def test_pose_with_covariance_stamped(self):
        m = self.T.pose_with_covariance_stamped_t.decode(self.event("/pose").data)
        p = self.pose
        self.assertEqual(m.header.utime, 100_999_999)
        self.assertEqual((m.header.seq, m.header.frame_id), (7, "map"))
        mp, pp = m.pose.pose, p.pose.pose
        self.assertEqual((mp.position.x, mp.position.y, mp.position.z),
                         (pp.position.x, pp.position.y, pp.position.z))
        self.assertEqual((mp.orientation.x, mp.orientation.y, mp.orientation.z,
                          mp.orientation.w),
                         (pp.orientation.x, pp.orientation.y, pp.orientation.z,
                          pp.orientation.w))
        self.assertEqual(list(m.pose.covariance), list(p.pose.covariance))

    def test_twist_with_covariance_stamped(self):
        m = self.T.twist_with_covariance_stamped_t.decode(self.event("/twist").data)
        t = self.twist
        self.assertEqual(m.header.utime, 99_000_001)
        self.assertEqual((m.header.seq, m.header.frame_id), (8, "base_link"))
        for part in ("linear", "angular"):
            a, b = getattr(m.twist.twist, part), getattr(t.twist.twist, part)
            self.assertEqual((a.x, a.y, a.z), (b.x, b.y, b.z))
        self.assertEqual(list(m.twist.covariance), list(t.twist.covariance))

    def test_selecting_unsupported_topic_is_an_error(self):
        proc = run_tool(self.bag_path, Path(self.tmp.name) / "x.lcm", "--topics", "/chatter")
        self.assertEqual(proc.returncode, 2)
        self.assertIn("std_msgs/String", proc.stderr)


class Errors(unittest.TestCase):
    def test_missing_bag(self):
        with tempfile.TemporaryDirectory() as d:
            proc = run_tool(Path(d) / "nope.bag", Path(d) / "out.lcm")
            self.assertEqual(proc.returncode, 2)
            self.assertIn("nope.bag", proc.stderr)
            self.assertNotIn("Traceback", proc.stderr)

    @unittest.skipUnless(HAVE_ROSBAG, "python3-rosbag missing")
    def test_garbage_bag(self):
        with tempfile.TemporaryDirectory() as d:
            bad = Path(d) / "garbage.bag"
            bad.write_bytes(b"this is not a bag\n" * 100)
            proc = run_tool(bad, Path(d) / "out.lcm")
            self.assertEqual(proc.returncode, 2)
            self.assertIn("garbage.bag", proc.stderr)
            self.assertNotIn("Traceback", proc.stderr)
            self.assertFalse((Path(d) / "out.lcm").exists())

    def test_help(self):
        proc = run_tool("--help")
        self.assertEqual(proc.returncode, 0)
        self.assertIn("--topics", proc.stdout)


if __name__ == "__main__":
    unittest.main()
