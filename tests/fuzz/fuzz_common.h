// Shared by the libFuzzer harnesses (tests/fuzz/README.md): readers that
// take a path get the input written to a file in a private folder; a refusal
// (carenav::InputError and the other std::exceptions the CLI turns into exit
// 2 or 1) is a normal end, anything else (a crash, a sanitizer report, a hang
// or an allocation beyond -rss_limit_mb) is a finding.
#pragma once

#include <unistd.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>

namespace carenav_fuzz {

/** A folder of this process for the harness's input files. */
inline const std::filesystem::path& folder() {
  static const std::filesystem::path d = [] {
    auto p =
        std::filesystem::temp_directory_path() / ("carenav_fuzz_" + std::to_string(::getpid()));
    std::filesystem::create_directories(p);
    return p;
  }();
  return d;
}

/** Writes the input to `name` in folder() and returns its path. */
inline std::string asFile(const uint8_t* data, size_t size, const std::string& name) {
  const auto p = folder() / name;
  std::ofstream(p, std::ios::binary | std::ios::trunc)
      .write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  return p.string();
}

inline std::string asText(const uint8_t* data, size_t size) {
  return std::string(reinterpret_cast<const char*>(data), size);
}

}  // namespace carenav_fuzz

/** Runs `body`; every std::exception is a refusal, not a finding. */
#define CARENAV_FUZZ_TRY(body)      \
  try {                             \
    body;                           \
  } catch (const std::exception&) { \
  }                                 \
  return 0
