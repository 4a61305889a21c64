// carenav rawlog info FILE [--json]
#include "commands.h"

#include <carenav/common/errors.h>
#include <carenav/io/rawlog_info.h>

#include <iostream>

namespace carenav::app {

namespace {
void addRawlogCommand(CLI::App& app, const GlobalOptions& g) {
  auto* cmd = app.add_subcommand("rawlog", "Inspect MRPT rawlogs");
  cmd->require_subcommand(1);
  struct Args {
    std::string file;
    bool json = false;
  };
  auto a = std::make_shared<Args>();
  auto* info = cmd->add_subcommand(
      "info",
      "Summarise a rawlog (plain or gzip; action/sensory-frame or observation-only form): "
      "entry count, time span, sensors (label, class, count, rate) and odometry path length. "
      "A truncated or corrupt file prints what was read before the break, then exits 2.");
  info->add_option("file", a->file, "MRPT .rawlog file")->required();
  info->add_flag("--json", a->json, "Print JSON instead of text");
  info->callback([a, &g] {
    const io::RawlogInfo ri = io::summarizeRawlog(a->file, !g.quiet);
    std::cout << (a->json ? ri.toJson() : ri.toText()) << std::flush;
    if (ri.error) throw InputError(*ri.error);
  });
}
}  // namespace

CARENAV_COMMAND(20, addRawlogCommand);

}  // namespace carenav::app
