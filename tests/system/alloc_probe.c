/* alloc_probe: an LD_PRELOAD allocation counter for the system test
 * system.zero_alloc.
 *
 * It interposes the allocation functions of the C library (operator new and
 * the rest of libstdc++ end up in malloc, so C++ allocations are caught too)
 * and defines rtfuse_alloc_probe_steady(), the weak hook rtfused calls with 1
 * once start-up is over and with 0 before shutdown. While armed, every
 * allocation is counted per thread; the first few are recorded with the
 * thread's name, the function, the size and a short call stack (program
 * counters only, taken with _Unwind_Backtrace; no backtrace(), no stdio).
 * steady(0) disarms and writes the report to $RTFUSE_ALLOC_REPORT with
 * write(2).
 *
 * Rules inside the hooks: no stdio, no locks, no allocation. The real
 * functions are found with dlsym(RTLD_NEXT, ...); dlsym itself may call
 * calloc/malloc, which is served from a static bootstrap buffer while the
 * lookup runs (free() recognises and ignores those blocks).
 *
 * Report (text, one item per line):
 *   rtfuse_alloc_probe 1
 *   armed_seen 1
 *   startup_allocations N        (before steady(1): proves interposition works)
 *   steady_allocations N         (the number the test asserts is 0)
 *   steady_bytes N
 *   steady_frees N
 *   threads_allocating N
 *   thread tid=T name=NAME allocations=N bytes=N
 *   event K tid=T name=NAME fn=malloc size=N
 *     frame 0x... FILE+0xOFFSET SYMBOL
 *   end
 */
#define _GNU_SOURCE
#include <dlfcn.h>
#include <errno.h>
#include <fcntl.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <sys/prctl.h>
#include <sys/syscall.h>
#include <unistd.h>
#include <unwind.h>

#define EXPORT __attribute__((visibility("default")))
#define TLS __thread __attribute__((tls_model("initial-exec")))

/* ---- the real functions ------------------------------------------------ */

typedef void* (*malloc_fn)(size_t);
typedef void* (*calloc_fn)(size_t, size_t);
typedef void* (*realloc_fn)(void*, size_t);
typedef void* (*reallocarray_fn)(void*, size_t, size_t);
typedef void (*free_fn)(void*);
typedef void* (*aligned_alloc_fn)(size_t, size_t);
typedef int (*posix_memalign_fn)(void**, size_t, size_t);
typedef void* (*memalign_fn)(size_t, size_t);
typedef void* (*valloc_fn)(size_t);

static malloc_fn real_malloc;
static calloc_fn real_calloc;
static realloc_fn real_realloc;
static reallocarray_fn real_reallocarray;
static free_fn real_free;
static aligned_alloc_fn real_aligned_alloc;
static posix_memalign_fn real_posix_memalign;
static memalign_fn real_memalign;
static valloc_fn real_valloc;
static valloc_fn real_pvalloc;

/* dlsym returns void*; ISO C has no object-to-function pointer conversion,
 * so copy the bits (POSIX guarantees they are the same). */
#define RESOLVE(var, name)                   \
  do {                                       \
    void* sym_ = dlsym(RTLD_NEXT, name);     \
    memcpy(&(var), &sym_, sizeof(sym_));     \
  } while (0)

/* ---- bootstrap buffer for allocations made by dlsym itself -------------- */

static _Alignas(64) unsigned char bootstrap[64 * 1024];
static size_t bootstrap_used; /* only touched while initialising (one thread) */
static volatile int initialising;
static volatile int initialised;

static int in_bootstrap(const void* p) {
  return (const unsigned char*)p >= bootstrap && (const unsigned char*)p < bootstrap + sizeof(bootstrap);
}

static void* bootstrap_alloc(size_t size, size_t align) {
  if (align < 16) align = 16;
  size_t start = (bootstrap_used + align - 1) & ~(align - 1);
  /* keep the size just before the block so realloc can copy it */
  start += align;
  if (start + size > sizeof(bootstrap)) return NULL;
  memcpy(bootstrap + start - sizeof(size_t), &size, sizeof(size_t));
  bootstrap_used = start + size;
  return bootstrap + start; /* static storage: already zeroed */
}

static size_t bootstrap_size(const void* p) {
  size_t n;
  memcpy(&n, (const unsigned char*)p - sizeof(size_t), sizeof(size_t));
  return n;
}

