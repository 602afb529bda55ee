"""Tests of tools/rl_params_to_toml.py; every output is parsed with tomllib."""

import math
import os
import subprocess
import sys
import tempfile
import textwrap
import tomllib
import unittest
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
TOOL = REPO / "tools" / "rl_params_to_toml.py"

try:
    import yaml  # noqa: F401
    HAVE_YAML = True
except ImportError:  # pyenv's python3 cannot see Debian's python3-yaml
    HAVE_YAML = False


def shared_data():
    return Path(os.environ.get("RTFUSE_SHARED_DATA", REPO.parent / "shared" / "data"))


class ToolCase(unittest.TestCase):
    def setUp(self):
        if not HAVE_YAML:
            self.skipTest("python3-yaml missing (run with /usr/bin/python3)")
        self._tmp = tempfile.TemporaryDirectory()
        self.tmp = Path(self._tmp.name)

    def tearDown(self):
        self._tmp.cleanup()

    def run_tool(self, yaml_text_or_path, *args, expect=0):
        if isinstance(yaml_text_or_path, Path):
            src = yaml_text_or_path
        else:
            src = self.tmp / "params.yaml"
            src.write_text(textwrap.dedent(yaml_text_or_path))
        out = self.tmp / "out.toml"
        if out.exists():
            out.unlink()
        proc = subprocess.run([sys.executable, str(TOOL), str(src), "-o", str(out)]
                              + list(args), capture_output=True, text=True)
        self.assertEqual(proc.returncode, expect, proc.stderr)
        self.assertNotIn("Traceback", proc.stderr)
        self.stderr = proc.stderr
        if expect != 0:
            self.assertFalse(out.exists())
            return None
        self.text = out.read_text()
        return tomllib.loads(self.text)  # proves the output is valid TOML


def mask(*names):
    order = ["x", "y", "z", "roll", "pitch", "yaw", "vx", "vy", "vz",
             "vroll", "vpitch", "vyaw", "ax", "ay", "az"]
    return [n in names for n in order]


class Bag2Yaml(ToolCase):
    """The robot_localization test parameters for test2.bag (ROS 2 form)."""

    def setUp(self):
        super().setUp()
        self.path = shared_data() / "robot_localization" / "test_ekf_localization_node_bag2.yaml"
        if not self.path.is_file():
            self.skipTest(f"{self.path} absent (set RTFUSE_SHARED_DATA)")
        self.cfg = self.run_tool(self.path)

    def test_picks_ekf_node(self):
        self.assertIn("node: test_ekf_localization_node_bag2_ekf", self.text)
        self.assertNotIn("final_x", self.text)   # from the _pose node

    def test_filter(self):
        f = self.cfg["filter"]
        self.assertEqual(f["frequency"], 50.0)
        self.assertIsInstance(f["frequency"], float)
        self.assertEqual(f["sensor_timeout"], 0.1)
        self.assertEqual((f["world_frame"], f["odom_frame"], f["base_link_frame"],
                          f["map_frame"]), ("odom", "odom", "base_link", "map"))
        # diagonal in the YAML -> the 15-value form
        self.assertEqual(f["process_noise_covariance"],
                         [0.03, 0.03, 0.04, 0.03, 0.03, 0.06, 0.025, 0.025, 0.05,
                          0.002, 0.002, 0.004, 0.01, 0.01, 0.01])
        self.assertEqual(f["initial_estimate_covariance"], [1e-9] * 15)

    def test_sensors(self):
        s = {x["name"]: x for x in self.cfg["sensor"]}
        self.assertEqual(list(s), ["odom0", "imu0"])
        self.assertEqual(s["odom0"]["type"], "odometry")
        self.assertEqual(s["odom0"]["channel"], "/jackal_velocity_controller/odom")
        self.assertEqual(s["odom0"]["config"], mask("vx", "vy", "vz", "vyaw"))
        self.assertIs(s["odom0"]["relative"], False)
        self.assertEqual(s["odom0"]["queue_size"], 10)
        self.assertEqual(s["imu0"]["type"], "imu")
        self.assertEqual(s["imu0"]["channel"], "/imu/data")
        self.assertEqual(s["imu0"]["config"],
                         mask("roll", "pitch", "yaw", "vroll", "vpitch", "vyaw",
                              "ax", "ay", "az"))
        self.assertIs(s["imu0"]["remove_gravitational_acceleration"], True)

    def test_unsupported_listed(self):
        for key in ("use_sim_time", "clear_params", "filter_type"):
            self.assertIn(key, self.stderr)
            self.assertIn(key, self.text)  # also recorded in the header comment

    def test_header_names_source(self):
        self.assertTrue(self.text.startswith("#"))
        self.assertIn(str(self.path), self.text.splitlines()[1])


