#include "objmap/sim/writer.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <mutex>
#include <optional>
#include <sstream>

#include <nlohmann/json.hpp>

#include "objmap/core/error.h"
#include "objmap/io/atomic.h"
#include "objmap/io/camera_io.h"
#include "objmap/io/png_encode.h"
#include "objmap/io/trajectory.h"
#include "objmap/segmentation/write.h"
#include "objmap/sim/parallel.h"
#include "objmap/sim/support.h"

namespace objmap::sim {

namespace fs = std::filesystem;
using json = nlohmann::ordered_json;  // keys in the order written

namespace {

json vec(const Vec3& v) { return json::array({v.x(), v.y(), v.z()}); }

void write_bytes(const fs::path& file, const char* data, std::size_t size) {
  std::ofstream out(file, std::ios::binary);
  out.write(data, static_cast<std::streamsize>(size));
  out.close();
  if (!out) throw InputError(file.string(), "cannot write the file");
}

void write_text(const fs::path& file, const std::string& text) {
  write_bytes(file, text.data(), text.size());
}

// io/png_encode.h: Sub filter and zlib level 1 RLE, several times faster than cv::imencode. The
// byte buffer is kept per thread: a fresh 1 MB buffer per image costs page faults.
void write_png(const fs::path& file, const cv::Mat& image) {
  thread_local std::vector<std::uint8_t> bytes;
  io::encode_png(image, &bytes);
  write_bytes(file, reinterpret_cast<const char*>(bytes.data()), bytes.size());
}

std::string describe(const SynthOptions& o) {
  return "synthetic " + o.preset + " seed " + std::to_string(o.seed) + " (objmap synth)";
}

}  // namespace

void check_output_dir(const fs::path& out) {
  require(!out.empty(), "--out", "is empty; expected a folder to write the sequence into");
  std::error_code ec;
  if (fs::exists(out, ec) && !fs::is_directory(out, ec))
    throw InputError(out.string(), "exists and is not a folder; expected a folder (or a new name)");
  const fs::path parent = fs::absolute(out, ec).parent_path();
  fs::create_directories(parent, ec);
  if (ec || !fs::is_directory(parent))
    throw InputError(out.string(), "cannot create the parent folder " + parent.string() + ": " +
                                       (ec ? ec.message() : std::string("not a folder")));
}

std::string timestamp_name(double timestamp) {
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, "%.6f", timestamp);
  return buffer;
}

namespace {

json surface_json(const SupportSurface& s) {
  json outline = json::array();
  for (const Vec3& corner : s.outline) outline.push_back(vec(corner));
  json j = {{"id", s.id},
            {"label", s.label},
            {"height_m", s.height_m},
            {"center", vec(s.center)},
            {"outline", outline},
            {"area_m2", s.area_m2}};
  if (s.object_id > 0) j["object"] = s.object_id;
  return j;
}

json relation_json(const std::optional<SupportRelation>& on) {
  if (!on) return nullptr;
  const bool surface = on->kind == SupportRelation::Kind::kSurface;
  return {{"kind", surface ? "surface" : "object"},
          {"id", on->id},
          {"label", on->label},
          {"gap_m", on->gap_m}};
}

}  // namespace

std::string objects_gt_json(const Scene& scene) {
  const SceneSupport support = scene_support(scene);
  json objects = json::array();
  for (std::size_t i = 0; i < scene.objects.size(); ++i) {
    const SceneObject& o = scene.objects[i];
    json rotation = json::array();
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) rotation.push_back(o.obb.rotation(r, c));
    objects.push_back({{"id", o.id},
                       {"class", o.class_name},
                       {"centroid", vec(o.centroid)},
                       {"obb",
                        {{"center", vec(o.obb.center)},
                         {"rotation", rotation},
                         {"half_extent", vec(o.obb.half_extent)}}},
                       {"volume_m3", o.volume_m3},
                       {"on", relation_json(support.on[i])}});
  }
  json surfaces = json::array();
  for (const SupportSurface& s : support.surfaces) surfaces.push_back(surface_json(s));
  json doc = {{"schema_version", 1},
              {"frame", "world frame of groundtruth.txt (z up, metres)"},
              {"centroid_definition", "solid volume"},
              {"up_in_world", vec(support.up)},
              {"surfaces", surfaces},
              {"objects", objects}};
  return doc.dump(2) + "\n";
}

