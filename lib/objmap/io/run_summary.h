#pragma once
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

// What one recording's run folder says, for `objmap summary`: the folder of an `objmap run` or of
// the Snakemake workflow (scripts/workflow/Snakefile), which share their layout: detect/, track/,
// map/ (objects.json, run.json), corrected/, eval/ (ate.json, rpe.json, objects.json and the
// _corrected trajectory errors), report/report.html, logs/<stage>.log and, from the workflow,
// benchmarks/<stage>.tsv (Snakemake's benchmark) and benchmarks/<stage>.time (GNU time: wall
// seconds and peak KB).
namespace objmap::io {

// The stages of a run folder in the order of the pipeline: each stage's log is logs/<name>.log and
// the file it writes last is `done` (relative to the run folder).
struct RunStage {
  const char* name;
  const char* done;
};
const std::vector<RunStage>& run_stages();

// Time and memory of one stage of one recording.
struct StageCost {
  std::string stage;
  double seconds = 0;                // benchmarks/<stage>.tsv "s", else .time, else stages.json
  std::optional<double> max_rss_mb;  // GNU time's peak (exact), else the benchmark's sample
};

struct RunSummary {
  std::string name;          // the folder's name
  std::string path;          // as given
  std::string status;        // "ok" (report written), "failed" (a stage failed), "incomplete"
  std::string failed_stage;  // failed: the first stage whose log exists and output does not
  std::string error;         // failed: the last non-empty line of that stage's log
  std::string map;           // the map read: "map" or "corrected"
  std::optional<long long> keyframes, objects, duplicates;  // run.json counts, objects.json
  std::map<std::string, long long> objects_per_class;       // objects.json, by class
  std::optional<double> ate_rmse_m, rpe_translational_rmse_m, rpe_rotational_rmse_deg;
  std::optional<double> ate_corrected_rmse_m, rpe_corrected_translational_rmse_m;
  std::optional<long long> gt_objects, matched_objects;  // eval/objects.json, overall
  std::optional<double> centroid_error_mean_m, centroid_error_rmse_m, count_error;
  std::vector<StageCost> stages;  // in run_stages() order, those that ran
};

// The last line of a log that says something (trailing spaces and CRs dropped); "" when none.
std::string last_line(const std::filesystem::path& log);

// Reads the run folder `run`. Throws InputError(run, ...) when it is not a run folder (neither
// logs/ nor map/), InputError(file, ...) for a file that is not what it should be.
RunSummary read_run_summary(const std::filesystem::path& run);

}  // namespace objmap::io
