// Robot profiles: one INI file per robot, layered over shared defaults,
// with `--set section.key=value` overrides and strict validation.
#pragma once

#include <carenav/common/errors.h>
#include <carenav/common/params.h>

#include <functional>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace mrpt::config {
class CConfigFileMemory;
}

namespace carenav {

/** Schema of one profile section, type-erased from a ParamTable<T>. */
struct SectionSchema {
  /** Exact section name ("robot"), or a family "sensor.*" matching any
   *  section whose name starts with "sensor.". */
  std::string name;
  /** For families with variants: the key that selects this schema ("type")
   *  and its value ("lidar2d"). Empty when the schema has no variants. */
  std::string variant_key, variant_value;
  std::string description;
  std::vector<ParamSpec> specs;
  /** Problems of a section's values as (key, message); key is "" for rules
   *  that span several keys. Unknown keys are reported as "unknown key". */
  std::function<std::vector<std::pair<std::string, std::string>>(
      const std::vector<std::pair<std::string, std::string>>&)>
      validate;

  bool matchesName(const std::string& section) const;

  /** `table` must outlive the schema (tables are function-local statics). */
  template <class T>
  static SectionSchema of(const ParamTable<T>& table, std::string name, std::string description,
                          std::string variant_key = "", std::string variant_value = "") {
    SectionSchema s;
    s.name = std::move(name);
    s.description = std::move(description);
    s.variant_key = std::move(variant_key);
    s.variant_value = std::move(variant_value);
    s.specs = table.specs();
    s.validate = [&table](const std::vector<std::pair<std::string, std::string>>& kv) {
      std::vector<std::pair<std::string, std::string>> problems;
      T obj{};
      for (const auto& [k, v] : kv) {
        if (!table.find(k)) {
          problems.emplace_back(k, "unknown key");
          continue;
        }
        try {
          table.set(obj, k, v);
        } catch (const ParamValueError& e) {
          problems.emplace_back(k, e.what());
        }
      }
      if (problems.empty())
        for (auto& p : table.crossCheck(obj)) problems.emplace_back("", p);
      return problems;
    };
    return s;
  }
};

/** A key that moved to another section (and maybe another name). Profiles
 *  written before the move still work: the old key is read as the new one,
 *  unless the new one is set too (the new one wins), and `profile check`
 *  reports it as renamed. */
struct RenamedKey {
  std::string old_section, old_key, new_section, new_key;
  std::string oldName() const { return old_section + "." + old_key; }
  std::string newName() const { return new_section + "." + new_key; }
};

/** Every section a profile may hold. Modules add theirs at start-up
 *  (common's own sections are always present). */
class ProfileSchemas {
 public:
  static ProfileSchemas& instance();
  void add(SectionSchema s);
  const std::vector<SectionSchema>& all() const { return schemas_; }
  /** Schemas whose name matches the section (all variants of a family). */
  std::vector<const SectionSchema*> candidates(const std::string& section) const;

  /** Declares that [old_section] `key` is now [new_section] `key`, for each key. */
  void addRenames(const std::string& old_section, const std::string& new_section,
                  const std::vector<std::string>& keys);
  void addRename(RenamedKey r);
  const std::vector<RenamedKey>& renames() const { return renames_; }
  /** The rename of [section] key, or nullptr when it was not renamed. */
  const RenamedKey* renamedFrom(const std::string& section, const std::string& key) const;

 private:
  ProfileSchemas();
  std::vector<SectionSchema> schemas_;
  std::vector<RenamedKey> renames_;
};

/** Where a value came from. */
struct ValueOrigin {
  std::string file;  ///< INI path, "--set" for a command-line override
  int line = 0;      ///< 1-based line in file; 0 for overrides
  std::string where() const;
};

/** One problem found in a profile. */
struct ProfileIssue {
  ValueOrigin origin;
  std::string section, key;
  std::string message;
  std::string text() const;  ///< "file:line: [section] key: message"
};

/** A loaded robot profile. Values are strings until a module reads its
 *  section into its parameter struct with section<T>(). */
class Profile {
 public:
  struct Entry {
    std::string value;
    ValueOrigin origin;
  };
  using Section = std::vector<std::pair<std::string, Entry>>;  ///< in file order

