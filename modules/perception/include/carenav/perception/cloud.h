// Point clouds for perception: PCD/PLY readers and writers, frame conventions
// and extraction of points from MRPT 3D observations.
#pragma once

#include <mrpt/obs/CObservation.h>
#include <mrpt/poses/CPose3D.h>

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace carenav::perception {

struct Point3f {
  float x = 0, y = 0, z = 0;
};

/** A point cloud. Organised clouds (height > 1) keep one point per pixel in
 *  row-major order, invalid pixels as NaN, so depth-image algorithms (FSPF+)
 *  can use the image structure. */
struct Cloud {
  std::vector<Point3f> points;
  size_t width = 0, height = 1;  ///< width * height == points.size() when organised
  bool organised() const { return height > 1 && width * height == points.size(); }
  size_t validCount() const;
};

inline bool validPoint(const Point3f& p) {
  // NaN/inf fail every comparison; a point at the exact origin is a zero depth.
  return std::abs(p.x) < 1e6f && std::abs(p.y) < 1e6f && std::abs(p.z) < 1e6f &&
         !(p.x == 0.f && p.y == 0.f && p.z == 0.f);
}

/** Limits of the cloud readers (docs/perceive.md, 'Bad input'): checked
 *  against the header and the file size before anything is allocated.
 *  2^24 points is 55 Kinect frames (640 x 480) or a 64-beam lidar sweep
 *  times 60; 1 GiB holds that many points in ascii. */
constexpr size_t kMaxCloudPoints = size_t{1} << 24;
constexpr uint64_t kMaxCloudFileBytes = uint64_t{1} << 30;
/** Largest PCD COUNT of one field (PCL's largest descriptors have a few hundred). */
constexpr uint64_t kMaxFieldCount = 65536;

/** Reads a PCD file (VERSION 0.7 header; DATA ascii, binary or
 *  binary_compressed; fields x y z required, others ignored). Throws
 *  InputError naming the file and the problem (missing/malformed header
 *  field, POINTS != WIDTH*HEIGHT, truncated data, bad number, sizes beyond
 *  the limits above or beyond what the file can hold...); messages never
 *  carry raw bytes of the file (non-printable bytes are written \xHH). */
Cloud readPcd(const std::string& path);
/** Reads the vertex element of a PLY file (ascii or binary_little_endian;
 *  properties x y z required). Throws InputError like readPcd. Without
 *  further elements, data after the declared vertices is an error (the header
 *  declares fewer vertices than the file holds). */
Cloud readPly(const std::string& path);
/** readPcd or readPly by extension (.pcd / .ply); anything else is an InputError. */
Cloud readCloudFile(const std::string& path);

/** Content check of a cloud read from a file for `perceive --cloud` (docs/perceive.md,
 *  'Bad input'). InputError naming `path` when the cloud holds no point, no valid point
 *  (all NaN, infinite, zero depth or beyond 1e6 m) or fewer than 3 valid points (no
 *  plane, no obstacle map can come out of it). Returns the warnings of an accepted
 *  cloud: points with absurd coordinates (infinite or beyond 1e6 m) that are ignored. */
std::vector<std::string> checkCloudContent(const std::string& path, const Cloud& c);

enum class PcdEncoding { Ascii, Binary };
void writePcd(const std::string& path, const Cloud& c, PcdEncoding enc);
enum class PlyEncoding { Ascii, BinaryLittleEndian };
void writePly(const std::string& path, const Cloud& c, PlyEncoding enc);

/** Camera optical frame (x right, y down, z forward) to MRPT's sensor frame
 *  (x forward, y left, z up). */
inline Point3f opticalToSensor(const Point3f& p) { return {p.z, -p.x, -p.y}; }

/** Sensor pose from "x,y,z,yaw,pitch,roll" (m and degrees, MRPT CPose3D;
 *  positive pitch looks down). Throws InputError. */
mrpt::poses::CPose3D parseSensorPose(const std::string& text);

/** Points of `c` (in the sensor frame given by `optical`) moved to the robot
 *  frame with `sensor_pose`. Invalid points stay NaN (organisation kept). */
Cloud toRobotFrame(const Cloud& c, const mrpt::poses::CPose3D& sensor_pose, bool optical);

/** Points of a 3D observation in the robot frame: CObservation3DRangeScan
 *  (depth image unprojected with its intrinsics; organised), CObservationPointCloud
 *  and CObservationVelodyneScan. The observation's own sensorPose is used
 *  unless `pose_override` is set. Returns nullopt for other observation
 *  classes. Zero/NaN depths are invalid points. */
std::optional<Cloud> cloudFromObservation(
    const mrpt::obs::CObservation& obs,
    const std::optional<mrpt::poses::CPose3D>& pose_override = std::nullopt);

}  // namespace carenav::perception