FULL_NOISE = [0.0] * 225
for i in range(15):
    FULL_NOISE[i * 15 + i] = 0.01 * (i + 1)
FULL_NOISE[0 * 15 + 1] = FULL_NOISE[1 * 15 + 0] = 0.002  # x-y correlation

ROS1_FLAT = f"""\
frequency: 30
sensor_timeout: 0.1
two_d_mode: true
transform_time_offset: 0.0
print_diagnostics: true
debug: false
publish_tf: false
use_control: true
control_config: [true, false, false, false, false, true]
acceleration_limits: [1.3, 0.0, 0.0, 0.0, 0.0, 3.4]
map_frame: map
odom_frame: odom
base_link_frame: "base \\\\ \\"link\\""
world_frame: odom
odom0: wheel/odometry
odom0_config: [true,  true,  false,
               false, false, true,
               true,  false, false,
               false, false, true,
               true,  false, false]
odom0_differential: true
odom0_relative: true
odom0_nodelay: true
odom0_pose_rejection_threshold: 5
odom0_twist_rejection_threshold: .inf
odom2: ignored/because/of/the/gap
pose0: amcl_pose
pose0_config: [true, true, false, false, false, true,
               true, false, false, false, false, false,
               false, false, false]
pose0_rejection_threshold: 2.5
twist0: visual/twist
twist0_config: [false, false, false, false, false, false,
                true, true, false, false, false, true,
                false, false, false]
twist0_rejection_threshold: 1e1
imu0: imu/data
imu0_config: [true, false, false,
              false, false, true,
              false, false, false,
              false, false, true,
              true, false, false]
imu0_queue_size: 5000
imu0_linear_acceleration_rejection_threshold: 0.8
imu0_remove_gravitational_acceleration: false
output_location: somewhere.txt
process_noise_covariance: {FULL_NOISE}
initial_state: [1.0, 2.0, 0.0, 0.0, 0.0, 0.5, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]
history_length: -0.5
smooth_lagged_data: true
"""


class Ros1Flat(ToolCase):
    def setUp(self):
        super().setUp()
        self.cfg = self.run_tool(ROS1_FLAT)

    def test_filter(self):
        f = self.cfg["filter"]
        self.assertEqual(f["frequency"], 30.0)
        self.assertIsInstance(f["frequency"], float)  # int in YAML, float in TOML
        self.assertIs(f["two_d_mode"], True)
        self.assertEqual(f["base_link_frame"], 'base \\ "link"')  # escaping survives
        self.assertEqual(f["process_noise_covariance"], FULL_NOISE)  # not diagonal: 225
        self.assertEqual(f["initial_state"][5], 0.5)
        self.assertEqual(f["history_length"], 0.5)  # abs(), as robot_localization
        self.assertIs(f["smooth_lagged_data"], True)
        self.assertIs(self.cfg["publish"]["publish_tf"], False)

    def test_sensors(self):
        s = {x["name"]: x for x in self.cfg["sensor"]}
        self.assertEqual(list(s), ["odom0", "pose0", "twist0", "imu0"])  # no odom2
        self.assertEqual([x["type"] for x in s.values()],
                         ["odometry", "pose", "twist", "imu"])
        o = s["odom0"]
        self.assertEqual(o["channel"], "wheel/odometry")
        # ax is not in an Odometry message: cleared, as robot_localization does
        self.assertEqual(o["config"], mask("x", "y", "yaw", "vx", "vyaw"))
        self.assertIs(o["differential"], True)
        self.assertIs(o["relative"], False)   # differential wins
        self.assertEqual(o["pose_rejection_threshold"], 5.0)
        self.assertEqual(o["twist_rejection_threshold"], math.inf)
        p = s["pose0"]
        self.assertEqual(p["config"], mask("x", "y", "yaw"))
        self.assertEqual(p["pose_rejection_threshold"], 2.5)
        t = s["twist0"]
        self.assertEqual(t["config"], mask("vx", "vy", "vyaw"))
        self.assertEqual(t["twist_rejection_threshold"], 10.0)
        i = s["imu0"]
        self.assertEqual(i["config"], mask("yaw", "vyaw", "ax"))  # x cleared
        self.assertEqual(i["queue_size"], 1024)  # clamped
        self.assertEqual(i["linear_acceleration_rejection_threshold"], 0.8)
        self.assertIs(i["remove_gravitational_acceleration"], False)

    def test_unsupported_listing(self):
        for key in ("transform_time_offset", "print_diagnostics", "debug",
                    "use_control", "control_config", "acceleration_limits",
                    "odom0_nodelay"):
            self.assertRegex(self.stderr, rf"(?m)^  {key} = ", key)
        unknown = self.stderr.split("not robot_localization EKF parameters")[1].split("\nnote:")[0]
        self.assertIn("output_location", unknown)
        self.assertNotIn("odom2", unknown)  # reported once, as ignored
        for note in ("odom2 ignored", "odom0_config: ax", "imu0_config: x",
                     "differential wins", "clamped", "history_length"):
            self.assertIn(note, self.stderr)
        self.assertNotIn("frequency", self.stderr.split("not carried over")[-1])


