// carenav import ros-map MAP.yaml --out X.gridmap.gz [--json]
#include <carenav/common/errors.h>
#include <carenav/io/map_io.h>

#include <filesystem>
#include <iostream>

#include "commands.h"

namespace carenav::app {

namespace {
void addImportRosMap(CLI::App& import_cmd, const GlobalOptions&) {
  struct Args {
    std::string yaml, out;
    bool json = false;
  };
  auto a = std::make_shared<Args>();
  auto* cmd = import_cmd.add_subcommand(
      "ros-map",
      "Convert a ROS map_server map (YAML + PGM/PNG) to an MRPT gridmap, reading it as "
      "map_server does (negate, occupied_thresh, free_thresh, mode trinary/scale/raw; a rotated "
      "origin is resampled). Prints the size, resolution, origin and occupied/free/unknown cell "
      "counts. A malformed YAML or image exits 2 naming the file, line and key.");
  cmd->add_option("yaml", a->yaml, "ROS map YAML (image, resolution, origin, ...)")->required();
  cmd->add_option("--out,-o", a->out,
                  "Output .gridmap.gz (or .gridmap) file; a folder gets <yaml name>.gridmap.gz")
      ->required();
  cmd->add_flag("--json", a->json, "Print the summary as JSON");
  cmd->callback([a] {
    namespace fs = std::filesystem;
    std::string out = a->out;
    std::error_code ec;
    if (fs::is_directory(out, ec))
      out = (fs::path(out) / (fs::path(a->yaml).stem().string() + ".gridmap.gz")).string();
    prepareOutputFile(out);
    io::checkMapOutputPath(out, /*gridmap_only=*/true);
    const auto grid = io::readRosMap(a->yaml);
    io::saveGridMap(grid, out);
    const io::GridStats s = io::gridStats(grid);
    if (a->json) {
      std::cout << s.toJson(a->yaml, "ros-yaml", out) << "\n";
    } else {
      std::cout << a->yaml << " -> " << out << "\n" << s.toText();
    }
  });
}
}  // namespace

CARENAV_IMPORT(addImportRosMap);

}  // namespace carenav::app
