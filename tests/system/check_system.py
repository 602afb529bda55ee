#!/usr/bin/python3
"""Checks for the system tests (run by run_system_test.sh, outside rtfused).

  check_system.py log LOG --rtfused-rc N --rtfused-stdout FILE
                  [--expect CHANNEL:MIN]... [--rate CHANNEL:LO:HI]...
      The LCM log lcm-logger recorded: every expected channel present at
      least MIN times, its rate (from the receive timestamps) within [LO, HI]
      Hz, one fingerprint per channel, header.seq increasing; rtfused exited 0,
      fused measurements and printed its final error line.

  check_system.py corrupt LOG OUT KIND
      Writes a damaged copy of LOG (KIND: fingerprint | truncate) for the
      negative controls of the Java decoder.

  check_system.py alloc REPORT [--selftest]
      The alloc_probe report: the probe was armed, saw start-up allocations
      (so interposition works) and counted 0 allocations in steady state.
      Any allocation is listed by thread, with its call stack resolved by
      addr2line. --selftest expects the probe's own self-test pattern instead.

Exit status 0 on success, 1 on a failed check, 2 on bad input.
"""

import argparse
import math
import os
import re
import shutil
import struct
import subprocess
import sys
from collections import Counter, defaultdict

HERE = os.path.dirname(os.path.abspath(__file__))
TOOLS_DIR = os.environ.get("RTFUSE_TOOLS_DIR", os.path.join(HERE, "..", "..", "tools"))

try:
    sys.path.insert(0, TOOLS_DIR)
    from rtfuse_tools.lcm_log import LogReader, LogWriter, LcmLogError  # noqa: E402
except ImportError:  # a checkout without tools/: the format is small enough to read here
    _HEADER = struct.Struct(">Iqqii")

    class LcmLogError(ValueError):
        pass

    class LogReader:
        def __init__(self, path, allow_truncated_tail=False):
            self._f = open(path, "rb")
            self.name = path

        def __iter__(self):
            from collections import namedtuple
            Ev = namedtuple("LogEvent", "eventnum timestamp channel data")
            index = 0
            while True:
                head = self._f.read(_HEADER.size)
                if not head:
                    return
                if len(head) < _HEADER.size:
                    raise LcmLogError(f"{self.name}: truncated event {index}")
                sync, num, ts, clen, dlen = _HEADER.unpack(head)
                if sync != 0xEDA1DA01:
                    raise LcmLogError(f"{self.name}: event {index}: bad sync word 0x{sync:08X}")
                chan = self._f.read(clen)
                data = self._f.read(dlen)
                if len(chan) < clen or len(data) < dlen:
                    raise LcmLogError(f"{self.name}: truncated event {index}")
                yield Ev(num, ts, chan.decode("utf-8"), data)
                index += 1

        def __enter__(self):
            return self

        def __exit__(self, *exc):
            self._f.close()

    class LogWriter:
        def __init__(self, path):
            self._f = open(path, "wb")
            self.count = 0

        def write(self, channel, data, timestamp):
            chan = channel.encode("utf-8")
            self._f.write(_HEADER.pack(0xEDA1DA01, self.count, timestamp, len(chan), len(data)))
            self._f.write(chan)
            self._f.write(data)
            self.count += 1

        def __enter__(self):
            return self

        def __exit__(self, *exc):
            self._f.close()


failures = []


def fail(msg):
    failures.append(msg)
    print("FAIL: " + msg)


def read_log(path):
    try:
        with LogReader(path) as r:
            return list(r)
    except (OSError, LcmLogError) as e:
        print(f"ERROR: cannot read the LCM log: {e}")
        sys.exit(1)


def header_seq(data):
    """header_t is the first member of every rtfuse output but tf_t:
    fingerprint(8) | utime(8) | seq(4) | frame_id (int32 length with NUL, bytes)."""
    if len(data) < 24:
        return None, None
    utime, seq, flen = struct.unpack_from(">qii", data, 8)
    if not 0 < flen <= len(data) - 24 or data[24 + flen - 1] != 0:
        return None, None
    return seq, data[24:24 + flen - 1].decode("utf-8", "replace")