std::string synth_json(const SynthSequence& s) {
  const SynthOptions& o = s.options;
  json confusions = json::array();
  for (const auto& c : o.seg_noise.confusions)
    confusions.push_back({{"from", c.from}, {"to", c.to}, {"probability", c.probability}});
  const auto& d = o.depth_noise;
  json doc = {{"generator", "objmap synth"},
              {"preset", o.preset},
              {"seed", o.seed},
              {"frames", o.frames},
              {"keep_every", o.keep_every},
              {"orbit_speed_deg_per_s", o.orbit_speed_deg_per_s},
              {"frame_rate_hz", o.frame_rate_hz},
              {"depth_time_offset_s", o.depth_time_offset_s},
              {"resolution_scale", o.resolution_scale},
              {"rgb_noise_sigma", o.rgb_noise_sigma},
              {"depth_noise",
               {{"enabled", d.enabled},
                {"sigma_base_m", d.sigma_base_m},
                {"sigma_quadratic", d.sigma_quadratic},
                {"sigma_ref_z_m", d.sigma_ref_z_m},
                {"disparity_step_px", d.disparity_step_px},
                {"baseline_m", d.baseline_m},
                {"min_range_m", d.min_range_m},
                {"max_range_m", d.max_range_m},
                {"edge_jump_m", d.edge_jump_m},
                {"edge_width_px", d.edge_width_px},
                {"edge_missing_prob", d.edge_missing_prob},
                {"dropout_prob", d.dropout_prob}}},
              {"segmentation_noise",
               {{"min_area_px", o.seg_noise.min_area_px},
                {"boundary_px", o.seg_noise.boundary_px},
                {"miss_prob", o.seg_noise.miss_prob},
                {"false_positives_per_frame", o.seg_noise.false_positives_per_frame},
                {"confusions", confusions},
                {"id_switch_prob", o.seg_noise.id_switch_prob},
                {"id_reuse_prob", o.seg_noise.id_reuse_prob}}},
              {"drift",
               {{"translation_fraction", o.drift.translation_fraction},
                {"yaw_deg_per_m", o.drift.yaw_deg_per_m},
                {"random_walk", o.drift.random_walk},
                {"white_noise_m", o.drift.white_noise_m}}},
              {"made",
               {{"true_instances", s.seg_stats.true_instances},
                {"missed", s.seg_stats.missed},
                {"confused", s.seg_stats.confused},
                {"false_positives", s.seg_stats.false_positives},
                {"id_switches", s.seg_stats.id_switches},
                {"id_reuses", s.seg_stats.id_reuses}}}};
  if (o.second_visit.enabled)  // only then, so that other synth.json files stay as they were
    doc["second_visit"] = {{"first_visit", o.second_visit.first_visit.string()},
                           {"first_seed", o.second_visit.first_seed},
                           {"move", o.second_visit.move},
                           {"remove", o.second_visit.remove},
                           {"add", o.second_visit.add}};
  // Recorded only when on, so that the synth.json of a sequence without bleed stays as it was.
  if (o.seg_noise.bleed_px > 0) {
    doc["segmentation_noise"]["bleed_px"] = o.seg_noise.bleed_px;
    doc["made"]["bleed_pixels"] = s.seg_stats.bleed_pixels;
  }
  return doc.dump(2) + "\n";
}

namespace {

void make_folders(const fs::path& dir) {
  for (const char* sub : {"rgb", "depth", "segmentation", "segmentation_gt"})
    io::create_output_folders(dir / sub);
}

void write_images(const fs::path& dir, const SynthFrame& f) {
  write_png(dir / "rgb" / (timestamp_name(f.timestamp) + ".png"), f.rgb);
  write_png(dir / "depth" / (timestamp_name(f.depth_timestamp) + ".png"), f.depth);
}

void write_segmentation(const fs::path& dir, const char* sub,
                        const segmentation::FrameSegmentation& frame) {
  segmentation::write_frame_json(dir / sub / segmentation::frame_file_name(frame.timestamp), frame);
}

// Everything but the frames: lists, camera, trajectories, objects, synth.json.
// Whether frame i is written (SynthOptions::keep_every).
bool kept(const SynthOptions& o, std::size_t i) {
  return i % static_cast<std::size_t>(o.keep_every) == 0;
}

// A sparse export's ids: each instance of a written frame its own, counted in frame order.
segmentation::FrameSegmentation sparse_ids(segmentation::FrameSegmentation frame,
                                           const SynthOptions& o, int& next_id) {
  if (o.keep_every > 1)
    for (auto& instance : frame.instances) instance.track_id = next_id++;
  return frame;
}

void write_sequence_files(const fs::path& dir, const SynthSequence& s) {
  const std::string what = describe(s.options);
  std::ostringstream rgb_txt, depth_txt;
  rgb_txt << "# color images\n# file: '" << what << "'\n# timestamp filename\n";
  depth_txt << "# depth maps\n# file: '" << what << "'\n# timestamp filename\n";
  for (std::size_t i = 0; i < s.groundtruth.poses.size(); ++i) {
    if (!kept(s.options, i)) continue;
    const double t = s.groundtruth.poses[i].timestamp;
    const double td = std::round((t + s.options.depth_time_offset_s) * 1e6) / 1e6;
    rgb_txt << timestamp_name(t) << " rgb/" << timestamp_name(t) << ".png\n";
    depth_txt << timestamp_name(td) << " depth/" << timestamp_name(td) << ".png\n";
  }
  write_text(dir / "rgb.txt", rgb_txt.str());
  write_text(dir / "depth.txt", depth_txt.str());

  io::write_camera_json(dir / "camera.json", s.camera);
  io::write_trajectory(dir / "groundtruth.txt", s.groundtruth,
                       "ground truth trajectory (world_from_cam) of " + what);
  char drift[64];
  std::snprintf(drift, sizeof drift, "%g%%", s.options.drift.translation_fraction * 100.0);
  io::write_trajectory(
      dir / "estimated.txt", s.estimated,
      "SLAM-like estimate with drift (" + std::string(drift) + " of the path length) of " + what);
  io::write_trajectory(dir / "estimated_slam_frame.txt", in_first_camera_frame(s.estimated),
                       "estimated.txt in the frame of its first camera (first pose = identity, as "
                       "ORB-SLAM2's CameraTrajectory.txt) of " +
                           what);
  write_text(dir / "objects_gt.json", objects_gt_json(s.scene));
  write_text(dir / "synth.json", synth_json(s));
  if (s.second_visit)
    write_text(dir / "changes_gt.json", changes_gt_json(*s.second_visit, s.options.second_visit));
}

}  // namespace

