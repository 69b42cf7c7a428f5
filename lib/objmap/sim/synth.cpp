#include "objmap/sim/synth.h"

#include <cmath>
#include <mutex>

#include "objmap/core/error.h"
#include "objmap/sim/parallel.h"
#include "objmap/sim/presets.h"
#include "objmap/sim/random.h"
#include "objmap/sim/render.h"
#include "objmap/sim/text.h"

namespace objmap::sim {

namespace {
double round_us(double t) { return std::round(t * 1e6) / 1e6; }
}  // namespace

void SynthOptions::check() const {
  check_scene_preset(preset);
  require(frames >= 1 && frames <= 100000, "--frames",
          "must be in [1, 100000], got " + std::to_string(frames));
  require(keep_every >= 1 && keep_every <= 1000, "--keep-every",
          "must be in [1, 1000], got " + std::to_string(keep_every));
  require(std::isfinite(frame_rate_hz) && frame_rate_hz > 0.0 && frame_rate_hz <= 1000.0,
          "SynthOptions.frame_rate_hz", "must be in (0, 1000], got " + num(frame_rate_hz));
  require(std::isfinite(start_time_s) && start_time_s >= 0.0 && start_time_s < 1e10,
          "SynthOptions.start_time_s", "must be in [0, 1e10), got " + num(start_time_s));
  require(std::isfinite(depth_time_offset_s) && std::abs(depth_time_offset_s) < 0.5 / frame_rate_hz,
          "--depth-offset",
          "must be shorter than half a frame period, got " + num(depth_time_offset_s));
  require(std::isfinite(resolution_scale) && resolution_scale >= 0.05 && resolution_scale <= 4.0,
          "--scale", "must be in [0.05, 4], got " + num(resolution_scale));
  require(std::isfinite(rgb_noise_sigma) && rgb_noise_sigma >= 0.0 && rgb_noise_sigma <= 50.0,
          "--rgb-noise", "must be in [0, 50] grey levels, got " + num(rgb_noise_sigma));
  require(threads >= 0 && threads <= 256, "--threads",
          "must be in [0, 256] (0 = all cores), got " + std::to_string(threads));
  depth_noise.check();
  seg_noise.check();
  drift.check();
  if (!use_preset_path) path.check();
  second_visit.check();
  require(std::isfinite(orbit_speed_deg_per_s) && orbit_speed_deg_per_s >= 0 &&
              orbit_speed_deg_per_s <= 360,
          "--orbit-speed", "must be in [0, 360] degrees per second (0: the preset's)");
}

void SynthOptions::set_noise_free() {
  rgb_noise_sigma = 0.0;
  depth_noise = DepthNoiseOptions::none();
  seg_noise = SegNoiseOptions::none();
  drift.translation_fraction = 0.0;
  drift.yaw_deg_per_m = 0.0;
  drift.white_noise_m = 0.0;
}

Camera synthetic_camera(double s) {
  Camera c = camera_preset("fr1");
  c.name = "synthetic (fr1 intrinsics, no distortion)";
  c.distortion = {0, 0, 0, 0, 0};
  c.width = static_cast<int>(std::lround(640 * s));
  c.height = static_cast<int>(std::lround(480 * s));
  // Pixel centres scale about the image corner (-0.5, -0.5).
  c.fx *= s;
  c.fy *= s;
  c.cx = (c.cx + 0.5) * s - 0.5;
  c.cy = (c.cy + 0.5) * s - 0.5;
  return c;
}

double frame_timestamp(double start_time_s, double frame_rate_hz, int index) {
  return round_us(start_time_s + index / frame_rate_hz);
}

Trajectory in_first_camera_frame(const Trajectory& trajectory) {
  Trajectory out;
  out.source = trajectory.source;
  if (trajectory.empty()) return out;
  const Pose first_from_world = trajectory.poses.front().world_from_cam.inverse();
  for (const StampedPose& p : trajectory.poses)
    out.poses.push_back({p.timestamp, first_from_world * p.world_from_cam});
  out.poses.front().world_from_cam = Pose::Identity();  // exactly, not to rounding
  return out;
}

namespace {

// One of the frames' segmentations (`which`) as one Segmentation.
segmentation::Segmentation collect(const std::vector<SynthFrame>& frames,
                                   segmentation::FrameSegmentation SynthFrame::*which,
                                   const std::string& source) {
  segmentation::Segmentation s;
  s.format = "json";
  s.source = source;
  for (const auto& f : frames) s.frames.push_back(f.*which);
  return s;
}

}  // namespace

segmentation::Segmentation SynthSequence::segmentation() const {
  return collect(frames, &SynthFrame::segmentation, "synthetic");
}

segmentation::Segmentation SynthSequence::segmentation_gt() const {
  return collect(frames, &SynthFrame::segmentation_gt, "synthetic (exact)");
}

SynthSequence prepare_sequence(const SynthOptions& options) {
  options.check();
  SynthSequence seq;
  seq.options = options;
  seq.camera = synthetic_camera(options.resolution_scale);

  // The scene and the camera path (ground truth), then the drifting estimate.
  const SecondVisitOptions& second = options.second_visit;
  seq.scene = make_scene(options.preset, second.enabled ? second.first_seed : options.seed);
  if (second.enabled) seq.second_visit = make_second_visit(seq.scene, second, options.seed);
  CameraPathOptions path =
      options.use_preset_path ? preset_camera_path(options.preset) : options.path;
  if (options.orbit_speed_deg_per_s > 0) path.speed_deg_per_s = options.orbit_speed_deg_per_s;
  std::vector<double> timestamps;
  for (int i = 0; i < options.frames; ++i)
    timestamps.push_back(frame_timestamp(options.start_time_s, options.frame_rate_hz, i));
  if (seq.second_visit) path.start_angle_deg += seq.second_visit->start_angle_offset_deg;
  seq.groundtruth = make_camera_path(path, timestamps, options.seed);
  if (seq.second_visit) {  // the scene and the path into the second visit's world
    const Pose& after_from_before = seq.second_visit->after_from_before;
    transform_scene(seq.scene, after_from_before);
    for (StampedPose& p : seq.groundtruth.poses)
      p.world_from_cam = after_from_before * p.world_from_cam;
  }
  seq.groundtruth.source = "synthetic ground truth";
  seq.estimated = add_drift(seq.groundtruth, options.drift, options.seed);
  return seq;
}

SynthFrame render_synth_frame(const SynthSequence& seq, int index) {
  const SynthOptions& options = seq.options;
  SynthFrame f;
  f.index = index;
  f.timestamp = seq.groundtruth.poses.at(index).timestamp;
  f.depth_timestamp = round_us(f.timestamp + options.depth_time_offset_s);
  RenderedFrame r =
      render_frame(seq.scene, seq.camera, seq.groundtruth.poses[index].world_from_cam, 1);
  // Each frame has its own random stream: frames can be made in any order, on any thread.
  Rng rng(derive_seed(options.seed, static_cast<std::uint64_t>(index), 0xF7A3E));
  const cv::Mat noisy = apply_depth_noise(r.depth_m, seq.camera, options.depth_noise, rng);
  f.depth = depth_to_u16(noisy, seq.camera.depth_factor);
  if (options.rgb_noise_sigma > 0.0) {
    for (int v = 0; v < r.rgb.rows; ++v) {
      auto* row = r.rgb.ptr<std::uint8_t>(v);
      for (int k = 0; k < r.rgb.cols * 3; ++k) {
        const double value = row[k] + options.rgb_noise_sigma * rng.fast_normal();
        row[k] = static_cast<std::uint8_t>(std::clamp(value + 0.5, 0.0, 255.0));
      }
    }
  }
  f.rgb = r.rgb;
  f.depth_exact_m = r.depth_m;
  f.labels = r.labels;
  f.segmentation_gt =
      exact_segmentation(r.labels, seq.scene, f.timestamp, options.seg_noise.min_area_px);
  return f;
}

SegmentationNoise make_segmentation_noise(const SynthOptions& options) {
  return SegmentationNoise(options.seg_noise, derive_seed(options.seed, 0, 0x5E9));
}

SynthSequence synthesize(const SynthOptions& options, const SynthProgress& progress) {
  // 1. Scene, ground-truth path and estimate.
  SynthSequence seq = prepare_sequence(options);

  // 2. Render each frame and apply the sensor noise, spread over the threads.
  seq.frames.resize(options.frames);
  std::mutex progress_mutex;
  std::size_t done = 0;
  parallel_for(seq.frames.size(), options.threads, [&](std::size_t i) {
    seq.frames[i] = render_synth_frame(seq, static_cast<int>(i));
    if (progress) {
      std::lock_guard<std::mutex> lock(progress_mutex);
      progress(++done, seq.frames.size());
    }
  });

  // 3. The detector + tracker output, in time order (track IDs carry from frame to frame).
  SegmentationNoise noise = make_segmentation_noise(options);
  for (auto& f : seq.frames)
    f.segmentation =
        noise.apply(f.segmentation_gt, seq.camera.width, seq.camera.height, f.depth_exact_m);
  seq.seg_stats = noise.stats();
  return seq;
}

}  // namespace objmap::sim
