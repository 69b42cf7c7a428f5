// objmap synth: writes a synthetic TUM RGB-D sequence with exact ground truth (trajectory, objects,
// segmentation) and a noisy segmentation and drifting trajectory, for tests and benchmarks.
#include <cstdio>
#include <memory>
#include <optional>
#include <set>

#include "command.h"
#include "objmap/io/atomic.h"
#include "objmap/sim/camera_path.h"
#include "objmap/sim/synth.h"
#include "objmap/sim/writer.h"
#include "progress.h"

namespace objmap::app {
namespace {

struct SynthCommand {
  std::string out;
  bool noise_free = false;
  std::optional<double> confusion_rate;  // unset: keep the per-pair defaults
  std::optional<int> new_track_after;    // unset: the preset's (walks 30 frames, else never)
  std::optional<double> merge_touching;  // unset: the preset's (walks 0.3, else 0)
  std::string second_visit_of;           // empty: a first visit
  sim::SynthOptions options;
};

void run_synth(SynthCommand& cmd) {
  sim::SynthOptions& o = cmd.options;
  if (cmd.confusion_rate)
    for (auto& c : o.seg_noise.confusions) c.probability = *cmd.confusion_rate;
  const bool walk = o.preset == "walkthrough" || o.preset == "apartment";
  o.seg_noise.new_track_after_frames = cmd.new_track_after.value_or(walk ? 30 : 0);
  o.seg_noise.merge_touching_prob = cmd.merge_touching.value_or(walk ? 0.3 : 0);
  if (cmd.noise_free) o.set_noise_free();
  if (!cmd.second_visit_of.empty()) {  // the first visit's scene: its preset and seed
    io::require_not_an_input({"--out", cmd.out}, {{"--second-visit-of", cmd.second_visit_of}});
    sim::read_first_visit(cmd.second_visit_of, o.second_visit, o.preset);
    o.second_visit.enabled = true;
  }
  o.check();
  sim::check_output_dir(cmd.out);

  std::unique_ptr<ProgressBar> bar;
  // Streaming: render and write a few frames at a time (memory does not grow with --frames).
  const sim::SynthSequence seq =
      sim::write_synthetic_sequence(cmd.out, o, [&](std::size_t done, std::size_t total) {
        if (!bar) bar = std::make_unique<ProgressBar>("synth", total);
        bar->update(done);
      });
  if (bar) bar->finish();

  std::set<std::string> classes;
  for (const auto& obj : seq.scene.objects) classes.insert(obj.class_name);
  const double length = sim::path_length_m(seq.groundtruth);
  const double end_error = (seq.estimated.poses.back().world_from_cam.translation() -
                            seq.groundtruth.poses.back().world_from_cam.translation())
                               .norm();
  std::printf("wrote         %s\n", cmd.out.c_str());
  std::printf("scene         %s, seed %llu: %zu objects of %zu classes\n", o.preset.c_str(),
              static_cast<unsigned long long>(o.seed), seq.scene.objects.size(), classes.size());
  std::printf("frames        %zu at %.0f Hz, %dx%d, depth %s\n", seq.groundtruth.size(),
              o.frame_rate_hz, seq.camera.width, seq.camera.height,
              o.depth_noise.enabled ? "with Kinect-like noise" : "exact");
  if (o.keep_every > 1)
    std::printf("written       %zu of them, one in %d, each instance with a track id of its own\n",
                (seq.groundtruth.size() + o.keep_every - 1) / o.keep_every, o.keep_every);
  std::printf("path          %.3f m; estimate ends %.3f m off (%.2f%% of the path)\n", length,
              end_error, length > 0 ? 100.0 * end_error / length : 0.0);
  const auto& st = seq.seg_stats;
  std::printf(
      "segmentation  %d true instances: %d missed, %d confused, %d false positives, "
      "%d id switches (%d re-used ids), %d new ids after an object was out of view\n",
      st.true_instances, st.missed, st.confused, st.false_positives, st.id_switches, st.id_reuses,
      st.revisit_ids);
  if (o.seg_noise.merge_touching_prob > 0.0)
    std::printf("packed        %d instances given inside another's mask (touching, one class)\n",
                st.merged);
  if (seq.second_visit) {
    int moved = 0, removed = 0, added = 0;
    for (const auto& c : seq.second_visit->changes) {
      moved += c.status == "moved";
      removed += c.status == "removed";
      added += c.status == "added";
    }
    std::printf("second visit  of %s: %d moved, %d removed, %d added; changes_gt.json\n",
                cmd.second_visit_of.c_str(), moved, removed, added);
  }
  if (o.seg_noise.bleed_px > 0)
    std::printf("mask bleed    %lld pixels added behind the objects (up to %d px from the masks)\n",
                st.bleed_pixels, o.seg_noise.bleed_px);
}

void setup_synth(CLI::App& app) {
  auto cmd = std::make_shared<SynthCommand>();
  sim::SynthOptions& o = cmd->options;
  auto* c = app.add_subcommand(
      "synth",
      "Write a synthetic TUM RGB-D sequence (ray-cast room, table(s) and the paper's eight object "
      "classes) with exact ground truth: groundtruth.txt, objects_gt.json (objects, up, support "
      "surfaces, 'on' relations), segmentation_gt/, and a noisy segmentation/ and drifting "
      "estimated.txt (and estimated_slam_frame.txt: the same in its first camera's frame). Same "
      "seed and options: identical files.");
  c->add_option("--out", cmd->out,
                "output folder (an earlier synthetic sequence there is replaced; any other folder "
                "is refused)")
      ->required();
  c->add_option("--seed", o.seed, "random seed")
      ->check([](const std::string& text) {
        // CLI11 wraps "-1" round to 2^64 - 1 for an unsigned option.
        return text.find_first_not_of("0123456789") == std::string::npos && !text.empty()
                   ? std::string()
                   : "must be a whole number >= 0, got '" + text + "'";
      })
      ->capture_default_str();
  c->add_option("--frames", o.frames, "number of frames (30 Hz)")->capture_default_str();
  c->add_option("--keep-every", o.keep_every,
                "a sparse export, as scans exported for 3D detection are (one frame in ~18): "
                "write only frames 0, K, 2K, ..., each instance with a track id of its own (no "
                "tracker carries an id across such gaps)")
      ->capture_default_str();
  c->add_option("--orbit-speed", o.orbit_speed_deg_per_s,
                "camera azimuth rate around the table, deg/s (0: the preset's, 20 for tabletop)")
      ->capture_default_str();
  c->add_option("--preset", o.preset,
                "scene: tabletop (one table), office (two tables), edge (a small table, its "
                "objects at the edges, the floor behind them: for the mask bleed), walkthrough "
                "(an 8 x 6 m room, three tables, 12 chairs, objects on the tables and the floor; "
                "the camera walks round it, 318 frames a loop: --frames 954 passes every table "
                "three times) or apartment (a bed, a couch, a refrigerator, a toilet, a dining "
                "table with two chairs, a television; 248 frames a loop: with --keep-every 18, "
                "the large furniture of scans exported for 3D detection)")
      ->capture_default_str();
  c->add_flag("--noise-free", cmd->noise_free,
              "exact depth and segmentation, no image noise, no drift (overrides the knobs below)");
  c->add_option("--threads", o.threads, "worker threads (0 = all cores)")->capture_default_str();
  c->add_option("--scale", o.resolution_scale, "image size as a fraction of 640x480")
      ->capture_default_str();
  c->add_option("--rgb-noise", o.rgb_noise_sigma, "colour noise sigma, grey levels")
      ->capture_default_str();
  c->add_option("--depth-offset", o.depth_time_offset_s, "depth timestamp - rgb timestamp, s")
      ->capture_default_str();
  c->add_option("--depth-sigma-base", o.depth_noise.sigma_base_m,
                "depth noise sigma(z) = base + quadratic * (z - 0.4)^2, metres")
      ->capture_default_str();
  c->add_option("--depth-sigma-quadratic", o.depth_noise.sigma_quadratic,
                "quadratic term of sigma(z), 1/m")
      ->capture_default_str();
  c->add_option("--disparity-step", o.depth_noise.disparity_step_px,
                "disparity quantisation step, pixels (0 = none)")
      ->capture_default_str();
  c->add_option("--max-range", o.depth_noise.max_range_m, "no depth beyond this, metres")
      ->capture_default_str();
  c->add_option("--edge-missing", o.depth_noise.edge_missing_prob,
                "probability that a pixel at a depth edge has no depth")
      ->capture_default_str();
  c->add_option("--depth-dropout", o.depth_noise.dropout_prob,
                "probability of a missing depth pixel anywhere")
      ->capture_default_str();
  c->add_option("--miss-rate", o.seg_noise.miss_prob, "probability of a missed detection")
      ->capture_default_str();
  c->add_option("--false-positives", o.seg_noise.false_positives_per_frame,
                "mean number of false detections per frame")
      ->capture_default_str();
  c->add_option("--confusion-rate", cmd->confusion_rate,
                "probability of teddy bear -> person and mouse -> cup (default 0.15 each)");
  c->add_option("--mask-boundary", o.seg_noise.boundary_px,
                "masks are eroded/dilated by up to this many pixels")
      ->capture_default_str();
  c->add_option("--mask-bleed-px", o.seg_noise.bleed_px,
                "masks also cover the pixels up to this far beyond the object's silhouette where "
                "the scene behind it shows (table, floor, wall, a farther object; never an "
                "occluder in front), as real masks overlap by 1-4 px; at a table's edge these "
                "back-project far behind the object (0 = off)")
      ->capture_default_str();
  c->add_option("--min-area", o.seg_noise.min_area_px, "smallest reported mask, pixels")
      ->capture_default_str();
  c->add_option("--id-switch-rate", o.seg_noise.id_switch_prob,
                "probability per instance and frame that a track changes its ID")
      ->capture_default_str();
  c->add_option("--new-track-after", cmd->new_track_after,
                "an object out of view for more than this many frames gets a new track ID when "
                "seen again, as a tracker that lost it gives (default: 30 for walkthrough, else "
                "never; 0 = never)");
  c->add_option("--merge-touching-rate", cmd->merge_touching,
                "share of the frames in which two instances of one class whose masks touch are "
                "given as one mask with the larger's track ID, as detectors do with chairs packed "
                "along a table (default: 0.3 for walkthrough, else 0)");
  c->add_option("--id-reuse", o.seg_noise.id_reuse_prob,
                "share of ID switches that re-use an ID dropped by another track")
      ->capture_default_str();
  c->add_option("--drift", o.drift.translation_fraction,
                "translation drift of estimated.txt at the end, fraction of the path length")
      ->capture_default_str();
  c->add_option("--yaw-drift", o.drift.yaw_deg_per_m, "yaw drift rate sigma, degrees per metre")
      ->capture_default_str();
  c->add_option("--second-visit-of", cmd->second_visit_of,
                "a second visit of the scene of this synth folder (its preset and seed): objects "
                "moved, removed and added (--move, --remove, --add; --seed drives the changes), "
                "another start pose, another world frame (a random yaw about up and a shift); "
                "writes changes_gt.json for objmap eval diff");
  c->add_option("--move", o.second_visit.move, "--second-visit-of: objects moved on the tables")
      ->capture_default_str();
  c->add_option("--remove", o.second_visit.remove, "--second-visit-of: objects taken away")
      ->capture_default_str();
  c->add_option("--add", o.second_visit.add, "--second-visit-of: objects added on the tables")
      ->capture_default_str();
  c->callback([cmd] { run_synth(*cmd); });
}

}  // namespace

OBJMAP_COMMAND(0, "synth", setup_synth);

}  // namespace objmap::app
