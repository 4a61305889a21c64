// Helpers for integration tests that run the real carenav binary.
#pragma once

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

namespace carenav_test {
namespace fs = std::filesystem;
inline const std::string kTestData = CARENAV_TEST_DATA;

inline const std::string kBin = CARENAV_BIN;
inline const std::string kSrc = CARENAV_SOURCE_DIR;
inline const std::string kDatasets = CARENAV_MRPT_DATASETS;
inline const std::string kSena = kDatasets + "/2006-01ENE-21-SENA_Telecom Faculty_one_loop_only.rawlog";

struct RunResult {
  int code = -1;
  std::string out, err;
};

inline std::string quote(const std::string& s) {
  std::string q = "'";
  for (char c : s) q += (c == '\'') ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

inline fs::path scratch() {
  auto d = fs::temp_directory_path() / ("carenav_cli_" + std::to_string(::getpid()));
  fs::create_directories(d);
  return d;
}

inline std::string slurp(const fs::path& p) {
  std::ifstream f(p, std::ios::binary);
  std::stringstream ss;
  ss << f.rdbuf();
  return ss.str();
}

/** Runs a shell command line; captures stdout, stderr and the exit code. */
inline RunResult shell(const std::string& cmdline) {
  const auto errfile = scratch() / "stderr.txt";
  RunResult r;
  FILE* p = popen((cmdline + " 2>" + quote(errfile.string())).c_str(), "r");
  if (!p) return r;
  std::array<char, 4096> buf;
  size_t n;
  while ((n = fread(buf.data(), 1, buf.size(), p)) > 0) r.out.append(buf.data(), n);
  const int st = pclose(p);
  r.code = WIFEXITED(st) ? WEXITSTATUS(st) : 128 + WTERMSIG(st);
  r.err = slurp(errfile);
  return r;
}

inline RunResult carenav(const std::vector<std::string>& args) {
  std::string cmd = quote(kBin);
  for (const auto& a : args) cmd += " " + quote(a);
  return shell(cmd);
}

inline uint64_t jsonNumber(const std::string& json, const std::string& key) {
  std::smatch m;
  if (!std::regex_search(json, m, std::regex("\"" + key + "\": ([0-9.]+)"))) {
    ADD_FAILURE() << "no key " << key << " in " << json;
    return 0;
  }
  return std::stoull(m[1]);
}

}  // namespace carenav_test
