// A bag's scans and odometry as observations (bag.h), read front to back
// with BagFile; sensor poses from tf.
#include <carenav/common/errors.h>
#include <carenav/io/rawlog_reader.h>
#include <carenav/ros/bag.h>

#include "bag_file.h"
#include "msg_convert.h"

#include <mrpt/obs/CObservationOdometry.h>
#include <nav_msgs/Odometry.h>
#include <ros/serialization.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/LaserScan.h>
#include <sensor_msgs/PointCloud2.h>
#include <tf2_msgs/TFMessage.h>

#include <optional>

namespace carenav::ros {

namespace {

using mrpt::obs::CObservation;
using mrpt::poses::CPose3D;

template <class M>
bool isType(const BagConnection& c) {
  return c.type == ::ros::message_traits::DataType<M>::value() &&
         (c.md5sum == "*" || c.md5sum == ::ros::message_traits::MD5Sum<M>::value());
}

template <class M>
M decode(const BagMessage& m) {
  M msg;
  ::ros::serialization::IStream s(const_cast<uint8_t*>(m.data), m.size);
  ::ros::serialization::deserialize(s, msg);
  return msg;
}

/** The robot's frames as tf gives them: child -> (parent, pose in parent). */
class FrameTree {
 public:
  void set(const std::string& parent, const std::string& child, const CPose3D& p) {
    links_[bareFrame(child)] = {bareFrame(parent), p};
  }
  /** `frame` in `base` (walking up at most 16 links); nullopt if not linked. */
  std::optional<CPose3D> in(const std::string& frame, const std::string& base) const {
    CPose3D acc;
    std::string f = bareFrame(frame);
    for (int i = 0; i < 16; ++i) {
      if (f == base) return acc;
      const auto it = links_.find(f);
      if (it == links_.end()) return std::nullopt;
      acc = it->second.second + acc;
      f = it->second.first;
    }
    return std::nullopt;
  }

 private:
  std::map<std::string, std::pair<std::string, CPose3D>> links_;
};

class BagSource : public io::ObservationSource {
 public:
  BagSource(const std::string& path, BagReadOptions o, std::shared_ptr<BagReadNotes> notes)
      : path_(path),
        o_(std::move(o)),
        notes_(notes ? notes : std::make_shared<BagReadNotes>()),
        bag_(open(path)) {
    for (const auto& s : o_.scans) scan_labels_.insert(topicLabel(s));
    for (const auto& s : o_.clouds)
      if (s != "none") cloud_labels_.insert(topicLabel(s));
    no_clouds_ = o_.clouds.size() == 1 && o_.clouds[0] == "none";
    chooseDepthTopics();
    o_.odom_frame = bareFrame(o_.odom_frame);
    o_.base_frame = bareFrame(o_.base_frame);
  }
  bool next(CObservation::Ptr& out) override;
  uint64_t position() const override { return bag_.position(); }

 private:
  static BagFile open(const std::string& path) {
    try {
      return BagFile(path);
    } catch (const BagBroken& b) {
      throw InputError(path + ": " + b.what);
    }
  }
  /** A depth image topic: its label ("" default) and CameraInfo topic. */
  struct DepthTopic {
    std::string label, info;
  };
  void chooseDepthTopics();
  CObservation::Ptr take(const BagMessage& m);
  static std::pair<std::string, std::string> topicLabel(const std::string& s) {
    const size_t eq = s.find('=');
    return {s.substr(0, eq), eq == std::string::npos ? "" : s.substr(eq + 1)};
  }
  CObservation::Ptr scan(const BagMessage& m, const std::string& label);
  CObservation::Ptr cloud(const BagMessage& m, const std::string& label);
  CObservation::Ptr depth(const BagMessage& m, const DepthTopic& d);
  /** The label (given, else the frame, else the topic) and the pose on the
   *  robot (tf, else the profile's by label, else the origin: `no_tf` counts).
   *  `optical`: the frame is a camera's optical frame (an image's), its
   *  default label the camera's and the pose the camera's body frame. */
  std::pair<std::string, CPose3D> placed(const std::string& frame_id, const std::string& given,
                                         const std::string& topic, size_t& no_tf,
                                         bool optical = false) const;
  CObservation::Ptr odometry(const BagMessage& m);
  CObservation::Ptr transforms(const BagMessage& m);
  bool odomTopic(const BagConnection& c);
  bool scanTopic(const BagConnection& c, std::string& label) const;
  bool cloudTopic(const BagConnection& c, std::string& label) const;
  bool depthTopic(const BagConnection& c, DepthTopic& d) const;

