#!/usr/bin/python3
"""rtfuse-plan as a user runs it, against a planner written here from the
issue's words alone (Dijkstra with heapq over the 8-connected free cells, no
diagonal step past a closed corner, steps of 1 and sqrt(2)):

  plain     random maps written as the mapper writes them (map_server PGM +
            YAML: occupied, free and unknown cells), random pairs, some in
            obstacles, unknown or outside: with --inflation 0 every pair
            reached or not as the reference says, the same cost to 1e-9,
            and the JSON's reached and cost_sum their totals; A* and
            --dijkstra give the same costs;
  inflated  --inflation 0.15 on a 0.05 m map: cells whose centre is within
            3 cells of an obstacle's closed too, costs as the reference's
            on that graph;
  bad       a missing map, a YAML without its resolution, a missing image,
            a pairs file with a short line, a size the planner refuses:
            one clear message naming the file (and line) and exit 1, never a
            crash; a goal in an obstacle or outside the map is a failure
            counted by its reason, not an error.
"""
import heapq
import json
import math
import os
import random
import shlex
import subprocess
import sys
import tempfile

PLAN = shlex.split(os.environ["RTFUSE_PLAN"])
SQRT2 = math.sqrt(2.0)


def fail(msg):
    print("FAIL:", msg)
    sys.exit(1)


def run(*args):
    return subprocess.run(PLAN + list(args), capture_output=True, text=True, timeout=300)


def summary(p):
    if p.returncode != 0:
        fail("exit %d: %s%s" % (p.returncode, p.stdout, p.stderr))
    return json.loads(p.stdout.strip().splitlines()[-1])


def write_map(tmp, name, cells, w, h, resolution=0.05):
    """cells[y][x], y = 0 the lowest row: 100, 0 or -1, as the mapper's PGM."""
    shade = {100: 0, 0: 254, -1: 205}
    with open(os.path.join(tmp, name + ".pgm"), "wb") as f:
        f.write(b"P5\n%d %d\n255\n" % (w, h))
        f.write(bytes(shade[cells[y][x]] for y in reversed(range(h)) for x in range(w)))
    with open(os.path.join(tmp, name + ".yaml"), "w") as f:
        f.write("image: %s.pgm\nmode: trinary\nresolution: %g\norigin: [-1.0, -2.0, 0.0]\nnegate: 0\n"
                "occupied_thresh: 0.65\nfree_thresh: 0.196\n" % (name, resolution))
    return os.path.join(tmp, name + ".yaml")


