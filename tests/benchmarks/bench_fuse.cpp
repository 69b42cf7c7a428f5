// The whole `objmap fuse` against the mere decoding of its PNGs, measured in one run (issue
// targets: fuse ≤ 1.5× decode per keyframe, peak RSS ≤ 500 MB, ≥ 20× faster than Open3D's
// 214 ms/frame). On $OBJMAP_DATA (default <repo>/../shared/data)/tum/fr1_rpy_every4 with
// groundtruth.txt and detections_yolofastest:
//   build-*/bin/bench_fuse [--threads 2] [--repeat 3] [--dataset DIR]
// Prints: ms per keyframe of the whole fuse (inputs to written run folder), ms per rgb+depth pair
// to decode the same keyframes' PNGs on 1 and on `threads` threads, the ratios, what the scene
// step (up, surfaces, relations) adds to the fuse (target ≤ 10%), peak RSS. Each
// figure is the best of `repeat` rounds. The fuse runs first, so the peak RSS is the fuse's.
#include <fcntl.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <thread>
#include <vector>

#include <opencv2/imgcodecs.hpp>

#include "bench_data.h"
#include "child_run.h"
#include "objmap/core/memory.h"
#include "objmap/core/version.h"
#include "objmap/io/image.h"
#include "objmap/io/tum_dataset.h"
#include "objmap/pipeline/fuse.h"

namespace fs = std::filesystem;
using namespace objmap;
using Clock = std::chrono::steady_clock;

namespace {

constexpr double kOpen3dMsPerFrame = 214.0;  // Open3D 0.16 on this machine (issue text)

using objmap::bench::data_dir;

// One whole fuse in a child process (its peak RSS its own). False when the child failed.
struct FuseRun {
  double seconds = 0.0;
  double scene[3] = {0.0, 0.0, 0.0};  // the scene step: up, surfaces, relations (wall seconds)
  double cpu_seconds = 0.0;           // user + system, all threads
  double peak_rss_mb = 0.0;
};
bool fuse_in_child(const pipeline::FuseOptions& options, FuseRun& run) {
  double s[4] = {0.0, 0.0, 0.0, 0.0};
  rusage usage{};
  const auto job = [&](double* out) {
    const pipeline::FuseResult r = pipeline::run_fuse(options);
    const double values[4] = {r.seconds_total, r.scene.seconds_up, r.scene.seconds_surfaces,
                              r.scene.seconds_relations};
    std::copy(values, values + 4, out);
  };
  if (!objmap::bench::in_child(job, s, 4, usage)) return false;
  run.seconds = s[0];
  for (int k = 0; k < 3; ++k) run.scene[k] = s[k + 1];
  run.peak_rss_mb = usage.ru_maxrss / 1024.0;
  run.cpu_seconds = usage.ru_utime.tv_sec + usage.ru_stime.tv_sec +
                    1e-6 * (usage.ru_utime.tv_usec + usage.ru_stime.tv_usec);
  return true;
}

double process_cpu_seconds() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return usage.ru_utime.tv_sec + usage.ru_stime.tv_sec +
         1e-6 * (usage.ru_utime.tv_usec + usage.ru_stime.tv_usec);
}

// Seconds to decode the rgb and depth PNGs of `frames` with `threads` threads (frame i on thread
// i mod threads), as the fuse workers do; `cpu_s`: the CPU time it took (user + system).
// With `opencv`, the files are read by cv::imread (libpng, zlib) instead of objmap's reader (the
// one fuse uses: libdeflate for these PNGs, the same pixels): the plain way of decoding them.
double decode_seconds(const std::vector<io::FramePair>& frames, int width, int height, int threads,
                      double* cpu_s = nullptr, bool opencv = false) {
  const double cpu0 = process_cpu_seconds();
  const auto t0 = Clock::now();
  auto work = [&](int t) {
    std::size_t bytes = 0;
    for (std::size_t i = static_cast<std::size_t>(t); i < frames.size(); i += threads) {
      if (opencv) {
        const cv::Mat bgr = cv::imread(frames[i].rgb_file.string(), cv::IMREAD_UNCHANGED);
        const cv::Mat depth = cv::imread(frames[i].depth_file.string(), cv::IMREAD_UNCHANGED);
        bytes += bgr.total() + depth.total();
        continue;
      }
      const cv::Mat bgr = io::read_rgb(frames[i].rgb_file, width, height);
      const cv::Mat depth = io::read_depth(frames[i].depth_file, width, height);
      bytes += bgr.total() + depth.total();
    }
    return bytes;
  };
  std::vector<std::thread> pool;
  for (int t = 1; t < threads; ++t) pool.emplace_back([&, t] { work(t); });
  work(0);
  for (auto& th : pool) th.join();
  const double seconds = std::chrono::duration<double>(Clock::now() - t0).count();
  if (cpu_s) *cpu_s = process_cpu_seconds() - cpu0;
  return seconds;
}

