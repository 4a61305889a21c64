#include <carenav/common/profile.h>
#include <carenav/localization/pose_at_end.h>

#include <sstream>

namespace carenav::localization {

LocalizationParams localizationParamsOf(const std::string& profile_path,
                                        const std::vector<std::string>& sets) {
  Profile prof = profile_path.empty() ? Profile::fromText("[localization]\n", "(embedded defaults)")
                                      : Profile::load(profile_path);
  prof.applyOverrides(sets);
  if (!profile_path.empty()) {
    prof.validate();
  } else {
    for (const auto& s : sets)
      if (s.rfind("localization.", 0) != 0)
        throw InputError("--set '" + s +
                         "': without --profile only localization.* values can be set");
  }
  return prof.section<LocalizationParams>("localization");
}

EndPose poseAtEnd(LocalizeJobOptions o) {
  o.out_dir.clear();
  const LocalizeJobResult r = runLocalize(o);
  if (r.rawlog_error) throw InputError(*r.rawlog_error + " (add-place --here needs the whole log)");
  if (!r.converged_at_end) {
    std::ostringstream m;
    m << "add-place --here: localisation on " << o.rawlog << " has not converged at its end "
      << "(particle spread " << r.final_spread << " m); give --init or --in-room, or drive "
      << "longer before the place";
    throw std::runtime_error(m.str());
  }
  const auto& e = r.track.back();
  return {e.x, e.y, e.yaw, r.scans, r.final_spread};
}

}  // namespace carenav::localization