def cmd_log(a):
    events = read_log(a.log)
    if not events:
        fail(f"{a.log}: the log is empty: lcm-logger received nothing over UDP multicast")
    counts = Counter(e.channel for e in events)
    stamps = defaultdict(list)
    fingerprints = defaultdict(set)
    for e in events:
        stamps[e.channel].append(e.timestamp)
        fingerprints[e.channel].add(e.data[:8])
    span = (events[-1].timestamp - events[0].timestamp) / 1e6 if events else 0.0
    print(f"{len(events)} events over {span:.2f} s in {a.log}")
    for ch in sorted(counts):
        ts = stamps[ch]
        rate = (len(ts) - 1) / ((ts[-1] - ts[0]) / 1e6) if len(ts) > 1 and ts[-1] > ts[0] else 0.0
        print(f"  {ch:<24} {counts[ch]:6d} events  {rate:7.1f} Hz")

    for spec in a.expect:
        ch, _, n = spec.rpartition(":")
        if counts[ch] < int(n):
            fail(f"channel {ch}: {counts[ch]} events, expected more than {int(n) - 1}"
                 + (" (missing)" if counts[ch] == 0 else ""))
    for spec in a.rate:
        ch, lo, hi = spec.split(":")
        ts = stamps.get(ch, [])
        if len(ts) < 2:
            continue  # already reported as missing
        rate = (len(ts) - 1) / max((ts[-1] - ts[0]) / 1e6, 1e-9)
        if not float(lo) <= rate <= float(hi):
            fail(f"channel {ch}: {rate:.1f} Hz, expected {lo}..{hi} Hz")
    for ch, fps in sorted(fingerprints.items()):
        if ch.startswith("rtfuse/") and len(fps) != 1:
            fail(f"channel {ch}: {len(fps)} different type fingerprints")
    # header.seq of the outputs that start with a header_t: strictly increasing
    for ch in ("rtfuse/odometry", "rtfuse/pose", "rtfuse/state", "rtfuse/diagnostics"):
        seqs = []
        frames = set()
        for e in events:
            if e.channel != ch:
                continue
            seq, frame = header_seq(e.data)
            if seq is None:
                fail(f"{ch} event {e.eventnum}: no readable header_t")
                break
            seqs.append(seq)
            frames.add(frame)
        if len(seqs) > 1:
            bad = sum(1 for x, y in zip(seqs, seqs[1:]) if y <= x)
            gaps = sum(y - x - 1 for x, y in zip(seqs, seqs[1:]) if y > x + 1)
            print(f"  {ch}: header.seq {seqs[0]}..{seqs[-1]}, {gaps} lost, frame_id {sorted(frames)}")
            if bad:
                fail(f"{ch}: header.seq goes backwards or repeats {bad} times")
            if "" in frames and ch != "rtfuse/diagnostics":  # diagnostics: no frame, as in ROS
                fail(f"{ch}: empty header.frame_id")

    if a.rtfused_rc is not None:
        if a.rtfused_rc != 0:
            fail(f"rtfused exited with status {a.rtfused_rc}, expected 0")
    if a.rtfused_stdout:
        try:
            out = open(a.rtfused_stdout, encoding="utf-8", errors="replace").read()
        except OSError as e:
            out = ""
            fail(f"cannot read rtfused's output: {e}")
        check_rtfused_output(out)

    if failures:
        print(f"{len(failures)} check(s) failed")
        return 1
    print("OK")
    return 0


def check_rtfused_output(out):
    ran = re.search(r"rtfused: ran ([0-9.]+) s, (\d+) ticks, (\d+) overruns, (\d+) measurements fused", out)
    if not ran:
        fail("rtfused did not print its summary line ('rtfused: ran ...')")
    else:
        fused = int(ran.group(4))
        print(f"rtfused: {ran.group(0)[len('rtfused: '):]}")
        if fused == 0:
            fail("rtfused fused no measurements: the simulated robot's messages never "
                 "came back over UDP multicast")
    err = re.search(r"position error against ground truth: final (\S+) m, RMS (\S+) m over (\d+) samples", out)
    if not err:
        fail("rtfused did not print its final error line "
             "('position error against ground truth: final ... m, RMS ... m')")
        return
    final, rms = float(err.group(1)), float(err.group(2))
    print(f"rtfused: final error {final:.3f} m, RMS {rms:.3f} m")
    # A diverged filter, not a tuning question: the figure eight is a few metres wide.
    if not (math.isfinite(final) and math.isfinite(rms)) or rms > 10.0:
        fail(f"rtfused's position error is implausible (final {final} m, RMS {rms} m)")


