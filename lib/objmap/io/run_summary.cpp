#include "objmap/io/run_summary.h"

#include <algorithm>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <system_error>

#include "objmap/core/error.h"
#include "objmap/io/json_file.h"

namespace objmap::io {

namespace fs = std::filesystem;
using nlohmann::json;

const std::vector<RunStage>& run_stages() {
  static const std::vector<RunStage> stages = {
      {"detect", "detect"},
      {"track", "track/tracks.json"},
      {"fuse", "map/objects.json"},
      {"correct", "corrected/objects.json"},
      {"eval_ate", "eval/ate.json"},
      {"eval_rpe", "eval/rpe.json"},
      {"eval_ate_corrected", "eval/ate_corrected.json"},
      {"eval_rpe_corrected", "eval/rpe_corrected.json"},
      {"eval_objects", "eval/objects.json"},
      {"report", "report/report.html"},
  };
  return stages;
}

namespace {

bool present(const fs::path& p) {
  std::error_code ec;
  return fs::exists(p, ec);
}

// A value of a JSON file by its JSON pointer ("/translational/rmse"), or nothing when the file or
// the value is absent; a value of the wrong type is an InputError naming the file and field.
template <typename T>
std::optional<T> value_at(const json& doc, const fs::path& file, const std::string& pointer) {
  const json::json_pointer ptr(pointer);
  if (!doc.contains(ptr) || doc.at(ptr).is_null()) return std::nullopt;
  const json& v = doc.at(ptr);
  if (!v.is_number()) throw InputError(file.string() + ": " + pointer, "not a number");
  return v.get<T>();
}

json read_if_exists(const fs::path& file) {
  return present(file) ? read_json_file(file, "cannot open") : json();
}

// The element of `array` (a JSON pointer to an array of rows) whose "class" is "overall".
json overall_row(const json& doc, const fs::path& file, const std::string& array) {
  const json::json_pointer ptr(array);
  if (!doc.contains(ptr)) return json();
  if (!doc.at(ptr).is_array()) throw InputError(file.string() + ": " + array, "not an array");
  for (const json& row : doc.at(ptr))
    if (row.is_object() && row.value("class", "") == "overall") return row;
  return json();
}

// benchmarks/<stage>.tsv: a header line and one line of values ("s", "max_rss" in MB, "NA" when
// Snakemake took no sample).
void read_benchmark_tsv(const fs::path& file, StageCost* cost) {
  std::ifstream in(file);
  std::string header, values;
  std::getline(in, header);
  std::getline(in, values);
  std::istringstream h(header), v(values);
  std::string name, value;
  while (std::getline(h, name, '\t') && std::getline(v, value, '\t')) {
    char* end = nullptr;
    const double x = std::strtod(value.c_str(), &end);
    const bool number = end != value.c_str() && *end == '\0';
    if (name == "s") {
      if (!number) throw InputError(file.string(), "column s: '" + value + "' is not a number");
      cost->seconds = x;
    }
    if (name == "max_rss" && number && !cost->max_rss_mb) cost->max_rss_mb = x;
  }
}

// benchmarks/<stage>.time (GNU time -f '%e %M'): the last line is "seconds peak_kb"; a line
// before it says when the command failed.
bool read_time_file(const fs::path& file, StageCost* cost) {
  std::istringstream line(last_line(file));
  double seconds = 0, kb = 0;
  if (!(line >> seconds >> kb)) return false;
  cost->seconds = seconds;
  cost->max_rss_mb = kb / 1024.0;
  return true;
}

std::vector<StageCost> read_costs(const fs::path& run) {
  const json stages_json = read_if_exists(run / "stages.json");  // objmap run
  std::vector<StageCost> costs;
  for (const RunStage& stage : run_stages()) {
    StageCost cost;
    cost.stage = stage.name;
    const fs::path bench = run / "benchmarks" / stage.name;
    bool found = read_time_file(fs::path(bench).concat(".time"), &cost);
    if (present(fs::path(bench).concat(".tsv"))) {
      read_benchmark_tsv(fs::path(bench).concat(".tsv"), &cost);
      found = true;
    }
    if (!found && stages_json.is_object() && stages_json.contains(stage.name)) {
      cost.seconds = stages_json[stage.name].value("seconds", 0.0);
      found = true;
    }
    if (found) costs.push_back(cost);
  }
  return costs;
}

void read_map(const fs::path& run, RunSummary* s) {
  s->map = present(run / "corrected" / "objects.json") ? "corrected" : "map";
  const fs::path objects_file = run / s->map / "objects.json";
  const json objects = read_if_exists(objects_file);
  if (objects.is_object()) {
    if (!objects.contains("objects") || !objects["objects"].is_array())
      throw InputError(objects_file.string() + ": objects", "missing or not an array");
    s->objects = static_cast<long long>(objects["objects"].size());
    for (const json& o : objects["objects"]) {
      if (!o.is_object() || !o.contains("class") || !o["class"].is_string())
        throw InputError(objects_file.string() + ": objects[].class", "missing or not a string");
      ++s->objects_per_class[o["class"].get<std::string>()];
    }
  }
  const fs::path run_file = run / s->map / "run.json";
  const json run_json = read_if_exists(run_file);
  s->keyframes = value_at<long long>(run_json, run_file, "/counts/keyframes");
  s->duplicates = value_at<long long>(run_json, run_file, "/duplicates/count");
}

void read_evaluations(const fs::path& run, RunSummary* s) {
  const fs::path eval = run / "eval";
  const fs::path ate = eval / "ate.json", rpe = eval / "rpe.json";
  const fs::path ate_c = eval / "ate_corrected.json", rpe_c = eval / "rpe_corrected.json";
  s->ate_rmse_m = value_at<double>(read_if_exists(ate), ate, "/rmse");
  const json rpe_json = read_if_exists(rpe);
  s->rpe_translational_rmse_m = value_at<double>(rpe_json, rpe, "/translational/rmse");
  s->rpe_rotational_rmse_deg = value_at<double>(rpe_json, rpe, "/rotational/rmse");
  s->ate_corrected_rmse_m = value_at<double>(read_if_exists(ate_c), ate_c, "/rmse");
  s->rpe_corrected_translational_rmse_m =
      value_at<double>(read_if_exists(rpe_c), rpe_c, "/translational/rmse");
  const fs::path objects = eval / "objects.json";
  const json doc = read_if_exists(objects);
  if (!doc.is_object()) return;
  const json counts = overall_row(doc, objects, "/counts");
  const json errors = overall_row(doc, objects, "/centroid_error");
  s->gt_objects = value_at<long long>(counts, objects, "/reference");
  s->count_error = value_at<double>(counts, objects, "/error");
  s->matched_objects = value_at<long long>(errors, objects, "/matched");
  s->centroid_error_mean_m = value_at<double>(errors, objects, "/distance_m/mean");
  s->centroid_error_rmse_m = value_at<double>(errors, objects, "/distance_m/rmse");
}

}  // namespace

std::string last_line(const fs::path& log) {
  std::ifstream in(log);
  std::string line, last;
  while (std::getline(in, line))
    if (line.find_first_not_of(" \t\r") != std::string::npos) last = line;
  while (!last.empty() && (last.back() == '\r' || last.back() == ' ')) last.pop_back();
  return last;
}

RunSummary read_run_summary(const fs::path& run) {
  std::error_code ec;
  if (!fs::is_directory(run, ec))
    throw InputError(run.string(),
                     "no such folder; expected a run folder (objmap run or workflow)");
  if (!fs::is_directory(run / "logs", ec) && !fs::is_directory(run / "map", ec))
    throw InputError(run.string(),
                     "not a run folder: it holds neither logs/ nor map/ (an objmap run or "
                     "workflow output for one recording)");
  RunSummary s;
  s.path = run.string();
  s.name = fs::absolute(run).lexically_normal().filename().string();
  if (s.name.empty()) s.name = fs::absolute(run).lexically_normal().parent_path().filename();
  // The first stage that left a log and not its output failed: Snakemake and objmap run remove
  // a failed stage's output, objmap's stages never leave half of one.
  for (const RunStage& stage : run_stages()) {
    const fs::path log = run / "logs" / (std::string(stage.name) + ".log");
    if (present(log) && !present(run / stage.done)) {
      s.status = "failed";
      s.failed_stage = stage.name;
      s.error = last_line(log);
      break;
    }
  }
  if (s.status.empty()) s.status = present(run / "report" / "report.html") ? "ok" : "incomplete";
  read_map(run, &s);
  read_evaluations(run, &s);
  s.stages = read_costs(run);
  return s;
}

}  // namespace objmap::io
