#!/usr/bin/python3
"""soak_check.py REPORT.jsonl ALLOC_REPORT DISTANCE_M: the verdict on a tools/soak.sh run.

REPORT.jsonl is rtfuse-sim --report-every's output (one JSON object per
report, the final result last); ALLOC_REPORT the allocation probe's report
(armed at the first report); DISTANCE_M the path's length. Exit 0 when every check holds, 1 otherwise;
prints the figures either way.
"""
import argparse
import json
import sys

RSS_GROWTH_KIB = 256     # page-granular noise allowed after the first report
MAX_VARIANCE_CAP = 1e6   # the filter's max_variance (estimation/filter_params.hpp)
IN_FLIGHT = 256          # measurements received but not yet fused or rejected
# No absolute position sensor: the error of dead reckoning grows with the
# distance driven, so the bound is a fraction of it.
FINAL_ERROR_FRACTION = 0.01


def main(argv):
    ap = argparse.ArgumentParser(description="the verdict on a tools/soak.sh run (docs/reliability.md, Soak)")
    ap.add_argument("report", help="rtfuse-sim --report-every's output (JSON lines, the final result last)")
    ap.add_argument("alloc_report", help="the allocation probe's report (armed at the first report)")
    ap.add_argument("distance_m", type=float, help="the length of the path driven, m")
    args = ap.parse_args(argv[1:])
    reports, final = [], None
    with open(args.report) as f:
        for n, line in enumerate(f, 1):
            try:
                obj = json.loads(line)
            except json.JSONDecodeError as e:
                print(f"{args.report}:{n}: not JSON: {e}")
                return 1
            if obj.get("report"):
                reports.append(obj)
            else:
                final = obj
    steady = None
    with open(args.alloc_report) as f:
        for line in f:
            if line.startswith("steady_allocations "):
                steady = int(line.split()[1])
    failures = []
    if len(reports) < 2:
        failures.append(f"only {len(reports)} reports: the run ended early")
    if final is None:
        failures.append("no final result line: rtfuse-sim failed")
    if steady is None:
        failures.append("the allocation probe's report has no steady_allocations (was it armed?)")
    elif steady != 0:
        failures.append(f"{steady} allocations after the first report")
    if reports:
        base = reports[0]["rss_kib"]
        growth = max(r["rss_kib"] for r in reports) - base
        if growth > RSS_GROWTH_KIB:
            failures.append(f"resident memory grew {growth} KiB after the first report (limit {RSS_GROWTH_KIB})")
        if not all(r["finite"] for r in reports):
            failures.append("a state or covariance entry was not finite")
        worst_var = max(r["max_variance"] for r in reports)
        if worst_var > MAX_VARIANCE_CAP:
            failures.append(f"a variance reached {worst_var:g}, above the cap {MAX_VARIANCE_CAP:g}")
        prev = None
        for r in reports:
            pending = r["received"] - r["accepted"] - r["rejected"]
            if pending < 0 or pending > IN_FLIGHT:
                failures.append(f"at {r['sim_s']} s: received {r['received']} != accepted {r['accepted']} + "
                                f"rejected {r['rejected']} (+ at most {IN_FLIGHT} in flight)")
                break
            if prev and (r["ticks"] <= prev["ticks"] or r["fused"] < prev["fused"] or r["received"] < prev["received"]):
                failures.append(f"at {r['sim_s']} s: a counter went backwards or stopped")
                break
            prev = r
        last = reports[-1]
        print(f"reports: {len(reports)} over {last['sim_s'] / 3600:.2f} h simulated in {last['wall_s'] / 60:.1f} min "
              f"({last['sim_s'] / max(last['wall_s'], 1e-9):.0f}x real time)")
        print(f"resident memory: {base} KiB at the first report, {last['rss_kib']} KiB at the last, "
              f"largest growth {growth} KiB")
        print(f"allocations after the first report: {steady}")
        print(f"finite throughout: {all(r['finite'] for r in reports)}; largest variance {worst_var:.4g} "
              f"(cap {MAX_VARIANCE_CAP:g}); position sigma at the end {last['position_sigma_m']:.3f} m")
        print(f"counters: {last['ticks']} ticks, {last['fused']} fused, {last['received']} received = "
              f"{last['accepted']} accepted + {last['rejected']} rejected + "
              f"{last['received'] - last['accepted'] - last['rejected']} in flight")
        print(f"error: {last['error_m']:.3f} m at the last report, largest {last['max_error_m']:.3f} m")
    if final is not None:
        print(f"final: error {final['final_error_m']:.3f} m, RMS {final['rms_error_m']:.3f} m, yaw "
              f"{final['final_yaw_error_rad']:.4f} rad; raw wheel odometry {final['raw_final_error_m']:.3f} m")
        distance = args.distance_m
        print(f"distance driven: {distance / 1000:.1f} km; final error {100 * final['final_error_m'] / distance:.3f} % of it")
        if final["final_error_m"] > FINAL_ERROR_FRACTION * distance:
            failures.append(f"final error {final['final_error_m']:.3f} m above {100 * FINAL_ERROR_FRACTION:g} % of "
                            f"the {distance:.0f} m driven")
    for f in failures:
        print("FAIL:", f)
    print("OK" if not failures else f"{len(failures)} check(s) failed")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
