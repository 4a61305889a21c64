// Hazard recall report (issue 6 item 8, docs/perceive.md "Hazard recall").
//
// Renders depth frames of the hazard scenes in maps/worlds/hazards/ (written
// by scripts/make_hazard_worlds.py) with the simulator (the profile's depth
// camera: Kinect One 512 x 424, 70.6 x 60 deg, its mounting pose, depth noise
// growing with the square of the range), runs every perception method on the
// same frames and scores the local occupancy grid against the ground truth
// taken from the world's height layer:
//   - hazard cells: 5 cm grid cells holding any non-plain world cell (drop,
//     rise, overhang) of a hazard scene, and seen by the camera (at least one
//     valid depth return falls in the cell: occluded cells cannot be judged);
//   - recall: share of those cells marked occupied (p > occupied_threshold);
//   - rows blocked: share of the rows (constant y, the walker driving along
//     +x) crossing a seen hazard where an occupied cell lies from 0.2 m
//     before the hazard's first cell to 0.1 m into it: the walker stops;
//   - false-obstacle rate on the floor: occupied share of the seen plain
//     floor cells farther than `--margin` from any hazard cell;
//   - traversable (the ramp scene): occupied share of the seen ramp and
//     landing cells, which must stay free.
//
//   hazard_recall [--profile ini/isr-aiwalker.ini] [--worlds maps/worlds/hazards]
//                 [--frames 1] [--seed 1] [--margin 0.2] [--set section.key=value]...
//                 [--dump SCENE]
// Writes Markdown tables on stdout (the second: false obstacles per 0.5 m of
// distance ahead); --dump prints the rrt-gpd grid and voxel classes of SCENE
// as text on stderr (HAZARD_DUMP_CELLS=1: the obstacle voxels' statistics).
#include <carenav/common/profile.h>
#include <carenav/common/robot.h>
#include <carenav/perception/pipeline.h>
#include <carenav/sim/sim_params.h>
#include <carenav/sim/simulator.h>
#include <carenav/sim/world.h>

#include <mrpt/obs/CObservation3DRangeScan.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

using namespace carenav;
using namespace carenav::perception;

