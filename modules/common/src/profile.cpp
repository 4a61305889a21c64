#include <carenav/common/data_dir.h>
#include <carenav/common/file.h>
#include <carenav/common/profile.h>
#include <carenav/common/robot.h>

#include <mrpt/config/CConfigFileMemory.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace fs = std::filesystem;

namespace carenav {

// ---------------------------------------------------------------- schemas

bool SectionSchema::matchesName(const std::string& section) const {
  if (name.size() >= 2 && name.compare(name.size() - 2, 2, ".*") == 0) {
    const std::string prefix = name.substr(0, name.size() - 1);  // keeps the dot
    return section.size() > prefix.size() && section.compare(0, prefix.size(), prefix) == 0;
  }
  return section == name;
}

ProfileSchemas::ProfileSchemas() = default;

ProfileSchemas& ProfileSchemas::instance() {
  static ProfileSchemas* inst = [] {
    auto* p = new ProfileSchemas();
    return p;
  }();
  static bool common_done = false;
  if (!common_done) {
    common_done = true;
    registerCommonSections();
  }
  return *inst;
}

void ProfileSchemas::add(SectionSchema s) {
  for (auto& existing : schemas_)
    if (existing.name == s.name && existing.variant_value == s.variant_value) {
      existing = std::move(s);  // re-registration replaces
      return;
    }
  schemas_.push_back(std::move(s));
}

void ProfileSchemas::addRename(RenamedKey r) {
  for (auto& existing : renames_)
    if (existing.old_section == r.old_section && existing.old_key == r.old_key) {
      existing = std::move(r);  // re-registration replaces
      return;
    }
  renames_.push_back(std::move(r));
}

void ProfileSchemas::addRenames(const std::string& old_section, const std::string& new_section,
                                const std::vector<std::string>& keys) {
  for (const auto& k : keys) addRename({old_section, k, new_section, k});
}

const RenamedKey* ProfileSchemas::renamedFrom(const std::string& section,
                                              const std::string& key) const {
  for (const auto& r : renames_)
    if (r.old_section == section && r.old_key == key) return &r;
  return nullptr;
}

std::vector<const SectionSchema*> ProfileSchemas::candidates(const std::string& section) const {
  std::vector<const SectionSchema*> out;
  for (const auto& s : schemas_)
    if (s.matchesName(section)) out.push_back(&s);
  return out;
}

// ---------------------------------------------------------------- issues

std::string ValueOrigin::where() const {
  if (line > 0) return file + ":" + std::to_string(line);
  return file;
}

std::string ProfileIssue::text() const {
  std::string s = origin.where() + ": [" + section + "]";
  if (!key.empty()) s += " " + key;
  return s + ": " + message;
}

size_t editDistance(const std::string& a, const std::string& b) {
  std::vector<size_t> prev(b.size() + 1), cur(b.size() + 1);
  for (size_t j = 0; j <= b.size(); ++j) prev[j] = j;
  for (size_t i = 1; i <= a.size(); ++i) {
    cur[0] = i;
    for (size_t j = 1; j <= b.size(); ++j)
      cur[j] = std::min({prev[j] + 1, cur[j - 1] + 1, prev[j - 1] + (a[i - 1] != b[j - 1])});
    std::swap(prev, cur);
  }
  return prev[b.size()];
}

// ---------------------------------------------------------------- parsing

namespace {

bool validName(const std::string& s) {
  if (s.empty()) return false;
  return std::all_of(s.begin(), s.end(), [](unsigned char c) {
    return std::isalnum(c) || c == '_' || c == '.' || c == '-';
  });
}

std::string stripInlineComment(const std::string& v) {
  for (size_t i = 1; i < v.size(); ++i)
    if ((v[i] == ';' || v[i] == '#') && (v[i - 1] == ' ' || v[i - 1] == '\t'))
      return v.substr(0, i);
  return v;
}

std::string readFileOrThrow(const std::string& path) {
  return readWholeFile(path, {"profile not found (no such file)", "is a directory, not a profile",
                              "cannot open the profile for reading", "a profile"});
}

/** Longest chain of `base` profiles read (the shipped ones use 2); longer is
 *  refused before the recursion can exhaust the stack. */
constexpr size_t kMaxBaseChain = 16;

/** A profile's `base`: relative to the profile's own folder; a relative name
 *  not found there is looked for among the shipped profiles (dataDir()/ini),
 *  so a robot profile copied elsewhere still finds defaults.ini. */
std::string resolveBase(const std::string& file, const std::string& base) {
  const fs::path b(base);
  const fs::path beside = (fs::path(file).parent_path() / b).lexically_normal();
  std::error_code ec;
  if (b.is_absolute() || fs::exists(beside, ec)) return beside.string();
  const std::string data = dataDir();
  if (!data.empty()) {
    const fs::path shipped = (fs::path(data) / "ini" / b).lexically_normal();
    if (fs::exists(shipped, ec)) return shipped.string();
  }
  return beside.string();
}

const Profile::Entry* entryIn(const Profile::Section* sec, const std::string& key) {
  if (sec)
    for (const auto& [k, e] : *sec)
      if (k == key) return &e;
  return nullptr;
}

/** Layer of a value: its file's place in the base chain (base first), and
 *  after every file the command line (--set). */
size_t layerOf(const ValueOrigin& o, const std::vector<std::string>& files) {
  if (o.file == "--set") return files.size();
  const auto it = std::find(files.begin(), files.end(), o.file);
  return static_cast<size_t>(it - files.begin());
}

/** When an old key and its new name are both set: the new one, unless the
 *  old one comes from a later layer (a robot profile over a newer base, or
 *  --set over any file), which overrides as it did before the rename. */
bool oldKeyWins(const Profile::Entry& old_e, const Profile::Entry& new_e,
                const std::vector<std::string>& files) {
  return layerOf(old_e.origin, files) > layerOf(new_e.origin, files);
}

void setEntry(Profile::Section& sec, const std::string& key, Profile::Entry e) {
  for (auto& [k, v] : sec)
    if (k == key) {
      v = std::move(e);
      return;
    }
  sec.emplace_back(key, std::move(e));
}

}  // namespace

void Profile::parseInto(Profile& p, const std::string& text, const std::string& file,
                        std::vector<std::string>& chain) {
  std::map<std::string, Section> own;
  std::vector<std::string> order;
  std::string current;
  bool have_section = false;
  std::istringstream is(text);
  std::string raw;
  int lineno = 0;
  auto fail = [&](const std::string& msg) {
    throw InputError(file + ":" + std::to_string(lineno) + ": " + msg);
  };
  while (std::getline(is, raw)) {
    ++lineno;
    if (lineno == 1 && raw.compare(0, 3, "\xEF\xBB\xBF") == 0) raw.erase(0, 3);  // UTF-8 BOM
    if (raw.find('\0') != std::string::npos) fail("not a text file (NUL byte)");
    const std::string line = trim(raw);
    if (line.empty() || line[0] == ';' || line[0] == '#') continue;
    if (line[0] == '[') {
      const auto close = line.find(']');
      if (close == std::string::npos) fail("section header without closing ']': " + line);
      const std::string rest = trim(stripInlineComment(" " + line.substr(close + 1)));
      if (!rest.empty()) fail("unexpected text after the section header: " + rest);
      current = trim(line.substr(1, close - 1));
      if (!validName(current))
        fail("bad section name '" + current + "' (letters, digits, '_', '.', '-')");
      if (!own.count(current)) order.push_back(current);
      own[current];
      have_section = true;
      continue;
    }
    const auto eq = line.find('=');
    if (eq == std::string::npos) fail("expected 'key = value' or '[section]', got: " + line);
    if (!have_section) fail("'key = value' before any [section]");
    const std::string key = trim(line.substr(0, eq));
    if (!validName(key)) fail("bad key name '" + key + "'");
    std::string value = trim(stripInlineComment(line.substr(eq + 1)));
    if (value.size() >= 2 && value.front() == '"' && value.back() == '"')
      value = value.substr(1, value.size() - 2);
    auto& sec = own[current];
    for (const auto& [k, e] : sec)
      if (k == key)
        fail("[" + current + "] " + key + " is set twice (first at line " +
             std::to_string(e.origin.line) + ")");
    sec.emplace_back(key, Entry{value, ValueOrigin{file, lineno}});
  }
  if (own.empty()) throw InputError(file + ": empty profile: no [section] in it");

  // Base first, then this file over it.
  auto pit = own.find("profile");
  if (pit != own.end()) {
    for (const auto& [k, e] : pit->second) {
      if (k != "base" || e.value.empty()) continue;
      const std::string bs = resolveBase(file, e.value);
      if (std::find(chain.begin(), chain.end(), bs) != chain.end())
        throw InputError(e.origin.where() + ": [profile] base: '" + bs +
                         "' is already being read (circular base chain)");
      if (chain.size() >= kMaxBaseChain)
        throw InputError(e.origin.where() + ": [profile] base: more than " +
                         std::to_string(kMaxBaseChain) + " profiles in the base chain");
      chain.push_back(bs);
      std::string btext;
      try {
        btext = readFileOrThrow(bs);
      } catch (const InputError& err) {
        throw InputError(e.origin.where() + ": [profile] base: " + err.what());
      }
      parseInto(p, btext, bs, chain);
    }
  }
  p.files_.push_back(file);
  for (const auto& name : order)
    for (auto& [k, e] : own[name]) {
      if (name == "profile" && k == "base") continue;  // consumed above
      setEntry(p.sections_[name], k, e);
    }
}

Profile Profile::load(const std::string& path) {
  Profile p;
  p.origin_ = path;
  std::vector<std::string> chain{fs::path(path).lexically_normal().string()};
  parseInto(p, readFileOrThrow(path), path, chain);
  return p;
}

Profile Profile::fromText(const std::string& text, const std::string& origin_name) {
  Profile p;
  p.origin_ = origin_name;
  std::vector<std::string> chain{origin_name};
  parseInto(p, text, origin_name, chain);
  return p;
}

void Profile::applyOverride(const std::string& assignment) {
  const auto eq = assignment.find('=');
  const std::string lhs = eq == std::string::npos ? "" : trim(assignment.substr(0, eq));
  const auto dot = lhs.rfind('.');
  if (eq == std::string::npos || dot == std::string::npos || dot == 0 || dot + 1 == lhs.size())
    throw InputError("--set '" + assignment +
                     "': expected section.key=value (e.g. robot.v_max=0.2)");
  const std::string section = lhs.substr(0, dot), key = lhs.substr(dot + 1);
  if (!validName(section) || !validName(key))
    throw InputError("--set '" + assignment + "': bad section or key name");
  setEntry(sections_[section], key,
           Entry{trim(assignment.substr(eq + 1)), ValueOrigin{"--set", 0}});
}

void Profile::applyOverrides(const std::vector<std::string>& assignments) {
  for (const auto& a : assignments) applyOverride(a);
}

namespace {

/** "unknown key (did you mean 'k'?); keys of [section]: ...". A misspelt
 *  old key gets its new place: "did you mean 'k_heading' (now
 *  nav.goal_dwa.k_heading)?". */
std::string unknownKeyMessage(const std::string& name, const std::string& key,
                              const SectionSchema& schema, const ProfileSchemas& reg) {
  std::string best, moved;
  size_t bestd = 3;
  for (const auto& s : schema.specs) {
    const size_t d = editDistance(key, s.key);
    if (d < bestd) bestd = d, best = s.key;
  }
  for (const auto& r : reg.renames()) {
    if (r.old_section != name) continue;
    const size_t d = editDistance(key, r.old_key);
    if (d < bestd) bestd = d, best = r.old_key, moved = " (now " + r.newName() + ")";
  }
  std::string m = "unknown key";
  if (!best.empty()) m += " (did you mean '" + best + "'" + moved + "?)";
  std::string keys;
  for (const auto& s : schema.specs) keys += (keys.empty() ? "" : ", ") + s.key;
  return m + "; keys of [" + name + "]: " + keys;
}

}  // namespace

// ---------------------------------------------------------------- renamed keys

std::map<std::string, Profile::Section> Profile::effectiveSections() const {
  const auto& reg = ProfileSchemas::instance();
  std::map<std::string, Section> out;
  for (const auto& [name, sec] : sections_) {
    Section& o = out[name];
    for (const auto& [k, e] : sec)
      if (!reg.renamedFrom(name, k)) o.emplace_back(k, e);
  }
  for (const auto& r : reg.renames()) {
    const Entry* old_e = entryIn(find(r.old_section), r.old_key);
    if (!old_e) continue;
    const Entry* new_e = entryIn(find(r.new_section), r.new_key);
    if (!new_e || oldKeyWins(*old_e, *new_e, files_))
      setEntry(out[r.new_section], r.new_key, *old_e);
  }
  return out;
}

std::optional<Profile::Section> Profile::effectiveSection(const std::string& name) const {
  auto all = effectiveSections();
  auto it = all.find(name);
  if (it == all.end()) return std::nullopt;
  return std::move(it->second);
}

std::vector<ProfileIssue> Profile::renamedKeys() const {
  std::vector<ProfileIssue> notes;
  for (const auto& r : ProfileSchemas::instance().renames()) {
    const Entry* old_e = entryIn(find(r.old_section), r.old_key);
    if (!old_e) continue;
    ProfileIssue is{old_e->origin, r.old_section, r.old_key,
                    r.oldName() + " is now " + r.newName()};
    if (const Entry* new_e = entryIn(find(r.new_section), r.new_key)) {
      const bool old_wins = oldKeyWins(*old_e, *new_e, files_);
      const Entry& w = old_wins ? *old_e : *new_e;
      is.message += "; both are set, " + (old_wins ? r.oldName() : r.newName()) + " (" +
                    w.origin.where() + ") wins: " + w.value;
    }
    notes.push_back(std::move(is));
  }
  return notes;
}

// ---------------------------------------------------------------- checks

ProfileIssue Profile::issueFor(const std::string& section, const std::string& key, const Entry& e,
                               const std::string& message, const ParamSpec* spec) const {
  ProfileIssue is;
  is.origin = e.origin;
  is.section = section;
  is.key = key;
  is.message = "'" + e.value + "': " + message;
  if (spec) is.message += "; allowed: " + spec->allowedText();
  return is;
}

std::vector<ProfileIssue> Profile::check() const {
  std::vector<ProfileIssue> issues;
  const auto& reg = ProfileSchemas::instance();
  for (const auto& [name, sec] : effectiveSections()) {
    const ValueOrigin sec_origin =
        sec.empty() ? ValueOrigin{origin_, 0} : sec.front().second.origin;
    auto cands = reg.candidates(name);
    if (cands.empty()) {
      std::string known;
      for (const auto& s : reg.all())
        if (known.find(s.name) == std::string::npos) known += (known.empty() ? "" : ", ") + s.name;
      issues.push_back({sec_origin, name, "", "unknown section (known: " + known + ")"});
      continue;
    }
    const SectionSchema* schema = cands.front();
    if (!schema->variant_key.empty()) {
      const std::string& vk = schema->variant_key;
      const Entry* ve = nullptr;
      for (const auto& [k, e] : sec)
        if (k == vk) ve = &e;
      std::string allowed;
      for (const auto* c : cands) allowed += (allowed.empty() ? "" : ", ") + c->variant_value;
      if (!ve) {
        issues.push_back({sec_origin, name, vk, "missing; it must be one of " + allowed});
        continue;
      }
      schema = nullptr;
      for (const auto* c : cands)
        if (c->variant_value == ve->value) schema = c;
      if (!schema) {
        issues.push_back({ve->origin, name, vk, "'" + ve->value + "' is not one of " + allowed});
        continue;
      }
    }
    std::vector<std::pair<std::string, std::string>> kv;
    for (const auto& [k, e] : sec) kv.emplace_back(k, e.value);
    for (const auto& [key, msg] : schema->validate(kv)) {
      if (key.empty()) {
        issues.push_back({sec_origin, name, "", msg});
        continue;
      }
      const Entry* e = nullptr;
      for (const auto& [k, en] : sec)
        if (k == key) e = &en;
      const ParamSpec* spec = nullptr;
      for (const auto& s : schema->specs)
        if (s.key == key) spec = &s;
      if (!spec) {
        issues.push_back(
            {e ? e->origin : sec_origin, name, key, unknownKeyMessage(name, key, *schema, reg)});
      } else {
        issues.push_back(issueFor(name, key, *e, msg, spec));
      }
    }
  }
  if (!sections_.count("robot"))
    issues.push_back(
        {ValueOrigin{origin_, 0}, "robot", "", "missing: every profile describes its robot"});
  return issues;
}

void Profile::validate() const {
  const auto issues = check();
  if (issues.empty()) return;
  std::string msg = origin_ + ": " + std::to_string(issues.size()) + " problem(s) in the profile:";
  for (const auto& is : issues) msg += "\n  " + is.text();
  throw InputError(msg);
}

// ---------------------------------------------------------------- access

std::vector<std::string> Profile::sectionNames() const {
  std::vector<std::string> out;
  for (const auto& [k, v] : sections_) out.push_back(k);
  return out;
}

std::vector<std::string> Profile::sectionsWithPrefix(const std::string& prefix) const {
  std::vector<std::string> out;
  for (const auto& [k, v] : sections_)
    if (k.compare(0, prefix.size(), prefix) == 0) out.push_back(k);
  return out;
}

const Profile::Section* Profile::find(const std::string& name) const {
  auto it = sections_.find(name);
  return it == sections_.end() ? nullptr : &it->second;
}

std::string Profile::value(const std::string& section, const std::string& key,
                           const std::string& fallback) const {
  if (const Section* s = find(section))
    for (const auto& [k, e] : *s)
      if (k == key) return e.value;
  return fallback;
}

std::string Profile::resolvedText() const {
  std::ostringstream os;
  os << "; resolved profile " << origin_ << "\n; files read:";
  for (const auto& f : files_) os << " " << f;
  os << "\n";
  const auto& reg = ProfileSchemas::instance();
  auto printSpecs = [&os](const SectionSchema& schema, const auto& entryOf) {
    for (const auto& spec : schema.specs) {
      const Entry* e = entryOf(spec.key);
      std::string line = spec.key + " = " + (e ? e->value : spec.default_text);
      if (line.size() < 34) line.resize(34, ' ');
      os << line << " ; " << (spec.unit.empty() ? "" : "[" + spec.unit + "] ")
         << (e ? "from " + e->origin.where() : std::string("default")) << ": " << spec.meaning
         << "\n";
    }
  };
  const auto effective = effectiveSections();
  for (const auto& [name, sec] : effective) {
    os << "\n[" << name << "]\n";
    auto cands = reg.candidates(name);
    const SectionSchema* schema = cands.empty() ? nullptr : cands.front();
    if (schema && !schema->variant_key.empty()) {
      const std::string v = value(name, schema->variant_key);
      schema = nullptr;
      for (const auto* c : cands)
        if (c->variant_value == v) schema = c;
    }
    const auto& entries = sec;  // a structured binding cannot be captured in C++17
    auto entryOf = [&entries](const std::string& key) -> const Entry* {
      for (const auto& [k, e] : entries)
        if (k == key) return &e;
      return nullptr;
    };
    if (!schema) {
      os << "; (no schema: not validated)\n";
      for (const auto& [k, e] : sec) os << k << " = " << e.value << "\n";
      continue;
    }
    printSpecs(*schema, entryOf);
  }
  // Sections the commands read with their defaults when the profile does not
  // have them ([icp], [rbpf], [localization], ...): listed too, so every
  // parameter a command uses is shown. Families ("sensor.*") describe
  // sections a profile adds, and have no defaults of their own.
  for (const auto& schema : reg.all()) {
    if (schema.name.find('*') != std::string::npos || effective.count(schema.name)) continue;
    if (!schema.variant_key.empty()) continue;
    os << "\n[" << schema.name << "]\n; not in the profile: " << schema.description
       << ", every key at its default\n";
    printSpecs(schema, [](const std::string&) -> const Entry* { return nullptr; });
  }
  return os.str();
}

void Profile::toMrptConfig(mrpt::config::CConfigFileMemory& out) const {
  std::ostringstream os;
  for (const auto& [name, sec] : sections_) {
    os << "[" << name << "]\n";
    for (const auto& [k, e] : sec) os << k << " = " << e.value << "\n";
  }
  out.setContent(os.str());
}

}  // namespace carenav
