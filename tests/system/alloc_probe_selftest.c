/* alloc_probe_selftest: a known allocation pattern for alloc_probe, so that
 * system.zero_alloc proves the probe can see allocations (per thread, with
 * names and stacks) before it trusts a report of zero from rtfused.
 *
 * Armed window: thread "probe-worker" makes 5 allocations (3 malloc, 1 calloc,
 * 1 realloc from NULL), thread "probe-main" makes 2 (posix_memalign,
 * aligned_alloc). Threads are created before arming: pthread_create allocates. */
#define _GNU_SOURCE
#include <pthread.h>
#include <stdlib.h>
#include <sys/prctl.h>
#include <unistd.h>

extern void rtfuse_alloc_probe_steady(int steady) __attribute__((weak));

static void* volatile sink[16];
static int go[2], done[2];

static void* worker(void* arg) {
  (void)arg;
  char c;
  prctl(PR_SET_NAME, (unsigned long)"probe-worker", 0, 0, 0);
  if (read(go[0], &c, 1) != 1) return NULL;
  sink[0] = malloc(24);
  sink[1] = malloc(100);
  sink[2] = malloc(4000);
  sink[3] = calloc(4, 8);
  sink[4] = realloc(NULL, 64);
  if (write(done[1], "x", 1) != 1) return NULL;
  return NULL;
}

int main(void) {
  static const char no_probe[] = "alloc_probe_selftest: rtfuse_alloc_probe_steady is unresolved (LD_PRELOAD the probe)\n";
  if (!rtfuse_alloc_probe_steady) {
    (void)!write(2, no_probe, sizeof(no_probe) - 1);
    return 1;
  }
  prctl(PR_SET_NAME, (unsigned long)"probe-main", 0, 0, 0);
  if (pipe(go) != 0 || pipe(done) != 0) return 1;
  sink[8] = malloc(10); /* start-up allocation */
  pthread_t t;
  if (pthread_create(&t, NULL, worker, NULL) != 0) return 1;

  rtfuse_alloc_probe_steady(1);
  char c;
  if (write(go[1], "x", 1) != 1 || read(done[0], &c, 1) != 1) return 1;
  void* p = NULL;
  if (posix_memalign(&p, 64, 256) != 0) return 1;
  sink[5] = p;
  sink[6] = aligned_alloc(64, 128);
  rtfuse_alloc_probe_steady(0);

  pthread_join(t, NULL);
  for (int i = 0; i < 16; ++i) free(sink[i]);
  return 0;
}
