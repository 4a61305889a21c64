// Where carenav's shipped data is: the robot profiles (ini/) and the maps,
// worlds and scenarios (maps/). Found at run time, relative to the running
// executable, so an installed carenav needs no path of the machine it was
// built on.
#pragma once

#include <string>

namespace carenav {

/** The data folder: $CARENAV_DATA_DIR when set, else <exe>/../share/carenav
 *  (the installed layout, <prefix>/bin/carenav beside
 *  <prefix>/share/carenav/; the build tree links that folder to the source
 *  tree). Empty when no candidate holds ini/defaults.ini. */
std::string dataDir();

/** dataDir()/rel when that file exists; otherwise throws InputError naming
 *  `what`, the path looked for and how to point carenav at its data. */
std::string dataFile(const std::string& rel, const std::string& what);

}  // namespace carenav
