"""Tests of tools/plot_trajectory.py on logs made here with known errors."""

import math
import subprocess
import sys
import tempfile
import unittest
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
TOOL = REPO / "tools" / "plot_trajectory.py"
sys.path.insert(0, str(REPO / "tools"))

from rtfuse_tools import lcm_log  # noqa: E402
from rtfuse_tools.lcmtypes_path import import_lcmtypes  # noqa: E402

try:
    import matplotlib  # noqa: F401
    HAVE_MATPLOTLIB = True
except ImportError:  # pyenv's python3 cannot see Debian's python3-matplotlib
    HAVE_MATPLOTLIB = False

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


def run_tool(*args):
    return subprocess.run([sys.executable, str(TOOL)] + [str(a) for a in args],
                          capture_output=True, text=True)


def odometry(T, utime, x, y):
    m = T.odometry_t()
    m.header.utime = utime
    m.header.frame_id = "odom"
    m.child_frame_id = "base_link"
    m.pose.pose.position.x = x
    m.pose.pose.position.y = y
    m.pose.pose.orientation.w = 1.0
    return m.encode()


def write_log(path, T, channels):
    """channels: {name: [(utime, x, y), ...]}, written interleaved by stamp."""
    events = sorted((utime, name, x, y) for name, samples in channels.items()
                    for utime, x, y in samples)
    with lcm_log.LogWriter(path) as w:
        for utime, name, x, y in events:
            w.write(name, odometry(T, utime, x, y), utime)


# Truth: 1 m/s along x for 10 s at 50 Hz. Estimate: 0.1 m to the left of it,
# stamped 3 ms later (nearest-stamp matching). Raw odometry: drifting left
# by 0.02 m per second, at 25 Hz.
TRUTH = [(1_000_000 + 20_000 * i, 0.02 * i, 0.0) for i in range(501)]
ESTIMATE = [(u + 3_000, x, 0.1) for u, x, _ in TRUTH]
RAW = [(1_000_000 + 40_000 * i, 0.04 * i, 0.02 * 0.04 * i) for i in range(251)]


def rms(values):
    return math.sqrt(sum(v * v for v in values) / len(values))


@unittest.skipUnless(HAVE_MATPLOTLIB, "python3-matplotlib missing (run with /usr/bin/python3)")
class PlotTrajectory(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.T = import_lcmtypes()

    def setUp(self):
        self.tmp = tempfile.TemporaryDirectory()
        self.dir = Path(self.tmp.name)

    def tearDown(self):
        self.tmp.cleanup()

    def assert_png(self, path):
        data = path.read_bytes()
        self.assertEqual(data[:8], PNG_MAGIC)
        self.assertGreater(len(data), 10_000)

    def test_errors_against_truth_and_the_png(self):
        log = self.dir / "drive.lcm"
        write_log(log, self.T, {"sim/ground_truth": TRUTH, "rtfuse/odometry": ESTIMATE,
                                "rtfuse/wheel_odometry": RAW, "rtfuse/diagnostics_other": []})
        out = self.dir / "drive.png"
        proc = run_tool(log, "-o", out)
        self.assertEqual(proc.returncode, 0, proc.stderr)
        self.assertIn("estimate (rtfuse/odometry): 501 samples, final error 0.100 m, RMS error 0.100 m",
                      proc.stdout)
        raw_rms = rms([y for _, _, y in RAW])  # 0.02 * sqrt(mean t^2): 0.116
        self.assertIn("raw odometry (rtfuse/wheel_odometry): 251 samples, final error 0.200 m, "
                      f"RMS error {raw_rms:.3f} m", proc.stdout)
        self.assertNotIn("note:", proc.stdout)
        self.assert_png(out)

    def test_missing_channels_are_skipped_with_a_note(self):
        log = self.dir / "no_raw.lcm"
        write_log(log, self.T, {"sim/ground_truth": TRUTH, "rtfuse/odometry": ESTIMATE})
        out = self.dir / "no_raw.png"
        proc = run_tool(log, "-o", out)
        self.assertEqual(proc.returncode, 0, proc.stderr)
        self.assertIn("note: no raw odometry in the log (channel 'rtfuse/wheel_odometry'); skipped", proc.stdout)
        self.assertIn("final error 0.100 m", proc.stdout)
        self.assert_png(out)

    def test_without_truth_it_still_plots(self):
        log = self.dir / "estimate_only.lcm"
        write_log(log, self.T, {"rtfuse/odometry": ESTIMATE})
        out = self.dir / "estimate_only.png"
        proc = run_tool(log, "-o", out)
        self.assertEqual(proc.returncode, 0, proc.stderr)
        self.assertIn("note: without ground truth no errors are computed", proc.stdout)
        self.assertNotIn("RMS", proc.stdout)
        self.assert_png(out)

    def test_channels_are_configurable_and_stamps_far_apart_do_not_match(self):
        log = self.dir / "custom.lcm"
        late = [(u + 500_000, x, y) for u, x, y in ESTIMATE]  # stamped 0.5 s late
        write_log(log, self.T, {"truth": TRUTH, "fused": late, "wheels": RAW})
        out = self.dir / "custom.png"
        proc = run_tool(log, "-o", out, "--truth", "truth", "--estimate", "fused", "--odometry", "wheels",
                        "--max-gap", "0.1")
        self.assertEqual(proc.returncode, 0, proc.stderr)
        # The last 21 stamps are more than 0.1 s past the truth's last one;
        # the others meet the truth 0.5 s later, 0.5 m ahead (hypot with the
        # 0.1 offset: 0.510), except the last, matched to the truth's end.
        self.assertIn("estimate (fused): 480 samples (21 unmatched), final error 0.432 m, RMS error 0.510 m",
                      proc.stdout)
        self.assertIn("raw odometry (wheels): 251 samples, final error 0.200 m", proc.stdout)

    def test_another_type_on_a_channel_is_noted_not_fatal(self):
        log = self.dir / "mixed.lcm"
        write_log(log, self.T, {"sim/ground_truth": TRUTH, "rtfuse/odometry": ESTIMATE})
        with lcm_log.LogWriter(self.dir / "extra.lcm") as w:
            for ev in lcm_log.read_events(log):
                w.write(ev.channel, ev.data, ev.timestamp)
            w.write("rtfuse/odometry", self.T.vector3_t().encode(), 99_000_000)
        proc = run_tool(self.dir / "extra.lcm", "-o", self.dir / "extra.png")
        self.assertEqual(proc.returncode, 0, proc.stderr)
        self.assertIn("note: 1 messages on 'rtfuse/odometry' are not odometry_t; skipped", proc.stdout)
        self.assertIn("final error 0.100 m", proc.stdout)

    def test_unreadable_or_empty_logs_exit_2(self):
        proc = run_tool(self.dir / "absent.lcm", "-o", self.dir / "x.png")
        self.assertEqual(proc.returncode, 2)
        self.assertIn("absent.lcm", proc.stderr)
        log = self.dir / "other.lcm"
        with lcm_log.LogWriter(log) as w:
            w.write("something/else", b"\x00", 1)
        proc = run_tool(log, "-o", self.dir / "y.png")
        self.assertEqual(proc.returncode, 2)
        self.assertIn("none of the channels in its 1 events", proc.stderr)
        self.assertFalse((self.dir / "y.png").exists())


if __name__ == "__main__":
    unittest.main()
