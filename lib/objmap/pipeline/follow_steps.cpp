// The steps of objmap follow (follow.cpp is their outline): the recording read again at each poll,
// keyframes selected as their poses arrive, fused as their segmentation arrives.
#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <memory>
#include <optional>

#include "objmap/core/error.h"
#include "objmap/io/atomic.h"
#include "objmap/io/camera_io.h"
#include "objmap/io/trajectory.h"
#include "objmap/pipeline/follow_state.h"
#include "objmap/pipeline/fuse_keyframes.h"
#include "objmap/segmentation/read.h"
#include "objmap/segmentation/write.h"

namespace objmap::pipeline {

namespace fs = std::filesystem;

namespace {

const io::OutputKind kFollowFolder{"objmap follow run", {"status.json"}, false};

// The camera is known once the recording has a frame: the maps and the ray table are made then.
void start_maps(FollowState& s) {
  const io::CameraChoice choice = io::choose_camera(s.dataset, s.options.fuse.camera);
  FuseResult& r = s.result;
  r.camera = choice.camera;
  r.camera_reason = choice.reason;
  r.layout = s.dataset.layout;
  r.threads = fuse_threads(s.options.fuse.threads);
  r.seg_format = "json";
  r.keyframes.mode = "motion";
  r.trajectory_source = s.tail ? s.options.trajectory.string()
                               : "the dataset's own poses (" + s.dataset.poses.source + ")";
  s.read.format = "json";
  s.read.image_width = r.camera.width;
  s.read.image_height = r.camera.height;
  s.read.default_class = s.options.fuse.default_class;
  s.rays.emplace(geometry::make_ray_table(r.camera, r.threads));
  s.maps.emplace(make_fuse_maps(s.options.fuse, s.choices, r));
  if (s.options.fuse.dense_map) s.dense_snapshot.emplace(s.maps->dense);
  s.maps->objects.set_record_cache(s.record_cache);
  s.maps->objects.set_pair_cache(s.pair_cache);
  s.maps->objects.set_contact_cache(s.contact_cache);
  s.live = std::make_unique<LiveKeyframes>(s.options.fuse, r.camera, *s.rays,
                                           s.options.fuse.dense_map ? &s.maps->dense : nullptr,
                                           s.maps->view_log.has_value(), r.threads);
}

// DATASET/segmentation's canonical JSON frames, sorted by timestamp.
std::vector<std::pair<double, fs::path>> list_segmentation(const fs::path& dir) {
  std::vector<std::pair<double, fs::path>> frames;
  std::error_code ec;
  for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
    double t = 0.0;
    if (it->path().extension() == ".json" &&
        segmentation::parse_timestamp(it->path().stem().string(), t))
      frames.emplace_back(t, it->path());
  }
  std::sort(frames.begin(), frames.end());
  return frames;
}

void warn(const FollowEvents& events, const std::string& line) {
  if (events.warning) events.warning(line);
}

// A keyframe's instances, read on a worker: its segmentation frame, or none.
using InstancesReader = std::function<std::optional<segmentation::FrameSegmentation>()>;

// Keyframe k's instances (nullopt: it waits): from the detector (--model), or its segmentation
// frame (named by its rgb timestamp, within 1 ms) once written, read by the reader returned: a
// keyframe waits until its own or a later frame's is there; with `ending` nothing waits.
std::optional<InstancesReader> keyframe_instances(FollowState& s, const Keyframe& k, bool ending) {
  const InstancesReader none = [] { return std::optional<segmentation::FrameSegmentation>(); };
  if (s.detector) {
    if (s.skipped.count(k.timestamp)) return none;
    if (!s.detected.count(k.timestamp)) {
      if (ending) s.detector->drain();
      std::optional<segmentation::FrameSegmentation> taken = s.detector->take(k.timestamp);
      if (!taken) return ending ? std::optional<InstancesReader>(none) : std::nullopt;
      segmentation::write_frame_json(
          s.options.fuse.segmentation / segmentation::frame_file_name(k.timestamp), *taken);
      s.detected[k.timestamp] = std::move(*taken);
    }
    auto frame = std::make_shared<const segmentation::FrameSegmentation>(s.detected[k.timestamp]);
    return [frame] { return std::optional<segmentation::FrameSegmentation>(*frame); };
  }
  const auto seg = std::lower_bound(s.segmentation.begin(), s.segmentation.end(),
                                    std::make_pair(k.timestamp - 1e-3, fs::path()));
  if (seg == s.segmentation.end())
    return ending ? std::optional<InstancesReader>(none) : std::nullopt;
  if (seg->first > k.timestamp + 1e-3) return none;
  return [file = seg->second, read = s.read] {
    return std::optional<segmentation::FrameSegmentation>(
        segmentation::read_frame_json(file, read));
  };
}

// The waiting keyframes from s.waiting[from] on queued on the workers (their instances read
// there) while fewer than `window` are, as the map's next keyframes (`taken` of the waiting ones
// are mapped in this turn). Returns false once no more may be queued in this turn: one waits for
// its segmentation, or the publish is due.
bool queue_keyframes(FollowState& s, bool ending, std::size_t& from, std::size_t taken,
                     std::size_t window) {
  for (; from < s.waiting.size() && s.live->queued() < window; ++from) {
    // A backlog does not hold back the publish that is due (none in flight, or the one in flight
    // done): the rest waits for the next poll.
    if (!ending && from > 0 && (!s.publishing.valid() || publish_done(s)) &&
        seconds_since(s.last_publish) >= s.options.publish_every_s)
      return false;
    const Keyframe& k = s.waiting[from].keyframe;
    std::optional<InstancesReader> instances = keyframe_instances(s, k, ending);
    if (!instances) return false;
    const std::size_t index = s.result.keyframes.keyframes.size() + (from - taken);
    s.live->submit(s.dataset, k, static_cast<int>(index), std::move(*instances));
  }
  return true;
}

}  // namespace

