#!/usr/bin/python3
"""Plot a drive from an LCM log: the estimate, the ground truth and the raw
wheel odometry in the x-y plane, and their position errors over time.

    tools/plot_trajectory.py LOG.lcm -o OUT.png

Every channel is an odometry_t (nav_msgs/Odometry): by default the fused
estimate rtfuse/odometry, the simulator's truth sim/ground_truth and the
wheel odometry's own dead reckoning rtfuse/wheel_odometry; --estimate,
--truth and --odometry choose others. A channel missing from the log is
skipped with a note. All three start in the same odom frame (the simulated
robot starts at its origin), so no alignment is made.

Against the truth, matched by the nearest header stamp (within --max-gap),
it prints the final and the RMS position error of the estimate and of the
raw odometry. Exit status 0, or 2 when the log cannot be read or holds none
of the channels.

Needs Debian's python3-matplotlib (Agg backend, no display), hence
/usr/bin/python3.
"""

import argparse
import bisect
import math
import struct
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from rtfuse_tools import lcm_log  # noqa: E402
from rtfuse_tools.lcmtypes_path import LcmTypesError, import_lcmtypes  # noqa: E402

EXIT_OK = 0
EXIT_ERROR = 2

DEFAULT_ESTIMATE = "rtfuse/odometry"
DEFAULT_TRUTH = "sim/ground_truth"
DEFAULT_ODOMETRY = "rtfuse/wheel_odometry"


class Track:
    """One channel's positions in stamp order."""

    def __init__(self, label, channel):
        self.label = label
        self.channel = channel
        self.t = []  # header stamp, s
        self.x = []
        self.y = []
        self.undecodable = 0

    def __len__(self):
        return len(self.t)

    def add(self, utime, x, y):
        self.t.append(utime * 1e-6)
        self.x.append(x)
        self.y.append(y)

    def sort(self):
        order = sorted(range(len(self.t)), key=lambda i: self.t[i])
        self.t = [self.t[i] for i in order]
        self.x = [self.x[i] for i in order]
        self.y = [self.y[i] for i in order]


class Errors:
    """Position error of a track against the truth at its matched samples."""

    def __init__(self, times, errors, unmatched):
        self.t = times
        self.e = errors
        self.unmatched = unmatched

    @property
    def final(self):
        return self.e[-1]

    @property
    def rms(self):
        return math.sqrt(sum(e * e for e in self.e) / len(self.e))


def read_tracks(path, tracks, odometry_t):
    """Fills the tracks from the log; returns the number of events read."""
    by_channel = {tr.channel: tr for tr in tracks}
    count = 0
    with lcm_log.LogReader(path, allow_truncated_tail=True) as reader:
        for ev in reader:
            count += 1
            tr = by_channel.get(ev.channel)
            if tr is None:
                continue
            try:
                msg = odometry_t.decode(ev.data)
            except (ValueError, struct.error):  # another type's fingerprint, or cut short
                tr.undecodable += 1
                continue
            p = msg.pose.pose.position
            tr.add(msg.header.utime, p.x, p.y)
    for tr in tracks:
        tr.sort()
    return count


def match_errors(track, truth, max_gap):
    """Errors of `track` against the truth sample nearest in stamp."""
    times, errors = [], []
    unmatched = 0
    for t, x, y in zip(track.t, track.x, track.y):
        i = bisect.bisect_left(truth.t, t)
        best = None
        for j in (i - 1, i):
            if 0 <= j < len(truth.t) and (best is None or abs(truth.t[j] - t) < abs(truth.t[best] - t)):
                best = j
        if best is None or abs(truth.t[best] - t) > max_gap:
            unmatched += 1
            continue
        times.append(t)
        errors.append(math.hypot(x - truth.x[best], y - truth.y[best]))
    return Errors(times, errors, unmatched)


