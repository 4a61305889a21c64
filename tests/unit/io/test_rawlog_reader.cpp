#include <carenav/io/carmen.h>
#include <carenav/io/rawlog_info.h>
#include <carenav/io/rawlog_reader.h>

#include <gtest/gtest.h>
#include <mrpt/io/CFileGZInputStream.h>
#include <mrpt/io/CFileGZOutputStream.h>
#include <mrpt/io/CFileOutputStream.h>
#include <mrpt/obs/CActionRobotMovement2D.h>
#include <mrpt/obs/CObservation2DRangeScan.h>
#include <mrpt/obs/CObservationOdometry.h>
#include <mrpt/obs/CRawlog.h>
#include <mrpt/serialization/CArchive.h>

#include <filesystem>
#include <fstream>

using namespace carenav;
using namespace carenav::io;
namespace fs = std::filesystem;

namespace {
const std::string kDatasets = CARENAV_MRPT_DATASETS;
const std::string kSena = kDatasets + "/2006-01ENE-21-SENA_Telecom Faculty_one_loop_only.rawlog";

fs::path scratch() {
  auto d = fs::temp_directory_path() / ("carenav_io_" + std::to_string(::getpid()));
  fs::create_directories(d);
  return d;
}

std::string readAll(const std::string& path) {
  mrpt::io::CFileGZInputStream in(path);  // decompresses .gz, passes plain files through
  std::string out;
  char buf[65536];
  size_t n;
  while ((n = in.Read(buf, sizeof buf)) > 0) out.append(buf, n);
  return out;
}

void writeBytes(const std::string& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary) << bytes;
}

/** Reads every entry; returns how many were read and the error, if any. */
struct ReadResult {
  size_t entries = 0;
  std::vector<uint64_t> ends;  // uncompressed stream offset after each entry
  std::optional<RawlogError> error;
};
ReadResult readAllEntries(const std::string& path) {
  ReadResult r;
  RawlogReader reader(path);
  RawlogEntry e;
  try {
    while (reader.next(e)) {
      EXPECT_EQ(e.index, r.entries);
      ++r.entries;
      r.ends.push_back(reader.streamOffset());
    }
  } catch (const RawlogError& err) {
    r.error = err;
  }
  return r;
}

/** MRPT's own reading, as the reference. CRawlog keeps a CObservationComment
 *  object as its comment text rather than as an entry: count it back. */
size_t mrptEntryCount(const std::string& path) {
  mrpt::obs::CRawlog log;
  EXPECT_TRUE(log.loadFromRawLogFile(path));
  return log.size() + (log.getCommentText().empty() ? 0 : 1);
}
}  // namespace

TEST(RawlogReader, EntryCountsMatchMrptOnRealDatasets) {
  for (const char* name :
       {"2006-01ENE-21-SENA_Telecom Faculty_one_loop_only.rawlog", "localization_demo.rawlog",
        "kf-slam_demo.rawlog", "test_rtk_path.rawlog", "RO-SLAM_demo.rawlog", "tests_rgbd.rawlog",
        "uwb_ro-localization_demo.rawlog"}) {
    SCOPED_TRACE(name);
    const std::string path = kDatasets + "/" + name;
    ASSERT_TRUE(fs::exists(path)) << "install Debian's mrpt-common (scripts/setup.sh)";
    const auto r = readAllEntries(path);
    EXPECT_FALSE(r.error.has_value()) << (r.error ? r.error->what() : "");
    EXPECT_EQ(r.entries, mrptEntryCount(path));
  }
}

TEST(RawlogReader, OdometryIncrementsOfActionSensoryFrameLog) {
  // Reference: MRPT's CRawlog, summing the motion actions' mean increments.
  mrpt::obs::CRawlog log;
  ASSERT_TRUE(log.loadFromRawLogFile(kSena));
  double ref_path = 0;
  size_t ref_count = 0;
  for (size_t i = 0; i < log.size(); ++i) {
    if (log.getType(i) != mrpt::obs::CRawlog::etActionCollection) continue;
    auto acts = log.getAsAction(i);
    if (auto m = acts->getActionByClass<mrpt::obs::CActionRobotMovement2D>()) {
      ref_path += m->poseChange->getMeanVal().norm();
      ++ref_count;
    }
  }
  ASSERT_GT(ref_count, 100u);
  const RawlogInfo info = summarizeRawlog(kSena, false);
  EXPECT_EQ(info.format, "actions-sensoryframes");
  EXPECT_EQ(info.odometry_increments, ref_count);
  EXPECT_NEAR(info.odometry_path_m, ref_path, 1e-9);
  EXPECT_GT(info.odometry_path_m, 50.0);  // one loop of a faculty building
  ASSERT_EQ(info.sensors.size(), 1u);
  EXPECT_EQ(info.sensors[0].class_name, "mrpt::obs::CObservation2DRangeScan");
  EXPECT_EQ(info.sensors[0].count, 225u);
  EXPECT_NEAR(info.sensors[0].rate(), 3.792, 0.01);  // as rawlog-edit --info reports
  EXPECT_FALSE(info.error.has_value());
}