// Seconds from the start of `objmap --version` (the objmap beside this program) to its exit: what
// every command pays before its work (loading its shared libraries), the median of `rounds`. 0 when
// it cannot run.
double startup_seconds(int rounds) {
  std::error_code error;
  const fs::path objmap = fs::read_symlink("/proc/self/exe", error).parent_path() / "objmap";
  if (error || !fs::exists(objmap)) return 0.0;
  std::vector<double> times;
  for (int r = 0; r < rounds; ++r) {
    std::fflush(stdout);  // nothing buffered is written twice
    const auto t0 = Clock::now();
    const pid_t pid = fork();
    if (pid == 0) {
      const int null = open("/dev/null", O_WRONLY);
      if (null < 0 || dup2(null, STDOUT_FILENO) < 0) _exit(127);
      execl(objmap.c_str(), "objmap", "--version", static_cast<char*>(nullptr));
      _exit(127);
    }
    int status = 0;
    if (pid < 0 || waitpid(pid, &status, 0) != pid || !WIFEXITED(status) ||
        WEXITSTATUS(status) != 0)
      return 0.0;
    times.push_back(std::chrono::duration<double>(Clock::now() - t0).count());
  }
  std::nth_element(times.begin(), times.begin() + times.size() / 2, times.end());
  return times[times.size() / 2];
}

}  // namespace

