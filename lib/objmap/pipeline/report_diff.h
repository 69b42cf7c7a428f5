#pragma once
#include <cstddef>
#include <filesystem>

#include "objmap/report/diff_page.h"

// `objmap report --diff DIFF`: the report page of a diff (docs/change.md, "The report"): the
// registration, a row per change with the object as each visit saw it, and the 3D view with both
// maps (the after run's registered into the before run's frame, each in a tint of its own) and an
// arrow per moved object. The runs are read from diff.json's before and after paths (as objmap
// diff was given them); a run that cannot be read leaves its pictures out and says why. Written
// atomically to OUT (default DIFF/report): report.html, report.md, thumbnails/.
namespace objmap::pipeline {

struct DiffReportOptions {
  std::filesystem::path diff;  // DIFF folder of objmap diff, or its diff.json
  std::filesystem::path out;   // default DIFF/report
  int thumbnail_px = 160;      // thumbnail side
  // Each map in the 3D view is thinned to at most this many points (half of --view-points each).
  std::size_t view_points = 200000;
  // Throws the usage error naming the flag; the output must be replaceable and not an input.
  void check() const;
  std::filesystem::path diff_file() const;   // DIFF/diff.json
  std::filesystem::path out_folder() const;  // out, or DIFF/report
};

struct DiffReportResult {
  report::DiffPageContent page;
  std::filesystem::path out;
};

// Reads diff.json and both runs, makes the page, writes the report folder. Throws InputError for
// a bad diff.json (naming the file and field) or a refused output.
DiffReportResult run_diff_report(const DiffReportOptions& options);

}  // namespace objmap::pipeline
