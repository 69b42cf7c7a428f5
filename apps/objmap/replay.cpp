// objmap replay: a finished recording written again into a folder at its own frame rate (the
// harness of objmap follow, and a demo), optionally with a loop closure that rewrites the
// trajectory part-way.
#include <cstdio>
#include <memory>

#include "command.h"
#include "objmap/pipeline/replay.h"
#include "progress.h"

namespace objmap::app {
namespace {

void replay_and_print(const pipeline::ReplayOptions& options) {
  options.check();
  std::unique_ptr<ProgressBar> bar;
  const pipeline::ReplayResult r =
      pipeline::run_replay(options, [&](std::size_t done, std::size_t total) {
        if (!bar) bar = std::make_unique<ProgressBar>("replay", total);
        bar->update(done);
      });
  if (bar) bar->finish();
  std::printf("replayed      %zu frames (%zu files, %s layout), %zu trajectory lines in %.1f s\n",
              r.frames, r.files, r.layout.c_str(), r.trajectory_lines, r.seconds);
  if (r.rewritten)
    std::printf("loop closure  the trajectory rewritten at --rewrite-at %.2f\n",
                options.rewrite_at);
  std::printf("late          at most %.3f s behind the recording's time\n", r.behind_s);
  std::printf("done          %s\n", (options.out / "done").c_str());
}

void setup_replay(CLI::App& app) {
  auto o = std::make_shared<pipeline::ReplayOptions>();
  CLI::App* c = app.add_subcommand(
      "replay",
      "Writes a recording (tum or 7scenes layout) into a new folder at its own frame rate, as a "
      "camera and a SLAM system would: each frame's files under a temporary name then renamed, "
      "rgb.txt/depth.txt and the trajectory's lines appended as their frames arrive, DST/done at "
      "the end. The harness of objmap follow (docs/follow.md).");
  c->add_option("--dataset", o->dataset, "the recording to replay (tum or 7scenes layout)")
      ->required();
  c->add_option("--out", o->out, "where to write it: new, empty or an earlier replay")->required();
  c->add_option("--trajectory", o->trajectory,
                "the trajectory streamed line by line (default: the source's groundtruth.txt)");
  c->add_option("--speed", o->speed, "2: twice the recording's own rate")->capture_default_str();
  c->add_option("--rewrite-at", o->rewrite_at,
                "a loop closure at this fraction of the frames: the trajectory is written with a "
                "drift until then, then rewritten whole with the source's poses (docs/cli.md)");
  c->add_option("--drift-deg", o->drift_deg, "--rewrite-at: the drift's rotation about z, degrees")
      ->capture_default_str();
  c->add_option("--drift-m", o->drift_m, "--rewrite-at: the drift's shift along x, metres")
      ->capture_default_str();
  c->callback([o] { replay_and_print(*o); });
}

}  // namespace

OBJMAP_COMMAND(85, "replay", setup_replay);

}  // namespace objmap::app
