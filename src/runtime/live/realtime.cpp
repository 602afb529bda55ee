#include "runtime/live/realtime.hpp"

#include <pthread.h>
#include <sched.h>
#include <sys/mman.h>
#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

namespace rtfuse {

RealtimeOutcome apply_memory_lock(const RealtimeConfig& rt) {
  RealtimeOutcome out;
  if (!rt.lock_memory) return out;
  if (mlockall(MCL_CURRENT | MCL_FUTURE) != 0) {
    const int e = errno;
    out.ok = false;
    out.warnings = std::string("realtime.lock_memory: mlockall failed: ") + std::strerror(e) +
                   " (grant CAP_IPC_LOCK or raise the memlock limit: ulimit -l unlimited / LimitMEMLOCK=infinity)\n";
  }
  return out;
}

RealtimeOutcome apply_thread_realtime(const RealtimeConfig& rt) {
  RealtimeOutcome out;
  if (rt.priority > 0) {
    sched_param sp{};
    sp.sched_priority = rt.priority;
    const int e = pthread_setschedparam(pthread_self(), SCHED_FIFO, &sp);
    if (e != 0) {
      out.ok = false;
      out.warnings += std::string("realtime.priority: SCHED_FIFO ") + std::to_string(rt.priority) +
                      " refused: " + std::strerror(e) +
                      " (run as root, grant CAP_SYS_NICE, or raise RLIMIT_RTPRIO: LimitRTPRIO=" +
                      std::to_string(rt.priority) + ")\n";
    }
  }
  if (rt.cpu >= 0) {
    cpu_set_t set;
    CPU_ZERO(&set);
    CPU_SET(rt.cpu, &set);
    const int e = pthread_setaffinity_np(pthread_self(), sizeof(set), &set);
    if (e != 0) {
      out.ok = false;
      out.warnings += std::string("realtime.cpu: pinning to CPU ") + std::to_string(rt.cpu) +
                      " refused: " + std::strerror(e) + " (is that CPU online and in this cgroup's cpuset?)\n";
    }
  }
  return out;
}

RealtimeOutcome apply_io_priority(const RealtimeConfig& rt, pthread_t thread, const char* what) {
  RealtimeOutcome out;
  if (rt.io_priority <= 0) return out;
  sched_param sp{};
  sp.sched_priority = rt.io_priority;
  const int e = pthread_setschedparam(thread, SCHED_FIFO, &sp);
  if (e != 0) {
    out.ok = false;
    out.warnings = std::string("realtime.io_priority: SCHED_FIFO ") + std::to_string(rt.io_priority) + " for " +
                   what + " refused: " + std::strerror(e) +
                   " (run as root, grant CAP_SYS_NICE, or raise RLIMIT_RTPRIO: LimitRTPRIO=" +
                   std::to_string(rt.priority) + ")\n";
  }
  return out;
}

void lower_this_thread(int nice_value) {
  (void)setpriority(PRIO_PROCESS, static_cast<id_t>(syscall(SYS_gettid)), nice_value);
}

void name_this_thread(const char* name) { pthread_setname_np(pthread_self(), name); }

}  // namespace rtfuse
