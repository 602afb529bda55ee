"""Tests of tools/rtfuse_tools/lcm_log.py, the pure-Python LCM log I/O."""

import io
import os
import shutil
import subprocess
import sys
import tempfile
import unittest
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(REPO / "tools"))

from rtfuse_tools import lcm_log  # noqa: E402
from rtfuse_tools.lcm_log import LcmLogError, LogReader, LogWriter  # noqa: E402

EVENTS = [
    ("rtfuse/odometry", b"\x01\x02\x03", 1_700_000_000_000_000),
    ("/imu/data", b"", 0),                        # empty payload is legal
    ("caf\u00e9/\u00fcber", bytes(range(256)) * 3, -5),  # UTF-8 channel, negative time
    ("x" * lcm_log.MAX_CHANNEL_LENGTH, b"\xff" * 10, 2**62),
]


def write_log(events):
    buf = io.BytesIO()
    with LogWriter(buf) as w:
        for ch, data, ts in events:
            w.write(ch, data, ts)
    return buf.getvalue()


class RoundTrip(unittest.TestCase):
    def test_round_trip(self):
        raw = write_log(EVENTS)
        got = list(LogReader(io.BytesIO(raw)))
        self.assertEqual(len(got), len(EVENTS))
        for i, (ev, (ch, data, ts)) in enumerate(zip(got, EVENTS)):
            self.assertEqual(ev.eventnum, i)
            self.assertEqual(ev.channel, ch)
            self.assertEqual(ev.data, data)
            self.assertEqual(ev.timestamp, ts)

    def test_file_round_trip(self):
        with tempfile.TemporaryDirectory() as d:
            path = Path(d) / "a.lcm"
            with LogWriter(path) as w:
                for ch, data, ts in EVENTS:
                    w.write(ch, data, ts)
            self.assertEqual(
                [(e.channel, e.data, e.timestamp) for e in lcm_log.read_events(path)],
                EVENTS)

    def test_byte_layout(self):
        # Spelled out by hand so the test does not just mirror the writer.
        raw = write_log([("AB", b"xyz", 0x0102030405060708)])
        expected = (bytes.fromhex("EDA1DA01")
                    + bytes.fromhex("0000000000000000")   # event number 0
                    + bytes.fromhex("0102030405060708")   # timestamp
                    + bytes.fromhex("00000002")           # channel length
                    + bytes.fromhex("00000003")           # data length
                    + b"AB" + b"xyz")                     # no NUL after channel
        self.assertEqual(raw, expected)
        self.assertEqual(lcm_log.HEADER_SIZE, 28)

    def test_event_numbers_count_up(self):
        raw = write_log([("c", b"", t) for t in range(5)])
        self.assertEqual([e.eventnum for e in LogReader(io.BytesIO(raw))],
                         list(range(5)))

    def test_writer_rejects_bad_channels(self):
        w = LogWriter(io.BytesIO())
        with self.assertRaises(ValueError):
            w.write("", b"", 0)
        with self.assertRaisesRegex(ValueError, "at most 63"):
            w.write("y" * 64, b"", 0)


class Corrupt(unittest.TestCase):
    def setUp(self):
        self.raw = write_log(EVENTS[:2])
        # event 1 starts after event 0's header, channel and data
        self.second = lcm_log.HEADER_SIZE + len(EVENTS[0][0]) + len(EVENTS[0][1])

    def check_truncated(self, cut, what):
        data = self.raw[:cut]
        with self.assertRaises(LcmLogError) as cm:
            list(LogReader(io.BytesIO(data)))
        msg = str(cm.exception)
        self.assertIn("truncated event 1", msg)
        self.assertIn(f"offset {self.second}", msg)
        self.assertIn(what, msg)
        # The tolerant mode returns what is complete and says it stopped early.
        r = LogReader(io.BytesIO(data), allow_truncated_tail=True)
        got = list(r)
        self.assertEqual([e.channel for e in got], [EVENTS[0][0]])
        self.assertTrue(r.truncated)

    def test_truncated_header(self):
        self.check_truncated(self.second + 10, "header")

    def test_truncated_channel(self):
        self.check_truncated(self.second + lcm_log.HEADER_SIZE + 3, "channel")

    def test_truncated_data(self):
        # event 1 has empty data, so cut into a longer event instead
        raw = write_log([EVENTS[0], EVENTS[2]])
        cut = self.second + lcm_log.HEADER_SIZE + len(EVENTS[2][0].encode()) + 5
        with self.assertRaisesRegex(LcmLogError,
                                    rf"truncated event 1 at byte offset {self.second}.*data"):
            list(LogReader(io.BytesIO(raw[:cut])))

    def test_bad_sync(self):
        raw = bytearray(self.raw)
        raw[self.second] ^= 0xFF
        with self.assertRaisesRegex(LcmLogError, rf"event 1 at byte offset {self.second}.*sync"):
            list(LogReader(io.BytesIO(bytes(raw))))

    def test_not_a_log(self):
        with self.assertRaisesRegex(LcmLogError, "sync"):
            list(LogReader(io.BytesIO(b"#ROSBAG V2.0\n" + b"\0" * 40)))

    def test_empty_file_has_no_events(self):
        self.assertEqual(list(LogReader(io.BytesIO(b""))), [])


