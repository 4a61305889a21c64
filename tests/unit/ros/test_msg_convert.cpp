// The message conversions of the ROS nodes (modules/ros/src/msg_convert.h):
// depth images with their CameraInfo and body-frame clouds as the depth
// observations carenav's perception pipeline reads.
#include <carenav/perception/cloud.h>

#include "msg_convert.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>

namespace {

using carenav::ros::cloudFromRos;
using carenav::ros::depthFromRos;

sensor_msgs::CameraInfo camera(double f, double cx, double cy) {
  sensor_msgs::CameraInfo c;
  c.K = {f, 0, cx, 0, f, cy, 0, 0, 1};
  return c;
}

TEST(RosMsgConvert, DepthImageMillimetresUnprojectsForward) {
  sensor_msgs::Image img;
  img.encoding = "16UC1";
  img.width = 3;
  img.height = 3;
  img.step = 6;
  std::vector<uint16_t> mm(9, 2000);
  mm[0] = 0;  // no return
  img.data.resize(18);
  std::memcpy(img.data.data(), mm.data(), 18);
  const mrpt::poses::CPose3D pose(0.1, 0, 0.5, 0, 0, 0);
  const auto o = depthFromRos(img, camera(2, 1, 1), "cam", pose);
  ASSERT_TRUE(o);
  const auto c = carenav::perception::cloudFromObservation(*o);
  ASSERT_TRUE(c);
  ASSERT_EQ(c->points.size(), 9u);
  EXPECT_EQ(c->height, 3u);
  EXPECT_FALSE(carenav::perception::validPoint(c->points[0]));
  const auto& centre = c->points[4];  // the optical axis: 2 m straight ahead
  EXPECT_NEAR(centre.x, 2.1, 1e-4);
  EXPECT_NEAR(centre.y, 0, 1e-4);
  EXPECT_NEAR(centre.z, 0.5, 1e-4);
  EXPECT_NEAR(c->points[3].y, 1.0, 1e-4) << "column 0 is to the left (y > 0)";
  EXPECT_NEAR(c->points[1].z, 1.5, 1e-4) << "row 0 is above (z > 0)";
}

TEST(RosMsgConvert, DepthImageMetresAndRefusals) {
  sensor_msgs::Image img;
  img.encoding = "32FC1";
  img.width = 2;
  img.height = 1;
  img.step = 8;
  const float m[2] = {1.5f, std::numeric_limits<float>::quiet_NaN()};
  img.data.resize(8);
  std::memcpy(img.data.data(), m, 8);
  const auto o = depthFromRos(img, camera(1, 0.5, 0), "cam", {});
  ASSERT_TRUE(o);
  EXPECT_EQ(o->rangeImage(0, 0), 1500);
  EXPECT_EQ(o->rangeImage(0, 1), 0);
  img.encoding = "rgb8";
  EXPECT_FALSE(depthFromRos(img, camera(1, 0.5, 0), "cam", {}));
  img.encoding = "32FC1";
  EXPECT_FALSE(depthFromRos(img, sensor_msgs::CameraInfo(), "cam", {})) << "no intrinsics";
  img.data.resize(4);
  EXPECT_FALSE(depthFromRos(img, camera(1, 0.5, 0), "cam", {})) << "short data";
}

/** An empty PointCloud2 of w x h points with float32 fields x, y, z (12 bytes a point). */
sensor_msgs::PointCloud2 xyzLayout(uint32_t w, uint32_t h) {
  sensor_msgs::PointCloud2 m;
  m.width = w;
  m.height = h;
  m.point_step = 12;
  for (int i = 0; i < 3; ++i) {
    sensor_msgs::PointField f;
    f.name = std::string(1, "xyz"[i]);
    f.offset = 4 * i;
    f.datatype = sensor_msgs::PointField::FLOAT32;
    f.count = 1;
    m.fields.push_back(f);
  }
  return m;
}

TEST(RosMsgConvert, CloudDropsNonFinitePoints) {
  sensor_msgs::PointCloud2 m = xyzLayout(2, 1);
  const float v[6] = {1, 2, 3, std::numeric_limits<float>::quiet_NaN(), 0, 0};
  m.data.resize(24);
  std::memcpy(m.data.data(), v, 24);
  const auto o = cloudFromRos(m, "cam", {});
  ASSERT_TRUE(o);
  ASSERT_EQ(o->points3D_x.size(), 1u);
  EXPECT_EQ(o->points3D_z[0], 3.f);
  m.fields.pop_back();
  EXPECT_FALSE(cloudFromRos(m, "cam", {})) << "no z field";
}

/** An xyz PointCloud2 of w x h points (row-major), NaN at pixel `hole`. */
sensor_msgs::PointCloud2 xyzCloud(uint32_t w, uint32_t h, size_t hole) {
  sensor_msgs::PointCloud2 m = xyzLayout(w, h);
  m.data.resize(size_t{w} * h * 12);
  for (size_t k = 0; k < size_t{w} * h; ++k) {
    const float nan = std::numeric_limits<float>::quiet_NaN();
    const float v[3] = {k == hole ? nan : 1.f + k, 0.1f * (k % w), -0.1f * (k / w)};
    std::memcpy(&m.data[k * 12], v, 12);
  }
  return m;
}

TEST(RosMsgConvert, AnOrganisedCloudKeepsItsImageLayoutForPerception) {
  // 4 x 3 pixels, pixel 5 (row 1, column 1) invalid: the perception cloud is
  // 4 x 3 again with NaN there, so the rules along image columns run on it.
  const auto o = cloudFromRos(xyzCloud(4, 3, 5), "cam", {});
  ASSERT_TRUE(o);
  const auto c = carenav::perception::cloudFromObservation(*o);
  ASSERT_TRUE(c);
  EXPECT_TRUE(c->organised());
  EXPECT_EQ(c->width, 4u);
  EXPECT_EQ(c->height, 3u);
  ASSERT_EQ(c->points.size(), 12u);
  EXPECT_FALSE(carenav::perception::validPoint(c->points[5]));
  EXPECT_FLOAT_EQ(c->points[6].x, 7.f) << "pixel 6 where it was";
  EXPECT_FLOAT_EQ(c->points[11].x, 12.f);
  // One row (an unorganised cloud): a list of its valid points, as before.
  const auto l =
      carenav::perception::cloudFromObservation(*cloudFromRos(xyzCloud(6, 1, 2), "cam", {}));
  ASSERT_TRUE(l);
  EXPECT_FALSE(l->organised());
  EXPECT_EQ(l->points.size(), 5u);
}

}  // namespace