def plot(out, tracks, truth, errors, title):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    styles = {
        "truth": dict(color="black", linewidth=1.6, label="ground truth"),
        "estimate": dict(color="tab:blue", linewidth=1.2, label="estimate"),
        "raw odometry": dict(color="tab:orange", linewidth=1.0, linestyle="--", label="raw wheel odometry"),
    }
    fig, (ax_xy, ax_err) = plt.subplots(2, 1, figsize=(8, 10), gridspec_kw={"height_ratios": [3, 1.2]})
    for tr in tracks:
        if len(tr):
            style = dict(styles[tr.label])
            style["label"] = f"{style['label']} ({tr.channel})"
            ax_xy.plot(tr.x, tr.y, **style)
    start = truth if truth is not None and len(truth) else next((tr for tr in tracks if len(tr)), None)
    if start is not None:
        ax_xy.plot(start.x[:1], start.y[:1], "o", color="green", label="start")
    ax_xy.set_xlabel("x [m]")
    ax_xy.set_ylabel("y [m]")
    ax_xy.set_aspect("equal", adjustable="datalim")
    ax_xy.grid(True, alpha=0.3)
    ax_xy.legend(loc="best", fontsize="small")
    ax_xy.set_title(title)

    t0 = min((tr.t[0] for tr in tracks if len(tr)), default=0.0)
    for label, err in errors.items():
        if err is not None and err.e:
            style = styles[label]
            ax_err.plot([t - t0 for t in err.t], err.e, color=style["color"],
                        linestyle=style.get("linestyle", "-"), label=f"{style['label']} (RMS {err.rms:.3f} m)")
    if not any(err is not None and err.e for err in errors.values()):
        ax_err.text(0.5, 0.5, "no ground truth to compare with", ha="center", va="center",
                    transform=ax_err.transAxes)
    else:
        ax_err.legend(loc="best", fontsize="small")
    ax_err.set_xlabel("time [s]")
    ax_err.set_ylabel("position error [m]")
    ax_err.grid(True, alpha=0.3)
    fig.tight_layout()
    fig.savefig(out, dpi=100)
    plt.close(fig)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("log", help="LCM log (lcm-logger format)")
    ap.add_argument("-o", "--output", required=True, help="PNG to write")
    ap.add_argument("--estimate", default=DEFAULT_ESTIMATE, help=f"fused odometry channel ({DEFAULT_ESTIMATE})")
    ap.add_argument("--truth", default=DEFAULT_TRUTH, help=f"ground-truth channel ({DEFAULT_TRUTH})")
    ap.add_argument("--odometry", default=DEFAULT_ODOMETRY,
                    help=f"raw wheel-odometry channel ({DEFAULT_ODOMETRY})")
    ap.add_argument("--max-gap", type=float, default=0.1,
                    help="longest stamp difference to the nearest truth sample, s (0.1)")
    ap.add_argument("--title", default=None, help="plot title (default: the log's name)")
    args = ap.parse_args(argv)

    try:
        T = import_lcmtypes()
    except LcmTypesError as e:
        print(f"error: {e}", file=sys.stderr)
        return EXIT_ERROR

    truth = Track("truth", args.truth)
    estimate = Track("estimate", args.estimate)
    raw = Track("raw odometry", args.odometry)
    tracks = [truth, estimate, raw]
    try:
        events = read_tracks(args.log, tracks, T.odometry_t)
    except (OSError, lcm_log.LcmLogError) as e:
        print(f"error: {e}", file=sys.stderr)
        return EXIT_ERROR

    for tr in tracks:
        if tr.undecodable:
            print(f"note: {tr.undecodable} messages on '{tr.channel}' are not odometry_t; skipped")
        if not len(tr):
            print(f"note: no {tr.label} in the log (channel '{tr.channel}'); skipped")
    if not any(len(tr) for tr in tracks):
        print(f"error: {args.log}: none of the channels in its {events} events", file=sys.stderr)
        return EXIT_ERROR

    errors = {"estimate": None, "raw odometry": None}
    if len(truth):
        for tr in (estimate, raw):
            if not len(tr):
                continue
            err = match_errors(tr, truth, args.max_gap)
            if not err.e:
                print(f"note: no {tr.label} sample within {args.max_gap} s of a truth sample")
                continue
            errors[tr.label] = err
            extra = f" ({err.unmatched} unmatched)" if err.unmatched else ""
            print(f"{tr.label} ({tr.channel}): {len(err.e)} samples{extra}, "
                  f"final error {err.final:.3f} m, RMS error {err.rms:.3f} m")
    else:
        print("note: without ground truth no errors are computed")

    try:
        plot(args.output, tracks, truth, errors, args.title or Path(args.log).name)
    except OSError as e:
        print(f"error: cannot write {args.output}: {e}", file=sys.stderr)
        return EXIT_ERROR
    print(f"wrote {args.output}")
    return EXIT_OK


if __name__ == "__main__":
    sys.exit(main())
