// Corrupt copies of a real rawlog (MRPT's SENA dataset): a damaged entry
// header is refused before MRPT reads the entry, a size field asking for
// more bytes than the file has left is refused before anything is allocated
// for it; the message names the file, the entry and its byte offset, and the
// entries before it stay read.
#include <carenav/io/rawlog_info.h>
#include <carenav/io/rawlog_reader.h>

#include <gtest/gtest.h>
#include <mrpt/io/CFileGZInputStream.h>
#include <mrpt/io/CFileGZOutputStream.h>
#include <mrpt/obs/CObservation2DRangeScan.h>

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <random>

using namespace carenav;
using namespace carenav::io;
namespace fs = std::filesystem;

namespace {
const std::string kSena =
    std::string(CARENAV_MRPT_DATASETS) + "/2006-01ENE-21-SENA_Telecom Faculty_one_loop_only.rawlog";

fs::path scratch() {
  auto d = fs::temp_directory_path() / ("carenav_io_corrupt_" + std::to_string(::getpid()));
  fs::create_directories(d);
  return d;
}

std::string readAll(const std::string& path) {
  mrpt::io::CFileGZInputStream in(path);
  std::string out;
  char buf[65536];
  size_t n;
  while ((n = in.Read(buf, sizeof buf)) > 0) out.append(buf, n);
  return out;
}

void writeBytes(const std::string& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary) << bytes;
}

struct Outcome {
  size_t entries = 0;
  std::vector<uint64_t> starts;  // stream offset where each entry began
  std::optional<RawlogError> error;
};
Outcome readAllEntries(const std::string& path) {
  Outcome r;
  RawlogReader reader(path);
  RawlogEntry e;
  try {
    for (;;) {
      const uint64_t at = reader.streamOffset();
      if (!reader.next(e)) break;
      r.starts.push_back(at);
      ++r.entries;
    }
  } catch (const RawlogError& err) {
    r.error = err;
  }
  return r;
}

/** The whole decompressed SENA log, and where each entry starts. */
struct Sena {
  std::string raw;
  std::vector<uint64_t> starts;
};
const Sena& sena() {
  static const Sena s = [] {
    Sena x;
    x.raw = readAll(kSena);
    const auto p = (scratch() / "sena_plain.rawlog").string();
    writeBytes(p, x.raw);
    x.starts = readAllEntries(p).starts;
    return x;
  }();
  return s;
}

/** Index of the entry holding byte `at`. */
size_t entryAt(const Sena& s, size_t at) {
  return static_cast<size_t>(std::upper_bound(s.starts.begin(), s.starts.end(), at) -
                             s.starts.begin()) -
         1;
}

void expectNamed(const RawlogError& e, const std::string& path, size_t entry, uint64_t offset) {
  const std::string msg = e.what();
  EXPECT_EQ(msg.rfind(path + ": rawlog broken at entry " + std::to_string(entry), 0), 0u) << msg;
  EXPECT_NE(msg.find("(byte " + std::to_string(offset) + " "), std::string::npos) << msg;
  EXPECT_EQ(e.entry(), entry);
  EXPECT_EQ(e.offset(), offset);
}

/** The beam-count fields of the scans: the 4 bytes after each
 *  "CObservation2DRangeScan" name that hold the scan's size (361 in SENA). */
std::vector<size_t> scanSizeFields(const std::string& raw) {
  std::vector<size_t> out;
  const std::string name = "CObservation2DRangeScan";
  const uint32_t n = 361;
  char pat[4];
  std::memcpy(pat, &n, 4);
  for (size_t p = raw.find(name); p != std::string::npos; p = raw.find(name, p + 1)) {
    const size_t f = raw.find(std::string(pat, 4), p + name.size());
    if (f != std::string::npos && f < p + name.size() + 200) out.push_back(f);
  }
  return out;
}

}  // namespace