static void init(void) {
  if (initialised || initialising) return;
  initialising = 1;
  RESOLVE(real_malloc, "malloc");
  RESOLVE(real_calloc, "calloc");
  RESOLVE(real_realloc, "realloc");
  RESOLVE(real_reallocarray, "reallocarray");
  RESOLVE(real_free, "free");
  RESOLVE(real_aligned_alloc, "aligned_alloc");
  RESOLVE(real_posix_memalign, "posix_memalign");
  RESOLVE(real_memalign, "memalign");
  RESOLVE(real_valloc, "valloc");
  RESOLVE(real_pvalloc, "pvalloc");
  if (!real_malloc || !real_calloc || !real_realloc || !real_free) {
    static const char msg[] = "alloc_probe: dlsym(RTLD_NEXT) failed to find malloc/calloc/realloc/free\n";
    (void)!write(2, msg, sizeof(msg) - 1);
    _exit(127);
  }
  initialising = 0;
  initialised = 1;
}

__attribute__((constructor)) static void probe_constructor(void) { init(); }

/* ---- counting ------------------------------------------------------------ */

#define MAX_THREADS 64
#define MAX_EVENTS 16
#define MAX_FRAMES 12

struct thread_slot {
  int tid; /* 0: free; claimed with a CAS */
  char name[16];
  unsigned long allocations;
  unsigned long bytes;
};

struct event {
  int tid;
  char name[16];
  const char* fn;
  size_t size;
  int nframes;
  uintptr_t frames[MAX_FRAMES];
};

static int armed;      /* 1 between steady(1) and steady(0) */
static int armed_seen; /* steady(1) was called at least once */
static int unwind_enabled = 1;
static unsigned long startup_allocations;
static unsigned long steady_allocations;
static unsigned long steady_bytes;
static unsigned long steady_frees;
static unsigned long overflow_allocations; /* threads beyond MAX_THREADS */
static struct thread_slot threads[MAX_THREADS];
static struct event events[MAX_EVENTS];
static unsigned events_claimed;

static TLS int my_tid;
static TLS int in_hook; /* recursion guard: the probe's own calls are not counted */

static int current_tid(void) {
  if (!my_tid) my_tid = (int)syscall(SYS_gettid);
  return my_tid;
}

static struct thread_slot* slot_for(int tid) {
  for (int i = 0; i < MAX_THREADS; ++i) {
    int t = __atomic_load_n(&threads[i].tid, __ATOMIC_ACQUIRE);
    if (t == tid) return &threads[i];
    if (t == 0) {
      int expected = 0;
      if (__atomic_compare_exchange_n(&threads[i].tid, &expected, tid, 0, __ATOMIC_ACQ_REL, __ATOMIC_ACQUIRE)) {
        char name[16] = {0};
        prctl(PR_GET_NAME, (unsigned long)name, 0, 0, 0);
        memcpy(threads[i].name, name, sizeof(name));
        return &threads[i];
      }
      if (expected == tid) return &threads[i];
    }
  }
  return NULL;
}

struct unwind_state {
  uintptr_t* frames;
  int n;
  int skip;
};

static _Unwind_Reason_Code unwind_one(struct _Unwind_Context* ctx, void* arg) {
  struct unwind_state* st = (struct unwind_state*)arg;
  uintptr_t pc = (uintptr_t)_Unwind_GetIP(ctx);
  if (!pc) return _URC_END_OF_STACK;
  if (st->skip > 0) {
    --st->skip;
    return _URC_NO_REASON;
  }
  st->frames[st->n++] = pc;
  return st->n >= MAX_FRAMES ? _URC_END_OF_STACK : _URC_NO_REASON;
}

/* noinline: the unwinder skips exactly this frame and the hook's */
__attribute__((noinline)) static void count(const char* fn, size_t size) {
  if (in_hook) return;
  if (!__atomic_load_n(&armed, __ATOMIC_ACQUIRE)) {
    __atomic_add_fetch(&startup_allocations, 1, __ATOMIC_RELAXED);
    return;
  }
  in_hook = 1;
  __atomic_add_fetch(&steady_allocations, 1, __ATOMIC_RELAXED);
  __atomic_add_fetch(&steady_bytes, size, __ATOMIC_RELAXED);
  const int tid = current_tid();
  struct thread_slot* slot = slot_for(tid);
  if (slot) {
    __atomic_add_fetch(&slot->allocations, 1, __ATOMIC_RELAXED);
    __atomic_add_fetch(&slot->bytes, size, __ATOMIC_RELAXED);
  } else {
    __atomic_add_fetch(&overflow_allocations, 1, __ATOMIC_RELAXED);
  }
  const unsigned k = __atomic_fetch_add(&events_claimed, 1, __ATOMIC_RELAXED);
  if (k < MAX_EVENTS) {
    struct event* e = &events[k];
    e->tid = tid;
    prctl(PR_GET_NAME, (unsigned long)e->name, 0, 0, 0);
    e->fn = fn;
    e->size = size;
    if (unwind_enabled) {
      /* skip unwind_one's caller chain inside the probe: count() and the hook */
      struct unwind_state st = {e->frames, 0, 2};
      _Unwind_Backtrace(unwind_one, &st);
      e->nframes = st.n;
    }
  }
  in_hook = 0;
}

