#pragma once
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

// `objmap run`: from a recording to a map and a report in one command. Each stage is the objmap
// command of its name (detect -> track -> fuse, with the scene -> report), run as its own process
// with its output in its own folder under OUT (logs/ has each stage's output); a stage whose inputs
// and options are those of its last run is reused (OUT/stages.json records them).
namespace objmap::pipeline {

struct RunOptions {
  std::string dataset;
  std::string layout = "auto";
  std::string topics;
  std::string model;
  std::string out;
  std::string trajectory;  // empty: the recording's own poses
  std::string camera;
  std::string classes;      // detect --classes; empty: every class the model knows
  std::string fuse_config;  // fuse --config
  bool force = false;       // run every stage again
  // The objmap binary each stage runs (default: this process's own, as `objmap run` is).
  std::string objmap = "/proc/self/exe";
};

// One stage: its name, the objmap arguments, the folder it writes and the file that says it is
// complete.
struct RunStage {
  std::string name;
  std::vector<std::string> args;
  std::filesystem::path out;
  std::string done_file;
};

// What happens to each stage, for the app to print: "reused", "running", then "done" (with its
// seconds) or "failed".
using RunEvent =
    std::function<void(const RunStage& stage, const std::string& what, double seconds)>;

struct RunResult {
  std::filesystem::path map;     // OUT/map (the fuse run)
  std::filesystem::path report;  // OUT/report/report.html
  std::string objects;           // the map's objects per class, "3 objects: 2 chair, 1 cup"
};

// Runs the stages that must run. Throws InputError for bad input (also a stage that exits with 2,
// naming its log), std::runtime_error for a stage's internal error.
RunResult run_stages(const RunOptions& options, const RunEvent& event);

}  // namespace objmap::pipeline