namespace {

struct SceneDef {
  const char* name;
  bool traversable;  ///< its features must stay free (the ramp)
};
const SceneDef kScenes[] = {{"flat", false},   {"stairs_down", false}, {"stairs_up", false},
                            {"outlet", false}, {"box2cm", false},      {"cable", false},
                            {"gutter", false}, {"table", false},       {"ramp6", true}};
const Method kMethods[] = {Method::RrtGpd, Method::Ransac, Method::HeightBand, Method::Mrpt2DScan};

// Robot pose of every scene (the worlds are laid out for it).
constexpr double kRobotX = 0.5, kRobotY = 2.5;
// Region scored: the floor the camera sees from 0.6 m to 4 m ahead.
constexpr double kRoiX0 = 1.1, kRoiX1 = 4.5, kRoiY0 = 0.5, kRoiY1 = 4.5;

enum class Label : uint8_t { Outside, Floor, Hazard, Traversable, Margin };

constexpr int kBands = 7;  // 0.5 m range bands from 1.0 m to 4.5 m ahead (robot frame x)
struct Score {
  size_t hazard = 0, hazard_occ = 0, rows = 0, rows_blocked = 0;
  size_t floor = 0, floor_occ = 0, trav = 0, trav_occ = 0;
  size_t band_n[kBands] = {}, band_occ[kBands] = {};  // floor + traversable cells by range
  std::string plane_source;
  double tilt_deg = 0;
};

std::string pct(size_t num, size_t den) {
  if (den == 0) return "-";
  char b[32];
  std::snprintf(b, sizeof b, "%.1f%%", 100.0 * num / den);
  return b;
}

/** Ground-truth label of each cell of the local grid (world frame: the
 *  odometry is the true pose). */
std::vector<Label> groundTruth(const sim::World& w, const LocalOccupancy& g, bool traversable,
                               double margin) {
  const int m = g.cells();
  const double h = 0.5 * g.resolution();
  std::vector<Label> lab(static_cast<size_t>(m) * m, Label::Outside);
  std::vector<int> hazard_cells;
  for (int i = 0; i < m; ++i)
    for (int j = 0; j < m; ++j) {
      const double cx = g.centreX(i), cy = g.centreY(j);
      if (cx < kRoiX0 || cx > kRoiX1 || cy < kRoiY0 || cy > kRoiY1) continue;
      bool plain = true;
      for (int wx = w.cellX(cx - h + 1e-6); wx <= w.cellX(cx + h - 1e-6); ++wx)
        for (int wy = w.cellY(cy - h + 1e-6); wy <= w.cellY(cy + h - 1e-6); ++wy)
          if (w.inside(wx, wy) && !w.cell(wx, wy).plain()) plain = false;
      Label& l = lab[static_cast<size_t>(i) * m + j];
      l = plain ? Label::Floor : (traversable ? Label::Traversable : Label::Hazard);
      if (l == Label::Hazard) hazard_cells.push_back(i * m + j);
    }
  const int r = static_cast<int>(std::ceil(margin / g.resolution() - 1e-9));
  for (int k : hazard_cells) {
    const int i = k / m, j = k % m;
    for (int di = -r; di <= r; ++di)
      for (int dj = -r; dj <= r; ++dj) {
        const int a = i + di, b = j + dj;
        if (!g.inside(a, b) || std::hypot(di, dj) * g.resolution() > margin + 1e-9) continue;
        Label& l = lab[static_cast<size_t>(a) * m + b];
        if (l == Label::Floor) l = Label::Margin;
      }
  }
  return lab;
}

Score score(const LocalOccupancy& g, const std::vector<Label>& lab, const std::vector<char>& seen,
            double occ_thr) {
  Score s;
  const int m = g.cells();
  auto at = [&](int i, int j) { return static_cast<size_t>(i) * m + j; };
  for (int j = 0; j < m; ++j) {
    int first = -1;
    bool row_seen = false;
    for (int i = 0; i < m; ++i) {
      const size_t k = at(i, j);
      const bool occ = g.prob(i, j) > occ_thr;
      if (lab[k] == Label::Hazard && first < 0) first = i;
      if (!seen[k]) continue;
      if (lab[k] == Label::Floor || lab[k] == Label::Traversable) {
        const int b = static_cast<int>(std::floor((g.centreX(i) - kRobotX - 1.0) / 0.5));
        if (b >= 0 && b < kBands) {
          ++s.band_n[b];
          s.band_occ[b] += occ;
        }
      }
      switch (lab[k]) {
        case Label::Hazard:
          ++s.hazard;
          s.hazard_occ += occ;
          row_seen = true;
          break;
        case Label::Floor:
          ++s.floor;
          s.floor_occ += occ;
          break;
        case Label::Traversable:
          ++s.trav;
          s.trav_occ += occ;
          break;
        default:
          break;
      }
    }
    if (first < 0 || !row_seen) continue;
    ++s.rows;
    const int before = static_cast<int>(std::lround(0.2 / g.resolution()));
    const int into = static_cast<int>(std::lround(0.1 / g.resolution()));
    for (int i = std::max(0, first - before); i <= std::min(m - 1, first + into); ++i)
      if (g.prob(i, j) > occ_thr) {
        ++s.rows_blocked;
        break;
      }
  }
  return s;
}

}  // namespace

