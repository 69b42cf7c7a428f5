// objmap follow's publish: a copy of the live maps finished as objmap fuse finishes its maps and
// written to OUT/map through a staging folder; OUT/status.json.
#include <algorithm>
#include <chrono>
#include <future>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>

#include "objmap/core/error.h"
#include "objmap/io/atomic.h"
#include "objmap/pipeline/follow_state.h"
#include "objmap/pipeline/fuse_inputs.h"
#include "objmap/scene/scene.h"

namespace objmap::pipeline {

namespace fs = std::filesystem;

namespace {

using ScenePromise = std::promise<std::shared_ptr<const scene::SceneGraph>>;

// A publish's up and surfaces (maps.scene): the last found, on the dense cloud of a publish before
// (on a thread of their own since), so that they are off its way; with `own_scene` (the last
// publish), or when there are none yet, those of its own cloud, unless nothing was fused since.
struct SceneChoice {
  std::size_t keyframes = 0;  // of the dense map the publish's up and surfaces are found on
  // Given when they are found on this publish's cloud, for it or the publishes after.
  std::optional<ScenePromise> make;
};

// They are found again on this publish's cloud (s.scene from then on) when its own are needed or
// the last were found scene_every_s or more before.
SceneChoice choose_scene(FollowState& s, FuseMaps& maps, bool own_scene) {
  const std::size_t keyframes = s.result.keyframes.keyframes.size();
  const bool before = s.scene.valid() && (!own_scene || s.scene_keyframes == keyframes);
  SceneChoice choice{before ? s.scene_keyframes : keyframes, std::nullopt};
  if (before) maps.scene = s.scene;
  if (before &&
      (s.scene_keyframes == keyframes || seconds_since(s.scene_started) < s.options.scene_every_s))
    return choice;
  s.scene = choice.make.emplace().get_future().share();
  if (!before) maps.scene = s.scene;
  s.scene_keyframes = keyframes;
  s.scene_started = s.publish_started;
  return choice;
}

// The dense map's changes taken now (on the loop's thread, after the publish's thread has started
// on the objects: their merge pass does not need the dense cloud) and, on a thread of their own,
// folded into the cloud (`cloud`); when `scene` is given, that thread then takes what the up and
// the surfaces read of the cloud (scene::SceneSample) and, on another thread, they are found on
// it. One apply at a time and one scene at a time, each after the one before. Only the publish
// reads the cloud besides the apply that made it, so the next apply changes it in place.
void start_dense_apply(FollowState& s, std::promise<std::shared_ptr<const DenseCloud>> cloud,
                       std::optional<ScenePromise> scene) {
  std::optional<std::promise<scene::SceneSample>> sample;
  std::future<scene::SceneSample> sampled;
  std::vector<Pose> cameras;
  if (scene) {
    sampled = sample.emplace().get_future();
    for (const Keyframe& k : s.result.keyframes.keyframes) cameras.push_back(k.world_from_cam);
  }
  s.dense_apply = std::async(
      std::launch::async,
      [snapshot = &*s.dense_snapshot, changes = s.dense_snapshot->take(s.maps->dense),
       cloud_promise = std::move(cloud), sample = std::move(sample), cameras = std::move(cameras),
       options = &s.options.fuse.scene, before = std::move(s.dense_apply)]() mutable {
        std::shared_ptr<const DenseCloud> made;
        try {
          if (before.valid()) before.get();  // the apply before done
          made = snapshot->apply(std::move(changes));
        } catch (...) {
          cloud_promise.set_exception(std::current_exception());
          if (sample) sample->set_exception(std::current_exception());
          return;
        }
        cloud_promise.set_value(made);
        if (!sample) return;
        try {
          sample->set_value(scene::SceneSample(cameras, made->cloud.points, *options));
        } catch (...) {
          sample->set_exception(std::current_exception());
        }
      });
  if (!scene) return;
  s.scene_making =
      std::async(std::launch::async,
                 [sampled = std::move(sampled), scene_promise = std::move(*scene),
                  before = std::move(s.scene_making), options = &s.options.fuse.scene]() mutable {
                   try {
                     if (before.valid()) before.get();  // the scene before done
                     auto graph = std::make_shared<scene::SceneGraph>();
                     scene::find_up_and_surfaces(sampled.get(), *options, *graph);
                     scene_promise.set_value(std::move(graph));
                   } catch (...) {
                     scene_promise.set_exception(std::current_exception());
                   }
                 });
}

}  // namespace

void start_publish(FollowState& s, bool own_scene, bool last) {
  require(!s.result.keyframes.keyframes.empty(), s.options.dataset.string(),
          "no keyframe to map: " + std::to_string(s.status.frames_seen) + " frames seen, " +
              std::to_string(s.status.frames_with_pose) +
              " with a pose; expected frames with poses (--trajectory) while following");
  s.publish_started = Clock::now();
  s.last_publish = s.publish_started;
  // What a fuse of the keyframes so far would have read, the dense map's cloud, its up and
  // surfaces, and a copy of the object map (its objects' voxels shared until one side changes
  // them: copy on write): the live maps go on growing meanwhile (follow
  // makes no meshes: no mesh model to copy).
  auto inputs = std::make_shared<FuseInputs>();
  inputs->dataset = s.dataset;
  inputs->trajectory = s.trajectory;
  inputs->read = s.read;
  inputs->with_seg = s.with_seg;
  auto result = std::make_shared<FuseResult>(s.result);
  result->frames = s.dataset.frames.size();
  result->keyframes.frames_with_pose = s.status.frames_with_pose;
  // The last publish takes the live object map and view log: nothing is fused after it, and its
  // merges and filters then change the objects' voxels in place rather than copying them.
  auto maps =
      std::make_shared<FuseMaps>(FuseMaps{s.maps->dense_options,
                                          fusion::VoxelMap(s.maps->dense_options),
                                          last ? std::move(s.maps->objects) : s.maps->objects,
                                          std::nullopt,
                                          std::nullopt,
                                          last ? std::move(s.maps->view_log) : s.maps->view_log,
                                          {},
                                          {}});
  std::promise<std::shared_ptr<const DenseCloud>> cloud;
  const std::size_t keyframes = s.result.keyframes.keyframes.size();
  SceneChoice choice{keyframes, std::nullopt};
  if (s.dense_snapshot) {
    maps->dense_cloud = cloud.get_future().share();
    choice = choose_scene(s, *maps, own_scene);
  }
  s.publishing_arrivals = std::move(s.unpublished);
  s.unpublished.clear();
  const FollowState* state = &s;  // its options, choices and class sizes do not change
  s.publishing = std::async(std::launch::async, [state, inputs, result, maps,
                                                 scene_keyframes = choice.keyframes,
                                                 complete = choice.keyframes == keyframes] {
    // The map written under a temporary name and renamed: a reader never sees half of it.
    io::StagingDir staging(state->options.fuse.out, io::kRunFolder);
    finish_fuse(state->options.fuse, state->choices, *inputs, state->class_sizes, *maps,
                staging.path(), state->started, *result);
    staging.commit();
    return PublishDone{result->objects.size(), staging.committed_at(), scene_keyframes, complete};
  });
  if (s.dense_snapshot) start_dense_apply(s, std::move(cloud), std::move(choice.make));
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
  s.status.scene_keyframes = done.scene_keyframes;
  s.scene_complete = done.scene_complete;
  // The lag of each keyframe this publish brought in: from its frame's arrival to the moment its
  // map was in place (not to when this loop noticed it). A publish that brought none (the last
  // map with its own up and surfaces) leaves the last lag as it was.
  const Clock::time_point now = done.committed;
  s.status.publish_seconds_last = std::chrono::duration<double>(now - s.publish_started).count();
  if (!s.publishing_arrivals.empty()) s.status.lag_last_s = 0.0;
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
  finish_publish(s, events, true);
  // The keyframes not yet published first, with the up and surfaces last found: their lag ends
  // there, not after the scene step of the whole dense map.
  if (!s.unpublished.empty() && s.status.publishes > 0) {
    start_publish(s, false);
    finish_publish(s, events, true);
  }
  // The last map is that of fuse: the up and surfaces of its own dense map. The publish before
  // is it when it holds every keyframe and had those.
  if (s.unpublished.empty() && s.status.publishes > 0 && s.scene_complete) {
    write_status(s);
    return;
  }
  // Nothing is fused or made again after the last publish: the kept keyframes go before it, it
  // takes the live object map, and the live dense map's tables go once their changes are taken
  // (the cloud the take's apply makes is the map from here on).
  s.kept = {};
  s.kept_pixels.reset();
  start_publish(s, true, true);
  if (s.maps) s.maps->dense = fusion::VoxelMap(s.maps->dense_options);
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
                                {"scene_keyframes", st.scene_keyframes},
                                {"reports", st.reports},
                                {"report_publish", st.report_publish},
                                {"report_seconds_last", st.report_seconds_last},
                                {"seconds", st.seconds},
                                {"peak_rss_kb", st.peak_rss_kb},
                                {"kept_pixels_kb", st.kept_pixels_kb}};
  io::write_file_atomic(s.options.out / "status.json", doc.dump(2) + "\n");
}

}  // namespace objmap::pipeline