FollowState start_follow(const FollowOptions& options) {
  options.check();
  io::require_not_an_input({"--out", options.out},
                           {{"--dataset", options.dataset}, {"--trajectory", options.trajectory}});
  io::require_replaceable(options.out, kFollowFolder);
  io::require_replaceable(options.out / "report", io::kReportFolder);  // made at the end at least
  FollowState s;
  s.options = options;
  FuseOptions& fuse = s.options.fuse;
  fuse.dataset = options.dataset;
  fuse.out = options.out / "map";
  fuse.trajectory = options.trajectory;
  fuse.segmentation = options.dataset / "segmentation";
  fuse.layout = options.layout;
  fuse.camera = options.camera;
  s.choices = fuse.check();
  require(!s.choices.meshes.objects && !s.choices.meshes.scene, "--mesh",
          "objmap follow makes no meshes; expected none (objmap fuse makes them afterwards)");
  s.class_sizes = segmentation::ClassSizes::from_spec(fuse.class_sizes);
  if (!options.trajectory.empty())
    s.tail = std::make_unique<io::TrajectoryTail>(options.trajectory);
  if (!options.model.empty()) {
    segmentation::DetectOptions detect;
    detect.model = options.model;
    s.detector = std::make_unique<LatestDetector>(detect);
    fuse.segmentation = options.out / "detect";  // what the model found, frame by frame
  }
  io::create_output_folders(options.out);
  if (s.detector) io::create_output_folders(fuse.segmentation);
  return s;
}

bool read_recording(FollowState& s, const FollowEvents& events) {
  const fs::path& root = s.options.dataset;
  bool news = false;
  try {
    io::Dataset dataset = io::read_dataset(
        root, {s.options.layout, s.options.fuse.max_diff_s, 30.0, s.options.fuse.topics});
    if (dataset.frames.size() >= s.dataset.frames.size()) {
      news = dataset.frames.size() > s.dataset.frames.size();
      s.arrived.resize(dataset.frames.size(), Clock::now());
      s.dataset = std::move(dataset);
    }
  } catch (const InputError&) {
    ++s.status.dataset_retries;  // not there yet, or a listing being written: the next poll
  }
  if (s.tail) {
    const io::TrajectoryTailPoll poll = s.tail->poll();
    for (const std::string& line : poll.malformed) warn(events, line);
    if (poll.rewritten) {
      warn(events, s.options.trajectory.string() +
                       ": earlier poses changed (a loop closure); the objects are moved with them");
      s.rewrite_pending = true;
    }
    news = news || poll.new_poses > 0;
    s.trajectory = s.tail->trajectory();
    s.status.trajectory_lines = s.tail->lines();
    s.status.trajectory_malformed = s.tail->malformed();
    s.status.trajectory_rewrites = s.tail->rewrites();
  } else {
    s.trajectory = s.dataset.poses;
  }
  if (!s.detector) s.segmentation = list_segmentation(s.options.fuse.segmentation);
  if (!s.maps && !s.dataset.frames.empty()) start_maps(s);
  s.status.frames_seen = s.dataset.frames.size();
  if (s.status.state == "waiting" && s.maps) s.status.state = "following";
  return news;
}

