// Output folders and files that cannot be written: every command with --out
// answers exit 2 before any work, naming the option, the path and why (not
// the raw filesystem_error text).
#include "cli_helpers.h"

using namespace carenav_test;

namespace {

const std::string kWalker = kSrc + "/ini/isr-aiwalker.ini";

/** The command's arguments with OUT where the output path goes. Inputs are
 *  placeholders: the output is checked before they are read. */
std::vector<std::vector<std::string>> folderCommands() {
  return {
      {"slam", "--profile", kWalker, "--rawlog", "in.rawlog", "--method", "icp", "--out", "OUT"},
      {"localize", "--profile", kWalker, "--map", "m.gridmap.gz", "--rawlog", "in.rawlog",
       "--global", "--out", "OUT"},
      {"perceive", "--profile", kWalker, "--rawlog", "in.rawlog", "--out", "OUT"},
      {"navigate", "--scenario", "s.yaml", "--out", "OUT"},
      {"eval", "--est", "a.tum", "--ref", "b.tum", "--out", "OUT"},
      {"demo", "--out", "OUT"},
  };
}
std::vector<std::vector<std::string>> fileCommands() {
  return {
      {"simulate", "--profile", kWalker, "--world", "w.yaml", "--path", "0,0 1,0", "--out", "OUT"},
      {"places", "render", "--map", "m.gridmap.gz", "--out", "OUT"},
      {"import", "carmen", "in.log", "--out", "OUT"},
      {"map", "convert", "m.gridmap.gz", "OUT"},
  };
}

std::vector<std::string> with(std::vector<std::string> args, const std::string& out) {
  for (auto& a : args)
    if (a == "OUT") a = out;
  return args;
}

}  // namespace

TEST(CliOutputs, UnwritableOutputFoldersExit2NamingTheFolderAndWhy) {
  const auto dir = scratch() / "outputs";
  fs::create_directories(dir);
  const auto file = dir / "a_file";
  std::ofstream(file) << "not a folder\n";
  struct Case {
    std::string out, why;
  };
  const std::vector<Case> cases{
      {"/proc/carenav-out", "cannot create the folder in /proc"},
      {file.string(), "is a file, not a folder"},
      {(file / "sub").string(), file.string() + " is a file, not a folder"},
  };
  for (const auto& cmd : folderCommands())
    for (const auto& c : cases) {
      const RunResult r = carenav(with(cmd, c.out));
      SCOPED_TRACE(cmd[0] + " --out " + c.out + ": " + r.err);
      EXPECT_EQ(r.code, 2);
      EXPECT_NE(r.err.find("--out " + c.out + ": "), std::string::npos);
      EXPECT_NE(r.err.find(c.why), std::string::npos);
      EXPECT_EQ(r.err.find("filesystem error"), std::string::npos);
    }
  EXPECT_EQ(slurp(file), "not a folder\n") << "the file is left alone";
  EXPECT_FALSE(fs::exists("/proc/carenav-out"));
}

TEST(CliOutputs, UnwritableOutputFilesExit2NamingTheFolderAndWhy) {
  const auto dir = scratch() / "outputs_f";
  fs::create_directories(dir);
  const auto file = dir / "a_file";
  std::ofstream(file) << "x\n";
  for (const auto& cmd : fileCommands()) {
    const std::string opt = cmd[0] == "map" ? "out" : "--out";
    const std::string ext = cmd[0] == "places" || cmd[0] == "map" ? ".png" : ".rawlog";
    struct Case {
      std::string out, why;
    };
    const std::vector<Case> cases{
        {"/proc/carenav-out" + ext, "cannot write in the folder /proc"},
        {(file / ("x" + ext)).string(), file.string() + " is a file, not a folder"},
        {(dir / "missing" / ("x" + ext)).string(), "does not exist"},
    };
    for (const auto& c : cases) {
      const RunResult r = carenav(with(cmd, c.out));
      SCOPED_TRACE(cmd[0] + " " + opt + " " + c.out + ": " + r.err);
      EXPECT_EQ(r.code, 2);
      EXPECT_NE(r.err.find(c.out), std::string::npos);
      EXPECT_NE(r.err.find(c.why), std::string::npos);
      EXPECT_EQ(r.err.find("filesystem error"), std::string::npos);
    }
  }
}

TEST(CliOutputs, AWritableFolderIsCreatedUpFront) {
  // The folder exists even when the command then fails on its input.
  const auto out = scratch() / "made" / "deep";
  fs::remove_all(scratch() / "made");
  const RunResult r = carenav({"slam", "--profile", kWalker, "--rawlog", "missing.rawlog",
                               "--method", "icp", "--out", out.string()});
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("missing.rawlog"), std::string::npos) << r.err;
  EXPECT_TRUE(fs::is_directory(out));
}
