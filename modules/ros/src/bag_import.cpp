// carenav import rosbag: a bag's scans, clouds, depth images and odometry to an observation-only
// rawlog (gzip), written to a temporary name and renamed.
#include <carenav/common/errors.h>
#include <carenav/common/json.h>
#include <carenav/common/progress.h>
#include <carenav/io/rawlog_reader.h>
#include <carenav/ros/bag.h>

#include <mrpt/io/CFileGZOutputStream.h>
#include <mrpt/serialization/CArchive.h>

#include <filesystem>
#include <sstream>

namespace carenav::ros {

namespace fs = std::filesystem;

std::string BagImportStats::toText() const {
  std::ostringstream o;
  o << "messages:     " << notes.messages << " (" << notes.skipped << " of topics not read)\n";
  o << "scans:        " << notes.scans;
  if (notes.scans_no_tf)
    o << " (" << notes.scans_no_tf << " placed by the profile or at the origin: no tf)";
  if (notes.clouds) {
    o << "\nclouds:       " << notes.clouds;
    if (notes.clouds_no_tf)
      o << " (" << notes.clouds_no_tf << " placed by the profile or at the origin: no tf)";
  }
  if (notes.depth_images || notes.depth_dropped) {
    o << "\ndepth images: " << notes.depth_images;
    if (notes.depth_no_tf)
      o << " (" << notes.depth_no_tf << " placed by the profile or at the origin: no tf)";
    if (notes.depth_dropped)
      o << " (" << notes.depth_dropped
        << " left out: no camera_info before them, or an encoding not read)";
  }
  o << "\nodometry:     " << notes.odometry << "\n";
  o << "written:      " << written << " observations\n";
  o << "topics:\n";
  for (const auto& [t, type] : notes.topics) o << "  " << t << "  " << type << "\n";
  return o.str();
}

std::string BagImportStats::toJson() const {
  JsonWriter j;
  j.beginObject();
  j.key("messages").value(static_cast<uint64_t>(notes.messages));
  j.key("skipped").value(static_cast<uint64_t>(notes.skipped));
  j.key("scans").value(static_cast<uint64_t>(notes.scans));
  j.key("scans_without_tf").value(static_cast<uint64_t>(notes.scans_no_tf));
  j.key("clouds").value(static_cast<uint64_t>(notes.clouds));
  j.key("clouds_without_tf").value(static_cast<uint64_t>(notes.clouds_no_tf));
  j.key("depth_images").value(static_cast<uint64_t>(notes.depth_images));
  j.key("depth_images_without_tf").value(static_cast<uint64_t>(notes.depth_no_tf));
  j.key("depth_images_left_out").value(static_cast<uint64_t>(notes.depth_dropped));
  j.key("odometry").value(static_cast<uint64_t>(notes.odometry));
  j.key("written").value(static_cast<uint64_t>(written));
  j.key("topics").beginObject();
  for (const auto& [t, type] : notes.topics) j.key(t).value(type);
  j.endObject();
  j.endObject();
  return j.str() + "\n";
}

BagImportStats importRosbag(const BagImportOptions& o, BagImportStats* stats) {
  BagImportStats local;
  BagImportStats& st = stats ? *stats : local;
  auto notes = std::make_shared<BagReadNotes>();
  auto src = openBag(o.input, o.read, notes);  // InputError: not a bag
  const std::string tmp = o.output + ".part";
  std::optional<io::RawlogError> broken;
  {
    mrpt::io::CFileGZOutputStream out;
    if (!out.open(tmp)) throw InputError(o.output + ": cannot write the rawlog here");
    auto arch = mrpt::serialization::archiveFrom(out);
    Progress progress("import " + o.input, fs::file_size(o.input));
    progress.setEnabled(o.progress && progress.enabled());
    mrpt::obs::CObservation::Ptr obs;
    try {
      while (src->next(obs)) {
        arch << *obs;
        ++st.written;
        progress.update(src->position(), st.written);
      }
    } catch (const io::RawlogError& e) {
      broken = e;
    }
    progress.finish();
  }
  st.notes = *notes;
  std::error_code ec;
  if (st.written == 0) {
    fs::remove(tmp, ec);
    if (broken)
      throw io::RawlogError(std::string(broken->what()) + "; no file written", broken->entry(),
                            broken->offset());
    throw InputError(o.input + ": no scans or odometry to import (topics: " +
                     std::to_string(notes->topics.size()) +
                     ", messages: " + std::to_string(notes->messages) + ")");
  }
  fs::rename(tmp, o.output, ec);
  if (ec) {
    fs::remove(tmp, ec);
    throw std::runtime_error(o.output + ": cannot write the rawlog: " + ec.message());
  }
  if (broken)
    throw io::RawlogError(std::string(broken->what()) + "; " + std::to_string(st.written) +
                              " observations written to " + o.output,
                          broken->entry(), broken->offset());
  return st;
}

}  // namespace carenav::ros