def cmd_corrupt(a):
    events = read_log(a.log)
    victim = next((i for i, e in enumerate(events)
                   if e.channel == "rtfuse/tf" or (a.kind == "fingerprint" and e.channel.startswith("rtfuse/"))),
                  None)
    if victim is None:
        print("ERROR: no rtfuse/* event to damage")
        return 2
    with LogWriter(a.out) as w:
        for i, e in enumerate(events):
            data = e.data
            if i == victim:
                if a.kind == "fingerprint":
                    data = bytes([data[0] ^ 0xFF]) + data[1:]
                else:
                    data = data[:-4]
            w.write(e.channel, data, e.timestamp)
    print(f"damaged event {victim} ({events[victim].channel}): {a.kind}")
    return 0


def parse_report(path):
    rep = {"threads": [], "events": []}
    try:
        lines = open(path, encoding="utf-8", errors="replace").read().splitlines()
    except OSError as e:
        return None, str(e)
    if not lines or not lines[0].startswith("rtfuse_alloc_probe"):
        return None, "not an alloc_probe report"
    if lines[-1] != "end":
        return None, "report is incomplete (no 'end' line)"
    for line in lines[1:-1]:
        if line.startswith("thread "):
            rep["threads"].append(dict(kv.split("=", 1) for kv in line.split()[1:]))
        elif line.startswith("event "):
            ev = dict(kv.split("=", 1) for kv in line.split()[2:])
            ev["frames"] = []
            rep["events"].append(ev)
        elif line.startswith("  frame "):
            rep["events"][-1]["frames"].append(line.split()[1:])
        else:
            k, _, v = line.partition(" ")
            rep[k] = int(v)
    return rep, None


def split_frame(frame):
    """[pc, FILE+0xOFF, SYMBOL] -> (file, offset, symbol) or None."""
    if len(frame) < 2 or "+" not in frame[1]:
        return None
    path, _, off = frame[1].rpartition("+")
    return path, off, (frame[2] if len(frame) > 2 and frame[2] != "?" else "")


def symbolize_all(events):
    """{(file, offset): 'function at file:line'}: one addr2line run per file."""
    wanted = defaultdict(set)
    for ev in events:
        for f in ev["frames"]:
            sf = split_frame(f)
            if sf:
                wanted[sf[0]].add(sf[1])
    names = {}
    for path, offs in wanted.items():
        offs = sorted(offs)
        if not (shutil.which("addr2line") and os.path.exists(path)):
            continue
        try:
            out = subprocess.run(["addr2line", "-f", "-C", "-i", "-p", "-e", path] + offs,
                                 capture_output=True, text=True, timeout=60).stdout
        except (OSError, subprocess.SubprocessError):
            continue
        entries = []
        for line in out.splitlines():
            if line.startswith(" (inlined by) ") and entries:
                entries[-1] += "\n          (inlined by) " + line[len(" (inlined by) "):]
            else:
                entries.append(line)
        if len(entries) == len(offs):
            for off, text in zip(offs, entries):
                if not text.startswith("??"):
                    names[(path, off)] = text
    return names


def print_offenders(rep):
    for t in rep["threads"]:
        print(f"  thread {t.get('name')} (tid {t.get('tid')}): {t.get('allocations')} allocations, "
              f"{t.get('bytes')} bytes")
    names = symbolize_all(rep["events"])
    # The first allocations recorded, grouped by thread, function and call stack.
    groups = {}
    for ev in rep["events"]:
        key = (ev.get("name"), ev.get("fn"), tuple(f[1] if len(f) > 1 else f[0] for f in ev["frames"]))
        g = groups.setdefault(key, {"ev": ev, "n": 0, "sizes": []})
        g["n"] += 1
        g["sizes"].append(ev.get("size"))
    print(f"  call stacks of the first {len(rep['events'])} allocations:")
    for (thread, fn, _), g in groups.items():
        print(f"  {g['n']}x thread {thread}: {fn}(size {', '.join(sorted(set(g['sizes'])))})")
        for f in g["ev"]["frames"]:
            sf = split_frame(f)
            if not sf:
                print(f"      at {f[0]}")
                continue
            path, off, sym = sf
            text = names.get((path, off)) or f"{sym or '?'}"
            print(f"      at {text}  [{os.path.basename(path)}+{off}]")


