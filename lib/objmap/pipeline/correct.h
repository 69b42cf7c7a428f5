#pragma once
#include <filesystem>
#include <string>
#include <vector>

#include "objmap/pipeline/fuse.h"
#include "objmap/pose/correct.h"
#include "objmap/pose/icp.h"
#include "objmap/pose/visible.h"

// `objmap correct`: object-constrained pose correction of a finished fuse run (paper §3.4,
// eqs 19-20; "graph" goes beyond the paper). Reads RUN/run.json (inputs and fuse options),
// RUN/objects.json (objects and their per-keyframe observations) and RUN/objects/*.ply (the object
// models), corrects the keyframe poses of the run's trajectory, spreads the corrections to every
// pose of it, fuses the map again with the corrected trajectory and writes OUT as a complete run
// folder plus OUT/trajectory_corrected.txt and OUT/correction.json
// (schemas/correction.schema.json). The input trajectory is never written. A refused correction
// still writes OUT: the input poses as trajectory_corrected.txt, the input run's map, and the
// reason in correction.json.
namespace objmap::pipeline {

struct CorrectOptions {
  std::filesystem::path run;  // a fuse run folder (run.json, objects.json, objects/)
  std::filesystem::path out;  // output run folder (replaced when complete)
  // How an observed centroid is compared with its object (docs/pose.md):
  // "icp" (default): each observation's points (re-made from the run's inputs) aligned by
  // point-to-plane ICP to the first view of its object (the anchor): the anchor's centroid where
  // that alignment puts it in the camera frame; observations that do not align fall back to
  // "visible". "visible": the centroid of the part of the object model visible from the keyframe
  // (partial-view bias removed). "centroid": the whole model's centroid (the paper).
  std::string view_model = "icp";
  pose::VisibilityOptions visibility;     // z-buffer rendering of the models
  pose::IcpOptions icp;                   // view_model icp
  double icp_max_view_angle_deg = 180.0;  // icp: anchors looking from within this angle are tried
  // icp: true: an observation no anchor aligns starts a new group (a landmark of its own); false:
  // one anchor per object (its first view) and the other observations keep the visible model.
  bool icp_groups = false;
  // icp: view links. Each observation is also aligned to up to this many earlier views of its
  // object that look at it from within icp_link_max_view_angle_deg (the previous such view, the
  // earliest and the one between); each alignment is a relative-pose factor between the two
  // keyframes in the graph. 0: no links.
  int icp_links = 3;
  double icp_link_max_view_angle_deg = 30.0;
  // Link alignments use thinner clouds than the anchor alignment (many more pairs): the view
  // thinned to this many points, each model to this many.
  std::size_t icp_link_max_points = 1000;
  std::size_t icp_link_max_model_points = 5000;
  // A link's std is this many times the alignment's own (rms² · H⁻¹; ICP errors are correlated
  // and larger than that); a link whose rotation std exceeds icp_link_max_sigma_deg is dropped.
  double icp_link_sigma_scale = 3.0;
  double icp_link_max_sigma_deg = 0.5;
  // With view links the bounds grow with the path travelled (correction.max_translation_fraction,
  // max_rotation_deg_per_m set to these); when the links do not confirm a correction, the problem
  // is solved again without them and with correction's own bounds. false: correction's bounds for
  // both (set when --max-translation-per-m or --max-rotation-per-m is given).
  bool link_bounds = true;
  double link_max_translation_per_m = 0.03;
  double link_max_rotation_deg_per_m = 1.5;
  // Acceptance thresholds by view model (correction.min_improvement, min_held_out_improvement):
  // icp 0.15 / 0.0, visible and centroid 0.10 / 0.20 (docs/pose.md: calibrated on synthetic
  // scenes with and without drift). false: correction's own values.
  bool view_model_thresholds = true;
  pose::CorrectionOptions correction;  // method (graph | paper), evidence, noise, bounds
  // After the re-fuse, the map's own consistency (median object scatter of the new run) must not
  // exceed the input run's, else the whole result is refused.
  bool check_map = true;
  int threads = 0;     // for the re-fuse and the observations' ICP; 0 = all cores
  void check() const;  // throws InputError naming the bad field
};

struct CorrectResult {
  pose::CorrectionResult correction;
  std::size_t landmarks = 0, observations = 0;
  std::size_t observations_without_view = 0;  // visible part too small: bias 0
  std::size_t observations_aligned = 0;       // view_model icp: aligned to their model
  std::size_t links = 0, links_tried = 0;     // view_model icp: view links made / pairs tried
  bool links_used = false;            // the accepted correction is the one with the view links
  std::string reason_with_links;      // why the correction with view links was refused (else empty)
  pose::CorrectionResult with_links;  // the solve with the view links (when there were any)
  bool accepted = false;              // the final verdict (correction and the re-fused map's check)
  std::string reason;
  double map_rms_before_m = 0.0;  // median object scatter of the input run (median_scatter_m)
  double map_rms_after_m = 0.0;   // ... of the re-fused run (0 when not re-fused)
  // Objects with observations in the input run and in the re-fused one (with view links, fewer
  // objects after lets the scatter rise: observations of a split object joined again).
  std::size_t map_objects_before = 0, map_objects_after = 0;
  bool refused_map = false;  // the map was fused again
  FuseResult fuse;           // the re-fuse (empty when refused before it)
  double seconds_correct = 0.0, seconds_total = 0.0;
};

// The problem a run poses: keyframes (timestamps of the observations, poses of `trajectory`),
// landmarks (confirmed objects seen by >= 1 keyframe, at their models' centroids), observations
// (centroid_in_cam, bias from the visible part when view_model is "visible").
struct RunProblem {
  pose::Problem problem;
  std::vector<int> object_ids;                     // per landmark
  std::vector<std::vector<int>> keyframe_objects;  // per keyframe, the object ids it observed
  std::size_t observations_without_view = 0;
  std::size_t observations_aligned = 0;  // view_model icp: observations aligned to their model
  std::size_t links_tried = 0;           // view_model icp: view pairs aligned for links
};
// `options` gives the view model (and for icp: the ICP options, threads, and OUT, beside which a
// temporary folder is made).
RunProblem problem_from_run(const std::filesystem::path& run, const Trajectory& trajectory,
                            const CorrectOptions& options);

// Runs the correction and writes OUT. Throws InputError for a bad run folder or options.
CorrectResult run_correct(const CorrectOptions& options, const FuseProgress& progress = {});

// `objmap fuse --correct-poses`: fuse into a temporary run folder, correct it into fuse.out, and
// remove the temporary folder. `correct.run` and `correct.out` are ignored.
CorrectResult run_fuse_and_correct(const FuseOptions& fuse, const CorrectOptions& correct,
                                   const FuseProgress& progress = {});

}  // namespace objmap::pipeline
