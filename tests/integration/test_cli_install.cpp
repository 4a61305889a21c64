// The installed carenav: `cmake --install` into a scratch prefix, then the
// installed binary run from another directory finds its own data (profiles,
// worlds) relative to itself, and holds no data path of the source or build
// tree (only source-file names of diagnostics may name the source tree).
#include "cli_helpers.h"

#include <algorithm>

using namespace carenav_test;

namespace {

const std::string kBuild = CARENAV_BINARY_DIR;

/** The NUL-terminated strings of `bytes` that contain `needle`. */
std::vector<std::string> stringsWith(const std::string& bytes, const std::string& needle) {
  std::vector<std::string> out;
  for (size_t at = bytes.find(needle); at != std::string::npos;
       at = bytes.find(needle, at + needle.size())) {
    size_t b = at;
    while (b > 0 && bytes[b - 1] != '\0') --b;
    const size_t e = bytes.find('\0', at);
    out.push_back(bytes.substr(b, (e == std::string::npos ? bytes.size() : e) - b));
  }
  return out;
}

bool isSourceFileName(const std::string& s) {
  static const std::regex src(R"(.*\.(cpp|cc|h|hpp|in)(:[0-9]+)?$)");
  return std::regex_match(s, src);
}

/** Installs the build into a fresh prefix once for every test here. */
const fs::path& prefix() {
  static const fs::path p = [] {
    const fs::path d = scratch() / "prefix";
    fs::remove_all(d);
    const RunResult r = shell("cmake --install " + quote(kBuild) + " --prefix " +
                              quote(d.string()) + " >/dev/null");
    EXPECT_EQ(r.code, 0) << r.err;
    return d;
  }();
  return p;
}

RunResult installed(const std::string& args) {
  // From the root folder, with nothing pointing carenav at the source tree.
  return shell("cd / && env -u CARENAV_DATA_DIR " + quote((prefix() / "bin" / "carenav").string()) +
               " " + args);
}

}  // namespace

TEST(CliInstall, InstallsTheBinaryItsProfilesMapsAndDocs) {
  const fs::path p = prefix();
  EXPECT_TRUE(fs::is_regular_file(p / "bin" / "carenav"));
  for (const char* f :
       {"ini/defaults.ini", "ini/isr-aiwalker.ini", "ini/interbot.ini", "ini/hobbit.ini",
        "maps/sena.gridmap.gz", "maps/sena.places.yaml", "maps/worlds/apartment.yaml",
        "maps/worlds/apartment.png", "maps/scenarios/walker-doorway.yaml"})
    EXPECT_TRUE(fs::is_regular_file(p / "share" / "carenav" / f)) << f;
  EXPECT_TRUE(fs::is_regular_file(p / "share" / "doc" / "carenav" / "LICENSE"));
  EXPECT_TRUE(fs::is_regular_file(p / "share" / "doc" / "carenav" / "design.md"));
}

TEST(CliInstall, TheBinaryHoldsNoPathOfTheSourceOrBuildTree) {
#ifdef CARENAV_SANITIZED
  GTEST_SKIP() << "a sanitizer build carries debug information (-g), which names its build "
                  "tree; the release build is the one installed";
#endif
  const std::string bytes = slurp(prefix() / "bin" / "carenav");
  ASSERT_GT(bytes.size(), 100000u);
  for (const auto& s : stringsWith(bytes, kSrc))
    EXPECT_TRUE(isSourceFileName(s)) << "a source-tree path compiled in: " << s;
  for (const auto& s : stringsWith(bytes, kBuild))
    EXPECT_TRUE(isSourceFileName(s)) << "a build-tree path compiled in: " << s;
}

TEST(CliInstall, TheLiveAppFindsItsDefaultWorldAndProfileFromAnotherFolder) {
  const auto d = scratch() / "installed_live";
  fs::remove_all(d);
  fs::create_directories(d);
  std::ofstream(d / "user.csv") << "t,v,w\n0,0.3,0\n3,0,0\n";
  const RunResult r = installed("-q navigate --intent csv:" + quote((d / "user.csv").string()) +
                                " --speed 0 --json --out " + quote((d / "run").string()));
  ASSERT_EQ(r.code, 0) << r.err;
  std::smatch m;
  ASSERT_TRUE(std::regex_search(r.out, m, std::regex("\"path_length_m\": ([0-9.]+)"))) << r.out;
  EXPECT_GT(std::stod(m[1]), 0.3) << "the scripted user pushed the walker 3 s at 0.3 m/s";
  EXPECT_TRUE(fs::is_regular_file(d / "run" / "navlog.csv"));
}

TEST(CliInstall, ACopiedProfileFindsItsBaseAmongTheInstalledProfiles) {
  const auto d = scratch() / "installed_profile";
  fs::create_directories(d);
  fs::copy_file(prefix() / "share" / "carenav" / "ini" / "isr-aiwalker.ini", d / "my-walker.ini",
                fs::copy_options::overwrite_existing);
  const RunResult r = installed("profile check " + quote((d / "my-walker.ini").string()));
  EXPECT_EQ(r.code, 0) << r.err;
}

TEST(CliInstall, TheDemoRunsFromAnotherFolder) {
  const auto d = scratch() / "installed_demo";
  fs::remove_all(d);
  const RunResult r = installed("-q demo --out " + quote(d.string()));
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(fs::is_regular_file(d / "map.png"));
  EXPECT_TRUE(fs::is_regular_file(d / "walk" / "run.png"));
}

TEST(CliInstall, CpackMakesADebianPackageThatDependsOnMrptsRuntime) {
  const auto d = scratch() / "cpack";
  fs::remove_all(d);
  const RunResult r = shell("cpack -G DEB --config " + quote(kBuild + "/CPackConfig.cmake") +
                            " -B " + quote(d.string()) + " >/dev/null");
  ASSERT_EQ(r.code, 0) << r.err;
  fs::path deb;
  for (const auto& e : fs::directory_iterator(d))
    if (e.path().extension() == ".deb") deb = e.path();
  ASSERT_FALSE(deb.empty()) << "no .deb in " << d;
  const RunResult info = shell("dpkg-deb -I " + quote(deb.string()));
  ASSERT_EQ(info.code, 0) << info.err;
  EXPECT_NE(info.out.find("Package: carenav"), std::string::npos) << info.out;
  EXPECT_TRUE(std::regex_search(info.out, std::regex("Depends:.*libmrpt-obs2\\.5"))) << info.out;
  const RunResult files = shell("dpkg-deb -c " + quote(deb.string()));
  EXPECT_NE(files.out.find("./usr/bin/carenav"), std::string::npos);
  EXPECT_NE(files.out.find("./usr/share/carenav/ini/defaults.ini"), std::string::npos);
  EXPECT_NE(files.out.find("./usr/share/carenav/maps/worlds/apartment.yaml"), std::string::npos);
}
