// Readers of outside input in `common` are bounded by construction: nesting
// and chains far deeper than any real file are refused with an InputError
// naming the file and line, never a stack overflow.
#include <carenav/common/profile.h>
#include <carenav/common/yaml.h>

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

using namespace carenav;
namespace fs = std::filesystem;

namespace {

template <class F>
std::string errorOf(F&& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  ADD_FAILURE() << "no InputError thrown";
  return "";
}

std::string nestedBlockMaps(int levels) {
  std::string t;
  for (int i = 0; i < levels; ++i) t += std::string(2 * i, ' ') + "k:\n";
  return t + std::string(2 * levels, ' ') + "k: 1\n";
}

}  // namespace

TEST(BoundedYaml, RealNestingParses) {
  const auto n = yaml::parse(nestedBlockMaps(10) + "x: [[1, 2], [3, [4, 5]]]\n", "w.yaml");
  EXPECT_EQ(n.kind, yaml::Node::Kind::Map);
}

TEST(BoundedYaml, DeepBlockNestingIsRefusedWithFileAndLine) {
  const std::string msg = errorOf([] { yaml::parse(nestedBlockMaps(5000), "deep.yaml"); });
  EXPECT_NE(msg.find("deep.yaml:"), std::string::npos) << msg;
  EXPECT_NE(msg.find("nested deeper than"), std::string::npos) << msg;
}

TEST(BoundedYaml, DeepFlowListsAreRefused) {
  const std::string t = "x: " + std::string(200000, '[') + "1" + std::string(200000, ']') + "\n";
  const std::string msg = errorOf([&] { yaml::parse(t, "flow.yaml"); });
  EXPECT_NE(msg.find("flow.yaml:1: nested deeper than"), std::string::npos) << msg;
}

TEST(BoundedYaml, DeepListItemsAreRefused) {
  std::string t;
  for (int i = 0; i < 5000; ++i) t += std::string(2 * i, ' ') + "-\n";
  t += std::string(2 * 5000, ' ') + "- 1\n";
  const std::string msg = errorOf([&] { yaml::parse(t, "seq.yaml"); });
  EXPECT_NE(msg.find("nested deeper than"), std::string::npos) << msg;
}

TEST(BoundedProfile, ALongBaseChainIsRefusedNamingTheFile) {
  const fs::path d = fs::temp_directory_path() / ("carenav_chain_" + std::to_string(::getpid()));
  fs::create_directories(d);
  const int n = 3000;
  for (int i = 0; i < n; ++i) {
    std::ofstream f(d / ("p" + std::to_string(i) + ".ini"));
    f << "[profile]\nname = p" << i << "\n";
    if (i + 1 < n) f << "base = p" << i + 1 << ".ini\n";
  }
  const std::string msg = errorOf([&] { Profile::load((d / "p0.ini").string()); });
  EXPECT_NE(msg.find("base chain"), std::string::npos) << msg;
  EXPECT_NE(msg.find(".ini:"), std::string::npos) << msg;
  // A short chain still loads.
  EXPECT_NO_THROW(Profile::load((d / ("p" + std::to_string(n - 5) + ".ini")).string()));
  fs::remove_all(d);
}
