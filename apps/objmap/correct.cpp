// objmap correct: object-constrained pose correction of a fuse run, then the map fused again.
#include <cstdio>
#include <memory>

#include "command.h"
#include "objmap/pipeline/correct.h"
#include "progress.h"

namespace objmap::app {
namespace {

void add_correction_flags(CLI::App* cmd, pipeline::CorrectOptions& o) {
  auto& c = o.correction;
  cmd->add_option("--method", c.method,
                  "graph: one pose graph over keyframes (odometry from the trajectory) and object "
                  "landmarks; paper: eq 20 alone per keyframe (Horn/Umeyama + robust refinement)")
      ->check(CLI::IsMember({"graph", "paper"}))
      ->capture_default_str();
  cmd->add_option("--paper-prior", c.paper_prior,
                  "paper: add a prior on each input pose with the drift the run may have "
                  "accumulated as its std (beyond the paper); false: eq 20 alone (the paper)")
      ->capture_default_str();
  cmd->add_option("--view-model", o.view_model,
                  "icp: align each observation's points to the object's first view "
                  "(point-to-plane ICP on the depth pixels) and use where that puts the first "
                  "view's centroid; observations that do not align fall back to visible; "
                  "visible: compare an observed centroid with the centroid of the object model's "
                  "part visible from the keyframe; centroid: with the whole model's (the paper)")
      ->check(CLI::IsMember({"icp", "visible", "centroid"}))
      ->capture_default_str();
  cmd->add_option("--icp-max-view-angle", o.icp_max_view_angle_deg,
                  "icp: an observation is aligned to earlier views of its object that look at it "
                  "from within this angle, degrees")
      ->capture_default_str();
  cmd->add_option("--icp-groups", o.icp_groups,
                  "icp: an observation that no earlier view aligns starts a group of its own "
                  "(true), or keeps the visible model against its object's first view (false)")
      ->capture_default_str();
  cmd->add_option("--icp-links", o.icp_links,
                  "icp: align each observation also to up to this many earlier views of its "
                  "object (the previous, the earliest, one between) that look at it from within "
                  "--icp-link-max-view-angle; each alignment is a relative-pose factor between "
                  "the two keyframes (graph); 0: none")
      ->check(CLI::Range(0, 3))
      ->capture_default_str();
  cmd->add_option("--icp-link-max-view-angle", o.icp_link_max_view_angle_deg,
                  "icp: views of an object further apart than this angle are not linked, degrees")
      ->capture_default_str();
  cmd->add_option("--link-sigma", c.link_sigma_m, "graph: std of a view link's translation, metres")
      ->capture_default_str();
  cmd->add_option("--link-sigma-deg", c.link_sigma_deg,
                  "graph: std of a view link's rotation, degrees")
      ->capture_default_str();
  cmd->add_option("--held-out-link-improvement", c.min_held_out_link_improvement,
                  "with view links: links held out of the fit must get this share closer to the "
                  "corrected poses (RMS in sigmas), else refused")
      ->capture_default_str();
  cmd->add_option("--icp-inlier-distance", o.icp.inlier_distance_m,
                  "icp: after the alignment, a point this close to the earlier view counts as "
                  "overlapping, metres")
      ->capture_default_str();
  cmd->add_option("--icp-min-overlap", o.icp.min_inlier_share,
                  "icp: share of an observation's points that must overlap the earlier view for "
                  "the alignment to count")
      ->capture_default_str();
  cmd->add_option("--min-pairs", c.min_pairs, "matched objects needed to correct a keyframe")
      ->capture_default_str();
  cmd->add_option("--observation-sigma", c.observation_sigma_m,
                  "floor of an object's centroid noise, metres (each object's own noise is "
                  "estimated from its observations)")
      ->capture_default_str();
  cmd->add_option("--odometry-sigma-fraction", c.odometry_sigma_fraction,
                  "graph: std of a relative pose, share of the step length")
      ->capture_default_str();
  cmd->add_option("--ray-sigma-factor", c.ray_sigma_factor,
                  "graph: an observed centroid's std along the viewing ray, times the lateral std")
      ->capture_default_str();
  cmd->add_option("--max-translation", c.max_translation_m,
                  "a larger correction of any keyframe refuses the result, metres")
      ->capture_default_str();
  cmd->add_option("--max-translation-per-m", c.max_translation_fraction,
                  "the translation bound grows by this share of the path travelled to the "
                  "keyframe (drift grows with the path); default: 0.03 for the correction with "
                  "view links, 0 without")
      ->each([&o](const std::string&) { o.link_bounds = false; });
  cmd->add_option("--max-rotation", c.max_rotation_deg,
                  "a larger correction of any keyframe refuses the result, degrees")
      ->capture_default_str();
  cmd->add_option("--max-rotation-per-m", c.max_rotation_deg_per_m,
                  "the rotation bound grows by this many degrees per metre travelled; default: "
                  "1.5 for the correction with view links, 0 without")
      ->each([&o](const std::string&) { o.link_bounds = false; });
  cmd->add_option("--held-out-improvement", c.min_held_out_improvement,
                  "corrections fitted to half of the objects must lower the other half's "
                  "residual RMS by this share, else refused (negative: a worsening allowed); "
                  "default by view model: icp 0, visible/centroid 0.2")
      ->each([&o](const std::string&) { o.view_model_thresholds = false; });
  cmd->add_option("--reweight-rounds", c.reweight_rounds,
                  "re-estimate each object's noise from the solution and solve again")
      ->capture_default_str();
  cmd->add_option("--min-improvement", c.min_improvement,
                  "the observation residual RMS must drop by this share, else refused; default "
                  "by view model: icp 0.15, visible/centroid 0.1")
      ->each([&o](const std::string&) { o.view_model_thresholds = false; });
}

void print_summary(const pipeline::CorrectOptions& o, const pipeline::CorrectResult& r) {
  const auto& c = r.correction;
  std::printf("method      %s (view model %s)\n", c.method.c_str(), o.view_model.c_str());
  std::printf("problem     %zu keyframes, %zu objects, %zu observations\n", c.keyframes.size(),
              r.landmarks, r.observations);
  if (o.view_model == "icp")
    std::printf("icp         %zu of %zu observations aligned to their model\n",
                r.observations_aligned, r.observations);
  if (o.view_model == "icp" && o.icp_links > 0)
    std::printf("links       %zu view links of %zu pairs tried; %s\n", r.links, r.links_tried,
                r.links_used  ? "used"
                : r.links > 0 ? "not used (they do not confirm)"
                              : "none");
  std::printf("residual    %.4f -> %.4f m (observation RMS)\n", c.residual_before_m,
              c.residual_after_m);
  std::printf("largest     %.4f m, %.3f deg\n", c.max_translation_m, c.max_rotation_deg);
  std::printf("result      %s\n", r.reason.c_str());
  std::printf("time        %.2f s correction, %.2f s total\n", r.seconds_correct, r.seconds_total);
  std::printf("written     %s/{trajectory_corrected.txt, correction.json, objects.json, ...}\n",
              o.out.c_str());
}

void setup_correct(CLI::App& app) {
  auto options = std::make_shared<pipeline::CorrectOptions>();
  auto* cmd = app.add_subcommand(
      "correct",
      "Correct the keyframe poses of a fuse run with its objects as landmarks (paper 3.4, eq 20; "
      "default: a pose graph), then fuse again. Writes OUT as a run folder plus "
      "OUT/trajectory_corrected.txt and OUT/correction.json; the input trajectory is never "
      "written. A refused correction keeps the input poses and says why.");
  cmd->add_option("--run", options->run, "fuse run folder (run.json, objects.json, objects/)")
      ->required();
  cmd->add_option("--out", options->out,
                  "output run folder (an earlier run there is replaced when complete; any other "
                  "folder is refused)")
      ->required();
  add_correction_flags(cmd, *options);
  cmd->add_option("--threads", options->threads, "threads of the re-fuse (0 = all cores)")
      ->capture_default_str();
  cmd->callback([options] {
    check_naming_flags(
        [&] { options->check(); },
        {{"CorrectOptions.icp_max_view_angle_deg", "--icp-max-view-angle"},
         {"CorrectOptions.icp_links", "--icp-links"},
         {"CorrectOptions.icp_link_max_view_angle_deg", "--icp-link-max-view-angle"},
         {"CorrectOptions.threads", "--threads"},
         {"IcpOptions.inlier_distance_m", "--icp-inlier-distance"},
         {"IcpOptions.min_inlier_share", "--icp-min-overlap"},
         {"CorrectionOptions.link_sigma_m", "--link-sigma"},
         {"CorrectionOptions.link_sigma_deg", "--link-sigma-deg"},
         {"CorrectionOptions.min_held_out_link_improvement", "--held-out-link-improvement"},
         {"CorrectionOptions.min_pairs", "--min-pairs"},
         {"CorrectionOptions.observation_sigma_m", "--observation-sigma"},
         {"CorrectionOptions.odometry_sigma_fraction", "--odometry-sigma-fraction"},
         {"CorrectionOptions.ray_sigma_factor", "--ray-sigma-factor"},
         {"CorrectionOptions.max_translation_m", "--max-translation"},
         {"CorrectionOptions.max_translation_fraction", "--max-translation-per-m"},
         {"CorrectionOptions.max_rotation_deg", "--max-rotation"},
         {"CorrectionOptions.max_rotation_deg_per_m", "--max-rotation-per-m"},
         {"CorrectionOptions.min_held_out_improvement", "--held-out-improvement"},
         {"CorrectionOptions.reweight_rounds", "--reweight-rounds"},
         {"CorrectionOptions.min_improvement", "--min-improvement"}});
    std::unique_ptr<ProgressBar> bar;
    const auto result = pipeline::run_correct(*options, [&](std::size_t done, std::size_t total) {
      if (!bar) bar = std::make_unique<ProgressBar>("re-fuse", total, "keyframes");
      bar->update(done);
    });
    if (bar) bar->finish();
    print_summary(*options, result);
  });
}

}  // namespace

OBJMAP_COMMAND(50, "correct", setup_correct);

}  // namespace objmap::app
