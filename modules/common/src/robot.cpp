#include <carenav/common/profile.h>
#include <carenav/common/robot.h>

#include <cmath>

namespace carenav {

const ParamTable<ProfileInfo>& ProfileInfo::table() {
  static const auto t = ParamTable<ProfileInfo>()
                            .text("name", &ProfileInfo::name, "short robot name")
                            .text("description", &ProfileInfo::description, "one line for humans")
                            .text("base", &ProfileInfo::base,
                                  "profile read first (its values are defaults for this one), "
                                  "path relative to this file");
  return t;
}

const ParamTable<RobotParams>& RobotParams::table() {
  static const auto t =
      ParamTable<RobotParams>()
          .choice("kinematics", &RobotParams::kinematics, {"diff-drive"},
                  "drive kinematics (differential drive: v along x, w about z)")
          .choice("control", &RobotParams::control, {"autonomous", "user-intent"},
                  "who commands the motion: the navigation stack, or the user (walker "
                  "handles) filtered by the user-intent planner")
          .polygon("footprint", &RobotParams::footprint, "m",
                   "outline in the robot frame (x forward, y left), \"x1,y1 x2,y2 ...\"")
          .real("height", &RobotParams::height, "m", 0.05, 3.0, "top of the robot above the floor")
          .real("v_max", &RobotParams::v_max, "m/s", 0.0, 3.0, "top forward speed")
          .real("v_min", &RobotParams::v_min, "m/s", -3.0, 0.0,
                "top reverse speed (0: never drive backwards)")
          .real("w_max", &RobotParams::w_max, "rad/s", 0.0, 10.0, "top turn rate")
          .real("acc_v", &RobotParams::acc_v, "m/s^2", 0.01, 10.0,
                "linear acceleration limit, also the braking deceleration")
          .real("acc_w", &RobotParams::acc_w, "rad/s^2", 0.01, 20.0, "angular acceleration limit")
          .real("safe_distance", &RobotParams::safe_distance, "m", 0.0, 5.0,
                "free distance to keep ahead of the footprint")
          .real("command_latency", &RobotParams::command_latency, "s", 0.0, 2.0,
                "between a velocity command and its effect on the base: the planners' rollouts "
                "and the safety supervisor start from the measured velocity and the last command")
          .check([](const RobotParams& r) -> std::optional<std::string> {
            bool contains_origin = false;  // crossing number for (0,0)
            const auto& p = r.footprint;
            for (size_t i = 0, j = p.size() - 1; i < p.size(); j = i++)
              if ((p[i].y > 0) != (p[j].y > 0) &&
                  0 < (p[j].x - p[i].x) * (0 - p[i].y) / (p[j].y - p[i].y) + p[i].x)
                contains_origin = !contains_origin;
            if (!contains_origin)
              return std::string("footprint must contain the robot origin (0,0)");
            return std::nullopt;
          });
  return t;
}

double RobotParams::circumscribedRadius() const {
  double r = 0;
  for (const auto& p : footprint) r = std::max(r, std::hypot(p.x, p.y));
  return r;
}

namespace {

ParamTable<SensorParams> commonSensorKeys() {
  ParamTable<SensorParams> t;
  t.choice("type", &SensorParams::type, SensorParams::types(), "kind of sensor")
      .text("model", &SensorParams::model, "product name, for humans")
      .real("x", &SensorParams::x, "m", -5, 5, "position on the robot, forward")
      .real("y", &SensorParams::y, "m", -5, 5, "position on the robot, left")
      .real("z", &SensorParams::z, "m", 0, 5, "height above the floor")
      .real("yaw", &SensorParams::yaw, "deg", -180, 180, "rotation about z (0: looks forward)")
      .real("pitch", &SensorParams::pitch, "deg", -90, 90,
            "rotation about y, positive looks down (MRPT CPose3D convention)")
      .real("roll", &SensorParams::roll, "deg", -180, 180, "rotation about x")
      .real("rate_hz", &SensorParams::rate_hz, "Hz", 0.1, 1000, "scan or frame rate");
  return t;
}

void addRanges(ParamTable<SensorParams>& t) {
  t.real("range_min", &SensorParams::range_min, "m", 0, 100, "nearest valid reading")
      .real("range_max", &SensorParams::range_max, "m", 0.01, 200, "farthest valid reading")
      .real("noise_std", &SensorParams::noise_std, "m", 0, 1,
            "range noise, 1 sigma (depth cameras: at 1 m, growing with range squared)")
      .check([](const SensorParams& s) -> std::optional<std::string> {
        if (s.range_min >= s.range_max)
          return "range_min (" + formatReal(s.range_min) + ") must be below range_max (" +
                 formatReal(s.range_max) + ")";
        return std::nullopt;
      });
}

}  // namespace

const std::vector<std::string>& SensorParams::types() {
  static const std::vector<std::string> t{"lidar2d", "depth-camera", "range-array", "bumper"};
  return t;
}

const ParamTable<SensorParams>& SensorParams::table() {
  static const auto t = commonSensorKeys();
  return t;
}

const ParamTable<SensorParams>& SensorParams::tableFor(const std::string& type) {
  static const auto lidar = [] {
    auto t = commonSensorKeys();
    addRanges(t);
    t.real("fov", &SensorParams::fov, "deg", 1, 360, "angular field of view of a scan")
        .integer("beams", &SensorParams::beams, "", 2, 100000, "rays per scan");
    return t;
  }();
  static const auto depth = [] {
    auto t = commonSensorKeys();
    addRanges(t);
    t.real("fov", &SensorParams::fov, "deg", 1, 179, "horizontal field of view")
        .real("vfov", &SensorParams::vfov, "deg", 1, 179, "vertical field of view")
        .integer("width", &SensorParams::width, "px", 1, 10000, "depth image columns")
        .integer("height", &SensorParams::height, "px", 1, 10000, "depth image rows")
        .check([](const SensorParams& s) -> std::optional<std::string> {
          if (s.width <= 0 || s.height <= 0 || s.vfov <= 0)
            return std::string("a depth-camera needs width, height and vfov");
          return std::nullopt;
        });
    return t;
  }();
  static const auto array = [] {
    auto t = commonSensorKeys();
    addRanges(t);
    t.real("fov", &SensorParams::fov, "deg", 1, 360, "horizontal field of view of all segments")
        .integer("segments", &SensorParams::segments, "", 1, 1024, "independent range segments");
    return t;
  }();
  static const auto bumper = commonSensorKeys();
  if (type == "lidar2d") return lidar;
  if (type == "depth-camera") return depth;
  if (type == "range-array") return array;
  if (type == "bumper") return bumper;
  throw ParamValueError("'" + type + "' is not a sensor type");
}

std::vector<SensorParams> loadSensors(const Profile& profile) {
  std::vector<SensorParams> out;
  for (const auto& name : profile.sectionsWithPrefix("sensor.")) {
    const std::string type = profile.value(name, "type");
    const ParamTable<SensorParams>* table = nullptr;
    try {
      table = &SensorParams::tableFor(type);
    } catch (const ParamValueError&) {
      throw InputError(profile.origin() + ": [" + name + "] type: '" + type +
                       "' is not one of lidar2d, depth-camera, range-array, bumper");
    }
    SensorParams s = profile.section<SensorParams>(name, *table);
    s.label = name.substr(std::string("sensor.").size());
    out.push_back(std::move(s));
  }
  return out;
}

void registerCommonSections() {
  auto& reg = ProfileSchemas::instance();
  reg.add(SectionSchema::of(ProfileInfo::table(), "profile", "identification and layering"));
  reg.add(SectionSchema::of(RobotParams::table(), "robot", "body and motion limits"));
  for (const auto& type : SensorParams::types())
    reg.add(SectionSchema::of(SensorParams::tableFor(type), "sensor.*",
                              "one sensor on the robot; <label> is its rawlog sensorLabel", "type",
                              type));
}

}  // namespace carenav
