#!/usr/bin/python3
"""rtfuse-map as a user runs it.

  cloud   a synthetic room seen from its middle: the JSON's counts, a .bt
          with OctoMap's header and as many nodes as it says, map_server's
          PGM + YAML, a PNG; a second run gives the same digest; the .bt
          read back (--bt) holds the same voxels and writes the same bytes;
  kitti   the real KITTI 06 pairs with their ground truth (frames 11-20,
          every third): four scans, the map and the grid non-trivial, the
          same digest twice;
  bad     a missing cloud, a malformed line, a bad origin, a pool too small,
          a KITTI folder without poses, a malformed poses file, a .bt cut
          short, of another tree type, not a .bt, too large for the pool:
          each one clear message (file and line or byte where there is
          one) and its exit status, never a crash.
"""
import json
import math
import os
import shlex
import subprocess
import sys
import tempfile

MAP = shlex.split(os.environ["RTFUSE_MAP"])
SEQ = os.path.join(os.environ["RTFUSE_SHARED_DATA"], "kitti", "kitti06_0000_0050")


def fail(msg):
    print("FAIL:", msg)
    sys.exit(1)


def run(*args):
    return subprocess.run(MAP + list(args), capture_output=True, text=True, timeout=300)


def summary(p):
    if p.returncode != 0:
        fail("exit %d: %s" % (p.returncode, p.stderr))
    return json.loads(p.stdout.strip().splitlines()[-1])


def room(path):
    """Walls of a 6 x 4 m room, 2.5 m high, a point every 5 cm."""
    with open(path, "w") as f:
        f.write("# a room\n")
        for i in range(121):
            for k in range(51):
                x, z = -3.0 + 0.05 * i, 0.05 * k
                f.write("%.3f %.3f %.3f\n%.3f %.3f %.3f\n" % (x, -2.0, z, x, 2.0, z))
        for j in range(81):
            for k in range(51):
                y, z = -2.0 + 0.05 * j, 0.05 * k
                f.write("%.3f %.3f %.3f\n%.3f %.3f %.3f\n" % (-3.0, y, z, 3.0, y, z))


def check_cloud(tmp):
    cloud = os.path.join(tmp, "room.xyz")
    room(cloud)
    out = os.path.join(tmp, "room.bt")
    args = ["--cloud", cloud, "--origin", "0.01,0.02,1.0", "--resolution", "0.1", "--out", out,
            "--grid", os.path.join(tmp, "room"), "--png", os.path.join(tmp, "room.png"), "--z-min", "0.2",
            "--z-max", "2.0", "--repeat", "2"]
    s = summary(run(*args))
    if s["points"] != 2 * 121 * 51 + 2 * 81 * 51:
        fail("points %d" % s["points"])
    if not (s["occupied_voxels"] > 1000 and s["known_voxels"] > 5 * s["occupied_voxels"]):
        fail("counts %s" % s)
    if s["dropped_updates"] or s["rejected"]:
        fail("dropped or rejected: %s" % s)
    with open(out, "rb") as f:
        bt = f.read()
    if not bt.startswith(b"# Octomap OcTree binary file\n") or (b"\nsize %d\n" % s["bt_nodes"]) not in bt:
        fail(".bt header: %r" % bt[:200])
    if len(bt) != s["bt_bytes"]:
        fail(".bt is %d bytes, the JSON says %d" % (len(bt), s["bt_bytes"]))
    with open(os.path.join(tmp, "room.yaml")) as f:
        yaml = f.read()
    if "image: room.pgm" not in yaml or "resolution: 0.1" not in yaml:
        fail("yaml: " + yaml)
    with open(os.path.join(tmp, "room.pgm"), "rb") as f:
        pgm = f.read()
    header = b"P5\n%d %d\n255\n" % (s["grid_width"], s["grid_height"])
    if not pgm.startswith(header) or len(pgm) != len(header) + s["grid_width"] * s["grid_height"]:
        fail("pgm header %r, %d bytes" % (pgm[:20], len(pgm)))
    # The walls surround free space: 6 x 4 m at 0.1 m is about 60 x 40 cells.
    if not (55 <= s["grid_width"] <= 62 and 38 <= s["grid_height"] <= 42):
        fail("grid %d x %d" % (s["grid_width"], s["grid_height"]))
    if s["grid_free"] < 1500 or s["grid_occupied"] < 150:
        fail("grid cells %s" % s)
    if pgm.count(b"\x00") < s["grid_occupied"] or pgm.count(b"\xfe") < s["grid_free"]:
        fail("pgm shades do not match the counts")
    if os.path.getsize(os.path.join(tmp, "room.png")) < 5000:
        fail("png too small")
    again = summary(run(*args))
    if again["digest"] != s["digest"]:
        fail("digest %s then %s" % (s["digest"], again["digest"]))
    # The .bt read back: the same voxels known and occupied, written again
    # to the same bytes.
    rewritten = os.path.join(tmp, "again.bt")
    b = summary(run("--bt", out, "--out", rewritten))
    if (b["mode"], b["known_voxels"], b["occupied_voxels"]) != ("bt", s["known_voxels"], s["occupied_voxels"]):
        fail("read back: %s" % b)
    with open(rewritten, "rb") as f:
        if f.read() != bt:
            fail("the .bt written back differs")
    print("cloud: %d points, %d known, %d occupied, %.1f ms, digest %s" %
          (s["points"], s["known_voxels"], s["occupied_voxels"], s["ms_median"], s["digest"]))