/* ---- the interposed functions ------------------------------------------- */

EXPORT void* malloc(size_t size) {
  if (!real_malloc) {
    if (initialising) return bootstrap_alloc(size, 16);
    init();
  }
  count("malloc", size);
  return real_malloc(size);
}

EXPORT void* calloc(size_t n, size_t size) {
  if (!real_calloc) {
    /* dlsym's own calloc during init: static memory is already zero */
    if (initialising) return (size && n > SIZE_MAX / size) ? NULL : bootstrap_alloc(n * size, 16);
    init();
  }
  count("calloc", n * size);
  return real_calloc(n, size);
}

EXPORT void* realloc(void* p, size_t size) {
  if (p && in_bootstrap(p)) {
    /* never returned to the real allocator: copy out (or stay in bootstrap) */
    const size_t old = bootstrap_size(p);
    void* q = real_malloc ? real_malloc(size) : bootstrap_alloc(size, 16);
    if (q) memcpy(q, p, old < size ? old : size);
    return q;
  }
  if (!real_realloc) {
    if (initialising) return bootstrap_alloc(size, 16);
    init();
  }
  if (size) count("realloc", size);
  return real_realloc(p, size);
}

EXPORT void* reallocarray(void* p, size_t n, size_t size) {
  if (size && n > SIZE_MAX / size) {
    errno = ENOMEM;
    return NULL;
  }
  if ((p && in_bootstrap(p)) || !real_reallocarray) return realloc(p, n * size);
  if (n != 0 && size != 0) count("reallocarray", n * size);
  return real_reallocarray(p, n, size);
}

EXPORT void free(void* p) {
  if (!p || in_bootstrap(p)) return;
  if (!real_free) init();
  if (!real_free) return; /* only during dlsym's own bootstrap: leak it */
  if (__atomic_load_n(&armed, __ATOMIC_RELAXED) && !in_hook) __atomic_add_fetch(&steady_frees, 1, __ATOMIC_RELAXED);
  real_free(p);
}

EXPORT void* aligned_alloc(size_t align, size_t size) {
  if (!real_aligned_alloc) {
    if (initialising) return bootstrap_alloc(size, align);
    init();
  }
  count("aligned_alloc", size);
  return real_aligned_alloc(align, size);
}

EXPORT int posix_memalign(void** out, size_t align, size_t size) {
  if (!real_posix_memalign) {
    if (initialising) {
      *out = bootstrap_alloc(size, align);
      return *out ? 0 : ENOMEM;
    }
    init();
  }
  count("posix_memalign", size);
  return real_posix_memalign(out, align, size);
}

EXPORT void* memalign(size_t align, size_t size) {
  if (!real_memalign) {
    if (initialising) return bootstrap_alloc(size, align);
    init();
  }
  count("memalign", size);
  return real_memalign(align, size);
}

EXPORT void* valloc(size_t size) {
  if (!real_valloc) {
    if (initialising) return bootstrap_alloc(size, 4096);
    init();
  }
  count("valloc", size);
  return real_valloc(size);
}

EXPORT void* pvalloc(size_t size) {
  if (!real_pvalloc) {
    if (initialising) return bootstrap_alloc(size, 4096);
    init();
  }
  count("pvalloc", size);
  return real_pvalloc(size);
}

/* ---- the report ------------------------------------------------------------ */

struct out {
  int fd;
  char buf[4096];
  size_t n;
};

static void out_flush(struct out* o) {
  size_t off = 0;
  while (off < o->n) {
    ssize_t w = write(o->fd, o->buf + off, o->n - off);
    if (w < 0) {
      if (errno == EINTR) continue;
      break;
    }
    off += (size_t)w;
  }
  o->n = 0;
}

static void out_str(struct out* o, const char* s) {
  while (*s) {
    if (o->n == sizeof(o->buf)) out_flush(o);
    o->buf[o->n++] = *s++;
  }
}

static void out_name(struct out* o, const char* name16) {
  /* thread names: at most 15 characters; keep the report one-token-per-field */
  char tmp[17];
  size_t i = 0;
  for (; i < 16 && name16[i]; ++i) tmp[i] = (name16[i] == ' ' || name16[i] == '\n') ? '_' : name16[i];
  if (i == 0) tmp[i++] = '?';
  tmp[i] = 0;
  out_str(o, tmp);
}

static void out_uint(struct out* o, unsigned long v) {
  char tmp[24];
  int i = (int)sizeof(tmp) - 1;
  tmp[i] = 0;
  do {
    tmp[--i] = (char)('0' + v % 10);
    v /= 10;
  } while (v);
  out_str(o, tmp + i);
}