void select_new_keyframes(FollowState& s, bool ending) {
  const KeyframeOptions& kf = s.options.fuse.keyframes;
  io::PoseLookupOptions lookup;
  lookup.max_diff_s = s.options.fuse.max_diff_s;
  lookup.interpolate = true;
  // A frame's pose is known once a pose later than the lookup's window is there.
  const double known_until = s.trajectory.empty() ? -std::numeric_limits<double>::infinity()
                                                  : s.trajectory.poses.back().timestamp;
  const double min_rotation_rad = kf.min_rotation_deg * M_PI / 180.0;
  const auto& frames = s.dataset.frames;
  for (std::size_t& i = s.status.frames_decided; i < frames.size(); ++i) {
    const double t = frames[i].rgb_timestamp;
    if (!ending && !(known_until > t + lookup.max_diff_s)) break;
    const std::optional<Pose> pose = io::lookup_pose(s.trajectory, t, lookup);
    if (!pose) continue;
    const std::size_t posed = s.status.frames_with_pose++;
    const Keyframe k{i, t, *pose};
    bool key = !s.last_keyframe || kf.mode == "all";
    if (kf.mode == "stride") {
      key = posed % static_cast<std::size_t>(kf.stride) == 0;
    } else if (!key) {  // fuse's motion rule: enough translation or rotation since the last one
      const Pose last_from_this = s.last_keyframe->world_from_cam.inverse() * k.world_from_cam;
      key = last_from_this.translation().norm() >= kf.min_translation_m ||
            Eigen::AngleAxisd(last_from_this.rotation()).angle() >= min_rotation_rad;
    }
    if (!key) continue;
    s.last_keyframe = k;
    s.waiting.push_back({k, s.arrived[i]});
    if (s.detector)  // the newest keyframe to the detector; one it had not reached is skipped
      if (const std::optional<double> skipped = s.detector->submit(t, frames[i].rgb_file)) {
        s.skipped.insert(*skipped);
        ++s.status.frames_skipped_detect;
      }
  }
  s.status.keyframes_waiting = s.waiting.size();
}

void fuse_waiting_keyframes(FollowState& s, bool ending, const FollowEvents& events) {
  if (!s.live) return;  // no frame yet: no camera, no maps, no keyframe
  const Clock::time_point t0 = Clock::now();
  FuseResult& r = s.result;
  // Keyframes decode and back-project ahead on the workers while this thread maps the oldest.
  const std::size_t window = static_cast<std::size_t>(r.threads);
  std::size_t n = 0, queued_to = 0;
  bool more = true;
  for (;;) {
    if (more) more = queue_keyframes(s, ending, queued_to, n, window);
    if (s.live->queued() == 0) break;
    const Keyframe& k = s.waiting[n].keyframe;
    LiveKeyframe live;
    try {
      live = s.live->take(r);
    } catch (const InputError& e) {
      s.live->drop();  // the keyframes after it are queued again, in their places
      if (!ending) {   // a file half-written or not there yet: the next poll reads it again
        ++s.status.frame_retries;
        if (s.retried_timestamp != k.timestamp)  // named once, not at every poll
          warn(events, std::string(e.what()) + "; retried at the next poll");
        s.retried_timestamp = k.timestamp;
        break;
      }
      ++s.status.keyframes_dropped;
      warn(events, std::string(e.what()) + "; the keyframe is left out");
      queued_to = ++n;
      more = true;
      continue;
    }
    s.detected.erase(k.timestamp);
    s.skipped.erase(k.timestamp);
    const cv::Mat view_depth = live.view_depth;  // shared, never written to: kept as well
    if (s.maps->view_log && !view_depth.empty())
      s.maps->view_log->add(k.timestamp, view_depth, k.world_from_cam);
    const std::size_t empty_before = r.instances_empty;
    count_added(s.maps->objects.add_frame(live.observations), r);
    s.empty_by_add += r.instances_empty - empty_before;
    keep_for_replacing(s, k, std::move(live.observations), std::move(live.pixels), view_depth);
    if (live.segmented) ++s.with_seg;
    r.keyframes.keyframes.push_back(k);
    s.unpublished.push_back(s.waiting[n].arrived);
    ++n;
  }
  s.waiting.erase(s.waiting.begin(), s.waiting.begin() + static_cast<std::ptrdiff_t>(n));
  if (s.detector)
    for (const std::string& line : s.detector->take_warnings()) warn(events, line);
  s.status.keyframes_mapped = s.result.keyframes.keyframes.size();
  s.status.keyframes_waiting = s.waiting.size();
  s.status.fuse_seconds += seconds_since(t0);
}

}  // namespace objmap::pipeline