void write_sequence(const fs::path& out, const SynthSequence& s, int threads) {
  io::StagingDir staging(out, io::kSyntheticSequence);
  make_folders(staging.path());
  std::vector<segmentation::FrameSegmentation> noisy(s.frames.size());
  int next_id = 1;
  for (std::size_t i = 0; i < s.frames.size(); ++i)
    if (kept(s.options, i)) noisy[i] = sparse_ids(s.frames[i].segmentation, s.options, next_id);
  parallel_for(s.frames.size(), threads, [&](std::size_t i) {
    if (!kept(s.options, i)) return;
    const SynthFrame& f = s.frames[i];
    write_images(staging.path(), f);
    write_segmentation(staging.path(), "segmentation", noisy[i]);
    write_segmentation(staging.path(), "segmentation_gt", f.segmentation_gt);
  });
  write_sequence_files(staging.path(), s);
  staging.commit();
}

SynthSequence write_synthetic_sequence(const fs::path& out, const SynthOptions& options,
                                       const SynthProgress& progress) {
  SynthSequence seq = prepare_sequence(options);
  io::StagingDir staging(out, io::kSyntheticSequence);
  make_folders(staging.path());
  const fs::path& dir = staging.path();
  const std::size_t total = seq.groundtruth.size();

  // One pass over the frames on the threads: each frame is rendered, its images and exact
  // segmentation written and its memory freed; only the exact segmentation waits in `pending`
  // for the segmentation noise, which must see the frames in time order (track ids carry over),
  // with the exact depth when the masks bleed. Whichever thread finds the next frame ready (and
  // the chain free) advances the chain, so the noise runs alongside the rendering. The files do
  // not depend on the thread count.
  SegmentationNoise noise = make_segmentation_noise(options);
  struct Pending {
    segmentation::FrameSegmentation exact;
    cv::Mat depth_exact_m;  // empty unless the masks bleed
  };
  std::vector<std::optional<Pending>> pending(total);
  std::mutex pending_mutex;       // guards `pending` and `next_in_chain`
  std::mutex chain_mutex;         // held by the thread advancing the chain (uses `noise`)
  std::size_t next_in_chain = 0;  // frames whose noisy segmentation is written
  int next_id = 1;                // a sparse export's next track id (the chain's)
  auto advance_chain = [&] {
    for (;;) {
      std::unique_lock<std::mutex> chain(chain_mutex, std::try_to_lock);
      if (!chain.owns_lock()) return;  // the owner will see our frame (it re-checks below)
      for (;;) {
        std::optional<Pending> ready;
        std::size_t index = 0;
        {
          std::lock_guard<std::mutex> lock(pending_mutex);
          if (next_in_chain >= total || !pending[next_in_chain]) break;
          index = next_in_chain;
          ready = std::move(pending[index]);
          pending[index].reset();
        }
        segmentation::FrameSegmentation noisy =
            noise.apply(ready->exact, seq.camera.width, seq.camera.height, ready->depth_exact_m);
        if (kept(options, index))
          write_segmentation(dir, "segmentation", sparse_ids(std::move(noisy), options, next_id));
        std::size_t done = 0;
        {
          std::lock_guard<std::mutex> lock(pending_mutex);
          done = ++next_in_chain;
        }
        if (progress) progress(done, total);
      }
      chain.unlock();
      // A frame may have become ready after our last look and before the unlock, while its
      // thread failed to take the chain: look again.
      std::lock_guard<std::mutex> lock(pending_mutex);
      if (next_in_chain >= total || !pending[next_in_chain]) return;
    }
  };
  parallel_for(total, options.threads, [&](std::size_t i) {
    SynthFrame f = render_synth_frame(seq, static_cast<int>(i));
    if (kept(options, i)) {
      write_images(dir, f);
      write_segmentation(dir, "segmentation_gt", f.segmentation_gt);
    }
    {
      std::lock_guard<std::mutex> lock(pending_mutex);
      pending[i] = Pending{std::move(f.segmentation_gt),
                           options.seg_noise.bleed_px > 0 ? f.depth_exact_m : cv::Mat()};
    }
    advance_chain();
  });
  require(next_in_chain == total, out.string(), "internal error: segmentation chain incomplete");
  seq.seg_stats = noise.stats();
  write_sequence_files(dir, seq);
  staging.commit();
  return seq;
}

}  // namespace objmap::sim
