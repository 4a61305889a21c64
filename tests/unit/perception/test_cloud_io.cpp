// Bounded point-cloud readers: declared sizes checked against the file and the
// documented limits before any allocation, malformed and binary files refused
// with an InputError naming the file, degenerate clouds (docs/perceive.md, 'Bad input').
#include <carenav/common/errors.h>
#include <carenav/perception/cloud.h>

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>

using namespace carenav;
using namespace carenav::perception;
namespace fs = std::filesystem;

namespace {

fs::path tmpDir() {
  auto d = fs::temp_directory_path() / ("carenav_cloudio_" + std::to_string(::getpid()));
  fs::create_directories(d);
  return d;
}

std::string writeFile(const std::string& name, const std::string& s) {
  const auto p = (tmpDir() / name).string();
  std::ofstream f(p, std::ios::binary);
  f << s;
  return p;
}

bool printableOnly(const std::string& m) {
  for (char ch : m) {
    const auto c = static_cast<unsigned char>(ch);
    if (c < 0x20 || c >= 0x7f) return false;
  }
  return true;
}

/** Expects an InputError whose message names the file, contains `what` and
 *  holds printable ASCII only. Any other exception fails the test. */
template <class F>
void expectInputError(F&& f, const std::string& file, const std::string& what) {
  try {
    f();
    ADD_FAILURE() << "no InputError for " << file;
  } catch (const InputError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find(file), std::string::npos) << m;
    EXPECT_NE(m.find(what), std::string::npos) << "expected '" << what << "' in: " << m;
    EXPECT_TRUE(printableOnly(m.substr(file.size()))) << m;
  }
}

const std::string kHdr = "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n";

std::string pcd(const std::string& dims, const std::string& enc, const std::string& body) {
  return kHdr + dims + "DATA " + enc + "\n" + body;
}

const std::string kPlyHead = "ply\nformat ";
const std::string kPlyProps = "property float x\nproperty float y\nproperty float z\n";

std::string floatBytes(const std::vector<float>& v) {
  return std::string(reinterpret_cast<const char*>(v.data()), v.size() * sizeof(float));
}

}  // namespace

TEST(CloudIoBounds, HugeDeclaredSizesInSmallFilesAreRefusedBeforeAllocating) {
  // A Point3f is 12 bytes: 2^31-1 points would be 24 GiB, 4e9 48 GB. Each of
  // these files is a few hundred bytes; the reader must refuse them from the
  // header alone (a std::bad_alloc or a crash fails the test: only InputError
  // is caught).
  for (const std::string enc : {"ascii", "binary", "binary_compressed"}) {
    const std::string body = enc == "binary_compressed" ? std::string(8, '\0') : "1 2 3\n";
    for (const std::string w : {"2147483647", "4000000000", "16777216", "200000000"}) {
      const auto f = writeFile("huge_" + enc + "_" + w + ".pcd",
                               pcd("WIDTH " + w + "\nHEIGHT 1\nPOINTS " + w + "\n", enc, body));
      expectInputError([&] { readPcd(f); }, f, w);
    }
    // WIDTH x HEIGHT overflows 64 bits.
    const auto ov = writeFile("overflow_" + enc + ".pcd",
                              pcd("WIDTH 4294967296\nHEIGHT 4294967296\n", enc, body));
    expectInputError([&] { readPcd(ov); }, ov, "overflows");
    // WIDTH x HEIGHT fits but exceeds the limit, without a POINTS line.
    const auto big =
        writeFile("big_" + enc + ".pcd", pcd("WIDTH 65536\nHEIGHT 65536\n", enc, body));
    expectInputError([&] { readPcd(big); }, big, "4294967296");
  }
  // A number that does not fit a long.
  const auto toolong =
      writeFile("toolong.pcd", pcd("WIDTH 99999999999999999999999\nHEIGHT 1\n", "ascii", ""));
  expectInputError([&] { readPcd(toolong); }, toolong, "not a non-negative integer");
  // PLY vertex counts.
  for (const std::string enc : {"ascii", "binary_little_endian"})
    for (const std::string n : {"2147483647", "4000000000", "300000000", "18446744073709551615"}) {
      const auto f =
          writeFile("huge_" + enc + "_" + n.substr(0, 4) + ".ply",
                    kPlyHead + enc + " 1.0\nelement vertex " + n + "\n" + kPlyProps +
                        "end_header\n" + (enc == "ascii" ? "1 2 3\n" : floatBytes({1, 2, 3})));
      try {
        readPly(f);
        ADD_FAILURE() << f;
      } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find(f), std::string::npos) << e.what();
      }
    }
}

