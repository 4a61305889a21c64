// A battery of malformed inputs for every reader of outside files, run
// through the real binary under an address-space limit: each reader's valid
// sample is emptied, cut, replaced by garbage, flipped byte by byte, given
// absurd numbers, nested without end, given a 2 MB line, a directory or a
// missing path. Whatever the input, carenav must end with 0 (the input still
// made sense) or 2 (refused, naming the file); never a signal, never exit 1
// (an unhandled error), never a hang. Inputs that cannot make sense (empty,
// garbage, endless nesting, a directory, a missing file) must be refused.
#include <cstdint>
#include <functional>
#include <random>

#include "cli_helpers.h"

using namespace carenav_test;

namespace {

/** One malformed variant of a valid sample. */
struct Variant {
  std::string label;
  std::string bytes;
  bool must_refuse = false;
  bool is_directory = false;
  bool is_missing = false;
};

/** A reader of outside input and how the CLI reaches it. */
struct Reader {
  std::string name, file_name;  // file_name: what the variant is written as
  bool text = true, yaml = false;
  int numbers = 6;  // how many of the sample's numbers are replaced
  std::function<std::string()> sample;
  /** Copies what the file needs beside it (images, bases) into `dir`. */
  std::function<void(const fs::path& dir)> beside;
  /** The arguments that make carenav read `file`; `out` is a scratch folder. */
  std::function<std::vector<std::string>(const fs::path& file, const fs::path& out)> args;
};

void PrintTo(const Reader& r, std::ostream* os) { *os << r.name; }

std::string repeat(const std::string& s, size_t n) {
  std::string r;
  r.reserve(s.size() * n);
  for (size_t i = 0; i < n; ++i) r += s;
  return r;
}

std::string garbage(size_t n, uint32_t seed) {
  std::mt19937 rng(seed);
  std::string g(n, '\0');
  for (auto& c : g) c = static_cast<char>(rng() & 0xff);
  return g;
}

/** Where the sample's numbers are: [begin, end) of each of the first `n`. */
std::vector<std::pair<size_t, size_t>> numberSpans(const std::string& s, int n) {
  std::vector<std::pair<size_t, size_t>> spans;
  const std::regex num(R"((^|[\s,\[:=])(-?[0-9]+(\.[0-9]+)?([eE][-+]?[0-9]+)?)(?=[\s,\]]|$))");
  for (auto it = std::sregex_iterator(s.begin(), s.end(), num);
       it != std::sregex_iterator() && static_cast<int>(spans.size()) < n; ++it) {
    const size_t b = static_cast<size_t>(it->position(2));
    spans.emplace_back(b, b + static_cast<size_t>(it->length(2)));
  }
  return spans;
}

std::vector<Variant> variants(const Reader& r) {
  const std::string s = r.sample();
  std::vector<Variant> v;
  v.push_back({"empty", "", true});
  v.push_back({"garbage", garbage(4096, 7), true});
  v.push_back({"directory", "", true, true});
  v.push_back({"missing", "", true, false, true});
  v.push_back({"one-byte", s.substr(0, 1), false});
  for (double f : {0.1, 0.5, 0.9})
    v.push_back({"cut-" + std::to_string(int(f * 100)) + "%",
                 s.substr(0, static_cast<size_t>(f * s.size())), false});
  v.push_back({"cut-last-byte", s.substr(0, s.size() - 1), false});
  v.push_back({"nul-in-middle", s.substr(0, s.size() / 2) + '\0' + s.substr(s.size() / 2)});
  v.push_back({"2MB-line", s + repeat("9", 2 << 20) + "\n"});
  for (int k = 0; k < 12; ++k) {
    std::string f = s;
    const size_t at = (s.size() - 1) * static_cast<size_t>(k) / 11;
    f[at] = static_cast<char>(f[at] ^ 0x5a);
    v.push_back({"flip@" + std::to_string(at), f});
  }
  if (r.text) {
    const std::vector<std::string> absurd = {
        "1e300", "-1e300", "nan", "inf", "-1", "4294967297", "1e-300", "99999999999999999999"};
    const auto spans = numberSpans(s, r.numbers);
    for (size_t i = 0; i < spans.size(); ++i)
      for (const auto& a : absurd)
        v.push_back({"number" + std::to_string(i) + "=" + a,
                     s.substr(0, spans[i].first) + a + s.substr(spans[i].second)});
  }
  if (r.yaml) {
    v.push_back({"deep-flow", "format: 1\nkey: " + repeat("[", 20000) + "\n", true});
    std::string block = "format: 1\n";
    for (int d = 0; d < 5000; ++d) block += std::string(static_cast<size_t>(d), ' ') + "- a:\n";
    v.push_back({"deep-block", block, true});
  }
  return v;
}

// Samples: the repository's own files where they exist, small ones made here
// where they do not (a PLY, a ROS map, a TUM trajectory).

std::string tumSample() {
  std::ostringstream o;
  for (int k = 0; k < 40; ++k)
    o << 100 + 0.1 * k << " " << 0.05 * k << " " << 0.01 * k << " 0 0 0 " << std::sin(0.005 * k)
      << " " << std::cos(0.005 * k) << "\n";
  return o.str();
}

std::string pcdAsciiSample() {
  std::ostringstream o;
  o << "# .PCD v0.7\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n"
    << "WIDTH 60\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 60\nDATA ascii\n";
  for (int k = 0; k < 60; ++k) o << 1 + 0.02 * (k % 10) << " " << 0.02 * (k / 10) << " 0\n";
  return o.str();
}

std::string plySample() {
  std::ostringstream o;
  o << "ply\nformat ascii 1.0\nelement vertex 60\nproperty float x\nproperty float y\n"
    << "property float z\nend_header\n";
  for (int k = 0; k < 60; ++k) o << 1 + 0.02 * (k % 10) << " " << 0.02 * (k / 10) << " 0\n";
  return o.str();
}

std::string pgmSample() {
  std::string p = "P5\n16 12\n255\n";
  for (int k = 0; k < 16 * 12; ++k) p += static_cast<char>(k % 7 == 0 ? 0 : 254);
  return p;
}

std::string carmenSample() {
  // The first 60 lines of a real log (tests/data/carmen, Radish).
  const auto r = shell("zcat " + quote(kTestData + "/carmen/intel-corrected.log.gz") +
                       " | grep -v '^#' | head -n 60");
  return r.out;
}

std::string file(const std::string& p) { return slurp(p); }

void copyTo(const fs::path& from, const fs::path& dir) {
  fs::copy_file(from, dir / from.filename(), fs::copy_options::overwrite_existing);
}

const std::string kInterbot = kSrc + "/ini/interbot.ini";

std::vector<Reader> readers() {
  std::vector<Reader> r;
  r.push_back({"profile",
               "robot.ini",
               true,
               false,
               6,
               [] { return file(kInterbot); },
               {},
               [](const fs::path& f, const fs::path&) {
                 return std::vector<std::string>{"profile", "check", f.string()};
               }});
  r.push_back({"places",
               "sena.places.yaml",
               true,
               true,
               6,
               [] { return file(kSrc + "/maps/sena.places.yaml"); },
               {},
               [](const fs::path& f, const fs::path&) {
                 return std::vector<std::string>{"places", "list",
                                                 "--map",  kSrc + "/maps/sena.gridmap.gz",
                                                 "--file", f.string()};
               }});
  r.push_back({"world", "world.yaml", true, true, 6,
               [] { return file(kSrc + "/maps/worlds/empty_room.yaml"); },
               [](const fs::path& d) { copyTo(kSrc + "/maps/worlds/empty_room.png", d); },
               [](const fs::path& f, const fs::path& out) {
                 return std::vector<std::string>{"simulate",
                                                 "--world",
                                                 f.string(),
                                                 "--profile",
                                                 kInterbot,
                                                 "--path",
                                                 "2,2 3,2",
                                                 "--duration",
                                                 "1",
                                                 "--out",
                                                 (out / "w.rawlog").string()};
               }});
  r.push_back({"scenario",
               "scenario.yaml",
               true,
               true,
               4,
               [] {
                 std::string s = file(kSrc + "/maps/scenarios/goal-doorway.yaml");
                 s = std::regex_replace(s, std::regex("duration: 120"), "duration: 2");
                 const std::string dir = kSrc + "/maps/scenarios/";
                 s = std::regex_replace(s, std::regex("world: \\.\\./"), "world: " + dir + "../");
                 return std::regex_replace(s, std::regex("profile: \\.\\./\\.\\./"),
                                           "profile: " + dir + "../../");
               },
               {},
               [](const fs::path& f, const fs::path& out) {
                 return std::vector<std::string>{"navigate", "--scenario", f.string(), "--out",
                                                 (out / "nav").string()};
               }});
  r.push_back({"drive-script",
               "cmds.txt",
               true,
               false,
               6,
               [] { return std::string("0 0.3 0\n1 0.3 0.2\n2 0 0\n"); },
               {},
               [](const fs::path& f, const fs::path& out) {
                 return std::vector<std::string>{"simulate",
                                                 "--world",
                                                 kSrc + "/maps/worlds/empty_room.yaml",
                                                 "--profile",
                                                 kInterbot,
                                                 "--script",
                                                 f.string(),
                                                 "--start",
                                                 "2,2,0",
                                                 "--out",
                                                 (out / "s.rawlog").string()};
               }});
  r.push_back(
      {"ros-map-yaml", "map.yaml", true, true, 6,
       [] {
         return std::string(
             "image: map.pgm\nresolution: 0.05\norigin: [-1.0, -2.0, 0.0]\nnegate: 0\n"
             "occupied_thresh: 0.65\nfree_thresh: 0.196\n");
       },
       [](const fs::path& d) { std::ofstream(d / "map.pgm", std::ios::binary) << pgmSample(); },
       [](const fs::path& f, const fs::path&) {
         return std::vector<std::string>{"map", "info", f.string()};
       }});
  r.push_back(
      {"ros-map-pgm", "map.pgm", false, false, 0, pgmSample,
       [](const fs::path& d) {
         std::ofstream(d / "map.yaml") << "image: map.pgm\nresolution: 0.05\n"
                                          "origin: [0, 0, 0]\n";
       },
       [](const fs::path& f, const fs::path&) {
         return std::vector<std::string>{"map", "info", (f.parent_path() / "map.yaml").string()};
       }});
  r.push_back({"gridmap",
               "m.gridmap.gz",
               false,
               false,
               0,
               [] { return file(kSrc + "/maps/sena.gridmap.gz"); },
               {},
               [](const fs::path& f, const fs::path&) {
                 return std::vector<std::string>{"map", "info", f.string()};
               }});
  r.push_back({"tum", "est.tum", true, false, 6, tumSample,
               [](const fs::path& d) { std::ofstream(d / "ref.tum") << tumSample(); },
               [](const fs::path& f, const fs::path&) {
                 return std::vector<std::string>{
                     "eval", "--ref", (f.parent_path() / "ref.tum").string(), "--est", f.string()};
               }});
  r.push_back({"carmen",
               "run.log",
               true,
               false,
               6,
               carmenSample,
               {},
               [](const fs::path& f, const fs::path& out) {
                 return std::vector<std::string>{
                     "import", "carmen", f.string(), "--out", (out / "c.rawlog").string(), "-q"};
               }});
  r.push_back({"pcd-ascii",
               "cloud.pcd",
               true,
               false,
               6,
               pcdAsciiSample,
               {},
               [](const fs::path& f, const fs::path& out) {
                 return std::vector<std::string>{"perceive", "--cloud", f.string(), "--out",
                                                 (out / "p").string()};
               }});
  r.push_back({"pcd-binary-compressed",
               "office.pcd",
               false,
               false,
               0,
               [] { return file(kTestData + "/pcd/office1.pcd"); },
               {},
               [](const fs::path& f, const fs::path& out) {
                 return std::vector<std::string>{"perceive", "--cloud", f.string(), "--out",
                                                 (out / "p").string()};
               }});
  r.push_back({"ply",
               "cloud.ply",
               true,
               false,
               6,
               plySample,
               {},
               [](const fs::path& f, const fs::path& out) {
                 return std::vector<std::string>{"perceive", "--cloud", f.string(), "--out",
                                                 (out / "p").string()};
               }});
  return r;
}

/** The rawlog reader: a small rawlog made from the CARMEN sample. */
Reader rawlogReader() {
  Reader r{"rawlog",
           "run.rawlog",
           false,
           false,
           0,
           [] {
             const auto d = scratch() / "rawlog_sample";
             fs::create_directories(d);
             std::ofstream(d / "s.log") << carmenSample();
             carenav({"import", "carmen", (d / "s.log").string(), "--out",
                      (d / "s.rawlog").string(), "--compression", "1", "-q"});
             return slurp(d / "s.rawlog");
           },
           {},
           [](const fs::path& f, const fs::path&) {
             return std::vector<std::string>{"rawlog", "info", f.string()};
           }};
  return r;
}

class BadInput : public ::testing::TestWithParam<Reader> {};

/** The memory bound every variant runs under: 3 GB of address space; a
 *  sanitizer build cannot run under an address-space limit (its shadow
 *  memory is reserved up front), so there ASan caps the resident memory. */
std::string memoryCap() {
#ifdef CARENAV_SANITIZED
  return "ASAN_OPTIONS=hard_rss_limit_mb=3000:allocator_may_return_null=1:detect_leaks=0 ";
#else
  return "ulimit -v 3000000; ";
#endif
}

TEST_P(BadInput, EndsWithZeroOrARefusalNamingTheFile) {
  const Reader& r = GetParam();
  ASSERT_FALSE(r.sample().empty()) << "no sample for " << r.name;
  const auto base = scratch() / ("bad_" + r.name);
  std::vector<std::string> failures;
  for (const auto& v : variants(r)) {
    fs::remove_all(base);
    const auto dir = base / "in", out = base / "out";
    fs::create_directories(dir);
    fs::create_directories(out);
    if (r.beside) r.beside(dir);
    const fs::path f = dir / r.file_name;
    if (v.is_directory)
      fs::create_directories(f);
    else if (!v.is_missing)
      std::ofstream(f, std::ios::binary) << v.bytes;
    std::string cmd = memoryCap() + "timeout -s KILL 600 " + quote(kBin);
    for (const auto& a : r.args(f, out)) cmd += " " + quote(a);
    const RunResult res = shell(cmd + " </dev/null");
    std::string why;
    if (res.code != 0 && res.code != 2)
      why = "exit " + std::to_string(res.code);
    else if (v.must_refuse && res.code != 2)
      why = "accepted (exit 0)";
    else if (res.code == 2 && res.err.find(r.file_name) == std::string::npos &&
             res.err.find(f.parent_path().filename().string()) == std::string::npos)
      why = "refused without naming the file";
    if (!why.empty()) failures.push_back(v.label + ": " + why + ": " + res.err.substr(0, 300));
  }
  EXPECT_TRUE(failures.empty()) << r.name << ": " << failures.size() << " variants failed:\n"
                                << [&] {
                                     std::string s;
                                     for (const auto& x : failures) s += "  " + x + "\n";
                                     return s;
                                   }();
}

std::vector<Reader> allReaders() {
  auto r = readers();
  r.push_back(rawlogReader());
  return r;
}

INSTANTIATE_TEST_SUITE_P(EveryReader, BadInput, ::testing::ValuesIn(allReaders()),
                         [](const auto& info) {
                           std::string n = info.param.name;
                           for (auto& c : n)
                             if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
                           return n;
                         });

/** The battery is as large as the issue asks: at least 200 inputs. */
TEST(BadInput, TheBatteryHoldsAtLeast200Inputs) {
  size_t n = 0;
  for (const auto& r : readers()) n += variants(r).size();
  EXPECT_GE(n, 200u);
}

}  // namespace
