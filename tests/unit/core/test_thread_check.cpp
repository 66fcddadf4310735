// The warning before a threaded run on busy CPUs (run/ThreadCheck.h).
#include <gtest/gtest.h>

#include "run/ThreadCheck.h"

using namespace crumble;

TEST(ThreadCheck, WarnsWhenMoreThreadsThanIdleCpusAndNoWaitPolicy) {
  // The measured case (docs/performance.md): 2 threads on 2 CPUs with one held by another process.
  const std::string w = thread_oversubscription_warning(2, CpuLoad{2, 1, false});
  EXPECT_NE(w.find("1 of 2 CPUs idle"), std::string::npos) << w;
  EXPECT_NE(w.find("--threads 1"), std::string::npos) << w;
  EXPECT_NE(w.find("OMP_WAIT_POLICY=passive"), std::string::npos) << w;
  // Every CPU busy: the advice is still one thread, never zero.
  EXPECT_NE(thread_oversubscription_warning(2, CpuLoad{2, 5, false}).find("--threads 1,"), std::string::npos);
}

TEST(ThreadCheck, WarnsWhenMoreThreadsThanCpusWhateverThePolicy) {
  // Measured: 4 threads on 2 CPUs with OMP_WAIT_POLICY=passive ran 7.5x slower than 2.
  for (bool policy : {false, true}) {
    const std::string w = thread_oversubscription_warning(4, CpuLoad{2, 0, policy});
    EXPECT_NE(w.find("--threads 4 on 2 CPUs"), std::string::npos) << w;
    EXPECT_NE(w.find("use --threads 2 or fewer"), std::string::npos) << w;
  }
}

TEST(ThreadCheck, SilentWhenTheThreadsFitOrTheUserChoseAWaitPolicy) {
  EXPECT_EQ(thread_oversubscription_warning(1, CpuLoad{2, 7, false}), "");  // one thread never spins
  EXPECT_EQ(thread_oversubscription_warning(2, CpuLoad{2, 0, false}), "");  // idle machine
  EXPECT_EQ(thread_oversubscription_warning(2, CpuLoad{4, 2, false}), "");
  EXPECT_EQ(thread_oversubscription_warning(2, CpuLoad{2, 1, true}), "");   // OMP_WAIT_POLICY / GOMP_SPINCOUNT set
}

TEST(ThreadCheck, ReadsThisMachine) {
  const CpuLoad l = current_cpu_load();
  EXPECT_GE(l.cpus, 1);
  EXPECT_GE(l.others_running, 0);
}
