#include "objmap/pipeline/run.h"

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>
#include <system_error>
#include <vector>

#include "objmap/core/checksum.h"
#include "objmap/core/clock.h"
#include "objmap/core/error.h"
#include "objmap/core/version.h"
#include "objmap/io/atomic.h"
#include "objmap/io/json_file.h"
#include "objmap/io/run_summary.h"

extern char** environ;

namespace objmap::pipeline {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

// What a file or folder is, cheaply: every file's relative name, size and modification time.
std::string fingerprint(const std::string& path) {
  if (path.empty()) return "-";
  std::error_code ec;
  std::string out;
  auto add = [&](const fs::path& file, const std::string& name) {
    const auto size = fs::file_size(file, ec);
    const auto time = fs::last_write_time(file, ec).time_since_epoch().count();
    out += name + " " + std::to_string(size) + " " + std::to_string(time) + "\n";
  };
  if (fs::is_regular_file(path, ec)) {
    add(path, fs::path(path).filename().string());
    return out;
  }
  std::vector<fs::path> files;
  for (auto it = fs::recursive_directory_iterator(path, ec); !ec && it != fs::end(it);
       it.increment(ec))
    if (it->is_regular_file(ec)) files.push_back(it->path());
  std::sort(files.begin(), files.end());
  for (const fs::path& f : files) add(f, fs::relative(f, path, ec).generic_string());
  return out;
}

std::vector<RunStage> plan(const RunOptions& c) {
  const fs::path run(c.out);
  std::vector<std::string> recording = {"--dataset", c.dataset, "--layout", c.layout};
  if (!c.topics.empty()) recording.insert(recording.end(), {"--topics", c.topics});
  auto with = [](std::vector<std::string> a, const std::vector<std::string>& b) {
    a.insert(a.end(), b.begin(), b.end());
    return a;
  };
  auto optional = [](const std::string& flag, const std::string& value) {
    return value.empty() ? std::vector<std::string>{} : std::vector<std::string>{flag, value};
  };
  RunStage detect{"detect",
                  with(with({"detect"}, recording),
                       with({"--model", c.model, "--out", (run / "detect").string(), "--classes",
                             c.classes.empty() ? "all" : c.classes},
                            {})),
                  run / "detect", ""};
  RunStage track{"track",
                 with(with({"track"}, recording), with({"--segmentation", detect.out.string(),
                                                        "--out", (run / "track").string()},
                                                       optional("--camera", c.camera))),
                 run / "track", "tracks.json"};
  RunStage fuse{
      "fuse",
      with(with({"fuse"}, recording),
           with(with({"--segmentation", track.out.string(), "--out", (run / "map").string()},
                     optional("--trajectory", c.trajectory)),
                with(optional("--camera", c.camera), optional("--config", c.fuse_config)))),
      run / "map", "objects.json"};
  RunStage report{"report",
                  {"report", "--run", fuse.out.string(), "--out", (run / "report").string()},
                  run / "report",
                  "report.html"};
  return {detect, track, fuse, report};
}

// The key of a stage: objmap's version, its arguments, what its input files are (`recording`:
// the fingerprint of the recording, trajectory and camera, taken once per run) and the key of the
// stage before it.
std::string stage_key(const RunStage& stage, const RunOptions& c, const std::string& recording,
                      const std::string& previous) {
  std::string text = std::string(objmap::version()) + "\n" + previous + "\n";
  for (const std::string& a : stage.args) text += a + "\n";
  if (stage.name != "report") {
    text += recording;
    if (stage.name == "detect") text += fingerprint(c.model);
    if (stage.name == "fuse") text += fingerprint(c.fuse_config);
  }
  return hex64(fnv1a(text));
}

// Runs this objmap binary with `args`, its output into `log`; returns the exit code.
int spawn_objmap(const std::string& objmap, const std::vector<std::string>& args,
                 const fs::path& log) {
  std::vector<std::string> argv_text = {"objmap"};
  argv_text.insert(argv_text.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (std::string& a : argv_text) argv.push_back(a.data());
  argv.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 0, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_addopen(&actions, 1, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&actions, 1, 2);
  pid_t pid = 0;
  const int failed = posix_spawn(&pid, objmap.c_str(), &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (failed != 0)
    throw std::runtime_error("cannot start objmap: " + std::string(strerror(failed)));
  int status = 0;
  while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  return WIFEXITED(status) ? WEXITSTATUS(status) : 1;
}

// Counts of the map's objects per class, "3 chair, 1 cup".
std::string object_summary(const fs::path& objects_json) {
  const json doc = io::read_json_file(objects_json, "cannot open");
  std::map<std::string, int> per_class;
  for (const json& o : doc.at("objects")) ++per_class[o.at("class").get<std::string>()];
  std::string text = std::to_string(doc.at("objects").size()) + " objects";
  std::string sep = ": ";
  for (const auto& [cls, n] : per_class) {
    text += sep + std::to_string(n) + " " + cls;
    sep = ", ";
  }
  return text;
}

}  // namespace

RunResult run_stages(const RunOptions& c, const RunEvent& event) {
  io::require_not_an_input({"--out", c.out}, {{"--dataset", c.dataset},
                                              {"--model", c.model},
                                              {"--trajectory", c.trajectory},
                                              {"--camera", c.camera},
                                              {"--config", c.fuse_config}});
  io::require_replaceable(c.out, io::kPipelineFolder);
  for (const auto& [flag, path] : {std::pair{"--dataset", c.dataset}, {"--model", c.model}})
    require(fs::exists(path), flag, "'" + path + "' does not exist");
  const fs::path run(c.out);
  fs::create_directories(run / "logs");
  const fs::path stages_file = run / "stages.json";
  json record = fs::exists(stages_file) ? io::read_json_file(stages_file, "cannot open") : json();
  if (!record.is_object()) record = json::object();
  const std::string recording =
      fingerprint(c.dataset) + fingerprint(c.trajectory) + fingerprint(c.camera);
  std::string previous;
  bool rerun = c.force;
  for (const RunStage& stage : plan(c)) {
    const std::string key = stage_key(stage, c, recording, previous);
    previous = key;
    const bool complete =
        fs::exists(stage.done_file.empty() ? stage.out : stage.out / stage.done_file);
    if (!rerun && complete && record.contains(stage.name) &&
        record[stage.name].value("key", "") == key) {
      if (event) event(stage, "reused", 0.0);
      continue;
    }
    rerun = true;  // every later stage reads this one's output
    if (event) event(stage, "running", 0.0);
    const fs::path log = run / "logs" / (stage.name + ".log");
    const auto t0 = Clock::now();
    const int code = spawn_objmap(c.objmap, stage.args, log);
    const double seconds = seconds_since(t0);
    if (code != 0) {
      if (event) event(stage, "failed", seconds);
      record.erase(stage.name);
      io::write_file_atomic(stages_file, record.dump(2) + "\n");
      const std::string why =
          io::last_line(log) + " (exit " + std::to_string(code) + "; " + log.string() + ")";
      if (code == 2) throw InputError("objmap run: stage " + stage.name, why);
      throw std::runtime_error("objmap run: stage " + stage.name + ": " + why);
    }
    if (event) event(stage, "done", seconds);
    record[stage.name] = {{"key", key}, {"args", stage.args}, {"seconds", seconds}};
    io::write_file_atomic(stages_file, record.dump(2) + "\n");
  }
  return {run / "map", run / "report" / "report.html",
          object_summary(run / "map" / "objects.json")};
}

}  // namespace objmap::pipeline
