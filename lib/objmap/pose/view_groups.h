#pragma once
#include <cstddef>
#include <memory>
#include <vector>

#include "objmap/core/types.h"
#include "objmap/pose/correct.h"
#include "objmap/pose/icp.h"

// The views of each object aligned to each other (point-to-plane ICP, icp.h): groups of views
// around an anchor view, whose members observe the anchor's centroid where their alignment puts
// it, and view links, the relative poses of two keyframes from two aligned views of one object
// (docs/pose.md). What `objmap correct --view-model icp` builds its problem from.
namespace objmap::pose {

// Per problem observation, its points in the world (input poses); null where there are none.
using ViewClouds = std::vector<const PointCloud*>;

struct ViewGroupOptions {
  IcpOptions icp;                         // the alignment to an anchor view
  double icp_max_view_angle_deg = 180.0;  // anchors looking from within this angle are tried
  int icp_links = 3;                      // earlier views each observation is linked to (0: none)
  double icp_link_max_view_angle_deg = 30.0;     // views further apart are not linked
  std::size_t icp_link_max_points = 1000;        // a link's view thinned to this many points
  std::size_t icp_link_max_model_points = 5000;  // ... and its model to this many
  double icp_link_sigma_scale = 3.0;    // a link's std: this many times the alignment's own
  double icp_link_max_sigma_deg = 0.5;  // a link with a larger rotation std is dropped
  int threads = 0;                      // 0 = all cores
};

struct GroupMember {
  std::size_t observation;
  Pose correction;
};

// An anchor view of an object and the views aligned to it.
struct ViewGroup {
  std::size_t landmark;
  Vec3 anchor_centroid, view;  // world frame; view: unit vector camera -> anchor centroid
  std::unique_ptr<ModelAligner> aligner;
  std::vector<GroupMember> members;
};

// The problem of problem_of_groups: a landmark per group, its object's id, and the counts.
struct GroupedProblem {
  Problem problem;
  std::vector<int> object_ids;  // per landmark
  std::size_t observations_without_view = 0;
  std::size_t observations_aligned = 0;
};

// Per object, its observations with points in keyframe order (the problem keeps them by object).
std::vector<std::vector<std::size_t>> in_keyframe_order(const Problem& problem,
                                                        const ViewClouds& source);

// One anchor per object (its first view); every other view aligns to it on its own, so all
// alignments run in parallel.
void align_to_first_views(const Problem& problem, const ViewClouds& source,
                          const std::vector<std::vector<std::size_t>>& of_landmark,
                          const ViewGroupOptions& options,
                          std::vector<std::vector<ViewGroup>>& groups);

// Groups: an observation joins the first anchor (closest direction first) that aligns it, or
// anchors a group of its own; the order matters, so each object runs in keyframe order.
void align_in_groups(const Problem& problem, const ViewClouds& source,
                     const std::vector<std::vector<std::size_t>>& of_landmark,
                     const ViewGroupOptions& options, std::vector<std::vector<ViewGroup>>& groups);

// View links: each observation aligned to a few earlier views of its object that look at the
// same side (the previous one, the earliest, the one between); an alignment measures the relative
// pose of the two keyframes. `source[i]` holds observation i's points (world frame, input poses),
// `of_landmark[j]` object j's observations in keyframe order; `tried` counts the alignments.
std::vector<ViewLink> view_links(const Problem& problem, const ViewClouds& source,
                                 const std::vector<std::vector<std::size_t>>& of_landmark,
                                 const ViewGroupOptions& options, std::size_t& tried_total);

// One anchor per object: each aligned view observes the anchor's centroid where its alignment
// puts it; the observations it does not align keep the visible-part model.
std::size_t observe_first_views(const std::vector<std::vector<ViewGroup>>& groups,
                                Problem& problem);

// The problem of the groups: one landmark per group of >= 2 members at its anchor's centroid;
// links keep their keyframes, their landmark becomes the object's first group.
GroupedProblem problem_of_groups(const std::vector<std::vector<ViewGroup>>& groups,
                                 const std::vector<ViewLink>& links, const ViewClouds& source,
                                 const Problem& problem, const std::vector<int>& object_ids);

}  // namespace objmap::pose
