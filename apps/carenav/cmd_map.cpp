// carenav map info MAP [--json]
// carenav map convert IN OUT
#include <carenav/common/errors.h>
#include <carenav/io/map_io.h>
#include <carenav/io/map_render.h>

#include <cctype>
#include <iostream>

#include "commands.h"

namespace carenav::app {

namespace {

struct MapLoadArgs {
  double resolution = 0;  // 0: not given
  std::vector<double> origin;
  bool negate = false;
  std::string mode = "trinary";
};

void addLoadOptions(CLI::App* sub, MapLoadArgs& a) {
  sub->add_option("--resolution", a.resolution,
                  "Metres per cell: the pixel size of a bare .png/.pgm (required for those), or "
                  "the cell size of the grid built from a .simplemap (default 0.05)");
  sub->add_option("--origin", a.origin,
                  "Lower-left corner of a bare image in the map frame: X Y metres (default 0 0)")
      ->expected(2)
      ->delimiter(',');
  sub->add_flag("--negate", a.negate, "Bare image: white is occupied (map_server's negate: 1)");
  sub->add_option("--mode", a.mode, "Bare image: trinary (default), scale or raw, as map_server")
      ->check(CLI::IsMember({"trinary", "scale", "raw"}));
}

io::MapLoadOptions loadOptions(const MapLoadArgs& a) {
  io::MapLoadOptions o;
  if (a.resolution != 0) {
    if (!(a.resolution > 0)) throw InputError("--resolution must be > 0 metres");
    o.simplemap_resolution = a.resolution;
    o.image_resolution = a.resolution;
  }
  if (a.origin.size() == 2) {
    o.image_origin_x = a.origin[0];
    o.image_origin_y = a.origin[1];
  }
  o.image_negate = a.negate;
  o.image_mode = a.mode == "scale" ? io::RosMapMode::Scale
                 : a.mode == "raw" ? io::RosMapMode::Raw
                                   : io::RosMapMode::Trinary;
  return o;
}

void addMapCommand(CLI::App& app, const GlobalOptions&) {
  auto* cmd = app.add_subcommand(
      "map",
      "Inspect and convert occupancy grid maps (.gridmap(.gz), .simplemap(.gz), ROS .yaml, "
      ".png/.pgm)");
  cmd->require_subcommand(1);

  struct InfoArgs {
    std::string file;
    bool json = false;
    MapLoadArgs load;
  };
  auto ia = std::make_shared<InfoArgs>();
  auto* info = cmd->add_subcommand(
      "info",
      "Summarise a map of any kind: size in cells and metres, resolution, origin and bounds, "
      "occupied/free/unknown cell counts (map_server's thresholds: p_occ > 0.65 occupied, "
      "< 0.196 free). A .simplemap is first drawn into a grid.");
  info->add_option("map", ia->file, "Map file")->required();
  info->add_flag("--json", ia->json, "Print JSON instead of text");
  addLoadOptions(info, ia->load);
  info->callback([ia] {
    const auto grid = io::loadGridMap(ia->file, loadOptions(ia->load));
    const io::GridStats s = io::gridStats(grid);
    const std::string kind = io::mapKindName(io::mapKindOf(ia->file));
    if (ia->json)
      std::cout << s.toJson(ia->file, kind) << "\n";
    else
      std::cout << "file: " << ia->file << "\nkind: " << kind << "\n" << s.toText();
  });

  struct ConvertArgs {
    std::string in, out;
    MapLoadArgs load;
    int pixels_per_cell = 1;
    bool crop = false;
  };
  auto ca = std::make_shared<ConvertArgs>();
  auto* convert = cmd->add_subcommand(
      "convert",
      "Convert a map; the output format follows OUT's name: .yaml (ROS map_server: YAML + PGM "
      "next to it), .gridmap.gz / .gridmap (MRPT), .png (picture: free white, occupied black, "
      "unknown grey, north up, with a scale bar).");
  convert->add_option("in", ca->in, "Input map file")->required();
  convert->add_option("out", ca->out, "Output file: .yaml, .gridmap.gz, .gridmap or .png")
      ->required();
  addLoadOptions(convert, ca->load);
  convert
      ->add_option("--pixels-per-cell", ca->pixels_per_cell,
                   "PNG output: pixels per cell (small maps are enlarged to 800 px wide)")
      ->check(CLI::Range(1, 64));
  convert->add_flag("--crop", ca->crop, "PNG output: crop to the known cells plus 1 m");
  convert->callback([ca] {
    prepareOutputFile(ca->out, "out");
    io::checkMapOutputPath(ca->out);
    const auto grid = io::loadGridMap(ca->in, loadOptions(ca->load));
    const std::string out_lower = [&] {
      std::string s = ca->out;
      for (auto& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
      return s;
    }();
    if (out_lower.size() > 4 && out_lower.compare(out_lower.size() - 4, 4, ".png") == 0) {
      io::RenderOptions ro;
      ro.pixels_per_cell = ca->pixels_per_cell;
      ro.crop_to_known = ca->crop;
      io::renderGridMapPng(grid, ca->out, ro);
    } else {
      io::saveMapByExtension(grid, ca->out);
    }
    std::cout << ca->in << " -> " << ca->out << "\n" << io::gridStats(grid).toText();
  });
}

}  // namespace

CARENAV_COMMAND(25, addMapCommand);

}  // namespace carenav::app