TEST(RawlogReader, ObservationOnlyOdometryBecomesIncrements) {
  using namespace mrpt::obs;
  using mrpt::poses::CPose2D;
  // A robot driving a 2 x 1 m rectangle, odometry and a scan at each corner step.
  const std::vector<CPose2D> poses = {{0, 0, 0},    {1, 0, 0},    {2, 0, M_PI / 2},
                                      {2, 1, M_PI}, {1, 1, M_PI}, {0, 1, -M_PI / 2}};
  const auto path = (scratch() / "odo_only.rawlog").string();
  {
    mrpt::io::CFileGZOutputStream f(path);
    auto arch = mrpt::serialization::archiveFrom(f);
    mrpt::Clock::time_point t = mrpt::Clock::fromDouble(1000.0);
    for (const auto& p : poses) {
      auto odo = CObservationOdometry::Create();
      odo->sensorLabel = "ODOMETRY";
      odo->odometry = p;
      odo->timestamp = t;
      arch << *odo;
      auto scan = CObservation2DRangeScan::Create();
      scan->sensorLabel = "LIDAR";
      scan->resizeScan(3);
      scan->timestamp = t + std::chrono::milliseconds(10);
      arch << *scan;
      t += std::chrono::milliseconds(500);
    }
  }
  RawlogReader reader(path);
  EXPECT_TRUE(reader.gzipped());
  RawlogEntry e;
  CPose2D integrated = poses.front();
  size_t increments = 0;
  while (reader.next(e)) {
    EXPECT_EQ(e.kind, EntryKind::Observation);
    if (!e.odometry_increment) continue;
    EXPECT_EQ(e.odometry_source, OdometrySource::OdometryObservation);
    integrated = integrated + *e.odometry_increment;
    ++increments;
  }
  EXPECT_EQ(increments, poses.size() - 1);
  EXPECT_NEAR(integrated.x(), poses.back().x(), 1e-9);
  EXPECT_NEAR(integrated.y(), poses.back().y(), 1e-9);
  EXPECT_NEAR(mrpt::math::wrapToPi(integrated.phi() - poses.back().phi()), 0, 1e-9);

  const RawlogInfo info = summarizeRawlog(path, false);
  EXPECT_EQ(info.format, "observations");
  EXPECT_EQ(info.entries, 12u);
  EXPECT_NEAR(info.odometry_path_m, 5.0, 1e-9);  // 1 + 1 + 1 + 1 + 1
  EXPECT_NEAR(info.duration(), 2.51, 1e-6);
  ASSERT_EQ(info.sensors.size(), 2u);
  EXPECT_EQ(info.sensors[0].label, "LIDAR");
  EXPECT_NEAR(info.sensors[0].rate(), 2.0, 1e-9);
}

TEST(RawlogReader, TruncatedFilesNameTheEntryAndKeepWhatWasRead) {
  const std::string raw = readAll(kSena);
  const auto full = readAllEntries(kSena);
  ASSERT_EQ(full.entries, 449u);
  ASSERT_EQ(full.ends.back(), raw.size());
  const auto dir = scratch();
  // Byte offsets inside entries: the first byte, inside the first entry, in the
  // middle of the file, one byte short of the end.
  for (size_t cut :
       {size_t(1), size_t(7), size_t(500), full.ends[100] + 3, raw.size() / 2, raw.size() - 1}) {
    SCOPED_TRACE("cut at byte " + std::to_string(cut));
    const auto p = (dir / "cut.rawlog").string();
    writeBytes(p, raw.substr(0, cut));
    const auto r = readAllEntries(p);
    ASSERT_TRUE(r.error.has_value());
    const size_t expected = std::upper_bound(full.ends.begin(), full.ends.end(), cut) -
                            full.ends.begin();  // entries wholly before the cut
    EXPECT_EQ(r.entries, expected);
    EXPECT_EQ(r.error->entry(), expected);
    const std::string msg = r.error->what();
    EXPECT_NE(msg.find(p), std::string::npos) << msg;
    EXPECT_NE(msg.find("entry " + std::to_string(expected)), std::string::npos) << msg;
    EXPECT_NE(msg.find("truncated"), std::string::npos) << msg;
    // The summary keeps what was read.
    if (expected > 0) {
      const RawlogInfo info = summarizeRawlog(p, false);
      EXPECT_EQ(info.entries, expected);
      ASSERT_TRUE(info.error.has_value());
    } else {
      EXPECT_THROW(summarizeRawlog(p, false), InputError);
    }
  }
  // A cut exactly between two entries is a shorter, valid rawlog.
  const auto p = (dir / "cut.rawlog").string();
  writeBytes(p, raw.substr(0, full.ends[99]));
  const auto r = readAllEntries(p);
  EXPECT_FALSE(r.error.has_value());
  EXPECT_EQ(r.entries, 100u);
}

