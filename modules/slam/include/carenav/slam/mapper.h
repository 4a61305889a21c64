// SLAM back ends behind one interface, registered by name ("icp",
// "icp-graph", "rbpf"), fed one scan at a time.
#pragma once

#include <carenav/io/scan_stream.h>
#include <carenav/io/trajectory.h>
#include <carenav/slam/slam_params.h>

#include <mrpt/maps/CSimpleMap.h>
#include <mrpt/math/CMatrixFixed.h>
#include <mrpt/poses/CPose2D.h>

#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace mrpt::config {
class CConfigFileBase;
}

namespace carenav::slam {

/** What a back end is built from. */
struct MapperConfig {
  SlamParams slam;
  IcpParams icp;
  RbpfParams rbpf;
  /** An MRPT icp-slam / rbpf-slam INI, when the user brought one: the back end
   *  then reads MRPT's own sections ([MappingApplication], [ICP], ...). */
  const mrpt::config::CConfigFileBase* mrpt_ini = nullptr;
  /** --resume: the map to extend and the pose to start from. */
  std::optional<mrpt::maps::CSimpleMap> resume_map;
  std::optional<mrpt::poses::CPose2D> start_pose;
};

struct MapperStats {
  size_t scans = 0;            ///< scans processed
  size_t inserted = 0;         ///< scans inserted in the map
  size_t icp_accepted = 0;     ///< ICP corrections accepted
  size_t icp_rejected = 0;     ///< ICP results below the goodness threshold
  size_t keyframes = 0;        ///< icp-graph: pose-graph nodes
  size_t loop_candidates = 0;  ///< icp-graph: loop closures tried
  size_t loop_closures = 0;    ///< icp-graph: loop closures kept
  size_t loop_rejected = 0;    ///< icp-graph: loop closures the optimised graph disagreed with
  size_t optimisations = 0;    ///< icp-graph: graph optimisations run
  /** icp-graph: scan matches the odometry's prior ruled out (dead-reckoned) */
  size_t prior_rejected = 0;
  /** icp: scans whose timestamp did not advance past the scan before, fed to
   *  MRPT's builder 1 ms after it (its pose extrapolator needs time to pass). */
  size_t restamped = 0;
};

class Mapper {
 public:
  virtual ~Mapper() = default;
  /** Consumes one scan and the odometry since the previous one. */
  virtual void process(const io::ScanStep& step) = 0;
  /** Ends the run (e.g. a final graph optimisation). */
  virtual void finish() {}
  /** Current pose estimate and its covariance (x, y, yaw). */
  virtual mrpt::poses::CPose2D pose() const = 0;
  virtual mrpt::math::CMatrixDouble33 covariance() const = 0;
  /** The map as sensory frames at poses (MRPT's .simplemap). */
  virtual mrpt::maps::CSimpleMap simpleMap() const = 0;
  /** The pose of every processed scan, at its time (after finish(): the
   *  final estimates, e.g. optimised). */
  virtual io::Trajectory2D trajectory() const = 0;
  virtual MapperStats stats() const = 0;
};

using MapperFactory = std::function<std::unique_ptr<Mapper>(const MapperConfig&)>;

/** Registry of back ends by name. */
void registerMapper(const std::string& name, MapperFactory f);
std::unique_ptr<Mapper> createMapper(const std::string& name, const MapperConfig& cfg);
std::vector<std::string> mapperNames();

/** Built-in back ends (called by createMapper on first use). */
std::unique_ptr<Mapper> makeIcpMapper(const MapperConfig& cfg);
std::unique_ptr<Mapper> makeIcpGraphMapper(const MapperConfig& cfg);
std::unique_ptr<Mapper> makeRbpfMapper(const MapperConfig& cfg);

/** The scan without ranges beyond `range_max` (0 keeps it as is). */
mrpt::obs::CObservation2DRangeScan::Ptr clipScan(const mrpt::obs::CObservation2DRangeScan::Ptr& s,
                                                 double range_max);

}  // namespace carenav::slam
