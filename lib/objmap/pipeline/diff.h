#pragma once
#include <filesystem>
#include <string>

#include "objmap/change/classify.h"
#include "objmap/change/register.h"
#include "objmap/change/visit.h"

// objmap diff: what changed between two visits of a place (docs/change.md). Two run folders of
// `objmap fuse` in, DIFF/diff.json out (schemas/diff.schema.json).
namespace objmap::pipeline {

struct DiffOptions {
  std::filesystem::path before;  // run folder of the first visit (objects.json, map_dense.ply,
                                 // run.json, objects/*.ply)
  std::filesystem::path after;   // run folder of the second visit
  std::filesystem::path out;     // DIFF folder: diff.json
  std::filesystem::path align;   // empty: registered; else a JSON file with before_from_after
                                 // (a diff.json, a changes_gt.json, or {"before_from_after": [16]})
  change::RegistrationOptions registration;
  change::ClassifyOptions classify;
  void check() const;  // throws InputError naming the bad field
};

struct DiffResult {
  change::Registration registration;
  change::ChangeResult changes;
  std::size_t before_objects = 0, after_objects = 0;
  std::size_t before_dense_points = 0, after_dense_points = 0;
  std::size_t before_views = 0, after_views = 0;
  double seconds_read = 0.0, seconds_register = 0.0, seconds_classify = 0.0;
};

// A run folder as the change detection needs it. Throws InputError naming the file and field.
change::Visit read_visit(const std::filesystem::path& run);

// before_from_after of an --align file. Throws InputError naming the file and field.
Pose read_align_file(const std::filesystem::path& file);

// diff.json text (deterministic: no times in it).
std::string diff_json(const DiffOptions& options, const DiffResult& result);

// The whole command: read both runs, register (or take --align), refuse a pair without a credible
// registration (InputError naming both runs and why), classify, write DIFF/diff.json atomically.
DiffResult run_diff(const DiffOptions& options);

}  // namespace objmap::pipeline
