// Scenario suites: `carenav navigate --suite DIR` and side-by-side runs of
// several plugins, each run in a fresh child process.
#pragma once

#include <carenav/runtime/scenario.h>

#include <string>
#include <vector>

namespace carenav::navigation {

/** The scenario files of a suite folder: every *.yaml in it but places files
 *  (*.places.yaml), sorted. Throws InputError "DIR: not a folder" or "DIR: no
 *  *.yaml scenario in it". */
std::vector<std::string> suiteFiles(const std::string& dir);

/** The live app's scenario without a scenario file: the walker in `world`
 *  (empty: maps/worlds/apartment.yaml of the data folder) with the data
 *  folder's walker profile, at 1.0,4.0,0, until stopped. Throws InputError
 *  "WORLD: no such world file (--world)". */
Scenario liveScenario(const std::string& world);

/** Runs one scenario in a child process and passes its metrics back as JSON:
 *  every run starts from a fresh process, so nothing one run leaves behind
 *  (caches, global random generators, here or in MRPT) changes the next, and
 *  a crash ends one run (outcome "crashed (signal N)"), not the suite. The
 *  child's InputError (PluginMismatchError kept apart) and other errors are
 *  thrown again in the parent. */
RunMetrics runInChild(const Scenario& s, const RunOptions& o);

/** Runs every scenario with every plugin (an empty list: the scenario's or
 *  the profile's). `base` holds the options shared by all runs; with an
 *  out_dir each run writes into its subfolder NAME or NAME-PLUGIN. One run
 *  (one scenario, at most one plugin) runs in this process; more run each in
 *  a child (runInChild), and a plugin that does not fit a scenario is skipped
 *  (said on stderr when base.progress). Throws InputError for a paced run
 *  (base.speed > 0) of more than one. */
std::vector<RunMetrics> runSuite(const std::vector<Scenario>& scenarios,
                                 const std::vector<std::string>& plugins, const RunOptions& base);

/** The runs as a table, one line each (scenario, plugin, success,
 *  collisions, clearances, time, path, speed, fidelity, cycle time,
 *  outcome), and how many succeeded. */
std::string runsTable(const std::vector<RunMetrics>& runs);
/** The runs as a JSON array of their summaries. */
std::string runsJson(const std::vector<RunMetrics>& runs);

}  // namespace carenav::navigation