class SeveralNodes(ToolCase):
    YAML = """\
    ekf_se_odom:
      frequency: 30
      world_frame: odom
      odom0: odometry/wheel
      odom0_config: [false, false, false, false, false, false,
                     true, true, false, false, false, true,
                     false, false, false]
    ekf_se_map:
      frequency: 30
      world_frame: map
      odom0: odometry/gps
      odom0_config: [true, true, false, false, false, false,
                     false, false, false, false, false, false,
                     false, false, false]
    navsat_transform:
      frequency: 30
      magnetic_declination_radians: 0
      yaw_offset: 0
    """

    def test_dual_set_up_without_a_heading_is_an_error(self):
        # Without --node the two EKFs become two instances; navsat_transform
        # then needs a heading the map EKF does not have.
        self.run_tool(self.YAML, expect=2)
        self.assertIn("no IMU sensor: set use_odometry_yaw or a datum", self.stderr)

    def test_three_ekf_nodes_need_node(self):
        text = self.YAML.replace("    navsat_transform:", """\
    ekf_third:
      frequency: 30
      odom0: odometry/wheel
      odom0_config: [false, false, false, false, false, false,
                     true, false, false, false, false, false,
                     false, false, false]
    navsat_transform:""")
        self.run_tool(text, expect=2)
        self.assertIn("--node", self.stderr)
        self.assertIn("ekf_se_odom", self.stderr)
        self.assertIn("ekf_third", self.stderr)
        self.assertNotIn("navsat_transform", self.stderr)

    def test_with_node(self):
        cfg = self.run_tool(self.YAML, "--node", "ekf_se_map")
        self.assertEqual(cfg["filter"]["world_frame"], "map")
        self.assertEqual(cfg["sensor"][0]["channel"], "odometry/gps")

    def test_unknown_node(self):
        self.run_tool(self.YAML, "--node", "ekf_se_nope", expect=2)
        self.assertIn("ekf_se_map", self.stderr)

    def test_ros2_namespaced_node(self):
        cfg = self.run_tool("""\
        robot1:
          ekf_filter_node:
            ros__parameters:
              frequency: 40.0
              imu0: imu
              imu0_config: [false, false, false, true, true, true,
                            false, false, false, true, true, true,
                            false, false, false]
              qos_overrides:
                /tf:
                  publisher:
                    depth: 100
        """, "--node", "ekf_filter_node")
        self.assertEqual(cfg["filter"]["frequency"], 40.0)
        self.assertIn("qos_overrides./tf.publisher.depth", self.stderr)

    def test_missing_frequency_uses_rl_default(self):
        cfg = self.run_tool("""\
        ekf:
          ros__parameters:
            odom0: odom
            odom0_config: [false, false, false, false, false, false,
                           true, false, false, false, false, false,
                           false, false, false]
        """)
        self.assertEqual(cfg["filter"]["frequency"], 30.0)