int main(int argc, char** argv) try {
  std::string profile_path = std::string(CARENAV_SOURCE_DIR) + "/ini/isr-aiwalker.ini";
  std::string worlds = std::string(CARENAV_SOURCE_DIR) + "/maps/worlds/hazards";
  int frames = 1;
  long seed = 1;
  double margin = 0.2;
  std::string dump;  // scene whose rrt-gpd grid and voxel classes are printed as text
  std::vector<std::string> sets = {"sim.depth_decimation=1"};
  for (int a = 1; a < argc; ++a) {
    const std::string k = argv[a];
    auto val = [&]() -> std::string {
      if (a + 1 >= argc) throw std::runtime_error(k + " needs a value");
      return argv[++a];
    };
    if (k == "--profile")
      profile_path = val();
    else if (k == "--worlds")
      worlds = val();
    else if (k == "--frames")
      frames = std::stoi(val());
    else if (k == "--seed")
      seed = std::stol(val());
    else if (k == "--margin")
      margin = std::stod(val());
    else if (k == "--dump")
      dump = val();
    else if (k == "--set")
      sets.push_back(val());
    else {
      std::cerr << "usage: hazard_recall [--profile P] [--worlds DIR] [--frames N] [--seed S] "
                   "[--margin M] [--set section.key=value]... [--dump SCENE]\n";
      return k == "--help" || k == "-h" ? 0 : 2;
    }
  }
  if (frames < 1) throw std::runtime_error("--frames must be >= 1");
  perception::registerProfileSections();
  sim::registerProfileSections();
  Profile prof = Profile::load(profile_path);
  prof.applyOverrides(sets);
  const auto pp = prof.section<PerceptionParams>("perception");
  auto sp = prof.section<sim::SimParams>("sim");
  sp.seed = static_cast<decltype(sp.seed)>(seed);
  const auto robot = prof.section<RobotParams>("robot");
  std::vector<SensorParams> cams;
  for (const auto& s : loadSensors(prof))
    if (s.type == "depth-camera") cams.push_back(s);
  if (cams.empty()) throw std::runtime_error(profile_path + ": no depth-camera sensor");
  cams.resize(1);

  std::vector<std::string> band_rows;
  std::printf(
      "| scene | method | plane | hazard cells seen | recall | rows blocked | "
      "floor cells seen | false obstacles (floor) | false obstacles (ramp) |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|\n");
  for (const SceneDef& sc : kScenes) {
    auto world =
        std::make_shared<const sim::World>(sim::loadWorld(worlds + "/" + sc.name + ".yaml"));
    sim::Simulator simu(world, robot, cams, sp);
    simu.reset({kRobotX, kRobotY, 0.0});
    std::vector<mrpt::obs::CObservation3DRangeScan::Ptr> obs;
    for (int f = 0; f < frames; ++f) {
      auto o = std::dynamic_pointer_cast<mrpt::obs::CObservation3DRangeScan>(simu.observe(0));
      if (!o) throw std::runtime_error("the simulator gave no depth frame");
      obs.push_back(o);
    }
    const mrpt::poses::CPose2D pose(kRobotX, kRobotY, 0.0);
    for (Method meth : kMethods) {
      Pipeline pipe(pp, meth);
      FrameResult last;
      std::vector<char> seen;
      for (auto& o : obs) {
        auto cloud = cloudFromObservation(*o);
        if (!cloud) throw std::runtime_error("no cloud from the depth frame");
        FrameInput in;
        in.cloud = &*cloud;
        in.sensor_origin = {static_cast<float>(o->sensorPose.x()),
                            static_cast<float>(o->sensorPose.y()),
                            static_cast<float>(o->sensorPose.z())};
        in.depth_obs = o.get();
        in.odometry = pose;
        last = pipe.process(in, false);
        const auto& g = pipe.grid();
        seen.assign(static_cast<size_t>(g.cells()) * g.cells(), 0);
        for (const auto& p : cloud->points) {
          if (!validPoint(p)) continue;
          const int i = g.cellX(kRobotX + p.x), j = g.cellY(kRobotY + p.y);
          if (g.inside(i, j)) seen[static_cast<size_t>(i) * g.cells() + j] = 1;
        }
      }
      const auto lab = groundTruth(*world, pipe.grid(), sc.traversable, margin);
      if (dump == sc.name && meth == Method::RrtGpd) {
        // Rows: x ahead from 4.5 m down to 0.6 m; columns: y from +1 m (left) to -1 m.
        // Grid: '#' occupied, '.' free, ' ' unknown, upper case on hazard cells (H, F, U).
        // Voxels: 'o' obstacle, 'g' ground, ' ' none.
        const auto& g = pipe.grid();
        const auto& e = pipe.elevation();
        for (double x = 4.5; x > 0.6; x -= g.resolution()) {
          std::string a, b;
          for (double y = 1.0; y > -1.0; y -= g.resolution()) {
            const int i = g.cellX(kRobotX + x), j = g.cellY(kRobotY + y);
            const double pr = g.prob(i, j);
            const bool hz = lab[static_cast<size_t>(i) * g.cells() + j] == Label::Hazard;
            a += pr > pp.occupied_threshold ? (hz ? 'H' : '#')
                 : pr < pp.free_threshold   ? (hz ? 'F' : '.')
                                            : (hz ? 'U' : ' ');
            const int ei = e.cellOf(x), ej = e.cellOf(y);
            const auto vc = e.inside(ei, ej)
                                ? last.voxel_classes[static_cast<size_t>(ei) * e.cells() + ej]
                                : VoxelClass::None;
            b += vc == VoxelClass::Obstacle ? 'o' : vc == VoxelClass::Ground ? 'g' : ' ';
            if (vc == VoxelClass::Obstacle && std::getenv("HAZARD_DUMP_CELLS")) {
              const auto& c = e.at(ei, ej);
              std::fprintf(
                  stderr, "  cell x %.2f y %.2f n %u lo %.4f mean %.4f hi %.4f plane %.4f\n", x, y,
                  c.n, c.z_lo, c.mean, c.z_hi,
                  last.plane ? last.plane->zAt(e.centre(ei), e.centre(ej)).value_or(0) : 0.0);
            }
          }
          std::fprintf(stderr, "%5.2f |%s|  |%s|\n", x, a.c_str(), b.c_str());
        }
      }
      const Score s = score(pipe.grid(), lab, seen, pp.occupied_threshold);
      char plane[64] = "-";
      if (last.plane)
        std::snprintf(plane, sizeof plane, "%s %.1f deg", last.plane_source.c_str(),
                      std::acos(std::min(1.0, last.plane->c)) * 180 / M_PI);
      std::printf("| %s | %s | %s | %zu | %s | %s | %zu | %s | %s |\n", sc.name, methodName(meth),
                  plane, s.hazard, pct(s.hazard_occ, s.hazard).c_str(),
                  pct(s.rows_blocked, s.rows).c_str(), s.floor, pct(s.floor_occ, s.floor).c_str(),
                  pct(s.trav_occ, s.trav).c_str());
      std::fflush(stdout);
      if (meth == Method::RrtGpd || meth == Method::Ransac) {
        std::string row = std::string("| ") + sc.name + " | " + methodName(meth) + " |";
        for (int b = 0; b < kBands; ++b) row += " " + pct(s.band_occ[b], s.band_n[b]) + " |";
        band_rows.push_back(row);
      }
    }
  }
  std::printf(
      "\nFalse obstacles on traversable cells (plain floor beyond the margin, ramp and landing) "
      "by distance ahead of the robot:\n\n| scene | method |");
  for (int b = 0; b < kBands; ++b) std::printf(" %.1f-%.1f m |", 1.0 + 0.5 * b, 1.5 + 0.5 * b);
  std::printf("\n|---|---|");
  for (int b = 0; b < kBands; ++b) std::printf("---|");
  std::printf("\n");
  for (const auto& r : band_rows) std::printf("%s\n", r.c_str());
  return 0;
} catch (const std::exception& e) {
  std::cerr << "hazard_recall: " << e.what() << "\n";
  return 2;
}
