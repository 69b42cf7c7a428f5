#pragma once
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "objmap/core/camera.h"
#include "objmap/core/trajectory.h"
#include "objmap/segmentation/types.h"
#include "objmap/sim/camera_path.h"
#include "objmap/sim/depth_noise.h"
#include "objmap/sim/scene.h"
#include "objmap/sim/second_visit.h"
#include "objmap/sim/seg_noise.h"

// A synthetic RGB-D sequence with exact ground truth: scene -> camera path -> ray-cast images ->
// depth noise -> exact and noisy segmentation -> drifting estimate. In memory; writer.h puts it on
// disk.
namespace objmap::sim {

struct SynthOptions {
  std::string preset = "tabletop";  // scene: "tabletop", "office", "edge", "walkthrough"
  std::uint64_t seed = 1;           // everything random derives from it
  int frames = 90;                  // 3 s at 30 Hz
  // A sparse export (scans exported for 3D detection keep one frame in ~18): only frames 0, K,
  // 2K, ... are written, and each written instance gets a track id of its own (no tracker carries
  // an id across such gaps). The segmentation noise still runs over every frame.
  int keep_every = 1;
  double frame_rate_hz = 30.0;
  double start_time_s = 1700000000.1;  // timestamp of the first rgb frame
  double depth_time_offset_s = 0.005;  // depth timestamps = rgb + this (exercises association)
  // Image size as a fraction of 640x480 (intrinsics scaled with it); tests use 0.25-0.5.
  double resolution_scale = 1.0;
  double rgb_noise_sigma = 1.5;  // sensor noise of the colour image, grey levels (0 = none)
  DepthNoiseOptions depth_noise;
  SegNoiseOptions seg_noise;
  DriftOptions drift;
  // Camera path: the preset's orbit, or `path` as given when use_preset_path is false.
  bool use_preset_path = true;
  CameraPathOptions path;
  double orbit_speed_deg_per_s = 0.0;  // > 0: the preset's orbit at this azimuth rate (more sides
                                       // of every object in the same number of frames)
  int threads = 0;  // worker threads (0 = all cores); results do not depend on it
  // A second visit of another sequence's scene (--second-visit-of): that scene (its seed), changed,
  // in another world frame, the orbit starting elsewhere; `seed` drives the changes and the rest.
  SecondVisitOptions second_visit;

  void check() const;  // throws InputError naming the bad option
  // Turns every noise off: exact depth, exact segmentation, no rgb noise, no drift. (The hand-held
  // jitter of the camera path stays: it is part of the true motion.)
  void set_noise_free();
};

// The camera of the synthetic sensor: TUM freiburg1 intrinsics without distortion, scaled.
Camera synthetic_camera(double resolution_scale = 1.0);

struct SynthFrame {
  int index = 0;
  double timestamp = 0.0;        // rgb timestamp (exactly representable with "%.6f")
  double depth_timestamp = 0.0;  // timestamp + depth_time_offset_s, rounded to 1e-6
  cv::Mat rgb;                   // CV_8UC3, BGR
  cv::Mat depth;                 // CV_16UC1, the PNG values (metres * depth_factor), 0 = missing
  cv::Mat depth_exact_m;         // CV_32FC1, exact depth (metres), 0 where nothing was hit
  cv::Mat labels;                // CV_16UC1, exact object id per pixel (0 = room, tables)
  segmentation::FrameSegmentation segmentation;     // noisy, as a detector + tracker would give
  segmentation::FrameSegmentation segmentation_gt;  // exact, track_id = object id
};

struct SynthSequence {
  SynthOptions options;
  Camera camera;
  Scene scene;
  std::vector<SynthFrame> frames;
  Trajectory groundtruth;  // world_from_cam at the rgb timestamps
  Trajectory estimated;    // drifting copy of groundtruth
  SegmentationNoise::Stats seg_stats;
  std::optional<SecondVisit> second_visit;  // the changes made (options.second_visit.enabled)

  segmentation::Segmentation segmentation() const;     // the noisy frames as one Segmentation
  segmentation::Segmentation segmentation_gt() const;  // the exact frames
};

// Progress callback: frames rendered so far and the total (called from worker threads, serialised).
using SynthProgress = std::function<void(std::size_t done, std::size_t total)>;

// The whole sequence in memory (~10 MB per 640x480 frame: use write_synthetic_sequence for long
// ones). Deterministic for given options, whatever options.threads.
SynthSequence synthesize(const SynthOptions& options, const SynthProgress& progress = {});

// The pieces synthesize() is made of, for streaming (writer.h):
// everything but the frames (camera, scene, trajectories; `frames` empty);
SynthSequence prepare_sequence(const SynthOptions& options);
// one frame (without the noisy segmentation, which is made in time order by the next);
SynthFrame render_synth_frame(const SynthSequence& prepared, int index);
// the stateful segmentation noise seeded as synthesize() seeds it.
SegmentationNoise make_segmentation_noise(const SynthOptions& options);

// The trajectory re-expressed in the frame of its first camera, as ORB-SLAM2 writes its
// CameraTrajectory.txt: pose i becomes T_0^-1 · T_i (the first pose the identity).
Trajectory in_first_camera_frame(const Trajectory& trajectory);

// t0 + i / rate rounded to the microsecond.
double frame_timestamp(double start_time_s, double frame_rate_hz, int index);

}  // namespace objmap::sim