  std::string path_;
  BagReadOptions o_;
  std::shared_ptr<BagReadNotes> notes_;
  BagFile bag_;
  std::map<std::string, std::string> scan_labels_;  // topic -> label ("" default)
  std::map<std::string, std::string> cloud_labels_;
  bool no_clouds_ = false;
  std::map<std::string, DepthTopic> depth_topics_;  // image topic -> label, CameraInfo topic
  bool no_depth_ = false;
  std::map<std::string, sensor_msgs::CameraInfo> infos_;  // CameraInfo topic -> the last
  FrameTree frames_;
  std::optional<std::string> odom_topic_;  // the Odometry topic read, once chosen
};

/** `/cam/depth/image_raw` -> `/cam/depth/camera_info`. */
std::string siblingCameraInfo(const std::string& topic) {
  const size_t slash = topic.rfind('/');
  return (slash == std::string::npos ? std::string() : topic.substr(0, slash + 1)) + "camera_info";
}

void BagSource::chooseDepthTopics() {
  no_depth_ = o_.depths.size() == 1 && o_.depths[0] == "none";
  if (no_depth_) return;
  if (!o_.camera_infos.empty() && o_.camera_infos.size() != o_.depths.size())
    throw InputError("give one camera_info topic per depth topic (" +
                     std::to_string(o_.depths.size()) + " depth, " +
                     std::to_string(o_.camera_infos.size()) + " camera_info)");
  for (size_t i = 0; i < o_.depths.size(); ++i) {
    const auto [topic, label] = topicLabel(o_.depths[i]);
    depth_topics_[topic] = {
        label, o_.camera_infos.empty() ? siblingCameraInfo(topic) : o_.camera_infos[i]};
  }
}

bool BagSource::next(CObservation::Ptr& out) {
  BagMessage m;
  for (;;) {
    try {
      if (!bag_.next(m)) return false;
      ++notes_->messages;
      notes_->topics[m.connection->topic] = m.connection->type;
      out = take(m);
    } catch (const BagBroken& b) {
      const size_t n = bag_.messages();
      throw io::RawlogError(path_ + ": bag broken at message " + std::to_string(n) + " (byte " +
                                std::to_string(b.offset) + "): " + b.what + "; the " +
                                std::to_string(n) + " messages before it were read",
                            n, b.offset);
    } catch (const ::ros::Exception& e) {  // a message shorter than its type
      const size_t n = bag_.messages();
      throw io::RawlogError(path_ + ": bag broken at message " + std::to_string(n) + " (byte " +
                                std::to_string(m.offset) + "): a " + m.connection->type +
                                " message on " + m.connection->topic + " that does not decode (" +
                                e.what() + "); the " + std::to_string(n - 1) +
                                " messages before it were read",
                            n, m.offset);
    }
    if (out) return true;
  }
}

CObservation::Ptr BagSource::take(const BagMessage& m) {
  const BagConnection& c = *m.connection;
  std::string label;
  if (scanTopic(c, label)) return scan(m, label);
  if (cloudTopic(c, label)) return cloud(m, label);
  if (DepthTopic d; depthTopic(c, d)) return depth(m, d);
  if (!no_depth_ && isType<sensor_msgs::CameraInfo>(c)) {
    infos_[c.topic] = decode<sensor_msgs::CameraInfo>(m);
    return nullptr;
  }
  if (odomTopic(c)) return odometry(m);
  if (isType<tf2_msgs::TFMessage>(c) && (c.topic == "/tf" || c.topic == "/tf_static"))
    return transforms(m);
  ++notes_->skipped;
  return nullptr;
}

bool BagSource::scanTopic(const BagConnection& c, std::string& label) const {
  if (!isType<sensor_msgs::LaserScan>(c)) return false;
  if (scan_labels_.empty()) return true;
  const auto it = scan_labels_.find(c.topic);
  if (it == scan_labels_.end()) return false;
  label = it->second;
  return true;
}

bool BagSource::cloudTopic(const BagConnection& c, std::string& label) const {
  if (no_clouds_ || !isType<sensor_msgs::PointCloud2>(c)) return false;
  if (cloud_labels_.empty()) return true;
  const auto it = cloud_labels_.find(c.topic);
  if (it == cloud_labels_.end()) return false;
  label = it->second;
  return true;
}

bool BagSource::depthTopic(const BagConnection& c, DepthTopic& d) const {
  if (no_depth_ || !isType<sensor_msgs::Image>(c)) return false;
  if (depth_topics_.empty()) {  // every depth image with a CameraInfo (depth() checks)
    d = {"", siblingCameraInfo(c.topic)};
    return true;
  }
  const auto it = depth_topics_.find(c.topic);
  if (it == depth_topics_.end()) return false;
  d = it->second;
  return true;
}

bool BagSource::odomTopic(const BagConnection& c) {
  if (!isType<nav_msgs::Odometry>(c) || o_.odom == "tf" || o_.odom == "none") return false;
  if (!odom_topic_) {
    if (!o_.odom.empty() && o_.odom != c.topic) return false;
    odom_topic_ = c.topic;  // the given one, or the first met
  }
  return *odom_topic_ == c.topic;
}

std::pair<std::string, CPose3D> BagSource::placed(const std::string& frame_id,
                                                  const std::string& given,
                                                  const std::string& topic, size_t& no_tf,
                                                  bool optical) const {
  const std::string frame = bareFrame(frame_id);
  const std::string label = !given.empty()   ? given
                            : !frame.empty() ? (optical ? cameraOfOpticalFrame(frame) : frame)
                                             : bareFrame(topic);
  if (const auto pose = frames_.in(frame, o_.base_frame))
    return {label, optical ? *pose + (-opticalInBody()) : *pose};
  ++no_tf;
  const auto it = o_.sensor_poses.find(label);
  return {label, it != o_.sensor_poses.end() ? it->second : CPose3D()};
}

CObservation::Ptr BagSource::scan(const BagMessage& m, const std::string& given) {
  const auto msg = decode<sensor_msgs::LaserScan>(m);
  const auto [label, pose] =
      placed(msg.header.frame_id, given, m.connection->topic, notes_->scans_no_tf);
  auto o = scanFromRos(msg, label, pose);
  if (msg.header.stamp.isZero()) o->timestamp = fromRosTime(::ros::Time(m.sec, m.nsec));
  ++notes_->scans;
  return o;
}

// A cloud without float x, y, z is skipped (counted as a topic not read).
CObservation::Ptr BagSource::cloud(const BagMessage& m, const std::string& given) {
  const auto msg = decode<sensor_msgs::PointCloud2>(m);
  size_t no_tf = 0;
  const auto [label, pose] = placed(msg.header.frame_id, given, m.connection->topic, no_tf);
  auto o = cloudFromRos(msg, label, pose);
  if (!o) return ++notes_->skipped, nullptr;
  if (msg.header.stamp.isZero()) o->timestamp = fromRosTime(::ros::Time(m.sec, m.nsec));
  notes_->clouds_no_tf += no_tf;
  ++notes_->clouds;
  return o;
}

// A depth image is read with the last CameraInfo of its camera; unchosen
// (every Image topic read) only in 16UC1 or 32FC1 and with one, else it is
// a topic not read.
CObservation::Ptr BagSource::depth(const BagMessage& m, const DepthTopic& d) {
  const auto msg = decode<sensor_msgs::Image>(m);
  const auto info = infos_.find(d.info);
  if (depth_topics_.empty() &&
      ((msg.encoding != "16UC1" && msg.encoding != "32FC1") || info == infos_.end()))
    return ++notes_->skipped, nullptr;
  if (info == infos_.end()) return ++notes_->depth_dropped, nullptr;
  size_t no_tf = 0;
  const auto [label, pose] = placed(msg.header.frame_id, d.label, m.connection->topic, no_tf, true);
  auto o = depthFromRos(msg, info->second, label, pose);
  if (!o) return ++notes_->depth_dropped, nullptr;
  if (msg.header.stamp.isZero()) o->timestamp = fromRosTime(::ros::Time(m.sec, m.nsec));
  notes_->depth_no_tf += no_tf;
  ++notes_->depth_images;
  return o;
}

CObservation::Ptr BagSource::odometry(const BagMessage& m) {
  const auto msg = decode<nav_msgs::Odometry>(m);
  auto o = mrpt::obs::CObservationOdometry::Create();
  o->sensorLabel = "odometry";
  o->timestamp =
      fromRosTime(msg.header.stamp.isZero() ? ::ros::Time(m.sec, m.nsec) : msg.header.stamp);
  const auto& p = msg.pose.pose;
  o->odometry = mrpt::poses::CPose2D(p.position.x, p.position.y, yawOf(p.orientation));
  o->hasVelocities = true;
  o->velocityLocal = {msg.twist.twist.linear.x, msg.twist.twist.linear.y,
                      msg.twist.twist.angular.z};
  ++notes_->odometry;
  return o;
}

// tf: frames of the robot's sensors, and odom -> base as odometry (when
// odometry comes from tf: "tf", or "" while the bag has shown no Odometry).
CObservation::Ptr BagSource::transforms(const BagMessage& m) {
  const auto msg = decode<tf2_msgs::TFMessage>(m);
  const bool tf_odom = o_.odom == "tf" || (o_.odom.empty() && !odom_topic_);
  CObservation::Ptr out;
  for (const auto& t : msg.transforms) {
    const std::string parent = bareFrame(t.header.frame_id), child = bareFrame(t.child_frame_id);
    if (parent == o_.odom_frame && child == o_.base_frame) {
      if (!tf_odom || out) continue;
      auto o = mrpt::obs::CObservationOdometry::Create();
      o->sensorLabel = "odometry";
      o->timestamp = fromRosTime(t.header.stamp);
      const CPose3D p = poseOf(t.transform);
      o->odometry = mrpt::poses::CPose2D(p.x(), p.y(), p.yaw());
      ++notes_->odometry;
      out = o;
    } else {
      frames_.set(parent, child, poseOf(t.transform));
    }
  }
  return out;
}

}  // namespace

std::unique_ptr<io::ObservationSource> openBag(const std::string& path, BagReadOptions options,
                                               std::shared_ptr<BagReadNotes> notes) {
  return std::make_unique<BagSource>(path, std::move(options), std::move(notes));
}

void registerBagFormat() {
  io::registerRawlogFormat(".bag", "ROS bag",
                           [](const std::string& path) { return openBag(path, {}); });
}

}  // namespace carenav::ros
