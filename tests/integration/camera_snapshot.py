#!/usr/bin/python3
"""rtfuse-camera-snapshot on the simulated robot's camera: a rectified pair as
a PNG with guide lines under a header band, the same from an rtfused --record
log, and the refusals (no [camera], a missing calibration, a recording without frames)."""
import json
import os
import shlex
import subprocess
import sys
import tempfile

import matplotlib
matplotlib.use("Agg")
import matplotlib.image  # noqa: E402
import numpy  # noqa: E402

SRC = os.environ["RTFUSE_SOURCE_DIR"]
TOOL = shlex.split(os.environ["RTFUSE_CAMERA_SNAPSHOT"])
RTFUSED = shlex.split(os.environ["RTFUSED"])
from sim_config import without_camera  # noqa: E402  (beside this file)

def sim_config(calibration):
    """config/sim.toml driving straight.toml, its camera's calibration at
    `calibration` (absolute), or without its [camera] (nor the visual
    odometry on it: [vo] and its [[sensor]]) when None."""
    with open(os.path.join(SRC, "config", "sim.toml")) as f:
        text = f.read()
    text = text.replace('scenario = "scenarios/demo.toml"',
                        'scenario = "%s"' % os.path.join(SRC, "config", "scenarios", "straight.toml"))
    if calibration is None:
        return without_camera(text)
    return text.replace('calibration = "calibration/SN10000001.conf"', 'calibration = "%s"' % calibration)


def check_png(out, summary_line):
    """The pair below its header band (the JSON's header_rows), as before."""
    top = json.loads(summary_line)["header_rows"]
    full = matplotlib.image.imread(out)
    if full.shape != (top + 376, 1344, 3):
        fail("PNG is %s, expected %d header rows + 376 x 1344 RGB (two VGA eyes)" % (full.shape, top))
    # The header band: dark text on light paper, not the camera's pixels.
    band = full[:top]
    if not (band > 0.9).mean() > 0.5 or not (band < 0.1).any():
        fail("the header band (rows 0..%d) holds no text on paper" % (top - 1))
    img = full[top:]
    # Guide lines are green across both eyes; other rows are grey.
    if not (img[24, :, 1] > 0.99).all() or not (img[24, :, 0] < 0.01).all():
        fail("row 24 is not a green guide line")
    grey = img[25:47]
    if not numpy.allclose(grey[..., 0], grey[..., 1]):
        fail("rows between guide lines are not grey")
    left, right = img[:, :672, 0], img[:, 672:, 0]
    # A rendered scene, both eyes alike in brightness, neither blank.
    for name, eye in (("left", left), ("right", right)):
        if eye.std() < 0.05:
            fail("the %s eye is nearly uniform (std %.3f)" % (name, eye.std()))
    if abs(left.mean() - right.mean()) > 0.05:
        fail("eye brightness differs: %.3f vs %.3f" % (left.mean(), right.mean()))


def run(config_text, tmp, *extra):
    path = os.path.join(tmp, "robot.toml")
    with open(path, "w") as f:
        f.write(config_text)
    out = os.path.join(tmp, "pair.png")
    p = subprocess.run(TOOL + ["-c", path, "-o", out, *extra], capture_output=True, text=True, timeout=240)
    return p, out


def fail(msg):
    print("FAIL:", msg)
    sys.exit(1)


def record(config_text, tmp, name):
    """rtfused --record for one second of the config; the log's path."""
    path = os.path.join(tmp, name + ".toml")
    with open(path, "w") as f:
        f.write(config_text)
    log = os.path.join(tmp, name + ".lcm")
    p = subprocess.run(RTFUSED + ["--config", path, "--duration", "1", "--quiet", "--lcm-url", "memq://",
                                  "--record", log], capture_output=True, text=True, timeout=240)
    if p.returncode != 0:
        fail("rtfused --record %s: exit %d: %s" % (name, p.returncode, p.stderr))
    return log


def main():
    cal = os.path.join(SRC, "config", "calibration", "SN10000001.conf")
    with tempfile.TemporaryDirectory() as tmp:
        p, out = run(sim_config(cal), tmp, "-g", "24", "-t", "10")
        if p.returncode != 0:
            fail("exit %d: %s" % (p.returncode, p.stderr))
        check_png(out, p.stdout.strip().splitlines()[-1])
        print("snapshot:", p.stdout.strip())

        # From a recording: its frames, configuration and calibration.
        log = record(sim_config(cal), tmp, "recorded")
        out = os.path.join(tmp, "recorded.png")
        p = subprocess.run(TOOL + ["--recording", log, "-o", out, "-n", "10"], capture_output=True, text=True,
                           timeout=240)
        if p.returncode != 0:
            fail("--recording: exit %d: %s" % (p.returncode, p.stderr))
        check_png(out, p.stdout.strip().splitlines()[-1])
        print("from a recording:", p.stdout.strip())

        p, _ = run(sim_config(None), tmp)
        if p.returncode != 2 or "has no [camera]" not in p.stderr:
            fail("a config without [camera]: exit %d, %r" % (p.returncode, p.stderr))
        p, _ = run(sim_config(os.path.join(tmp, "SN404.conf")), tmp)
        if p.returncode != 1 or "SN404.conf" not in p.stderr:
            fail("a missing calibration file: exit %d, %r" % (p.returncode, p.stderr))
        print("refusals:", p.stderr.strip().splitlines()[-1])
        log = record(sim_config(None), tmp, "no_camera")
        p = subprocess.run(TOOL + ["--recording", log, "-o", os.path.join(tmp, "none.png")], capture_output=True,
                           text=True, timeout=240)
        if p.returncode != 2 or "holds no camera frames" not in p.stderr:
            fail("a recording without a camera: exit %d, %r" % (p.returncode, p.stderr))
        print("refusals:", p.stderr.strip().splitlines()[-1])
    print("PASS")


if __name__ == "__main__":
    main()