TEST(CloudIoBounds, CountZeroOrHugeIsRefused) {
  for (const std::string enc : {"ascii", "binary"}) {
    for (const std::string cnt : {"0 1 1", "1 1 0", "4294967297 1 1", "1 70000 1"}) {
      const auto f = writeFile("count_" + enc + ".pcd",
                               "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT " + cnt +
                                   "\nWIDTH 2\nHEIGHT 1\nPOINTS 2\nDATA " + enc + "\n" +
                                   (enc == "ascii" ? "1 2\n3 4\n" : std::string(16, '\1')));
      expectInputError([&] { readPcd(f); }, f, "COUNT");
    }
  }
  // A legitimate COUNT > 1 on another field still reads (x y z + a 3-vector).
  const auto ok =
      writeFile("count_ok.pcd",
                "VERSION 0.7\nFIELDS x y z n\nSIZE 4 4 4 4\nTYPE F F F F\nCOUNT 1 1 1 3\n"
                "WIDTH 2\nHEIGHT 1\nPOINTS 2\nDATA ascii\n1 2 3 0 0 1\n4 5 6 0 1 0\n");
  const Cloud c = readPcd(ok);
  ASSERT_EQ(c.points.size(), 2u);
  EXPECT_FLOAT_EQ(c.points[1].z, 6.f);
}

