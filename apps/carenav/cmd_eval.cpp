// carenav eval --est A.tum --ref B.tum [--relations R] [--out DIR] [--json]
#include "commands.h"

#include <carenav/common/errors.h>
#include <carenav/slam/eval_job.h>

#include <cmath>
#include <iostream>

namespace carenav::app {

namespace {

struct EvalArgs {
  slam::EvalJobOptions job;
  bool no_align = false;
  bool json = false;
};

/** A CLI11 check: a finite number above (or from) `low`; `what` is the rest
 *  of the message ("must be a finite number > 0 (metres)"). */
CLI::Validator finiteFrom(double low, bool inclusive, const std::string& what) {
  return CLI::Validator(
      [=](std::string& s) -> std::string {
        double v = NAN;
        if (!CLI::detail::lexical_cast(s, v) || !std::isfinite(v) || v < low ||
            (!inclusive && v == low))
          return what;
        return {};
      },
      "");
}

/** The checks CLI11 cannot express: which of the files are needed. */
void checkFiles(const slam::EvalJobOptions& o) {
  if (o.make_relations.empty() && o.est.empty())
    throw InputError("--est is required (the trajectory to evaluate)");
  if (!o.est.empty() && o.ref.empty() && o.relations.empty() && o.make_relations.empty())
    throw InputError("nothing to compare with: give --ref, --relations or both");
}

void runEval(EvalArgs& a, const GlobalOptions& g) {
  checkFiles(a.job);
  if (!a.job.out_dir.empty()) prepareOutputFolder(a.job.out_dir);
  a.job.align = !a.no_align;
  a.job.progress = !g.quiet;
  const slam::EvalJobResult r = slam::runEvalJob(a.job);
  if (r.computed()) std::cout << (a.json ? r.toJson(a.job) : r.toText(a.job)) << std::flush;
  if (r.error) throw *r.error;
}

void addEvalCommand(CLI::App& app, const GlobalOptions& g) {
  auto a = std::make_shared<EvalArgs>();
  slam::EvalJobOptions& o = a->job;
  auto* cmd = app.add_subcommand(
      "eval",
      "Trajectory accuracy of an estimate (SLAM or localisation output, TUM file) against a "
      "reference: poses paired by timestamp; ATE after a least-squares SE(2) alignment "
      "(RMSE, mean, median, std, max of the translation and rotation errors); RPE per step and "
      "over travelled distances; the relations metric of Kuemmerle et al. 2009 with a "
      "relations file (t1 t2 x y z roll pitch yaw). With --out DIR: eval.json, "
      "trajectories.png, ate.png and estimate_aligned.tum. See docs/eval.md.\n"
      "Examples:\n"
      "  carenav eval --est slam.tum --ref gt.tum --out eval/\n"
      "  carenav eval --est slam.tum --relations intel.relations --json\n"
      "  carenav eval --ref gt.tum --make-relations gt.relations --rel-dist 1");
  cmd->add_option("--est", o.est, "Estimated trajectory (TUM: t x y z qx qy qz qw)");
  cmd->add_option("--ref", o.ref, "Reference trajectory (TUM); optional with --relations");
  cmd->add_option("--relations", o.relations,
                  "Relations file (t1 t2 x y z roll pitch yaw per line, as the Freiburg "
                  "benchmark's): adds the Kuemmerle et al. 2009 metric");
  cmd->add_option("--out", o.out_dir,
                  "Output directory: eval.json, trajectories.png, ate.png, estimate_aligned.tum");
  cmd->add_flag("--json", a->json, "Print JSON instead of text");
  cmd->add_option("--max-dt", o.assoc.max_dt,
                  "Largest time difference (s) of a pose pair matched by nearest timestamps")
      ->capture_default_str()
      ->check(finiteFrom(0, true, "must be a finite number >= 0 (seconds)"));
  cmd->add_flag("--interpolate", o.assoc.interpolate,
                "Interpolate the reference linearly at the estimate's timestamps (when the "
                "reference is sampled at other times); nearest matching elsewhere");
  cmd->add_option("--max-gap", o.assoc.max_gap,
                  "With --interpolate: longest reference gap (s) to interpolate across")
      ->capture_default_str()
      ->check(finiteFrom(0, false, "must be a finite number > 0 (seconds)"));
  cmd->add_flag("--by-index", o.assoc.by_index,
                "Pair the k-th estimated pose with the k-th reference pose, timestamps ignored "
                "(both files must have as many poses): for logs whose timestamps repeat")
      ->excludes("--interpolate")
      ->needs("--ref");
  cmd->add_flag("--no-align", a->no_align,
                "ATE without the SE(2) alignment (when both are in the same frame already)");
  cmd->add_option("--rpe-dist", o.rpe_dist,
                  "Travelled distances (m) of the RPE, comma-separated, e.g. 1,2,5,10")
      ->delimiter(',')
      ->capture_default_str()
      ->check(finiteFrom(0, false, "every distance must be a finite number > 0 (metres)"));
  cmd->add_option("--make-relations", o.make_relations,
                  "Write a relations file made from --ref (a pair for each pose and the first "
                  "pose --rel-dist metres further along the path); with --est, also evaluate it")
      ->type_name("FILE")
      ->needs("--ref")
      ->excludes("--relations");
  cmd->add_option("--rel-dist", o.rel_dist, "Travelled distance (m) of --make-relations pairs")
      ->capture_default_str()
      ->check(finiteFrom(0, false, "must be a finite number > 0 (metres)"));
  cmd->callback([a, &g] { runEval(*a, g); });
}

}  // namespace

CARENAV_COMMAND(90, addEvalCommand);

}  // namespace carenav::app
