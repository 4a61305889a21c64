// Where a rawlog ends on a known map: localisation over the whole log and its
// last estimate (how `places add-place --here` records a place by driving the
// robot there). Its messages are those of that command.
#pragma once

#include <carenav/localization/localize_job.h>

#include <string>
#include <vector>

namespace carenav::localization {

/** The [localization] section of the profile at `profile_path` after the
 *  `--set` overrides, the whole profile validated. Without a profile (empty
 *  path) the built-in defaults, and only localization.* values can be set:
 *  throws InputError "--set 'S': without --profile only localization.* values
 *  can be set" for any other. Throws InputError for a bad profile or value. */
LocalizationParams localizationParamsOf(const std::string& profile_path,
                                        const std::vector<std::string>& sets);

/** The last estimate of localisation over a whole rawlog. */
struct EndPose {
  double x = 0, y = 0, yaw = 0;  ///< m, m, rad
  size_t scans = 0;              ///< scans localised
  double spread = 0;             ///< m, particle spread after the last scan
};

/** Runs the localize job `o` (nothing written: out_dir is ignored) and
 *  returns where the rawlog ends. Throws what runLocalize throws; InputError
 *  "<rawlog error> (add-place --here needs the whole log)" when the rawlog
 *  breaks part way; std::runtime_error "add-place --here: localisation on R
 *  has not converged at its end (particle spread S m); ..." when the final
 *  estimate has not converged. */
EndPose poseAtEnd(LocalizeJobOptions o);

}  // namespace carenav::localization
