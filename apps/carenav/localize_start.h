// Shared by `carenav localize --in-room` and `carenav places add-place --here`:
// the start of localisation inside a named room of a places file.
#pragma once

#include <carenav/localization/localize_job.h>

#include <string>

namespace carenav::app {

/** The named room (case-insensitive) of a places file as a localisation
 *  region. Throws InputError naming the file and the rooms it has when the
 *  room is missing. */
localization::LocalizeJobOptions::Region roomRegion(const std::string& places_file,
                                                    const std::string& name);

}  // namespace carenav::app
