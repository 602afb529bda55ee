#pragma once
// Real-time settings the OS may refuse (EPERM without CAP_SYS_NICE /
// CAP_IPC_LOCK): reported once, fatal only when the config demands them.
#include <pthread.h>

#include <string>

#include "runtime/config/config.hpp"

namespace rtfuse {

struct RealtimeOutcome {
  bool ok = true;          // every requested setting applied
  std::string warnings;    // one line per refused setting, with errno text and the fix
};

// Process-wide: mlockall. Call once before threads start.
RealtimeOutcome apply_memory_lock(const RealtimeConfig& rt);
// For the calling thread: SCHED_FIFO priority and CPU affinity.
RealtimeOutcome apply_thread_realtime(const RealtimeConfig& rt);
// For another thread of the process: `io_priority` (SCHED_FIFO), if set;
// `what` names the thread in the warning.
RealtimeOutcome apply_io_priority(const RealtimeConfig& rt, pthread_t thread, const char* what);
// The calling thread's nice value (Linux keeps one per thread): a worker
// that may fall behind (the mapper) yields to every other thread of the
// machine at its level. Raising it needs no privilege; a failure changes
// nothing that matters and is ignored.
void lower_this_thread(int nice_value);
// Names the calling thread (15 chars max) for top -H and debuggers.
void name_this_thread(const char* name);

}  // namespace rtfuse