# The C program uses LCM's own eventlog code to write one log and read ours,
# which proves compatibility with lcm-logger/lcm-logplayer, not just that the
# Python writer and reader agree with each other.
C_PROGRAM = r"""
#include <lcm/lcm.h>
#include <stdio.h>
#include <string.h>
int main(int argc, char **argv) {
  if (argc == 3 && strcmp(argv[1], "write") == 0) {
    lcm_eventlog_t *log = lcm_eventlog_create(argv[2], "w");
    if (!log) return 1;
    for (int i = 0; i < 3; ++i) {
      char chan[32]; unsigned char data[5] = {1, 2, 3, 4, (unsigned char)i};
      snprintf(chan, sizeof chan, "chan/%d", i);
      lcm_eventlog_event_t ev;
      ev.eventnum = 0; ev.timestamp = 1000000 + i; ev.channel = chan;
      ev.channellen = (int32_t)strlen(chan); ev.data = data; ev.datalen = 2 + i;
      if (lcm_eventlog_write_event(log, &ev) != 0) return 1;
    }
    lcm_eventlog_destroy(log);
    return 0;
  }
  if (argc == 3 && strcmp(argv[1], "read") == 0) {
    lcm_eventlog_t *log = lcm_eventlog_create(argv[2], "r");
    if (!log) return 1;
    lcm_eventlog_event_t *ev;
    while ((ev = lcm_eventlog_read_next_event(log)) != NULL) {
      printf("%lld %lld %s ", (long long)ev->eventnum, (long long)ev->timestamp, ev->channel);
      for (int i = 0; i < ev->datalen; ++i) printf("%02x", ((unsigned char *)ev->data)[i]);
      printf("\n");
      lcm_eventlog_free_event(ev);
    }
    lcm_eventlog_destroy(log);
    return 0;
  }
  return 2;
}
"""


def _build_c_helper(d):
    cc = shutil.which("cc") or shutil.which("gcc")
    if not cc or not shutil.which("pkg-config"):
        return None
    flags = subprocess.run(["pkg-config", "--cflags", "--libs", "lcm"],
                           capture_output=True, text=True)
    if flags.returncode != 0:
        return None
    src = Path(d) / "lcmlog_check.c"
    exe = Path(d) / "lcmlog_check"
    src.write_text(C_PROGRAM)
    proc = subprocess.run([cc, str(src), "-o", str(exe)] + flags.stdout.split(),
                          capture_output=True, text=True)
    if proc.returncode != 0:
        raise AssertionError(f"compiling the LCM check failed:\n{proc.stderr}")
    return exe


class AgainstLibLcm(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.tmp = tempfile.TemporaryDirectory()
        cls.exe = _build_c_helper(cls.tmp.name)

    @classmethod
    def tearDownClass(cls):
        cls.tmp.cleanup()

    def setUp(self):
        if self.exe is None:
            self.skipTest("no C compiler or liblcm-dev (pkg-config lcm): "
                          "cannot cross-check against LCM's own eventlog code")

    def test_liblcm_reads_our_log(self):
        path = Path(self.tmp.name) / "ours.lcm"
        with LogWriter(path) as w:
            for ch, data, ts in EVENTS:
                w.write(ch, data, ts)
        out = subprocess.run([str(self.exe), "read", str(path)],
                             capture_output=True, text=True, check=True).stdout
        expected = "".join(f"{i} {ts} {ch} {data.hex()}\n"
                           for i, (ch, data, ts) in enumerate(EVENTS))
        self.assertEqual(out, expected)

    def test_we_read_liblcm_log(self):
        path = Path(self.tmp.name) / "theirs.lcm"
        subprocess.run([str(self.exe), "write", str(path)], check=True)
        got = lcm_log.read_events(path)
        self.assertEqual([(e.eventnum, e.timestamp, e.channel, e.data) for e in got],
                         [(i, 1000000 + i, f"chan/{i}", bytes([1, 2, 3, 4, i])[:2 + i])
                          for i in range(3)])


class LcmTypesPath(unittest.TestCase):
    """tools/rtfuse_tools/lcmtypes_path.py: where the generated types come from."""

    def setUp(self):
        from rtfuse_tools import lcmtypes_path
        self.mod = lcmtypes_path
        self._tmp = tempfile.TemporaryDirectory()
        self.tmp = Path(self._tmp.name)
        self._env = os.environ.get(lcmtypes_path.ENV_VAR)

    def tearDown(self):
        if self._env is None:
            os.environ.pop(self.mod.ENV_VAR, None)
        else:
            os.environ[self.mod.ENV_VAR] = self._env
        self._tmp.cleanup()

    def test_wrong_env_is_an_error_not_a_fallback(self):
        os.environ[self.mod.ENV_VAR] = str(self.tmp)
        with self.assertRaisesRegex(self.mod.LcmTypesError, self.mod.ENV_VAR):
            self.mod.find_lcmtypes_python()

    def test_env_wins(self):
        (self.tmp / "rtfuse").mkdir()
        (self.tmp / "rtfuse" / "__init__.py").write_text("")
        os.environ[self.mod.ENV_VAR] = str(self.tmp)
        self.assertEqual(self.mod.find_lcmtypes_python(), self.tmp)

    def test_generate_into_cache(self):
        if shutil.which("lcm-gen") is None:
            self.skipTest("lcm-gen missing (apt-get install liblcm-bin)")
        cache = self.tmp / "cache"
        d = self.mod.generate(REPO / "lcmtypes", cache_root=cache)
        self.assertTrue((d / "rtfuse" / "imu_t.py").is_file())
        self.assertEqual(self.mod.generate(REPO / "lcmtypes", cache_root=cache), d)
        self.assertEqual([p.name for p in cache.iterdir()], [d.name])  # no temp left

    def test_missing_lcm_gen_is_explained(self):
        path = os.environ.get("PATH", "")
        os.environ["PATH"] = str(self.tmp)
        try:
            with self.assertRaisesRegex(self.mod.LcmTypesError, "liblcm-bin"):
                self.mod.generate(REPO / "lcmtypes", cache_root=self.tmp / "c")
        finally:
            os.environ["PATH"] = path


if __name__ == "__main__":
    unittest.main()