static void out_hex(struct out* o, uintptr_t v) {
  static const char digits[] = "0123456789abcdef";
  char tmp[24];
  int i = (int)sizeof(tmp) - 1;
  tmp[i] = 0;
  do {
    tmp[--i] = digits[v & 15];
    v >>= 4;
  } while (v);
  tmp[--i] = 'x';
  tmp[--i] = '0';
  out_str(o, tmp + i);
}

static void write_report(const char* path) {
  struct out o;
  o.fd = open(path, O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  o.n = 0;
  if (o.fd < 0) {
    static const char msg[] = "alloc_probe: cannot open RTFUSE_ALLOC_REPORT for writing\n";
    (void)!write(2, msg, sizeof(msg) - 1);
    return;
  }
  out_str(&o, "rtfuse_alloc_probe 1\narmed_seen ");
  out_uint(&o, (unsigned long)armed_seen);
  out_str(&o, "\nstartup_allocations ");
  out_uint(&o, __atomic_load_n(&startup_allocations, __ATOMIC_RELAXED));
  out_str(&o, "\nsteady_allocations ");
  out_uint(&o, __atomic_load_n(&steady_allocations, __ATOMIC_RELAXED));
  out_str(&o, "\nsteady_bytes ");
  out_uint(&o, __atomic_load_n(&steady_bytes, __ATOMIC_RELAXED));
  out_str(&o, "\nsteady_frees ");
  out_uint(&o, __atomic_load_n(&steady_frees, __ATOMIC_RELAXED));
  out_str(&o, "\noverflow_allocations ");
  out_uint(&o, __atomic_load_n(&overflow_allocations, __ATOMIC_RELAXED));
  unsigned long nthreads = 0;
  for (int i = 0; i < MAX_THREADS; ++i)
    if (__atomic_load_n(&threads[i].tid, __ATOMIC_ACQUIRE)) ++nthreads;
  out_str(&o, "\nthreads_allocating ");
  out_uint(&o, nthreads);
  out_str(&o, "\n");
  for (int i = 0; i < MAX_THREADS; ++i) {
    const struct thread_slot* t = &threads[i];
    if (!t->tid) continue;
    out_str(&o, "thread tid=");
    out_uint(&o, (unsigned long)t->tid);
    out_str(&o, " name=");
    out_name(&o, t->name);
    out_str(&o, " allocations=");
    out_uint(&o, t->allocations);
    out_str(&o, " bytes=");
    out_uint(&o, t->bytes);
    out_str(&o, "\n");
  }
  unsigned nev = __atomic_load_n(&events_claimed, __ATOMIC_RELAXED);
  if (nev > MAX_EVENTS) nev = MAX_EVENTS;
  for (unsigned k = 0; k < nev; ++k) {
    const struct event* e = &events[k];
    out_str(&o, "event ");
    out_uint(&o, k);
    out_str(&o, " tid=");
    out_uint(&o, (unsigned long)e->tid);
    out_str(&o, " name=");
    out_name(&o, e->name);
    out_str(&o, " fn=");
    out_str(&o, e->fn ? e->fn : "?");
    out_str(&o, " size=");
    out_uint(&o, e->size);
    out_str(&o, "\n");
    for (int f = 0; f < e->nframes; ++f) {
      /* return addresses point after the call: report pc-1 so addr2line
       * names the calling line */
      const uintptr_t pc = e->frames[f] - 1;
      Dl_info info;
      out_str(&o, "  frame ");
      out_hex(&o, pc);
      if (dladdr((void*)pc, &info) && info.dli_fname) {
        out_str(&o, " ");
        out_str(&o, info.dli_fname[0] ? info.dli_fname : "?");
        out_str(&o, "+");
        out_hex(&o, pc - (uintptr_t)info.dli_fbase);
        out_str(&o, " ");
        out_str(&o, info.dli_sname ? info.dli_sname : "?");
      }
      out_str(&o, "\n");
    }
  }
  out_str(&o, "end\n");
  out_flush(&o);
  close(o.fd);
}

EXPORT void rtfuse_alloc_probe_steady(int steady) {
  if (!initialised) init();
  if (steady) {
    const char* no_unwind = getenv("RTFUSE_ALLOC_PROBE_NO_UNWIND");
    unwind_enabled = !(no_unwind && no_unwind[0] == '1');
    armed_seen = 1;
    __atomic_store_n(&armed, 1, __ATOMIC_RELEASE);
    return;
  }
  __atomic_store_n(&armed, 0, __ATOMIC_RELEASE);
  const char* path = getenv("RTFUSE_ALLOC_REPORT");
  if (path && path[0]) {
    in_hook = 1; /* dladdr and open may allocate; they are the probe's own */
    write_report(path);
    in_hook = 0;
  }
}
