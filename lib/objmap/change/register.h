#pragma once
#include <string>

#include "objmap/change/visit.h"
#include "objmap/core/types.h"

// Registration of two visits' world frames (docs/change.md, "Registration"). Each map knows its up
// direction, so the unknowns are 4: the yaw about up and a translation. Step 1: a coarse estimate
// from the objects (pairs of same-class object pairs vote for a yaw and a translation, the
// hypothesis with most same-class objects in agreement wins, refined by least squares on them).
// Step 2: PCL's ICP of the two dense maps from there, restricted to the same 4 DoF. Step 3: the
// fitness (share of the after map's points close to the before map) and the uncertainty of the
// result (point-to-plane information of the final pairs).
namespace objmap::change {

struct RegistrationOptions {
  double object_match_m = 0.25;  // coarse: a same-class pair agrees within this distance
  double min_pair_span_m = 0.2;  // coarse: two objects closer than this do not fix a yaw
  int min_common_objects = 2;    // fewer objects agree with the best hypothesis: not credible
                                 // (two fix a yaw; the dense maps must then agree: fitness)
  std::size_t max_hypotheses = 200000;     // beyond this, a fixed-seed sample of the pairs of pairs
  double icp_voxel_m = 0.03;               // dense maps thinned to one point per voxel for ICP
  std::size_t icp_max_points = 10000;      // ICP points of the map moved (the smaller), at most
  double icp_max_correspondence_m = 0.15;  // first rounds pair points closer than this ...
  double icp_final_correspondence_m = 0.04;  // ... shrinking to this
  int icp_max_iterations = 30;               // per round (three rounds)
  double icp_crop_margin_m = 1.0;  // ICP uses the dense points within the common objects' spread
                                   // + this (horizontally) of their centroid
  // A last ICP round in all 6 DoF: corrects where the two maps' up estimates disagree (a short run
  // estimates its up a few degrees off); the result's tilt is reported.
  bool refine_tilt = true;
  double inlier_m = 0.03;    // fitness: an after point within this of the before map
  double min_fitness = 0.3;  // a lower fitness: not credible
  // Fewer common objects than min_common_objects (one, found by a yaw sweep about it): credible
  // only when both maps' shares near the other reach this (a wall and one object fit anywhere).
  double min_fitness_few_objects = 0.6;
  void check() const;  // throws InputError naming the bad field
};

struct Registration {
  Pose before_from_after = Pose::Identity();  // world of the before map from world of the after
  double yaw_deg = 0.0;                       // about up (the before map's gravity frame)
  double tilt_deg = 0.0;       // the after map's up, registered, against the before map's
  int common_objects = 0;      // coarse: objects that agree with the chosen hypothesis
  double coarse_rms_m = 0.0;   // coarse: RMS distance of those pairs after the refinement
  std::size_t hypotheses = 0;  // coarse: pairs of pairs tried
  double fitness = 0.0;        // the larger of the two maps' shares of points near the other
  double fitness_both = 0.0;   // the smaller of the two maps' shares (the fitness: the larger)
  double rms_m = 0.0;          // RMS distance of those inliers
  std::size_t icp_points = 0;  // points of the map moved (the smaller) used by ICP
  // Uncertainty: standard deviations from rms² · H⁻¹ of the point-to-plane problem in the 4
  // unknowns at the end (the least constrained translation direction, and the yaw).
  double sigma_translation_m = 0.0;
  double sigma_yaw_deg = 0.0;
  // A realistic uncertainty, from the common objects: their residuals after the registration give
  // a per-axis σ (3n − 4 degrees of freedom); a 4-DoF fit to n of them spread r (RMS horizontal
  // distance from their centroid) has σ/√n per translation axis and σ/(√n r) in yaw; at the
  // objects, the expected RMS error sqrt(3σ²/n + (σ_yaw r)²). Infinite with fewer than 2 objects.
  double uncertainty_at_objects_m = 0.0;
  double uncertainty_yaw_deg = 0.0;
  std::string source = "objects+icp";  // "objects+icp", or "given" (--align)
  bool credible = false;
  std::string why;  // when not credible: "too few common objects (2 of 3 needed)" or the fitness
};

// Registers `after` to `before`. Never throws for data that does not register: the result says
// credible = false and why. Deterministic.
Registration register_visits(const Visit& before, const Visit& after,
                             const RegistrationOptions& options);

// The fitness and uncertainty of a given transform (--align): the same figures as above, no search.
Registration score_registration(const Visit& before, const Visit& after,
                                const Pose& before_from_after, const RegistrationOptions& options);

// The yaw (degrees, about up) and the translation of a 4-DoF transform given in two gravity frames.
double yaw_deg_of(const Eigen::Matrix3d& rotation);

// Classes a detector takes for one another (a monitor is a "tv" in one run, a "laptop" in the
// next): the coarse step pairs them as one kind; the statuses do not.
bool same_kind(const std::string& a, const std::string& b);

}  // namespace objmap::change
