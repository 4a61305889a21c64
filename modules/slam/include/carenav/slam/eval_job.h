// `carenav eval`: an estimated trajectory against a reference (ATE, RPE) and
// against relations (Kuemmerle et al. 2009), with its report and outputs.
#pragma once

#include <carenav/common/errors.h>
#include <carenav/common/json_fwd.h>
#include <carenav/io/evaluation.h>

#include <optional>
#include <string>
#include <vector>

namespace carenav::slam {

struct EvalJobOptions {
  std::string est, ref;        ///< TUM files (est may be empty with make_relations)
  std::string relations;       ///< relations file to evaluate against
  std::string make_relations;  ///< relations file to write from ref
  std::string out_dir;         ///< eval.json, trajectories.png, ate.png, estimate_aligned.tum
  io::AssociationParams assoc;
  bool align = true;                   ///< ATE after the SE(2) alignment
  std::vector<double> rpe_dist{1, 5};  ///< m, travelled distances of the RPE
  double rel_dist = 1;                 ///< m, between the poses of a made relation
  bool progress = true;                ///< say on stderr what was written
};

/** Everything computed; a stage that failed leaves its field empty. */
struct EvalJobResult {
  io::Trajectory2D est, ref;
  std::optional<io::Association> assoc;
  std::optional<io::AteResult> ate;
  std::optional<io::RpeResult> rpe_step;
  std::vector<io::RpeResult> rpe;
  std::optional<io::RelationsResult> rel;
  std::vector<std::string> outputs;
  /** Bad input met by a stage (timestamps that do not overlap, relations
   *  outside the estimate): the other stages' results are still here; the
   *  caller reports them, then throws this. */
  std::optional<InputError> error;
  /** Something to report: an ATE or a relations metric. */
  bool computed() const { return ate || rel; }
  Json toJsonValue(const EvalJobOptions& o) const;
  std::string toJson(const EvalJobOptions& o) const;  ///< eval.json, `--json`
  std::string toText(const EvalJobOptions& o) const;  ///< the report
};

/** Reads the files, writes the relations file (make_relations), computes
 *  every metric the inputs allow and, when something was computed and
 *  out_dir is set, writes the outputs there (out_dir must exist or be
 *  creatable). Unreadable or malformed files throw InputError naming the
 *  file (and line); see EvalJobResult::error for the rest. */
EvalJobResult runEvalJob(const EvalJobOptions& o);

}  // namespace carenav::slam
