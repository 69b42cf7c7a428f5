// objmap follow's publish: a copy of the live maps finished as objmap fuse finishes its maps and
// written to OUT/map through a staging folder; OUT/status.json.
#include <algorithm>
#include <nlohmann/json.hpp>

#include "objmap/core/error.h"
#include "objmap/io/atomic.h"
#include "objmap/pipeline/follow_state.h"
#include "objmap/pipeline/fuse_inputs.h"

namespace objmap::pipeline {

namespace fs = std::filesystem;

void publish(FollowState& s, const FollowEvents& events) {
  require(!s.result.keyframes.keyframes.empty(), s.options.dataset.string(),
          "no keyframe to map: " + std::to_string(s.status.frames_seen) + " frames seen, " +
              std::to_string(s.status.frames_with_pose) +
              " with a pose; expected frames with poses (--trajectory) while following");
  // What a fuse of the keyframes so far would have read.
  FuseInputs inputs;
  inputs.dataset = s.dataset;
  inputs.trajectory = s.trajectory;
  inputs.read = s.read;
  inputs.with_seg = s.with_seg;
  FuseResult result = s.result;
  result.frames = s.dataset.frames.size();
  result.keyframes.frames_with_pose = s.status.frames_with_pose;
  // A deep copy: the live maps go on growing (follow makes no meshes: no mesh model to copy).
  FuseMaps maps{s.maps->dense_options, s.maps->dense, s.maps->objects,
                std::nullopt,          std::nullopt,  s.maps->view_log};

  // The map written under a temporary name and renamed: a reader never sees half of it.
  io::StagingDir staging(s.options.fuse.out, io::kRunFolder);
  finish_fuse(s.options.fuse, s.choices, inputs, s.class_sizes, maps, staging.path(), s.started,
              result);
  staging.commit();

  // The lag of each keyframe this publish brought in: from its frame's arrival to now.
  const Clock::time_point now = Clock::now();
  s.status.lag_last_s = 0.0;
  for (const Clock::time_point& arrived : s.unpublished)
    s.status.lag_last_s =
        std::max(s.status.lag_last_s, std::chrono::duration<double>(now - arrived).count());
  s.status.lag_max_s = std::max(s.status.lag_max_s, s.status.lag_last_s);
  s.unpublished.clear();
  s.last_publish = now;
  s.status.objects = result.objects.size();
  ++s.status.publishes;
  write_status(s);
  if (events.published) events.published(s.status);
}

void write_status(FollowState& s) {
  s.status.seconds = seconds_since(s.started);
  s.status.peak_rss_kb = peak_rss_kb();
  const FollowStatus& st = s.status;
  nlohmann::ordered_json doc = {{"schema_version", 1},
                                {"dataset", s.options.dataset.string()},
                                {"map", s.options.fuse.out.string()},
                                {"state", st.state},
                                {"ended_by", st.ended_by},
                                {"frames_seen", st.frames_seen},
                                {"frames_decided", st.frames_decided},
                                {"frames_with_pose", st.frames_with_pose},
                                {"keyframes_mapped", st.keyframes_mapped},
                                {"keyframes_waiting", st.keyframes_waiting},
                                {"keyframes_dropped", st.keyframes_dropped},
                                {"frames_skipped_detect", st.frames_skipped_detect},
                                {"frame_retries", st.frame_retries},
                                {"dataset_retries", st.dataset_retries},
                                {"trajectory_lines", st.trajectory_lines},
                                {"trajectory_malformed", st.trajectory_malformed},
                                {"trajectory_rewrites", st.trajectory_rewrites},
                                {"publishes", st.publishes},
                                {"objects", st.objects},
                                {"lag_last_s", st.lag_last_s},
                                {"lag_max_s", st.lag_max_s},
                                {"seconds", st.seconds},
                                {"peak_rss_kb", st.peak_rss_kb}};
  io::write_file_atomic(s.options.out / "status.json", doc.dump(2) + "\n");
}

}  // namespace objmap::pipeline