TEST(CloudIoBounds, PlyWithoutFinalNewlineOrWrongVertexCount) {
  // Ascii, last vertex without its newline: read, 2 vertices.
  const auto a = writeFile("nonl.ply", kPlyHead + "ascii 1.0\nelement vertex 2\n" + kPlyProps +
                                           "end_header\n1 2 3\n4 5 6");
  const Cloud ca = readPly(a);
  ASSERT_EQ(ca.points.size(), 2u);
  EXPECT_FLOAT_EQ(ca.points[1].z, 6.f);
  // end_header is the last line, without newline: no data, refused, no read past the buffer.
  for (const std::string enc : {"ascii", "binary_little_endian"}) {
    const auto h = writeFile(
        "hdr_nonl.ply", kPlyHead + enc + " 1.0\nelement vertex 2\n" + kPlyProps + "end_header");
    expectInputError([&] { readPly(h); }, h, "2");
  }
  // An empty vertex element with end_header unterminated: an empty cloud.
  const auto z = writeFile("zero.ply", kPlyHead + "binary_little_endian 1.0\nelement vertex 0\n" +
                                           kPlyProps + "end_header");
  EXPECT_TRUE(readPly(z).points.empty());
  // Fewer vertices declared than held.
  const auto fa = writeFile("fewer.ply", kPlyHead + "ascii 1.0\nelement vertex 2\n" + kPlyProps +
                                             "end_header\n1 2 3\n4 5 6\n7 8 9\n");
  expectInputError([&] { readPly(fa); }, fa, "more vertex");
  const auto fb = writeFile("fewer_bin.ply",
                            kPlyHead + "binary_little_endian 1.0\nelement vertex 2\n" + kPlyProps +
                                "end_header\n" + floatBytes({1, 2, 3, 4, 5, 6, 7, 8, 9}));
  expectInputError([&] { readPly(fb); }, fb, "bytes after");
  // More declared than held.
  const auto ma = writeFile("more.ply", kPlyHead + "ascii 1.0\nelement vertex 4\n" + kPlyProps +
                                            "end_header\n1 2 3\n4 5 6\n7 8 9\n");
  expectInputError([&] { readPly(ma); }, ma, "truncated");
  const auto mb =
      writeFile("more_bin.ply", kPlyHead + "binary_little_endian 1.0\nelement vertex 4\n" +
                                    kPlyProps + "end_header\n" + floatBytes({1, 2, 3, 4, 5, 6}));
  expectInputError([&] { readPly(mb); }, mb, "truncated");
  // Faces after the vertices are another element, not extra vertices.
  const auto mesh =
      writeFile("mesh.ply", kPlyHead + "ascii 1.0\nelement vertex 3\n" + kPlyProps +
                                "element face 1\nproperty list uchar int vertex_indices\n"
                                "end_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
  EXPECT_EQ(readPly(mesh).points.size(), 3u);
}

TEST(CloudIoBounds, BinaryFilesGiveAMessageWithoutRawBytes) {
  // The start of a PNG, and random binary, given as .pcd and .ply.
  std::string png = "\x89PNG\r\n\x1a\n";
  png += std::string("\0\0\0\rIHDR\0\0\x02\x80\0\0\x01\xe0\x08\x06\0\0\0", 21);
  std::mt19937 rng(3);
  std::string noise;
  for (int i = 0; i < 600; ++i) noise += static_cast<char>(rng() & 0xff);
  for (const auto& [name, bytes] : {std::pair{std::string("png"), png}, {"noise", noise}}) {
    const auto f = writeFile(name + ".pcd", bytes);
    const auto g = writeFile(name + ".ply", bytes);
    for (const auto& file : {f, g}) {
      try {
        readCloudFile(file);
        ADD_FAILURE() << file;
      } catch (const InputError& e) {
        const std::string m = e.what();
        ASSERT_EQ(m.rfind(file, 0), 0u) << m;
        EXPECT_TRUE(printableOnly(m.substr(file.size()))) << m;
      }
    }
  }
  // A header line whose key is non-ASCII text is echoed with \xHH escapes.
  const auto k = writeFile("png_key.pcd", "\x89PNG\r\n");
  expectInputError([&] { readPcd(k); }, k, "\\x89PNG");
}

TEST(CloudIoBounds, EveryTruncationAndByteFlipIsAnInputErrorOrAValidCloud) {
  // Valid files of every encoding cut at every length and with seeded random
  // byte changes: the reader returns a cloud no larger than the file can hold,
  // or throws InputError naming the file; nothing else (no crash, no
  // bad_alloc, no other exception).
  Cloud c;
  c.width = 4;
  c.height = 3;
  for (int i = 0; i < 12; ++i) c.points.push_back({0.1f * i, -0.2f * i, 1.0f + i});
  const auto d = tmpDir();
  std::vector<std::pair<std::string, std::string>> files;  // (extension, content)
  auto slurp = [](const std::string& p) {
    std::ifstream f(p, std::ios::binary);
    return std::string((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
  };
  for (auto enc : {PcdEncoding::Ascii, PcdEncoding::Binary}) {
    writePcd((d / "v.pcd").string(), c, enc);
    files.emplace_back(".pcd", slurp((d / "v.pcd").string()));
  }
  for (auto enc : {PlyEncoding::Ascii, PlyEncoding::BinaryLittleEndian}) {
    writePly((d / "v.ply").string(), c, enc);
    files.emplace_back(".ply", slurp((d / "v.ply").string()));
  }
  std::mt19937 rng(11);
  size_t refused = 0, read = 0;
  auto attempt = [&](const std::string& ext, const std::string& bytes) {
    const auto f = (d / ("t" + ext)).string();
    {
      std::ofstream o(f, std::ios::binary | std::ios::trunc);
      o << bytes;
    }
    try {
      const Cloud r = readCloudFile(f);
      EXPECT_LE(r.points.size() * 2, bytes.size() + 1) << ext << " " << bytes.size();
      ++read;
    } catch (const InputError& e) {
      const std::string m = e.what();
      EXPECT_EQ(m.rfind(f, 0), 0u) << m;
      EXPECT_TRUE(printableOnly(m.substr(f.size()))) << m;
      ++refused;
    }
  };
  for (const auto& [ext, full] : files) {
    for (size_t len = 0; len < full.size(); ++len) attempt(ext, full.substr(0, len));
    const size_t hdr =
        full.find("DATA") != std::string::npos ? full.find("DATA") : full.find("end_header");
    for (int k = 0; k < 200; ++k) {
      std::string m = full;
      const int flips = 1 + static_cast<int>(rng() % 3);
      for (int q = 0; q < flips; ++q) {
        const size_t at = rng() % (hdr + 12);  // mostly the header
        m[at] = static_cast<char>(k % 2 ? '0' + rng() % 10 : rng() & 0xff);
      }
      attempt(ext, m);
    }
  }
  EXPECT_GT(refused, 500u);
  EXPECT_GT(read, 4u);
}

TEST(CloudIoContent, EmptyAllNaNOnePointAndAbsurdClouds) {
  const float q = std::numeric_limits<float>::quiet_NaN();
  // POINTS 0 reads (a valid PCD) but perceive refuses it.
  const auto e = writeFile("zero.pcd", pcd("WIDTH 0\nHEIGHT 1\nPOINTS 0\n", "ascii", ""));
  const Cloud ce = readPcd(e);
  EXPECT_TRUE(ce.points.empty());
  expectInputError([&] { checkCloudContent(e, ce); }, e, "no point");
  Cloud nan;
  nan.width = 8;
  nan.height = 2;
  nan.points.assign(16, {q, q, q});
  expectInputError([&] { checkCloudContent("nan.pcd", nan); }, "nan.pcd", "no valid point");
  Cloud one;
  one.points = {{1, 2, 3}};
  expectInputError([&] { checkCloudContent("one.pcd", one); }, "one.pcd", "at least 3");
  Cloud absurd;
  absurd.points.assign(10, {1e30f, 1e30f, 1e30f});
  expectInputError([&] { checkCloudContent("absurd.pcd", absurd); }, "absurd.pcd",
                   "10 infinite or beyond 1e6 m");
  // Through the reader: 1e30 and 1e400 (inf) in an ascii PCD.
  const auto f =
      writeFile("absurd.pcd", pcd("WIDTH 2\nHEIGHT 1\n", "ascii", "1e30 0 1\n1e400 0 1\n"));
  const Cloud cf = readPcd(f);
  EXPECT_EQ(cf.validCount(), 0u);
  expectInputError([&] { checkCloudContent(f, cf); }, f, "no valid point");
  // A usable cloud with a few absurd points: accepted with a warning.
  Cloud mixed;
  for (int i = 0; i < 100; ++i) mixed.points.push_back({0.01f * i, 1.f, 2.f});
  mixed.points.push_back({1e30f, 0, 1});
  mixed.points.push_back({q, q, q});  // NaN holes are normal, no warning
  const auto w = checkCloudContent("mixed.pcd", mixed);
  ASSERT_EQ(w.size(), 1u);
  EXPECT_NE(w[0].find("mixed.pcd: 1 of 102 points"), std::string::npos) << w[0];
  nan.points[3] = {1, 2, 3};
  nan.points[4] = {1, 2, 4};
  nan.points[5] = {1, 3, 4};
  EXPECT_TRUE(checkCloudContent("three.pcd", nan).empty());
}
