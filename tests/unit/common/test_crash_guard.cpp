#include <carenav/common/crash_guard.h>

#include <gtest/gtest.h>
#include <signal.h>
#include <sys/resource.h>

using namespace carenav;

TEST(CrashGuardDeathTest, FatalSignalInsideAContextIsBadInput) {
  EXPECT_EXIT(
      {
        installCrashGuard();
        CrashContext c("x.rawlog: rawlog broken at entry 3");
        ::raise(SIGSEGV);
      },
      ::testing::ExitedWithCode(2), "carenav: error: x.rawlog: rawlog broken at entry 3");
}

TEST(CrashGuardDeathTest, FatalSignalOutsideAnyContextStaysACrash) {
  EXPECT_EXIT(
      {
        installCrashGuard();
        { CrashContext c("gone"); }
        ::raise(SIGSEGV);
      },
      ::testing::KilledBySignal(SIGSEGV), "");
}

TEST(CrashGuard, ContextsNest) {
  EXPECT_EQ(CrashContext::current(), "");
  {
    CrashContext a("outer");
    EXPECT_EQ(CrashContext::current(), "outer");
    {
      CrashContext b("inner");
      EXPECT_EQ(CrashContext::current(), "inner");
    }
    EXPECT_EQ(CrashContext::current(), "outer");
  }
  EXPECT_EQ(CrashContext::current(), "");
}

TEST(CrashGuardDeathTest, MemoryCapTurnsAbsurdAllocationsIntoBadAlloc) {
  if (builtWithAddressSanitizer())
    GTEST_SKIP() << "ASan build: no address-space cap (ASan limits allocations itself)";
  EXPECT_EXIT(
      {
        limitAddressSpace(2048);
        try {
          std::vector<double> v(size_t(1) << 32);  // 32 GiB
          std::exit(1);
        } catch (const std::bad_alloc&) {
          std::exit(7);
        }
      },
      ::testing::ExitedWithCode(7), "");
}