def check_kitti(tmp):
    if not os.path.isdir(SEQ):
        print("no shared KITTI frames at", SEQ)
        sys.exit(77)
    args = ["--kitti", SEQ, "--first", "11", "--last", "20", "--every", "3", "--resolution", "0.1",
            "--max-range", "15", "--out", os.path.join(tmp, "k.bt"), "--grid", os.path.join(tmp, "k"),
            "--z-min", "-0.2", "--z-max", "1.5"]
    s = summary(run(*args))
    if s["scans"] != 4 or s["points"] < 4 * 40000:
        fail("scans %d points %d" % (s["scans"], s["points"]))
    if not (s["known_voxels"] > 300000 and s["occupied_voxels"] > 10000 and s["grid_free"] > s["grid_occupied"]):
        fail("counts %s" % s)
    if not (s["disparity_ms_median"] > 0 and s["ms_median"] > 0):
        fail("times %s" % s)
    if summary(run(*args))["digest"] != s["digest"]:
        fail("the same frames gave another map")
    print("kitti: %d scans, %d points, %d known, %d occupied, disparity %.1f ms, insert %.1f ms" %
          (s["scans"], s["points"], s["known_voxels"], s["occupied_voxels"], s["disparity_ms_median"],
           s["ms_median"]))


def expect(p, status, *words):
    if p.returncode != status:
        fail("exit %d, wanted %d: %s" % (p.returncode, status, p.stderr))
    for w in words:
        if w not in p.stderr:
            fail("%r not in: %s" % (w, p.stderr))


def check_bad(tmp):
    out = os.path.join(tmp, "x.bt")
    missing = os.path.join(tmp, "missing.xyz")
    expect(run("--cloud", missing, "--out", out), 1, missing, "No such file")
    bad = os.path.join(tmp, "bad.xyz")
    with open(bad, "w") as f:
        f.write("1 2 3\n\n1 2 x\n")
    expect(run("--cloud", bad, "--out", out), 1, bad + ":3:", '"x" is not a number')
    with open(bad, "w") as f:
        f.write("1 2 3\n4 5\n")
    expect(run("--cloud", bad, "--out", out), 1, bad + ":2:", "expected 3 numbers")
    with open(bad, "w") as f:
        f.write("1 2 nan\n")
    expect(run("--cloud", bad, "--out", out), 1, bad + ":1:", "not finite")
    good = os.path.join(tmp, "good.xyz")
    with open(good, "w") as f:
        for i in range(2000):
            a = 2 * math.pi * i / 2000
            f.write("%.4f %.4f 0.5\n" % (8 * math.cos(a), 8 * math.sin(a)))
    expect(run("--cloud", good, "--origin", "1,2", "--out", out), 2, "--origin")
    expect(run("--cloud", good, "--resolution", "0", "--out", out), 2, "resolution")
    expect(run("--cloud", good, "--resolution", "0.02", "--pool-mib", "1", "--out", out), 3, "raise --pool-mib")
    expect(run("--cloud", good, "--out", os.path.join(tmp, "no", "dir", "x.bt")), 1, "cannot write")
    good_bt = os.path.join(tmp, "good.bt")
    summary(run("--cloud", good, "--resolution", "0.02", "--out", good_bt))
    with open(good_bt, "rb") as f:
        data = f.read()
    cut = os.path.join(tmp, "cut.bt")
    with open(cut, "wb") as f:
        f.write(data[: len(data) - 7])
    expect(run("--bt", cut, "--out", out), 1, cut + ": cut short at byte")
    with open(cut, "wb") as f:
        f.write(b"# Octomap OcTree binary file\nid ColorOcTree\nsize 1\nres 0.1\ndata\n\x00\x00")
    expect(run("--bt", cut, "--out", out), 1, "only OcTree")
    expect(run("--bt", good, "--out", out), 1, "not an OctoMap binary tree")
    expect(run("--bt", good_bt, "--pool-mib", "1", "--out", out), 3, "cannot hold the file")
    if os.path.isdir(SEQ):
        nop = os.path.join(tmp, "nop")
        os.makedirs(nop)
        for name in ("image_l", "image_r", "calib.txt"):
            os.symlink(os.path.join(SEQ, name), os.path.join(nop, name))
        expect(run("--kitti", nop, "--out", out), 2, "--poses")
        poses = os.path.join(tmp, "poses.txt")
        with open(poses, "w") as f:
            f.write("1 0 0 0 0 1 0 0 0 0 1 0\n1 0 0\n")
        expect(run("--kitti", nop, "--poses", poses, "--out", out), 1, poses + ":2:")
    print("bad: every case refused with its message")


def main():
    with tempfile.TemporaryDirectory() as tmp:
        {"cloud": check_cloud, "kitti": check_kitti, "bad": check_bad}[sys.argv[1]](tmp)


if __name__ == "__main__":
    main()
