// The one whole-file reader: each reader's words, and a size bound before reading.
#include <carenav/common/errors.h>
#include <carenav/common/file.h>

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include <unistd.h>

using namespace carenav;
namespace fs = std::filesystem;

namespace {

std::string errorOf(const std::string& path, std::uintmax_t max = kMaxTextFileBytes) {
  try {
    readWholeFile(path, {"gone", "a folder", "locked", "a test file"}, max);
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no error)";
}

}  // namespace

TEST(ReadWholeFile, BytesAndTheReadersWords) {
  const fs::path d = fs::temp_directory_path() / ("carenav_file_" + std::to_string(::getpid()));
  fs::create_directories(d);
  const std::string p = (d / "a.txt").string();
  std::ofstream(p, std::ios::binary) << std::string("a\0b\n", 4);
  EXPECT_EQ(readWholeFile(p), std::string("a\0b\n", 4));
  EXPECT_EQ(errorOf((d / "none").string()), (d / "none").string() + ": gone");
  EXPECT_EQ(errorOf(d.string()), d.string() + ": a folder");
  EXPECT_EQ(errorOf(p, 3), p + ": 4 bytes is too large for a test file (at most 3)");
  EXPECT_EQ(errorOf(p, 4), "(no error)");
  fs::remove_all(d);
}
