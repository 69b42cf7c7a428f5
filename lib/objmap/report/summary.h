#pragma once
#include <string>
#include <vector>

#include "objmap/io/run_summary.h"

// One table for a dataset (`objmap summary RUN...`): every recording's objects, duplicates,
// trajectory and object errors (where there is ground truth), time and memory per stage, and the
// recordings that failed with their stage and error line; as Markdown, CSV and JSON
// (schemas/summary.schema.json), and two SVG bar charts.
namespace objmap::report {

std::string summary_markdown(const std::vector<io::RunSummary>& runs);

// One row per recording; numbers in full precision (the shortest text that reads back the same
// double), an absent value empty. Columns: the fixed ones, then seconds_<stage> and
// max_rss_mb_<stage> for each stage any recording ran, then objects_<class> for each class.
std::string summary_csv(const std::vector<io::RunSummary>& runs);

std::string summary_json(const std::vector<io::RunSummary>& runs);

// Objects and suspected duplicate pairs per recording (a failed one marked in its label).
std::string objects_per_recording_svg(const std::vector<io::RunSummary>& runs);

// ATE RMSE and mean object centroid error per recording, in metres ("no ground truth" when no
// recording has either).
std::string errors_per_recording_svg(const std::vector<io::RunSummary>& runs);

}  // namespace objmap::report
