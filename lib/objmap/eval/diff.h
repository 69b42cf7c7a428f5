#pragma once
#include <filesystem>
#include <string>

#include "objmap/core/types.h"

// `objmap eval diff`: a diff.json of `objmap diff` against the changes_gt.json of `objmap synth
// --second-visit-of` (docs/change.md, "Evaluation"): the registration's error and the precision,
// recall and F1 of the moved, added and removed objects. A found change is right when a true one
// of the same kind lies within match_m of it (moved: at both ends; each true change counts once),
// so a moved object reported as removed + added is two false positives and a miss.
namespace objmap::eval {

struct DiffEvalOptions {
  double match_m = 0.25;  // a found change and a true one closer than this are the same object
  void check() const;     // throws InputError naming the bad field
};

struct ChangeScore {
  int truth = 0;    // true changes of this kind
  int found = 0;    // reported ones
  int correct = 0;  // reported ones matched to a true one
  double precision() const { return found ? double(correct) / found : 1.0; }
  double recall() const { return truth ? double(correct) / truth : 1.0; }
  double f1() const;  // 1 when there is nothing to find and nothing found
};

struct DiffEvalResult {
  // Registration: the rotation's error and the RMS of |est·p − true·p| over the true objects'
  // after positions (the error where the objects are), and the translation part of true⁻¹·est.
  double rotation_error_deg = 0.0;
  double error_at_objects_m = 0.0;
  double translation_error_m = 0.0;
  ChangeScore moved, added, removed;
  ChangeScore all() const;  // the three summed
  int not_seen = 0;         // objects the diff left unknown (not_seen_again / _before)
};

// Throws InputError naming the file and field for a malformed diff.json or changes_gt.json.
DiffEvalResult evaluate_diff(const std::filesystem::path& diff_json,
                             const std::filesystem::path& changes_gt_json,
                             const DiffEvalOptions& options);

// The result as JSON (schemas/eval_diff.schema.json).
std::string diff_eval_json(const DiffEvalResult& result, const DiffEvalOptions& options);

}  // namespace objmap::eval