TEST(RawlogReader, TruncatedGzipFile) {
  std::ifstream f(kSena, std::ios::binary);
  std::string gz((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
  const auto p = (scratch() / "cut.rawlog.gz").string();
  writeBytes(p, gz.substr(0, gz.size() / 3));
  const auto r = readAllEntries(p);
  ASSERT_TRUE(r.error.has_value());
  EXPECT_GT(r.entries, 10u);
  EXPECT_LT(r.entries, 449u);
  EXPECT_EQ(r.error->entry(), r.entries);
}

TEST(RawlogReader, GarbageAfterValidEntriesIsReportedAtThatEntry) {
  const std::string raw = readAll(kSena);
  const auto p = (scratch() / "garbage.rawlog").string();
  std::string bytes = raw.substr(0, 0) + raw;
  bytes += std::string("\x05Hello world, this is not an MRPT object at all", 47);
  writeBytes(p, bytes);
  const auto r = readAllEntries(p);
  ASSERT_TRUE(r.error.has_value());
  EXPECT_EQ(r.entries, 449u);
  EXPECT_EQ(r.error->entry(), 449u);
  EXPECT_EQ(r.error->offset(), raw.size());
}

TEST(RawlogReader, NotARawlogEmptyMissingDirectory) {
  const auto dir = scratch();
  const auto text = (dir / "text.rawlog").string();
  writeBytes(text, "this is a text file\n");
  try {
    RawlogReader reader(text);
    RawlogEntry e;
    reader.next(e);
    FAIL() << "no error";
  } catch (const RawlogError& err) {
    EXPECT_NE(std::string(err.what()).find("not an MRPT rawlog"), std::string::npos) << err.what();
  }
  const auto empty = (dir / "empty.rawlog").string();
  writeBytes(empty, "");
  EXPECT_THROW(RawlogReader{empty}, InputError);
  EXPECT_THROW(RawlogReader{(dir / "missing.rawlog").string()}, InputError);
  EXPECT_THROW(RawlogReader{dir.string()}, InputError);
  // A gzip stream with nothing in it: no entries.
  const auto emptygz = (dir / "empty.rawlog.gz").string();
  { mrpt::io::CFileGZOutputStream f(emptygz); }
  EXPECT_THROW(summarizeRawlog(emptygz, false), InputError);
}

TEST(RawlogReader, StreamsInConstantMemory) {
  // Entries are handed out one at a time and dropped by the reader: after
  // reading the whole log only the current entry is referenced.
  RawlogReader reader(kSena);
  RawlogEntry e;
  std::weak_ptr<mrpt::serialization::CSerializable> first;
  ASSERT_TRUE(reader.next(e));
  first = e.object;
  while (reader.next(e)) {
  }
  EXPECT_TRUE(first.expired());
}

TEST(RawlogReader, FilePositionOfAGzipRawlogIsInCompressedBytes) {
  // Progress compares filePosition() with the file's size: for a .gz both
  // must count compressed bytes, or a quarter of the log already reads 100 %.
  CarmenImportOptions o;
  o.input = std::string(CARENAV_TEST_DATA) + "/carmen/intel-corrected.log.gz";
  o.output = (scratch() / "intel_progress.rawlog.gz").string();
  o.write_tum = false;
  o.compression = 6;
  importCarmen(o);
  RawlogReader reader(o.output);
  ASSERT_TRUE(reader.gzipped());
  const double size = static_cast<double>(reader.fileSize());
  std::vector<double> frac;
  RawlogEntry e;
  uint64_t last = 0;
  while (reader.next(e)) {
    const uint64_t pos = reader.filePosition();
    EXPECT_LE(pos, reader.fileSize());
    EXPECT_GE(pos, last);  // never goes back
    last = pos;
    frac.push_back(pos / size);
  }
  ASSERT_GT(frac.size(), 1000u);
  // The uncompressed stream is several times the file: a quarter of the
  // entries is far from the end of the file, and the last entry at it.
  EXPECT_GT(static_cast<double>(reader.streamOffset()), 2 * size);
  EXPECT_LT(frac[frac.size() / 4], 0.5);
  EXPECT_GT(frac[frac.size() / 4], 0.05);
  EXPECT_GT(frac.back(), 0.95);
}
