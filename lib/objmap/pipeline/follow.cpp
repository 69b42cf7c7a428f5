// `objmap follow` as an outline (run_follow): each poll 1. reads the recording again, 2. selects
// the keyframes whose poses arrived, 3. fuses them as their segmentation arrives, 4. publishes the
// map every publish_every_s seconds, 5. makes OUT/report of a published map every report_every_s
// seconds; the end (DATASET/done, or idle_exit_s without news) fuses what is left, publishes once
// more and reports that map. The steps: follow_steps.cpp, follow_publish.cpp, follow_report.cpp.
#include "objmap/pipeline/follow.h"

#include <chrono>
#include <cmath>
#include <thread>

#include "objmap/core/error.h"
#include "objmap/pipeline/follow_state.h"

namespace objmap::pipeline {

namespace fs = std::filesystem;

void FollowOptions::check() const {
  require(!dataset.empty(), "--dataset", "missing; expected the recording's folder");
  require(!out.empty(), "--out", "missing; expected the run folder to keep up to date");
  require(std::isfinite(publish_every_s) && publish_every_s > 0, "--publish-every",
          "must be > 0 s");
  require(std::isfinite(idle_exit_s) && idle_exit_s >= 0, "--idle-exit",
          "must be >= 0 s (0: only DATASET/done ends it)");
  require(std::isfinite(poll_s) && poll_s > 0 && poll_s <= 10, "--poll", "must be in (0, 10] s");
  require(std::isfinite(report_every_s) && report_every_s >= 0, "--report-every",
          "must be >= 0 s (0: the report of the last map only)");
  require(std::isfinite(scene_every_s) && scene_every_s >= 0, "--scene-every",
          "must be >= 0 s (0: on every publish's dense map)");
  require(fs::is_directory(dataset), dataset.string(),
          "not a folder; expected the recording being written");
}

namespace {

// The recording gone: one line saying so, whichever step noticed it first.
void require_recording(const FollowOptions& options) {
  require(fs::exists(options.dataset), options.dataset.string(),
          "the recording folder was removed while following; the last published map is kept in " +
              (options.out / "map").string());
}

FollowStatus follow_loop(FollowState& s, const FollowOptions& options, const FollowEvents& events) {
  for (;;) {
    require_recording(options);
    // The end is known before the recording is read, so that the last read sees all of it.
    const bool done = fs::exists(options.dataset / "done");
    // 1. The recording as it is now (gone: exit 2 above, OUT/map keeps the last published map).
    if (read_recording(s, events)) s.last_news = Clock::now();
    const bool idle = options.idle_exit_s > 0 && seconds_since(s.last_news) >= options.idle_exit_s;
    const bool ending = done || idle;
    // 2. Keyframes by fuse's rule as their poses arrive.
    select_new_keyframes(s, ending);
    // 3. Each into the live maps once its segmentation frame is there; after a loop closure the
    //    objects are made again from the observations moved with the new poses.
    fuse_waiting_keyframes(s, ending, events);
    replace_after_loop_closure(s);
    // 4. Published every publish_every_s seconds when something is new (on a thread of its own),
    //    and at the end.
    // 5. OUT/report from the map just published when it is due (on a thread of its own).
    if (finish_publish(s, events, false)) start_report_if_due(s, events);
    finish_report(s, events, false);
    if (ending) {
      s.status.state = "finished";
      s.status.ended_by = done ? "done file" : "idle";
      publish(s, events);
      report_last_map(s, events);
      return s.status;
    }
    if (!s.publishing.valid() && !s.unpublished.empty() &&
        seconds_since(s.last_publish) >= options.publish_every_s)
      start_publish(s);
    else
      write_status(s);
    // Until the next poll, or until the publish in flight is done (the next may start at once).
    const auto poll = std::chrono::duration<double>(options.poll_s);
    if (s.publishing.valid())
      s.publishing.wait_for(poll);
    else
      std::this_thread::sleep_for(poll);
  }
}

}  // namespace

FollowStatus run_follow(const FollowOptions& options, const FollowEvents& events) {
  FollowState s = start_follow(options);
  write_status(s);
  try {
    return follow_loop(s, options, events);
  } catch (const InputError&) {
    require_recording(options);  // a file gone under a step: the folder's removal said as such
    throw;
  }
}

}  // namespace objmap::pipeline
