#include <carenav/common/run_health.h>

#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <random>
#include <vector>

using carenav::DurationHistogram;

TEST(DurationHistogram, QuantilesMatchSortingToOneBin) {
  std::mt19937 rng(7);
  std::lognormal_distribution<double> d(0.0, 0.8);  // ms, a long right tail
  DurationHistogram h(0.01, 1000);
  std::vector<double> all;
  for (int i = 0; i < 20000; ++i) {
    const double ms = d(rng);
    h.add(ms);
    all.push_back(ms);
  }
  std::sort(all.begin(), all.end());
  for (double q : {0.5, 0.9, 0.99, 0.999}) {
    const double exact = all[static_cast<size_t>(std::ceil(q * all.size())) - 1];
    EXPECT_NEAR(h.quantile(q), exact, 0.0100001) << "q " << q;
    EXPECT_GE(h.quantile(q), exact) << "the bin's upper edge";
  }
  EXPECT_EQ(h.count(), 20000u);
  EXPECT_DOUBLE_EQ(h.quantile(1.0), all.back());
}

TEST(DurationHistogram, LongDurationsAreKeptInTheMaximum) {
  DurationHistogram h(0.1, 10);
  for (int i = 0; i < 98; ++i) h.add(1.0);
  h.add(55.0);
  h.add(80.0);
  EXPECT_NEAR(h.quantile(0.5), 1.1, 1e-9);
  EXPECT_DOUBLE_EQ(h.quantile(0.995), 80.0) << "beyond the last bin: the true maximum";
  EXPECT_DOUBLE_EQ(h.max(), 80.0);
  h.clear();
  EXPECT_EQ(h.count(), 0u);
  EXPECT_EQ(h.quantile(0.99), 0.0);
}

TEST(DurationHistogram, NegativeAndNanDurationsDoNotBreakIt) {
  DurationHistogram h;
  h.add(-3);
  h.add(std::nan(""));
  h.add(2.0);
  EXPECT_EQ(h.count(), 3u);
  EXPECT_NEAR(h.quantile(1.0), 2.0, 1e-12);
}

TEST(ResidentMemory, GrowsWhenMemoryIsTouched) {
  const double before = carenav::residentMegabytes();
  ASSERT_TRUE(std::isfinite(before));
  EXPECT_GT(before, 0.5);
  constexpr size_t kBytes = 64u << 20;
  {
    std::unique_ptr<char[]> block(new char[kBytes]);
    for (size_t i = 0; i < kBytes; i += 4096) block[i] = static_cast<char>(i);
    const double during = carenav::residentMegabytes();
    EXPECT_GT(during, before + 50) << "64 MiB touched";
    volatile char sink = block[kBytes / 2];
    (void)sink;
  }
}
