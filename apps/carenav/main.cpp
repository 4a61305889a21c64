// carenav: mapping, localisation and navigation for assistive indoor robots.
#include "commands.h"

#include <carenav/common/crash_guard.h>
#include <carenav/common/errors.h>
#include <carenav/localization/localization_params.h>
#include <carenav/navigation/navigation_params.h>
#include <carenav/perception/perception_params.h>
#include <carenav/sim/sim_params.h>
#include <carenav/slam/slam_params.h>

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <iostream>

#ifndef CARENAV_VERSION
#define CARENAV_VERSION "dev"
#endif
#ifndef CARENAV_DEFAULT_DATASETS
#define CARENAV_DEFAULT_DATASETS "/usr/share/mrpt/datasets"
#endif

namespace carenav::app {
std::vector<std::pair<int, CommandAdder>>& commandRegistry() {
  static std::vector<std::pair<int, CommandAdder>> r;
  return r;
}
std::vector<CommandAdder>& importRegistry() {
  static std::vector<CommandAdder> r;
  return r;
}
namespace {
namespace fs = std::filesystem;

std::string errnoText(int e) { return std::error_code(e, std::generic_category()).message(); }

/** Creates and removes a file in `dir`; the reason when it cannot. */
std::string cannotWriteIn(const fs::path& dir) {
  const fs::path probe = dir / (".carenav-write-test-" + std::to_string(::getpid()));
  const int fd = ::open(probe.c_str(), O_WRONLY | O_CREAT | O_EXCL, 0600);
  if (fd < 0) return errnoText(errno);
  ::close(fd);
  ::unlink(probe.c_str());
  return {};
}

/** The nearest existing folder at or above `p`, or the path component that
 *  exists and is not a folder (then `blocked` is set). */
fs::path nearestExisting(const fs::path& p, bool& blocked) {
  blocked = false;
  fs::path cur = p;
  std::error_code ec;
  while (!cur.empty()) {
    const auto st = fs::status(cur, ec);
    if (!ec && fs::exists(st)) {
      blocked = !fs::is_directory(st);
      return cur;
    }
    if (cur == cur.root_path() || !cur.has_parent_path() || cur.parent_path() == cur) break;
    cur = cur.parent_path();
  }
  return fs::path(".");
}
}  // namespace

void prepareOutputFolder(const std::string& dir, const std::string& option) {
  const std::string head = option + " " + dir + ": ";
  if (dir.empty()) throw InputError(option + ": empty folder name");
  const fs::path p = fs::absolute(fs::path(dir)).lexically_normal();
  bool blocked = false;
  const fs::path have = nearestExisting(p, blocked);
  if (blocked)
    throw InputError(head + (have == p ? std::string("is a file, not a folder")
                                       : have.string() + " is a file, not a folder"));
  std::error_code ec;
  fs::create_directories(p, ec);
  if (ec || !fs::is_directory(p))
    throw InputError(head + "cannot create the folder in " + have.string() + ": " +
                     (ec ? ec.message() : std::string("not created")));
  if (const std::string why = cannotWriteIn(p); !why.empty())
    throw InputError(head + "cannot write in the folder: " + why);
}

void prepareOutputFile(const std::string& path, const std::string& option) {
  const std::string head = option + " " + path + ": ";
  if (path.empty()) throw InputError(option + ": empty file name");
  const fs::path p = fs::absolute(fs::path(path)).lexically_normal();
  std::error_code ec;
  if (fs::is_directory(p, ec)) throw InputError(head + "is a folder, expected a file name");
  const fs::path parent = p.parent_path();
  const auto st = fs::status(parent, ec);
  if (ec || !fs::exists(st)) {
    bool blocked = false;
    const fs::path have = nearestExisting(parent, blocked);
    throw InputError(head + "the folder " + parent.string() + " does not exist" +
                     (blocked ? " (" + have.string() + " is a file)" : std::string()));
  }
  if (!fs::is_directory(st)) throw InputError(head + parent.string() + " is a file, not a folder");
  if (const std::string why = cannotWriteIn(parent); !why.empty())
    throw InputError(head + "cannot write in the folder " + parent.string() + ": " + why);
}

std::string mrptDatasetsDir() {
  if (const char* e = std::getenv("CARENAV_MRPT_DATASETS"); e && *e) return e;
  return CARENAV_DEFAULT_DATASETS;
}
}  // namespace carenav::app

namespace {
/** "unknown command 'x' ..." when the first word that is not an option names
 *  no command (CLI11 would only say that a subcommand is required); empty
 *  otherwise. */
std::string unknownCommand(const CLI::App& app, int argc, char** argv) {
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (!a.empty() && a[0] == '-') continue;
    std::string names;
    for (const auto* c : app.get_subcommands({})) {
      if (c->get_name() == a) return {};
      names += (names.empty() ? "" : ", ") + c->get_name();
    }
    return "unknown command '" + a + "' (commands: " + names + "; carenav --help)";
  }
  return {};
}
}  // namespace

int main(int argc, char** argv) {
  using namespace carenav;
  installCrashGuard();
  limitAddressSpace(defaultMemoryLimitMB());
  // Every module's profile sections, so `profile check` knows all keys.
  slam::registerProfileSections();
  localization::registerProfileSections();
  navigation::registerProfileSections();
  perception::registerProfileSections();
  sim::registerProfileSections();
  CLI::App app{
      "carenav: mapping, localisation and navigation for assistive indoor robots "
      "(walkers, social and care robots), on MRPT.\n"
      "Exit codes: 0 ok, 1 runtime failure, 2 bad usage or bad input."};
  app.set_version_flag("--version", std::string(CARENAV_VERSION));
  app.require_subcommand(1);
  app::GlobalOptions g;
  app.add_flag("-q,--quiet", g.quiet, "No progress display and no chatter on stderr");
  auto& cmds = app::commandRegistry();
  std::stable_sort(cmds.begin(), cmds.end(),
                   [](const auto& a, const auto& b) { return a.first < b.first; });
  for (const auto& [order, add] : cmds) add(app, g);
  if (const std::string unknown = unknownCommand(app, argc, argv); !unknown.empty()) {
    std::fprintf(stderr, "carenav: error: %s\n", unknown.c_str());
    return kExitInput;
  }

  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    app.exit(e);  // prints the message and a hint
    return kExitInput;
  } catch (const InputError& e) {
    std::fprintf(stderr, "carenav: error: %s\n", e.what());
    return kExitInput;
  } catch (const std::filesystem::filesystem_error& e) {
    // Paths come from the user (--out folders, files to write): their input.
    std::fprintf(stderr, "carenav: error: %s: %s (%s)\n", e.path1().c_str(),
                 e.code().message().c_str(), e.what());
    return kExitInput;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "carenav: failure: %s\n", e.what());
    return kExitRuntime;
  }
  return kExitOk;
}
