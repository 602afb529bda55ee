#!/usr/bin/python3
"""rtfuse-camera-snapshot on the simulated robot's camera: a rectified pair as
a PNG with guide lines, and its refusals (no [camera], a missing calibration)."""
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

CAMERA = """
[camera]
calibration = "{cal}"
resolution = "VGA"
fps = 30

[[static_transform]]
parent = "base_link"
child = "camera_optical"
translation = [0.2, 0.06, 0.3]
rpy = [-1.5707963267948966, 0.0, -1.5707963267948966]
"""


def sim_config(camera):
    with open(os.path.join(SRC, "config", "sim.toml")) as f:
        text = f.read()
    text = text.replace('scenario = "scenarios/demo.toml"',
                        'scenario = "%s"' % os.path.join(SRC, "config", "scenarios", "straight.toml"))
    return text + camera


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


def main():
    cal = os.path.join(SRC, "config", "calibration", "SN10000001.conf")
    with tempfile.TemporaryDirectory() as tmp:
        p, out = run(sim_config(CAMERA.format(cal=cal)), tmp, "-g", "24", "-t", "10")
        if p.returncode != 0:
            fail("exit %d: %s" % (p.returncode, p.stderr))
        img = matplotlib.image.imread(out)
        if img.shape != (376, 1344, 3):
            fail("PNG is %s, expected 376 x 1344 RGB (two VGA eyes)" % (img.shape,))
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
        print("snapshot:", p.stdout.strip())

        p, _ = run(sim_config(""), tmp)
        if p.returncode != 2 or "has no [camera]" not in p.stderr:
            fail("a config without [camera]: exit %d, %r" % (p.returncode, p.stderr))
        p, _ = run(sim_config(CAMERA.format(cal=os.path.join(tmp, "SN404.conf"))), tmp)
        if p.returncode != 1 or "SN404.conf" not in p.stderr:
            fail("a missing calibration file: exit %d, %r" % (p.returncode, p.stderr))
        print("refusals:", p.stderr.strip().splitlines()[-1])
    print("PASS")


if __name__ == "__main__":
    main()