  /** Reads `path` and, first, the chain of files named by `[profile] base`.
   *  Throws InputError for a missing, empty or malformed file (with the line).
   *  Does not validate keys: call check() or validate(). */
  static Profile load(const std::string& path);
  /** Parses INI text as if read from `origin_name` (used by tests and for
   *  embedded defaults). */
  static Profile fromText(const std::string& text, const std::string& origin_name);

  /** Applies "section.key=value" (the section may itself contain dots: the
   *  key is what follows the last dot). Throws InputError on bad syntax. */
  void applyOverride(const std::string& assignment);
  void applyOverrides(const std::vector<std::string>& assignments);

  /** All problems: unknown sections, unknown keys (with a suggestion),
   *  wrong types, out-of-range values, inconsistent values. */
  std::vector<ProfileIssue> check() const;
  /** Throws InputError listing every problem of check(). */
  void validate() const;
  /** Old keys set in the profile (see RenamedKey), one note each:
   *  "navigation.k_heading is now nav.goal_dwa.k_heading", plus, when the new
   *  key is set too, which value wins. Not problems: check() accepts them. */
  std::vector<ProfileIssue> renamedKeys() const;

  /** The named section read into T (defaults for absent keys). Throws
   *  InputError naming file, line, section, key and the allowed range. */
  template <class T>
  T section(const std::string& name) const {
    return section<T>(name, T::table());
  }
  template <class T>
  T section(const std::string& name, const ParamTable<T>& table, T obj = T{}) const {
    const auto sec = effectiveSection(name);
    if (!sec) return obj;
    std::string problems;  // every bad key, not only the first
    for (const auto& [key, e] : *sec) {
      try {
        table.set(obj, key, e.value);
      } catch (const ParamValueError& err) {
        problems += (problems.empty() ? "" : "\n  ") +
                    issueFor(name, key, e, err.what(), table.find(key)).text();
      }
    }
    if (problems.empty())
      for (const auto& p : table.crossCheck(obj))
        problems += (problems.empty() ? "" : "\n  ") + origin() + ": [" + name + "]: " + p;
    if (!problems.empty()) throw InputError(problems);
    return obj;
  }

  bool hasSection(const std::string& name) const { return sections_.count(name) > 0; }
  /** The section as its readers see it: renamed keys moved from their old
   *  section to the new one (the new key wins when both are set); nullopt
   *  when neither the section nor any old key of it is in the profile. */
  std::optional<Section> effectiveSection(const std::string& name) const;
  /** Section names in sorted order. */
  std::vector<std::string> sectionNames() const;
  std::vector<std::string> sectionsWithPrefix(const std::string& prefix) const;
  const Section* find(const std::string& name) const;
  /** The raw value, or `fallback` when absent. */
  std::string value(const std::string& section, const std::string& key,
                    const std::string& fallback = "") const;

  /** The profile file given to load() ("(embedded)" for fromText). */
  const std::string& origin() const { return origin_; }
  /** Every file read, base first. */
  const std::vector<std::string>& files() const { return files_; }

  /** Resolved profile as INI text: every declared key of every present or
   *  required section, with its value, unit and where it came from. */
  std::string resolvedText() const;
  /** The resolved values as an MRPT config (for MRPT classes that read
   *  their parameters with loadFromConfigFile). */
  void toMrptConfig(mrpt::config::CConfigFileMemory& out) const;

 private:
  static void parseInto(Profile& p, const std::string& text, const std::string& file,
                        std::vector<std::string>& chain);
  ProfileIssue issueFor(const std::string& section, const std::string& key, const Entry& e,
                        const std::string& message, const ParamSpec* spec) const;

  /** Every section as its readers see it (effectiveSection of each). */
  std::map<std::string, Section> effectiveSections() const;

  std::map<std::string, Section> sections_;
  std::string origin_;
  std::vector<std::string> files_;
};

/** Levenshtein distance, for "did you mean" suggestions. */
size_t editDistance(const std::string& a, const std::string& b);

}  // namespace carenav