# robot_localization's dual_ekf_navsat_example parameters (ROS 2), trimmed.
DUAL_YAML = """\
ekf_filter_node_odom:
  ros__parameters:
    frequency: 30.0
    two_d_mode: true
    publish_tf: true
    map_frame: map
    odom_frame: odom
    base_link_frame: base_link
    world_frame: odom
    odom0: odometry/wheel
    odom0_config: [false, false, false, false, false, false,
                   true, true, false, false, false, true,
                   false, false, false]
    odom0_queue_size: 10
    imu0: imu/data
    imu0_config: [false, false, false, false, false, true,
                  false, false, false, false, false, true,
                  false, false, false]
    imu0_remove_gravitational_acceleration: true
    process_noise_covariance: PROCESS_NOISE
    use_control: false
ekf_filter_node_map:
  ros__parameters:
    frequency: 50.0
    two_d_mode: true
    map_frame: map
    odom_frame: odom
    base_link_frame: base_link
    world_frame: map
    odom0: odometry/wheel
    odom0_config: [false, false, false, false, false, false,
                   true, true, false, false, false, true,
                   false, false, false]
    odom1: odometry/gps
    odom1_config: [true, true, false, false, false, false,
                   false, false, false, false, false, false,
                   false, false, false]
    odom1_queue_size: 10
    odom1_pose_rejection_threshold: 5.0
    imu0: imu/data
    imu0_config: [false, false, false, false, false, true,
                  false, false, false, false, false, true,
                  false, false, false]
navsat_transform:
  ros__parameters:
    frequency: 30.0
    delay: 3.0
    magnetic_declination_radians: 0.0429351
    yaw_offset: 1.570796327
    zero_altitude: true
    broadcast_cartesian_transform: true
    publish_filtered_gps: true
    use_odometry_yaw: false
    wait_for_datum: false
""".replace("PROCESS_NOISE", "[" + ", ".join(
    str(0.5 if i == j else 0.0) if i == j else "0.0" for i in range(15) for j in range(15)) + "]")


class DualEkf(ToolCase):
    def test_two_instances(self):
        cfg = self.run_tool(DUAL_YAML)
        f = cfg["filter"]
        self.assertEqual(f["name"], "local")
        self.assertEqual(f["world_frame"], "odom")
        # One loop runs both: the faster node's rate.
        self.assertEqual(f["frequency"], 50.0)
        self.assertIn("one loop runs both instances at 50.0 Hz", self.stderr)
        self.assertEqual([s["name"] for s in cfg["sensor"]], ["odom0", "imu0"])
        [inst] = cfg["instance"]
        self.assertEqual(inst["name"], "global")
        self.assertEqual(inst["world_frame"], "map")
        self.assertTrue(inst["two_d_mode"])
        # robot_localization's default, not the local node's value inherited.
        self.assertEqual(f["process_noise_covariance"][0], 0.5)
        self.assertEqual(inst["process_noise_covariance"][0], 0.05)
        # Each node's own default timeout, 1 / its own frequency.
        self.assertAlmostEqual(f["sensor_timeout"], 1.0 / 30.0)
        self.assertAlmostEqual(inst["sensor_timeout"], 1.0 / 50.0)
        names = [s["name"] for s in inst["sensor"]]
        self.assertEqual(names, ["odom0", "odom1", "imu0"])
        gps = inst["sensor"][1]
        self.assertEqual(gps["type"], "navsat")
        self.assertEqual(gps["channel"], "gps/fix")
        self.assertEqual(gps["config"], mask("x", "y"))
        self.assertEqual(gps["pose_rejection_threshold"], 5.0)
        self.assertAlmostEqual(gps["magnetic_declination_radians"], 0.0429351)
        self.assertAlmostEqual(gps["yaw_offset"], 1.570796327)
        self.assertTrue(gps["zero_altitude"])
        self.assertEqual(gps["heading_imu"], "imu0")
        self.assertNotIn("use_odometry_yaw", gps)
        self.assertIn("broadcast_cartesian_transform", self.stderr)
        self.assertIn("instances local and global", self.stderr)

    def test_names_from_the_command_line(self):
        cfg = self.run_tool(DUAL_YAML, "--name", "ekf_filter_node_odom=odom_ekf",
                            "--name", "ekf_filter_node_map=map_ekf")
        self.assertEqual(cfg["filter"]["name"], "odom_ekf")
        self.assertEqual(cfg["instance"][0]["name"], "map_ekf")
        self.run_tool(DUAL_YAML, "--name", "ekf_filter_node_map=Map!", expect=2)
        self.assertIn("expected NODE=NAME", self.stderr)

    def test_a_configured_datum(self):
        text = DUAL_YAML.replace("wait_for_datum: false",
                                 "wait_for_datum: true\n    datum: [55.944904, -3.186693, 0.0]")
        gps = self.run_tool(text)["instance"][0]["sensor"][1]
        self.assertEqual(gps["datum"], [55.944904, -3.186693, 0.0])
        self.assertNotIn("heading_imu", gps)
        bad = DUAL_YAML.replace("wait_for_datum: false", "wait_for_datum: true\n    datum: [95.0, 0.0, 0.0]")
        self.run_tool(bad, expect=2)
        self.assertIn("datum: latitude 95.0", self.stderr)

    def test_a_remapped_navsat_output_must_be_named(self):
        text = DUAL_YAML.replace("odom1: odometry/gps", "odom1: gps/odometry")
        self.run_tool(text, expect=2)
        self.assertIn("--navsat-output", self.stderr)
        cfg = self.run_tool(text, "--navsat-output", "gps/odometry", "--fix-topic", "fix")
        self.assertEqual(cfg["instance"][0]["sensor"][1]["channel"], "fix")

    def test_disagreeing_frames_are_an_error(self):
        text = DUAL_YAML.replace("    base_link_frame: base_link\n    world_frame: map",
                                 "    base_link_frame: base_footprint\n    world_frame: map")
        self.run_tool(text, expect=2)
        self.assertIn("base_link_frame: 'base_footprint'", self.stderr)


