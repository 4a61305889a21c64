// carenav import <format> ...: foreign formats to MRPT/carenav ones. Each
// format lives in its own cmd_import_<format>.cpp and registers with
// CARENAV_IMPORT.
#include "commands.h"

namespace carenav::app {

namespace {
void addImportCommand(CLI::App& app, const GlobalOptions& g) {
  auto* cmd = app.add_subcommand("import", "Convert foreign logs and maps to MRPT/carenav formats");
  cmd->require_subcommand(1);
  for (CommandAdder f : importRegistry()) f(*cmd, g);
}
}  // namespace

CARENAV_COMMAND(80, addImportCommand);

}  // namespace carenav::app