// A simulated depth frame as a 16UC1 Image + CameraInfo and back: the same
// range image and intrinsics (what `ros sim --depth` publishes and a bag of
// it imports as).
TEST(RosMsgConvert, DepthObservationRoundTrip) {
  auto o = mrpt::obs::CObservation3DRangeScan::Create();
  o->hasRangeImage = true;
  o->range_is_depth = true;
  o->rangeUnits = 0.001f;
  o->rangeImage_setSize(4, 5);
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 5; ++c) o->rangeImage(r, c) = static_cast<uint16_t>(r * 1000 + c * 7);
  o->cameraParams.ncols = 5;
  o->cameraParams.nrows = 4;
  o->cameraParams.setIntrinsicParamsFromValues(4.5, 3.5, 2.0, 1.5);
  sensor_msgs::Image img;
  sensor_msgs::CameraInfo info;
  ASSERT_TRUE(carenav::ros::depthToRos(*o, "cam_optical", ::ros::Time(12, 5), img, info));
  EXPECT_EQ(img.encoding, "16UC1");
  EXPECT_EQ(img.header.frame_id, "cam_optical");
  EXPECT_EQ(info.header.stamp, ::ros::Time(12, 5));
  const auto back = depthFromRos(img, info, "cam", mrpt::poses::CPose3D());
  ASSERT_TRUE(back);
  EXPECT_EQ(back->rangeImage, o->rangeImage);
  EXPECT_DOUBLE_EQ(back->cameraParams.fx(), 4.5);
  EXPECT_DOUBLE_EQ(back->cameraParams.fy(), 3.5);
  EXPECT_DOUBLE_EQ(back->cameraParams.cx(), 2.0);
  EXPECT_DOUBLE_EQ(back->cameraParams.cy(), 1.5);
  auto none = mrpt::obs::CObservation3DRangeScan::Create();
  EXPECT_FALSE(carenav::ros::depthToRos(*none, "cam", ::ros::Time(1), img, info));
}

// The optical frame (z ahead, x right, y down) in the body frame (x ahead,
// y left, z up), and a camera's name from its optical frame's.
TEST(RosMsgConvert, OpticalFrame) {
  const auto R = carenav::ros::opticalInBody();
  mrpt::math::TPoint3D ahead, right, down;
  R.composePoint({0, 0, 1}, ahead);
  R.composePoint({1, 0, 0}, right);
  R.composePoint({0, 1, 0}, down);
  EXPECT_NEAR(ahead.x, 1, 1e-12);
  EXPECT_NEAR(right.y, -1, 1e-12);
  EXPECT_NEAR(down.z, -1, 1e-12);
  EXPECT_EQ(carenav::ros::cameraOfOpticalFrame("kinect_optical"), "kinect");
  EXPECT_EQ(carenav::ros::cameraOfOpticalFrame("camera_depth_optical_frame"), "camera_depth");
  EXPECT_EQ(carenav::ros::cameraOfOpticalFrame("kinect"), "kinect");
  EXPECT_EQ(carenav::ros::cameraOfOpticalFrame("_optical"), "_optical");
}
