// A warning before a threaded run on CPUs that are already busy. OpenMP (libgomp) threads
// spin at every barrier unless OMP_WAIT_POLICY or GOMP_SPINCOUNT says otherwise; when another
// process holds one of the CPUs, a thread that spins waits on a partner the scheduler has set
// aside, and a run can go 20× slower than on one thread (docs/performance.md, "Threads on a
// busy machine"). libgomp reads those variables when it loads, before main(), so crumble
// cannot change them for its own process: it says so instead.
#pragma once
#include <string>

namespace crumble {

struct CpuLoad {
  int cpus = 1;           // CPUs this process may run on (sched_getaffinity)
  int others_running = 0; // runnable threads of the machine besides this one (/proc/stat procs_running − 1)
  bool wait_policy_set = false;  // OMP_WAIT_POLICY or GOMP_SPINCOUNT in the environment
};

// The CPUs this process may run on (Linux: its affinity mask; elsewhere the standard library's count).
int usable_cpus();

// The machine as it is now (Linux; elsewhere: cpus from the standard library, nothing running).
CpuLoad current_cpu_load();

// The warning for `threads` on `load`, or "" when none is due: more threads than CPUs, or
// more threads than idle CPUs while the user has not chosen a wait policy.
std::string thread_oversubscription_warning(int threads, const CpuLoad& load);

}  // namespace crumble
