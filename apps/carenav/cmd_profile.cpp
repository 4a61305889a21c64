// carenav profile show|check FILE [--set section.key=value ...]
#include "commands.h"

#include <carenav/common/profile.h>
#include <carenav/common/robot.h>

#include <iostream>

namespace carenav::app {

namespace {
struct ProfileArgs {
  std::string file;
  std::vector<std::string> sets;
};

Profile loadChecked(const ProfileArgs& a) {
  Profile p = Profile::load(a.file);
  p.applyOverrides(a.sets);
  p.validate();
  loadSensors(p);  // every sensor section reads into its struct
  // Keys of the previous version: still read, not problems; told once each.
  for (const auto& note : p.renamedKeys()) std::cerr << "warning: " << note.text() << "\n";
  return p;
}

void addCommon(CLI::App* sub, ProfileArgs& a) {
  sub->add_option("file", a.file, "Robot profile INI (e.g. ini/isr-aiwalker.ini)")->required();
  sub->add_option("--set", a.sets,
                  "Override a value: section.key=value (repeatable), e.g. robot.v_max=0.2");
}
}  // namespace

namespace {
void addProfileCommand(CLI::App& app, const GlobalOptions& g) {
  auto* cmd = app.add_subcommand("profile", "Inspect and validate robot profiles");
  cmd->require_subcommand(1);
  auto args = std::make_shared<ProfileArgs>();

  auto* show = cmd->add_subcommand(
      "show",
      "Print the resolved profile: every key of every section with its value, unit and where "
      "it came from (file:line, --set, or default). Exits 2 on any problem.");
  addCommon(show, *args);
  show->callback([args] {
    Profile p = loadChecked(*args);
    std::cout << p.resolvedText();
  });

  auto* check = cmd->add_subcommand(
      "check",
      "Validate a profile: unknown sections or keys (misspellings), wrong types, out-of-range "
      "or inconsistent values. Prints every problem with file, line, section and key; exit 2. "
      "Keys that moved to another section are still read and reported as warnings "
      "('navigation.k_heading is now nav.goal_dwa.k_heading').");
  addCommon(check, *args);
  check->callback([args, &g] {
    Profile p = loadChecked(*args);
    if (!g.quiet) {
      std::cout << args->file << ": OK (" << p.sectionNames().size() << " sections, "
                << loadSensors(p).size() << " sensors; files:";
      for (const auto& f : p.files()) std::cout << " " << f;
      std::cout << ")\n";
    }
  });
}
}  // namespace

CARENAV_COMMAND(10, addProfileCommand);

}  // namespace carenav::app
