// objmap diff on two maps of fr1_rpy_every4's size (issue target: ≤ 2 s on these machines). Fuses
// $OBJMAP_DATA (default <repo>/../shared/data)/tum/fr1_rpy_every4 and tum/fr1_desk_9 once
// (groundtruth.txt, detections_yolofastest), then times `run_diff` of fr1_rpy_every4 against
// itself (two maps of that size) and of the two recordings in both orders:
//   build-*/bin/bench_diff [--repeat 3] [--data DIR] [--work DIR]
// Prints per pair: wall seconds of the whole diff (read, register, classify, write) and of each
// step, CPU seconds, peak RSS, the registration's fitness. Each diff runs in a child process of
// its own (its peak RSS is its own); each figure is the median of `repeat` runs, pairs interleaved.
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include "bench_data.h"
#include "child_run.h"
#include "objmap/pipeline/diff.h"
#include "objmap/pipeline/fuse.h"

namespace fs = std::filesystem;
using namespace objmap;

namespace {

struct DiffRun {
  double seconds[4] = {0, 0, 0, 0};  // whole, read, register, classify
  double cpu_seconds = 0.0;
  double peak_rss_mb = 0.0;
  double fitness = 0.0;
};

bool fuse(const fs::path& dataset, const fs::path& out) {
  pipeline::FuseOptions options;
  options.dataset = dataset;
  options.trajectory = dataset / "groundtruth.txt";
  options.segmentation = dataset / "detections_yolofastest";
  options.out = out;
  double unused = 0.0;
  rusage usage{};
  return bench::in_child([&](double*) { pipeline::run_fuse(options); }, &unused, 1, usage);
}

bool diff(const fs::path& before, const fs::path& after, const fs::path& out, DiffRun& run) {
  pipeline::DiffOptions options;
  options.before = before;
  options.after = after;
  options.out = out;
  double values[5] = {0, 0, 0, 0, 0};
  rusage usage{};
  const auto t0 = std::chrono::steady_clock::now();
  const bool ok = bench::in_child(
      [&](double* v) {
        const pipeline::DiffResult r = pipeline::run_diff(options);
        v[0] = r.seconds_read;
        v[1] = r.seconds_register;
        v[2] = r.seconds_classify;
        v[3] = r.registration.fitness;
      },
      values, 5, usage);
  run.seconds[0] = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  for (int k = 0; k < 3; ++k) run.seconds[k + 1] = values[k];
  run.fitness = values[3];
  run.cpu_seconds = usage.ru_utime.tv_sec + usage.ru_utime.tv_usec * 1e-6 + usage.ru_stime.tv_sec +
                    usage.ru_stime.tv_usec * 1e-6;
  run.peak_rss_mb = usage.ru_maxrss / 1024.0;
  return ok;
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0.0 : v[v.size() / 2];
}

}  // namespace

int main(int argc, char** argv) {
  int repeat = 3;
  fs::path data = bench::data_dir(), work;
  for (int i = 1; i + 1 < argc; i += 2) {
    if (!std::strcmp(argv[i], "--repeat"))
      repeat = std::max(1, std::atoi(argv[i + 1]));
    else if (!std::strcmp(argv[i], "--data"))
      data = argv[i + 1];
    else if (!std::strcmp(argv[i], "--work"))
      work = argv[i + 1];
  }
  const fs::path rpy = data / "tum" / "fr1_rpy_every4", desk = data / "tum" / "fr1_desk_9";
  if (!fs::exists(rpy) || !fs::exists(desk)) {
    std::fprintf(stderr, "bench_diff: real data absent under %s\n", data.c_str());
    return 2;
  }
  if (work.empty())
    work = fs::temp_directory_path() / ("objmap_bench_diff_" + std::to_string(getpid()));
  fs::create_directories(work);
  std::printf("fusing fr1_rpy_every4 and fr1_desk_9 into %s ...\n", work.c_str());
  if (!fuse(rpy, work / "rpy") || !fuse(desk, work / "desk")) return 1;
  struct Pair {
    const char* name;
    fs::path before, after;
    std::vector<DiffRun> runs;
  };
  std::vector<Pair> pairs = {{"fr1_rpy_every4 -> itself", work / "rpy", work / "rpy", {}},
                             {"fr1_rpy_every4 -> fr1_desk_9", work / "rpy", work / "desk", {}},
                             {"fr1_desk_9 -> fr1_rpy_every4", work / "desk", work / "rpy", {}}};
  for (int round = 0; round < repeat; ++round)
    for (Pair& p : pairs) {
      DiffRun run;
      if (!diff(p.before, p.after, work / "diff", run)) return 1;
      p.runs.push_back(run);
    }
  std::printf(
      "| pair | wall s | read s | register s | classify s | CPU s | peak RSS | fitness |\n");
  std::printf("|---|---|---|---|---|---|---|---|\n");
  for (const Pair& p : pairs) {
    const auto med = [&](auto field) {
      std::vector<double> v;
      for (const DiffRun& r : p.runs) v.push_back(field(r));
      return median(v);
    };
    std::printf("| %s | %.2f | %.2f | %.2f | %.2f | %.2f | %.0f MB | %.3f |\n", p.name,
                med([](const DiffRun& r) { return r.seconds[0]; }),
                med([](const DiffRun& r) { return r.seconds[1]; }),
                med([](const DiffRun& r) { return r.seconds[2]; }),
                med([](const DiffRun& r) { return r.seconds[3]; }),
                med([](const DiffRun& r) { return r.cpu_seconds; }),
                med([](const DiffRun& r) { return r.peak_rss_mb; }),
                med([](const DiffRun& r) { return r.fitness; }));
  }
  std::printf("(median of %d runs each, pairs interleaved; target: <= 2 s)\n", repeat);
  fs::remove_all(work);
  return 0;
}