def cmd_alloc(a):
    rep, err = parse_report(a.report)
    if rep is None:
        print(f"FAIL: no usable allocation report at {a.report}: {err}. Was the probe loaded "
              "(LD_PRELOAD) and did rtfused call rtfuse_alloc_probe_steady(1) and (0)? "
              "rtfused must be a PIE linked dynamically for its weak hook to bind to the probe.")
        return 1
    print(f"alloc_probe: armed {rep.get('armed_seen')}, {rep.get('startup_allocations')} allocations "
          f"during start-up, {rep.get('steady_allocations')} in steady state "
          f"({rep.get('steady_bytes')} bytes, {rep.get('steady_frees')} frees) "
          f"in {rep.get('threads_allocating')} thread(s)")
    if rep.get("armed_seen") != 1:
        fail("the probe was never armed")
    if not rep.get("startup_allocations"):
        fail("the probe saw no allocation at all during start-up: interposition is not working")

    if a.selftest:
        # alloc_probe_selftest: 3 mallocs + 1 calloc + 1 operator-new-free realloc in
        # thread 'probe-worker', 2 posix_memalign/aligned_alloc in the main thread.
        names = {t["name"]: int(t["allocations"]) for t in rep["threads"]}
        print_offenders(rep)
        if rep.get("steady_allocations") != 7:
            fail(f"self-test: expected 7 steady allocations, the probe counted {rep.get('steady_allocations')}")
        if names.get("probe-worker") != 5 or names.get("probe-main") != 2:
            fail(f"self-test: expected probe-worker=5 and probe-main=2, got {names}")
        if not any(ev["frames"] for ev in rep["events"]):
            fail("self-test: no call stack recorded")
        elif not any("selftest" in " ".join(f) or "worker" in " ".join(f)
                     for ev in rep["events"] for f in ev["frames"]):
            fail("self-test: no recorded call stack reaches the self-test's code")
    else:
        if rep.get("steady_allocations") != 0 or rep["threads"]:
            fail(f"{rep.get('steady_allocations')} heap allocation(s) in steady state "
                 "(rtfuse promises none once start-up is over); by thread and call stack:")
            print_offenders(rep)
    if a.rtfused_stdout:
        try:
            out = open(a.rtfused_stdout, encoding="utf-8", errors="replace").read()
        except OSError as e:
            out = ""
            fail(f"cannot read rtfused's output: {e}")
        # zero allocations only mean something if the daemon really worked
        check_rtfused_output(out)
    if failures:
        return 1
    print("OK")
    return 0


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = p.add_subparsers(dest="cmd", required=True)
    lg = sub.add_parser("log")
    lg.add_argument("log")
    lg.add_argument("--expect", action="append", default=[], metavar="CHANNEL:MIN")
    lg.add_argument("--rate", action="append", default=[], metavar="CHANNEL:LO:HI")
    lg.add_argument("--rtfused-rc", type=int)
    lg.add_argument("--rtfused-stdout")
    co = sub.add_parser("corrupt")
    co.add_argument("log")
    co.add_argument("out")
    co.add_argument("kind", choices=["fingerprint", "truncate"])
    al = sub.add_parser("alloc")
    al.add_argument("report")
    al.add_argument("--selftest", action="store_true")
    al.add_argument("--rtfused-stdout", help="also require rtfused's summary (it ran and fused data)")
    a = p.parse_args()
    return {"log": cmd_log, "corrupt": cmd_corrupt, "alloc": cmd_alloc}[a.cmd](a)


if __name__ == "__main__":
    sys.exit(main())
