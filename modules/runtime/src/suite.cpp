#include <carenav/common/data_dir.h>
#include <carenav/common/errors.h>
#include <carenav/common/file.h>
#include <carenav/common/json.h>
#include <carenav/common/text.h>
#include <carenav/common/yaml.h>
#include <carenav/runtime/suite.h>

#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <limits>
#include <stdexcept>

namespace carenav::navigation {

namespace fs = std::filesystem;

namespace {

/** A carenav world file: a top-level `map:` key and no `world:` key (a
 *  scenario names its world with `world:`). A file that does not parse is
 *  left in the suite, where its run reports what is wrong. */
bool isWorldFile(const fs::path& p) {
  try {
    const yaml::Node root = yaml::parse(readWholeFile(p.string()), p.string());
    return root.kind == yaml::Node::Kind::Map && root.find("map") && !root.find("world");
  } catch (const InputError&) {
    return false;
  }
}

}  // namespace

std::vector<std::string> suiteFiles(const std::string& dir) {
  if (!fs::is_directory(dir)) throw InputError(dir + ": not a folder");
  std::vector<std::string> files;
  for (const auto& e : fs::directory_iterator(dir))
    if (e.path().extension() == ".yaml" &&
        e.path().string().find(".places.") == std::string::npos && !isWorldFile(e.path()))
      files.push_back(e.path().string());
  std::sort(files.begin(), files.end());
  if (files.empty()) throw InputError(dir + ": no *.yaml scenario in it");
  return files;
}

Scenario liveScenario(const std::string& world) {
  Scenario s;
  s.name = "live";
  s.file = "navigate";
  s.world = !world.empty() ? world
                           : dataFile("maps/worlds/apartment.yaml", "the default world (--world)");
  if (!fs::exists(s.world)) throw InputError(s.world + ": no such world file (--world)");
  s.profile = dataFile("ini/isr-aiwalker.ini", "the default profile (--profile)");
  s.start = {1.0, 4.0, 0};
  s.duration = std::numeric_limits<double>::infinity();
  return s;
}

namespace {

/** How a child's run ended, as passed to the parent. */
enum class ChildStatus { kOk, kInput, kPluginMismatch, kError };

NLOHMANN_JSON_SERIALIZE_ENUM(ChildStatus, {{ChildStatus::kOk, "ok"},
                                           {ChildStatus::kInput, "input"},
                                           {ChildStatus::kPluginMismatch, "plugin_mismatch"},
                                           {ChildStatus::kError, "error"}})

/** The child's answer: {"status": ..., "metrics": {...} | "message": "..."}. */
std::string childAnswer(const Scenario& s, const RunOptions& o) {
  Json j;
  try {
    j["metrics"] = runScenario(s, o).toJsonValue(true);
    j["status"] = ChildStatus::kOk;
  } catch (const PluginMismatchError& e) {
    j = {{"status", ChildStatus::kPluginMismatch}, {"message", e.what()}};
  } catch (const InputError& e) {
    j = {{"status", ChildStatus::kInput}, {"message", e.what()}};
  } catch (const std::exception& e) {
    j = {{"status", ChildStatus::kError}, {"message", e.what()}};
  }
  return dumpJson(j, false);
}

void writeAll(int fd, const std::string& out) {
  size_t done = 0;
  while (done < out.size()) {
    const ssize_t w = write(fd, out.data() + done, out.size() - done);
    if (w <= 0) break;
    done += static_cast<size_t>(w);
  }
}

std::string readAll(int fd) {
  std::string text;
  char buf[4096];
  ssize_t r;
  while ((r = read(fd, buf, sizeof buf)) > 0) text.append(buf, static_cast<size_t>(r));
  return text;
}

/** The metrics of a child that gave no answer (it crashed). */
RunMetrics noAnswer(const Scenario& s, const RunOptions& o, int status) {
  RunMetrics m;
  m.scenario = s.name;
  m.plugin = o.plugin;
  m.outcome = WIFSIGNALED(status) ? "crashed (signal " + std::to_string(WTERMSIG(status)) + ")"
                                  : "ended without a result";
  return m;
}

/** The parent's side: the metrics, or the child's error thrown again. */
RunMetrics fromAnswer(const Json& j) {
  const std::string message = j.value("message", "");
  switch (j.at("status").get<ChildStatus>()) {
    case ChildStatus::kOk:
      return RunMetrics::fromJson(j.at("metrics"));
    case ChildStatus::kPluginMismatch:
      throw PluginMismatchError(message);
    case ChildStatus::kInput:
      throw InputError(message);
    case ChildStatus::kError:
      break;
  }
  throw std::runtime_error(message);
}

}  // namespace

RunMetrics runInChild(const Scenario& s, const RunOptions& o) {
  int fd[2];
  if (pipe(fd) != 0) throw std::runtime_error("navigate: cannot create a pipe");
  std::cout.flush();
  std::cerr.flush();
  const pid_t pid = fork();
  if (pid < 0) throw std::runtime_error("navigate: cannot fork");
  if (pid == 0) {
    close(fd[0]);
    writeAll(fd[1], childAnswer(s, o));
    close(fd[1]);
    _exit(0);
  }
  close(fd[1]);
  const std::string text = readAll(fd[0]);
  close(fd[0]);
  int status = 0;
  waitpid(pid, &status, 0);
  const Json answer = Json::parse(text, nullptr, false);
  if (!answer.is_object() || !answer.contains("status")) return noAnswer(s, o, status);
  return fromAnswer(answer);
}

std::vector<RunMetrics> runSuite(const std::vector<Scenario>& scenarios,
                                 const std::vector<std::string>& plugins, const RunOptions& base) {
  const bool single = scenarios.size() == 1 && plugins.size() <= 1;
  if (base.speed > 0 && !single)
    throw InputError("navigate: --speed paces one run; a suite runs as fast as it can");
  const std::vector<std::string> ps = plugins.empty() ? std::vector<std::string>{""} : plugins;
  std::vector<RunMetrics> runs;
  for (const auto& s : scenarios) {
    for (const auto& p : ps) {
      RunOptions o = base;
      o.plugin = p;
      if (!base.out_dir.empty())
        o.out_dir = (fs::path(base.out_dir) / (s.name + (p.empty() ? "" : "-" + p))).string();
      if (single) {
        runs.push_back(runScenario(s, o));
        continue;
      }
      try {
        runs.push_back(runInChild(s, o));
      } catch (const PluginMismatchError& e) {
        if (base.progress) std::cerr << "[navigate] skipped: " << e.what() << "\n";
      }
    }
  }
  return runs;
}

namespace {

std::string cell(double v, int prec = 2) { return std::isnan(v) ? "-" : formatFixed(v, prec); }

}  // namespace

std::string runsTable(const std::vector<RunMetrics>& runs) {
  std::string out;
  const auto line = [&out](const char* format, auto... args) {
    std::string b(static_cast<size_t>(std::snprintf(nullptr, 0, format, args...)), '\0');
    std::snprintf(b.data(), b.size() + 1, format, args...);
    out += b;
  };
  line("%-24s %-16s %-7s %5s %7s %7s %7s %7s %6s %8s %7s  %s\n", "scenario", "plugin", "success",
       "coll", "minclr", "meanclr", "time_s", "path_m", "v_mps", "fidelity", "cyc_ms", "outcome");
  size_t ok = 0;
  for (const auto& r : runs) {
    line("%-24s %-16s %-7s %5zu %7s %7s %7s %7s %6s %8s %7s  %s\n", r.scenario.c_str(),
         r.plugin.c_str(), r.success ? "yes" : "NO", r.collisions, cell(r.min_clearance_m).c_str(),
         cell(r.mean_clearance_m).c_str(), cell(r.duration_s, 1).c_str(),
         cell(r.path_length_m).c_str(), cell(r.mean_speed_mps).c_str(),
         cell(r.intent_fidelity, 3).c_str(), cell(r.cycle_ms_mean, 2).c_str(), r.outcome.c_str());
    ok += r.success;
  }
  line("%zu of %zu runs succeeded\n", ok, runs.size());
  return out;
}

std::string runsJson(const std::vector<RunMetrics>& runs) {
  std::string out = "[\n";
  for (size_t i = 0; i < runs.size(); ++i)
    out += runs[i].toJson() + (i + 1 < runs.size() ? ",\n" : "\n");
  return out + "]\n";
}

}  // namespace carenav::navigation
