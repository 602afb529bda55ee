"""tools/check-target-abi.sh on binaries built here with known glibc needs.

Debian 12's glibc is 2.36: a program calling pthread_create needs
GLIBC_2.34 (where libpthread moved into libc), which a JetPack 4.6 board
(glibc 2.27) does not have; a static one needs nothing from the target.
"""
import os
import shutil
import subprocess
import tempfile
import unittest

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..")
SCRIPT = os.path.join(ROOT, "tools", "check-target-abi.sh")
PROGRAM = r"""
#include <pthread.h>
#include <stdio.h>
static void* run(void* arg) { return arg; }
int main(void) {
  pthread_t t;
  if (pthread_create(&t, NULL, run, NULL) != 0) return 1;
  pthread_join(t, NULL);
  puts("ok");
  return 0;
}
"""


@unittest.skipUnless(shutil.which("gcc") and shutil.which("readelf"), "needs gcc and readelf (binutils)")
class CheckTargetAbi(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.tmp = tempfile.mkdtemp()
        src = os.path.join(cls.tmp, "prog.c")
        with open(src, "w") as f:
            f.write(PROGRAM)
        cls.dynamic = os.path.join(cls.tmp, "dynamic")
        cls.static = os.path.join(cls.tmp, "static")
        subprocess.run(["gcc", "-O1", "-pthread", src, "-o", cls.dynamic], check=True)
        subprocess.run(["gcc", "-O1", "-static", "-pthread", src, "-o", cls.static], check=True)

    @classmethod
    def tearDownClass(cls):
        shutil.rmtree(cls.tmp)

    def check(self, *args):
        return subprocess.run(["bash", SCRIPT, *args], capture_output=True, text=True)

    def test_newer_glibc_symbols_are_listed_and_fail(self):
        p = self.check(self.dynamic, "--glibc", "2.27")
        self.assertEqual(p.returncode, 1, p.stdout + p.stderr)
        self.assertIn("GLIBC_2.34: ", p.stdout)
        self.assertIn("pthread_create", p.stdout)
        self.assertIn("newer than the target (glibc 2.27)", p.stdout)
        self.assertIn("sysroot", p.stderr)

    def test_a_target_with_this_glibc_passes(self):
        p = self.check(self.dynamic, "--glibc", "2.36")
        self.assertEqual(p.returncode, 0, p.stdout + p.stderr)
        self.assertIn("OK, no symbol newer than glibc 2.36", p.stdout)

    def test_a_static_binary_needs_nothing_from_the_target(self):
        p = self.check(self.static, "--glibc", "2.17")
        self.assertEqual(p.returncode, 0, p.stdout + p.stderr)

    def test_several_binaries_fail_if_one_does(self):
        p = self.check(self.static, self.dynamic, "--glibc", "2.27")
        self.assertEqual(p.returncode, 1)
        self.assertIn("static", p.stdout)
        self.assertIn("dynamic", p.stdout)

    def test_bad_input_is_a_usage_error_with_a_reason(self):
        text = os.path.join(self.tmp, "notes.txt")
        with open(text, "w") as f:
            f.write("not a program\n")
        for args, reason in (([text, "--glibc", "2.27"], "not an ELF file"),
                             ([os.path.join(self.tmp, "missing"), "--glibc", "2.27"], "no such file"),
                             ([self.dynamic], "usage:"),
                             ([self.dynamic, "--glibc", "two"], "is not a version")):
            p = self.check(*args)
            self.assertEqual(p.returncode, 2, args)
            self.assertIn(reason, p.stderr, args)


if __name__ == "__main__":
    unittest.main()
