#include "run/ThreadCheck.h"

#include <algorithm>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <thread>

#if defined(__linux__)
#include <sched.h>
#endif

namespace crumble {

int usable_cpus() {
#if defined(__linux__)
  cpu_set_t set;
  if (sched_getaffinity(0, sizeof(set), &set) == 0) return std::max(1, CPU_COUNT(&set));
#endif
  return static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
}

CpuLoad current_cpu_load() {
  CpuLoad l;
  l.cpus = usable_cpus();
#if defined(__linux__)
  std::ifstream stat("/proc/stat");
  std::string key;
  long value = 0;
  while (stat >> key) {
    if (key == "procs_running" && stat >> value) {
      l.others_running = static_cast<int>(std::max(0L, value - 1));
      break;
    }
    stat.ignore(1 << 20, '\n');
  }
#endif
  l.wait_policy_set = std::getenv("OMP_WAIT_POLICY") != nullptr || std::getenv("GOMP_SPINCOUNT") != nullptr;
  return l;
}

std::string thread_oversubscription_warning(int threads, const CpuLoad& load) {
  if (threads <= 1) return "";
  std::ostringstream os;
  if (threads > load.cpus) {  // measured 7.5x slower than 2 threads with 4 on 2 CPUs, even with a passive policy
    os << "--threads " << threads << " on " << load.cpus << " CPUs: threads that share a CPU wait on each other at "
       << "every barrier and a step takes several times longer (docs/performance.md, \"Threads on a busy machine\"); "
       << "use --threads " << load.cpus << " or fewer";
    return os.str();
  }
  const int idle = std::max(0, load.cpus - load.others_running);
  if (threads <= idle || load.wait_policy_set) return "";
  os << "--threads " << threads << " with " << idle << " of " << load.cpus << " CPUs idle ("
     << "other runnable threads: " << load.others_running << "): OpenMP threads spin at every barrier and a step can take "
     << "20x longer than on one thread while another process holds a CPU (docs/performance.md, \"Threads on a busy "
     << "machine\"); use --threads " << std::max(1, idle) << ", or set OMP_WAIT_POLICY=passive before starting crumble";
  return os.str();
}

}  // namespace crumble