int main(int argc, char** argv) {
  objmap::keep_freed_memory();  // as the objmap command keeps it (the fuses run in children)
  int threads = 2, repeat = 3;
  fs::path dataset = data_dir() / "tum" / "fr1_rpy_every4";
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string a = argv[i];
    if (a == "--threads") {
      threads = std::max(1, std::atoi(argv[i + 1]));
    } else if (a == "--repeat") {
      repeat = std::max(1, std::atoi(argv[i + 1]));
    } else if (a == "--dataset") {
      dataset = argv[i + 1];
    } else {
      std::fprintf(stderr, "usage: bench_fuse [--threads N] [--repeat N] [--dataset DIR]\n");
      return 2;
    }
  }
  if (!fs::exists(dataset / "groundtruth.txt") || !fs::exists(dataset / "detections_yolofastest")) {
    std::printf("bench_fuse: skipped, no %s (set OBJMAP_DATA)\n", dataset.string().c_str());
    return 0;
  }
  const fs::path out = fs::temp_directory_path() / ("bench_fuse_" + std::to_string(getpid()));

  try {
    // 1. The whole fuse, as `objmap fuse --dataset D --trajectory D/groundtruth.txt
    //    --segmentation D/detections_yolofastest --out OUT --threads N`.
    pipeline::FuseOptions options;
    options.dataset = dataset;
    options.trajectory = dataset / "groundtruth.txt";
    options.segmentation = dataset / "detections_yolofastest";
    options.out = out;
    options.threads = threads;
    // The same without the scene step (up given as +z: no plane search; no surfaces), rounds
    // interleaved so that both see the same load.
    pipeline::FuseOptions no_scene = options;
    no_scene.scene.up.mode = "z";
    no_scene.scene.surfaces.enabled = false;
    double fuse_s = 1e30, cpu_s = 1e30, rss_mb = 0.0, bare_s = 1e30, bare_cpu_s = 1e30;
    FuseRun fastest;  // the round of the best wall time: its scene step's figures
    for (int r = 0; r < repeat; ++r) {
      FuseRun run, bare;
      if (!fuse_in_child(options, run) || !fuse_in_child(no_scene, bare)) {
        std::fprintf(stderr, "bench_fuse: the fuse failed\n");
        return 1;
      }
      if (run.seconds < fuse_s) fastest = run;
      fuse_s = std::min(fuse_s, run.seconds);
      cpu_s = std::min(cpu_s, run.cpu_seconds);
      rss_mb = std::max(rss_mb, run.peak_rss_mb);
      bare_s = std::min(bare_s, bare.seconds);
      bare_cpu_s = std::min(bare_cpu_s, bare.cpu_seconds);
    }
    // The keyframes of the runs (once more, in this process, for the list of PNGs).
    const pipeline::FuseResult result = pipeline::run_fuse(options);
    fs::remove_all(out);
    const std::size_t n = result.keyframes.keyframes.size();

    // 2. Decoding the same keyframes' PNGs, nothing else.
    io::TumOptions tum;
    tum.max_diff_s = options.max_diff_s;
    const io::Dataset data = io::read_tum_dataset(dataset, tum);
    std::vector<io::FramePair> frames;
    for (const auto& k : result.keyframes.keyframes) frames.push_back(data.frames[k.frame]);
    double dec1_s = 1e30, decn_s = 1e30, dec1_cpu_s = 1e30, cv1_s = 1e30;
    for (int r = 0; r < repeat; ++r) {
      double cpu = 0.0;
      dec1_s = std::min(dec1_s,
                        decode_seconds(frames, result.camera.width, result.camera.height, 1, &cpu));
      dec1_cpu_s = std::min(dec1_cpu_s, cpu);
      decn_s = std::min(decn_s,
                        decode_seconds(frames, result.camera.width, result.camera.height, threads));
      cv1_s = std::min(cv1_s, decode_seconds(frames, result.camera.width, result.camera.height, 1,
                                             nullptr, /*opencv=*/true));
    }

    const double fuse_ms = 1000.0 * fuse_s / n, dec1_ms = 1000.0 * dec1_s / n,
                 decn_ms = 1000.0 * decn_s / n, cv1_ms = 1000.0 * cv1_s / n;
    std::printf("objmap %s, bench_fuse\n", objmap::version());
    std::printf("dataset              %s (%zu keyframes, ground-truth trajectory)\n",
                dataset.string().c_str(), n);
    std::printf("fuse, %d threads      %8.2f ms/keyframe  (%.2f s total, best of %d)\n", threads,
                fuse_ms, fuse_s, repeat);
    std::printf(
        "fuse CPU time        %8.2f ms/keyframe  (user + system, all threads; the process)\n",
        1000.0 * cpu_s / n);
    std::printf(
        "decode, 1 thread     %8.2f ms/keyframe  (rgb + depth PNG, objmap's reader as in fuse)\n",
        dec1_ms);
    std::printf("decode, %d threads    %8.2f ms/keyframe\n", threads, decn_ms);
    std::printf("fuse / decode(1)     %8.2f   (target <= 1.5)\n", fuse_ms / dec1_ms);
    std::printf("fuse / decode(%d)     %8.2f\n", threads, fuse_ms / decn_ms);
    std::printf("OpenCV imread, 1 thr %8.2f ms/keyframe  (the same PNGs, libpng + zlib)\n", cv1_ms);
    std::printf("fuse / imread(1)     %8.2f\n", fuse_ms / cv1_ms);
    // `objmap fuse` as a command also loads its libraries first.
    const double start_s = startup_seconds(11);
    std::printf("objmap start-up      %8.1f ms  (objmap --version, median of 11)\n",
                1000.0 * start_s);
    std::printf("command / imread(1)  %8.2f   (the fuse + start-up, against imread)\n",
                (fuse_s + start_s) / (cv1_s));
    // CPU time against CPU time: steadier than wall time on a loaded machine. With `threads`
    // cores free, the wall-time ratio approaches this / threads.
    std::printf("decode CPU, 1 thread %8.2f ms/keyframe\n", 1000.0 * dec1_cpu_s / n);
    std::printf(
        "fuse CPU / decode CPU %7.2f   (the wall ratio is about this / threads when %d "
        "cores are free)\n",
        cpu_s / dec1_cpu_s, threads);
    // The scene step (up direction, surfaces, relations; docs/scene.md): up and surfaces run
    // beside the objects' filtering, so its cost is the fuse with it against the fuse without.
    std::printf(
        "scene step           %+8.2f ms/keyframe  (fuse with it - without: %.2f vs %.2f; CPU "
        "%+.2f)\n",
        1000.0 * (fuse_s - bare_s) / n, 1000.0 * fuse_s / n, 1000.0 * bare_s / n,
        1000.0 * (cpu_s - bare_cpu_s) / n);
    std::printf("scene / fuse without %8.1f %%  (target <= 10)\n",
                100.0 * (fuse_s - bare_s) / bare_s);
    std::printf(
        "scene parts          up %.0f ms, surfaces %.0f ms (beside the objects), upright boxes "
        "and relations %.0f ms\n",
        1000.0 * fastest.scene[0], 1000.0 * fastest.scene[1], 1000.0 * fastest.scene[2]);
    std::printf("peak RSS             %8.1f MB (target <= 500)\n", rss_mb);
    std::printf("vs Open3D 214 ms/fr  %8.1fx faster (target >= 20)\n", kOpen3dMsPerFrame / fuse_ms);
  } catch (const std::exception& e) {
    fs::remove_all(out);
    std::fprintf(stderr, "bench_fuse: %s\n", e.what());
    return 1;
  }
  return 0;
}