def random_map(rng, w, h):
    cells = [[0] * w for _ in range(h)]
    for _ in range(w * h // 40):  # boxes
        x0, y0 = rng.randrange(w), rng.randrange(h)
        for y in range(y0, min(h, y0 + rng.randrange(1, 6))):
            for x in range(x0, min(w, x0 + rng.randrange(1, 6))):
                cells[y][x] = 100
    for _ in range(w * h // 25):
        cells[rng.randrange(h)][rng.randrange(w)] = -1
    return cells


def reference(open_cell, w, h, s, g):
    """Dijkstra over open cells; None when there is no route."""
    if not (0 <= s[0] < w and 0 <= s[1] < h and 0 <= g[0] < w and 0 <= g[1] < h):
        return None
    if not open_cell(*s) or not open_cell(*g):
        return None
    dist = {s: 0.0}
    heap = [(0.0, s)]
    while heap:
        d, (x, y) = heapq.heappop(heap)
        if (x, y) == g:
            return d
        if d > dist[(x, y)]:
            continue
        for dx in (-1, 0, 1):
            for dy in (-1, 0, 1):
                if dx == 0 and dy == 0:
                    continue
                nx, ny = x + dx, y + dy
                if not (0 <= nx < w and 0 <= ny < h) or not open_cell(nx, ny):
                    continue
                if dx and dy and not (open_cell(x + dx, y) and open_cell(x, y + dy)):
                    continue  # no corner cutting
                nd = d + (SQRT2 if dx and dy else 1.0)
                if nd < dist.get((nx, ny), math.inf):
                    dist[(nx, ny)] = nd
                    heapq.heappush(heap, (nd, (nx, ny)))
    return None


def random_pairs(rng, w, h, n):
    pairs = []
    for _ in range(n):
        pairs.append((rng.randrange(-2, w + 2), rng.randrange(-2, h + 2), rng.randrange(w), rng.randrange(h)))
    return pairs


def write_pairs(tmp, pairs):
    path = os.path.join(tmp, "pairs.txt")
    with open(path, "w") as f:
        f.write("# sx sy gx gy\n")
        for p in pairs:
            f.write("%d %d %d %d\n" % p)
    return path


def per_pair(p):
    """The costs from the per-pair lines, None for a failure."""
    costs = []
    for line in p.stdout.strip().splitlines()[:-1]:
        costs.append(float(line.split("cost ")[1].split(" ")[0]) if ": cost " in line else None)
    return costs


def compare(tmp, cells, w, h, open_cell, pairs, *options):
    yaml = write_map(tmp, "map", cells, w, h)
    pairs_path = write_pairs(tmp, pairs)
    want = [reference(open_cell, w, h, (p[0], p[1]), (p[2], p[3])) for p in pairs]
    for search in ([], ["--dijkstra"]):
        p = run("--map", yaml, "--pairs", pairs_path, *options, *search)
        result = summary(p)
        got = per_pair(p)
        if len(got) != len(pairs):
            fail("%d pair lines for %d pairs:\n%s" % (len(got), len(pairs), p.stdout))
        for pair, a, b in zip(pairs, got, want):
            if (a is None) != (b is None) or (a is not None and abs(a - b) > 1e-9 * max(1.0, b)):
                fail("pair %s %s: rtfuse-plan %s, the reference %s" % (pair, options + tuple(search), a, b))
        reached = sum(c is not None for c in want)
        total = sum(c for c in want if c is not None)
        if result["reached"] != reached or abs(result["cost_sum"] - total) > 1e-6:
            fail("JSON %s, the reference: %d reached, cost_sum %.9f" % (result, reached, total))
    return result, reached


def check_plain(tmp):
    rng = random.Random(1)
    for trial in range(6):
        w, h = rng.randrange(20, 70), rng.randrange(20, 60)
        cells = random_map(rng, w, h)
        pairs = random_pairs(rng, w, h, 40)
        result, reached = compare(tmp, cells, w, h, lambda x, y: cells[y][x] == 0, pairs, "--inflation", "0")
        if not 5 <= reached < len(pairs):
            fail("trial %d: %d of %d reached: the maps test too little" % (trial, reached, len(pairs)))
        print("plain %dx%d: %d of %d reached, cost_sum %.3f, failures %s, %.3f ms median" %
              (w, h, reached, len(pairs), result["cost_sum"], result["failures"], result["ms_median"]))


def check_inflated(tmp):
    rng = random.Random(2)
    w, h = 80, 60
    cells = [[0] * w for _ in range(h)]
    for _ in range(30):
        cells[rng.randrange(h)][rng.randrange(w)] = 100
    obstacles = [(x, y) for y in range(h) for x in range(w) if cells[y][x] == 100]

    def open_cell(x, y):  # 0.15 m at 0.05 m: centres more than 3 cells from every obstacle
        return all((x - ox) ** 2 + (y - oy) ** 2 > 9 for ox, oy in obstacles)

    pairs = random_pairs(rng, w, h, 40)
    result, reached = compare(tmp, cells, w, h, open_cell, pairs, "--inflation", "0.15")
    if reached < 10:
        fail("only %d pairs reached" % reached)
    print("inflated: %d of %d reached, failures %s" % (reached, len(pairs), result["failures"]))


def expect(p, code, *texts):
    if p.returncode != code:
        fail("exit %d, expected %d: %s%s" % (p.returncode, code, p.stdout, p.stderr))
    for t in texts:
        if t not in p.stderr + p.stdout:
            fail("%r not in: %s%s" % (t, p.stdout, p.stderr))


def check_bad(tmp):
    cells = [[0] * 10 for _ in range(8)]
    cells[4][4] = 100
    yaml = write_map(tmp, "small", cells, 10, 8)
    pairs = write_pairs(tmp, [(1, 1, 4, 4), (1, 1, 20, 3), (1, 1, 8, 6)])
    result = summary(run("--map", yaml, "--pairs", pairs))
    if result["reached"] != 1 or result["failures"] != {"goal in an obstacle": 1, "goal outside the grid": 1}:
        fail("failures by reason: %s" % result)
    expect(run("--map", os.path.join(tmp, "none.yaml"), "--pairs", pairs), 1, "none.yaml: cannot be read")
    no_res = os.path.join(tmp, "nores.yaml")
    with open(no_res, "w") as f:
        f.write("image: small.pgm\norigin: [0, 0, 0]\noccupied_thresh: 0.65\nfree_thresh: 0.196\n")
    expect(run("--map", no_res, "--pairs", pairs), 1, "nores.yaml: key 'resolution' is missing")
    no_image = os.path.join(tmp, "noimage.yaml")
    with open(no_image, "w") as f:
        f.write("image: gone.pgm\nresolution: 0.05\norigin: [0, 0, 0]\noccupied_thresh: 0.65\nfree_thresh: 0.196\n")
    expect(run("--map", no_image, "--pairs", pairs), 1, "gone.pgm cannot be read")
    short = os.path.join(tmp, "short.txt")
    with open(short, "w") as f:
        f.write("1 1 4 4\n1 2 3\n")
    expect(run("--map", yaml, "--pairs", short), 1, "short.txt:2: expected 4 numbers")
    expect(run("--map", yaml, "--pairs", pairs, "--inflation", "5", "--decay", "9"), 2, "at most 10 m")
    print("bad: every case refused or counted with its reason")


def main():
    checks = {"plain": check_plain, "inflated": check_inflated, "bad": check_bad}
    with tempfile.TemporaryDirectory() as tmp:
        checks[sys.argv[1]](tmp)
    print("OK:", sys.argv[1])


if __name__ == "__main__":
    main()
