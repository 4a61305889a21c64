// Rawlog reading throughput: carenav's streaming reader against MRPT's
// CRawlog::loadFromRawLogFile (which holds the whole log in memory), side by
// side on the same real dataset.
#include <carenav/io/rawlog_reader.h>

#include <benchmark/benchmark.h>
#include <mrpt/obs/CRawlog.h>

namespace {
const std::string kSena =
    std::string(CARENAV_MRPT_DATASETS) + "/2006-01ENE-21-SENA_Telecom Faculty_one_loop_only.rawlog";
const std::string kRgbd = std::string(CARENAV_MRPT_DATASETS) + "/tests_rgbd.rawlog";

void carenavStream(benchmark::State& st, const std::string& path) {
  size_t n = 0;
  for (auto _ : st) {
    carenav::io::RawlogReader r(path);
    carenav::io::RawlogEntry e;
    while (r.next(e)) ++n;
  }
  st.counters["entries/s"] = benchmark::Counter(n, benchmark::Counter::kIsRate);
}

void mrptLoad(benchmark::State& st, const std::string& path) {
  size_t n = 0;
  for (auto _ : st) {
    mrpt::obs::CRawlog log;
    log.loadFromRawLogFile(path);
    n += log.size();
  }
  st.counters["entries/s"] = benchmark::Counter(n, benchmark::Counter::kIsRate);
}
}  // namespace

BENCHMARK_CAPTURE(carenavStream, sena, kSena)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(mrptLoad, sena, kSena)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(carenavStream, rgbd, kRgbd)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(mrptLoad, rgbd, kRgbd)->Unit(benchmark::kMillisecond);

BENCHMARK_MAIN();