class StaticTf(ToolCase):
    YAML = """\
    frequency: 50.0
    imu0: imu/data
    imu0_config: [false, false, false, true, true, true, false, false, false,
                  true, true, true, false, false, false]
    """

    def test_rpy_order(self):
        cfg = self.run_tool(self.YAML,
                            "--static-tf", "0.1 -0.2 0.3 1.5 0.25 -0.125 base_link imu_link",
                            "--static-tf", "1 2 3 0 0 0.7071067811865476 0.7071067811865476 "
                                           "base_link gps")
        a, b = cfg["static_transform"]
        self.assertEqual((a["parent"], a["child"]), ("base_link", "imu_link"))
        self.assertEqual(a["translation"], [0.1, -0.2, 0.3])
        # tf2 gives yaw pitch roll; rtfuse stores roll pitch yaw
        self.assertEqual(a["rpy"], [-0.125, 0.25, 1.5])
        self.assertNotIn("quaternion", a)
        self.assertEqual(b["quaternion"], [0.0, 0.0, 0.7071067811865476, 0.7071067811865476])
        self.assertEqual(b["translation"], [1.0, 2.0, 3.0])

    def test_bad_static_tf(self):
        self.run_tool(self.YAML, "--static-tf", "0 0 0 0 0 base_link imu", expect=2)
        self.assertIn("yaw pitch roll", self.stderr)
        self.run_tool(self.YAML, "--static-tf", "0 0 0 a 0 0 base_link imu", expect=2)


class BadInput(ToolCase):
    def test_wrong_type(self):
        self.run_tool("frequency: fast\nodom0: odom\n", expect=2)
        self.assertIn("frequency", self.stderr)

    def test_wrong_matrix_size(self):
        self.run_tool("frequency: 10.0\nprocess_noise_covariance: [1.0, 2.0]\n", expect=2)
        self.assertIn("225", self.stderr)

    def test_no_ekf(self):
        self.run_tool("navsat:\n  yaw_offset: 0.0\n  frequency: 10\n", expect=2)
        self.assertIn("no EKF node", self.stderr)

    def test_missing_file(self):
        self.run_tool(self.tmp / "nope.yaml", expect=2)
        self.assertIn("nope.yaml", self.stderr)


if __name__ == "__main__":
    unittest.main()