TEST(RawlogCorrupt, HugeScanSizeIsRefusedBeforeAnyAllocation) {
  const Sena& s = sena();
  ASSERT_EQ(s.starts.size(), 449u);
  const auto fields = scanSizeFields(s.raw);
  ASSERT_GT(fields.size(), 200u) << "SENA's scans have 361 beams";
  const auto dir = scratch();
  // Sizes far beyond the file (2^31-1 floats: 8 GB), and just beyond what is left.
  for (const size_t k : {size_t(0), fields.size() / 2, fields.size() - 1}) {
    for (const uint32_t huge : {0x7fffffffu, 0xffffffffu, 0x10000000u}) {
      SCOPED_TRACE("scan " + std::to_string(k) + " size " + std::to_string(huge));
      std::string d = s.raw;
      std::memcpy(&d[fields[k]], &huge, 4);
      const auto p = (dir / "huge_scan.rawlog").string();
      writeBytes(p, d);
      const size_t entry = entryAt(s, fields[k]);
      const Outcome r = readAllEntries(p);
      ASSERT_TRUE(r.error.has_value());
      expectNamed(*r.error, p, entry, s.starts[entry]);
      EXPECT_EQ(r.entries, entry) << "the entries before it are read";
      const std::string msg = r.error->what();
      EXPECT_NE(msg.find("corrupt size field"), std::string::npos) << msg;
      EXPECT_NE(msg.find("bytes left"), std::string::npos) << msg;
      EXPECT_EQ(msg.find("truncated"), std::string::npos) << "it is not truncated: " << msg;
    }
  }
  // Gzip-compressed: the bound is what the compressed rest can hold at most.
  std::string d = s.raw;
  const uint32_t huge = 0x7fffffffu;
  std::memcpy(&d[fields[3]], &huge, 4);
  const auto gz = (dir / "huge_scan.rawlog.gz").string();
  {
    mrpt::io::CFileGZOutputStream out(gz);
    out.Write(d.data(), d.size());
  }
  const Outcome r = readAllEntries(gz);
  ASSERT_TRUE(r.error.has_value());
  const size_t entry = entryAt(s, fields[3]);
  expectNamed(*r.error, gz, entry, s.starts[entry]);
  EXPECT_NE(std::string(r.error->what()).find("corrupt size field"), std::string::npos)
      << r.error->what();
}

TEST(RawlogCorrupt, DamagedEntryHeadersAreRefusedNamingTheEntry) {
  const Sena& s = sena();
  const auto dir = scratch();
  const size_t entry = 200;
  const size_t at = s.starts[entry];
  struct Case {
    std::string name;
    std::function<void(std::string&)> damage;
    std::string expect;
  };
  const std::vector<Case> cases{
      {"unknown class", [&](std::string& d) { d[at + 3] = 'Z'; }, "unknown to MRPT"},
      {"control byte in the name", [&](std::string& d) { d[at + 4] = '\x1b'; }, "is not a name"},
      {"name length 0", [&](std::string& d) { d[at] = '\x80'; }, "class name of 0 characters"},
      {"name length 127", [&](std::string& d) { d[at] = '\xff'; }, "class name of 127"},
      {"old-form header with garbage", [&](std::string& d) { d[at] = 0x10, d[at + 1] = 0x55; },
       "is no class-name length"},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.name);
    std::string d = s.raw;
    c.damage(d);
    const auto p = (dir / "bad_header.rawlog").string();
    writeBytes(p, d);
    const Outcome r = readAllEntries(p);
    ASSERT_TRUE(r.error.has_value());
    expectNamed(*r.error, p, entry, at);
    EXPECT_EQ(r.entries, entry);
    const std::string msg = r.error->what();
    EXPECT_NE(msg.find("corrupt entry header"), std::string::npos) << msg;
    EXPECT_NE(msg.find(c.expect), std::string::npos) << msg;
    for (char ch : msg)
      EXPECT_FALSE(static_cast<unsigned char>(ch) < 0x20) << "raw byte in: " << msg;
    // rawlog info keeps the summary of what was read.
    const RawlogInfo info = summarizeRawlog(p, false);
    EXPECT_EQ(info.entries, entry);
    ASSERT_TRUE(info.error.has_value());
  }
}

TEST(RawlogCorrupt, RandomDamageNeverAllocatesBeyondTheFile) {
  // Random bytes over entry headers and the fields after them: every
  // outcome is a clean read or a RawlogError naming the file and an entry
  // at or after the damaged one (a misread entry can throw the next one off).
  const Sena& s = sena();
  const auto dir = scratch();
  std::mt19937 rng(2024);
  int refused = 0;
  for (int trial = 0; trial < 60; ++trial) {
    std::string d = s.raw;
    const size_t entry = 1 + rng() % (s.starts.size() - 1);
    const size_t at = s.starts[entry] + rng() % 120;
    for (int k = 0; k < 1 + static_cast<int>(rng() % 4) && at + k < d.size(); ++k)
      d[at + k] = static_cast<char>(rng() & 0xff);
    const auto p = (dir / "random.rawlog").string();
    writeBytes(p, d);
    const Outcome r = readAllEntries(p);
    if (!r.error) continue;
    ++refused;
    const std::string msg = r.error->what();
    EXPECT_EQ(msg.rfind(p + ": rawlog broken at entry ", 0), 0u) << msg;
    EXPECT_GE(r.error->entry(), entry) << msg;
    EXPECT_EQ(r.entries, r.error->entry()) << msg;
  }
  EXPECT_GT(refused, 20);
}
