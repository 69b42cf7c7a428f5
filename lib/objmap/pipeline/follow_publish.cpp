// objmap follow's publish: a copy of the live maps finished as objmap fuse finishes its maps and
// written to OUT/map through a staging folder; OUT/status.json.
#include <algorithm>
#include <chrono>
#include <future>
#include <memory>
#include <nlohmann/json.hpp>

#include "objmap/core/error.h"
#include "objmap/io/atomic.h"
#include "objmap/pipeline/follow_state.h"
#include "objmap/pipeline/fuse_inputs.h"

namespace objmap::pipeline {

namespace fs = std::filesystem;

void start_publish(FollowState& s) {
  require(!s.result.keyframes.keyframes.empty(), s.options.dataset.string(),
          "no keyframe to map: " + std::to_string(s.status.frames_seen) + " frames seen, " +
              std::to_string(s.status.frames_with_pose) +
              " with a pose; expected frames with poses (--trajectory) while following");
  s.publish_started = Clock::now();
  s.last_publish = s.publish_started;
  // What a fuse of the keyframes so far would have read, the dense map's cloud and a deep copy of
  // the object map: the live maps go on growing meanwhile (follow makes no meshes: no mesh model
  // to copy).
  auto inputs = std::make_shared<FuseInputs>();
  inputs->dataset = s.dataset;
  inputs->trajectory = s.trajectory;
  inputs->read = s.read;
  inputs->with_seg = s.with_seg;
  auto result = std::make_shared<FuseResult>(s.result);
  result->frames = s.dataset.frames.size();
  result->keyframes.frames_with_pose = s.status.frames_with_pose;
  // The dense map's changes taken here, after the publish's thread has started on the objects
  // (their merge pass does not need the dense cloud); its cloud brought up to date on a thread of
  // its own (the one publish in flight applies them: one apply at a time).
  std::promise<std::shared_ptr<const DenseCloud>> dense_promise;
  std::shared_future<std::shared_ptr<const DenseCloud>> dense_cloud;
  if (s.dense_snapshot) dense_cloud = dense_promise.get_future().share();
  auto maps = std::make_shared<FuseMaps>(
      FuseMaps{s.maps->dense_options, fusion::VoxelMap(s.maps->dense_options), s.maps->objects,
               std::nullopt, std::nullopt, s.maps->view_log, dense_cloud});
  s.publishing_arrivals = std::move(s.unpublished);
  s.unpublished.clear();
  const FollowState* state = &s;  // its options, choices and class sizes do not change
  s.publishing = std::async(std::launch::async, [state, inputs, result, maps] {
    // The map written under a temporary name and renamed: a reader never sees half of it.
    io::StagingDir staging(state->options.fuse.out, io::kRunFolder);
    finish_fuse(state->options.fuse, state->choices, *inputs, state->class_sizes, *maps,
                staging.path(), state->started, *result);
    staging.commit();
    return PublishDone{result->objects.size(), staging.committed_at()};
  });
  if (s.dense_snapshot)
    s.dense_apply = std::async(std::launch::async, [snapshot = &*s.dense_snapshot,
                                                    changes = s.dense_snapshot->take(s.maps->dense),
                                                    promise = std::move(dense_promise)]() mutable {
      try {
        promise.set_value(snapshot->apply(std::move(changes)));
      } catch (...) {
        promise.set_exception(std::current_exception());
      }
    });
}

bool publish_done(const FollowState& s) {
  return s.publishing.valid() &&
         s.publishing.wait_for(std::chrono::seconds(0)) == std::future_status::ready;
}

bool finish_publish(FollowState& s, const FollowEvents& events, bool wait) {
  if (!s.publishing.valid()) return false;
  if (!wait && !publish_done(s)) return false;
  const PublishDone done = s.publishing.get();
  s.status.objects = done.objects;
  // The lag of each keyframe this publish brought in: from its frame's arrival to the moment its
  // map was in place (not to when this loop noticed it).
  const Clock::time_point now = done.committed;
  s.status.publish_seconds_last = std::chrono::duration<double>(now - s.publish_started).count();
  s.status.lag_last_s = 0.0;
  for (const Clock::time_point& arrived : s.publishing_arrivals) {
    s.lags.push_back(std::chrono::duration<double>(now - arrived).count());
    s.status.lag_last_s = std::max(s.status.lag_last_s, s.lags.back());
  }
  if (!s.lags.empty()) {
    std::vector<double> sorted = s.lags;
    const auto mid = sorted.begin() + static_cast<std::ptrdiff_t>(sorted.size() / 2);
    std::nth_element(sorted.begin(), mid, sorted.end());
    s.status.lag_median_s = *mid;
  }
  s.status.lag_max_s = std::max(s.status.lag_max_s, s.status.lag_last_s);
  s.publishing_arrivals.clear();
  ++s.status.publishes;
  write_status(s);
  if (events.published) events.published(s.status);
  return true;
}

void publish(FollowState& s, const FollowEvents& events) {
  // The one in flight, or the last one done, is enough when it holds every keyframe.
  finish_publish(s, events, true);
  if (s.unpublished.empty() && s.status.publishes > 0) {
    write_status(s);
    return;
  }
  start_publish(s);
  finish_publish(s, events, true);
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
                                {"replacements", st.replacements},
                                {"publishes", st.publishes},
                                {"objects", st.objects},
                                {"lag_last_s", st.lag_last_s},
                                {"lag_max_s", st.lag_max_s},
                                {"lag_median_s", st.lag_median_s},
                                {"fuse_seconds", st.fuse_seconds},
                                {"publish_seconds_last", st.publish_seconds_last},
                                {"seconds", st.seconds},
                                {"peak_rss_kb", st.peak_rss_kb}};
  io::write_file_atomic(s.options.out / "status.json", doc.dump(2) + "\n");
}

}  // namespace objmap::pipeline
