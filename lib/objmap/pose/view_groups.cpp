#include "objmap/pose/view_groups.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <optional>

#include "objmap/core/parallel.h"
#include "objmap/geometry/bounds.h"

namespace objmap::pose {

namespace {

constexpr double kRadPerDeg = 3.14159265358979323846 / 180.0;

// The direction from the keyframe's camera to observation i's centroid, world frame.
Vec3 view_direction(const Problem& problem, std::size_t i) {
  const Pose& pose = problem.keyframes[problem.observations[i].keyframe].world_from_cam;
  return (pose * problem.observations[i].centroid_in_cam - pose.translation()).normalized();
}

ViewGroup make_group(const Problem& problem, const ViewClouds& source,
                     const ViewGroupOptions& options, std::size_t j, std::size_t i) {
  ViewGroup group;
  group.landmark = j;
  group.anchor_centroid = geometry::centroid(*source[i]);
  group.view = view_direction(problem, i);
  group.aligner = std::make_unique<ModelAligner>(*source[i], options.icp);
  group.members.push_back({i, Pose::Identity()});
  return group;
}

}  // namespace

// Per object, its observations with points in keyframe order (the problem keeps them by object).
std::vector<std::vector<std::size_t>> in_keyframe_order(const Problem& problem,
                                                        const ViewClouds& source) {
  std::vector<std::vector<std::size_t>> of_landmark(problem.landmarks.size());
  for (std::size_t i = 0; i < problem.observations.size(); ++i)
    if (source[i]) of_landmark[problem.observations[i].landmark].push_back(i);
  for (auto& v : of_landmark)
    std::stable_sort(v.begin(), v.end(), [&](std::size_t a, std::size_t b) {
      return problem.observations[a].keyframe < problem.observations[b].keyframe;
    });
  return of_landmark;
}

// One anchor per object (its first view); every other view aligns to it on its own, so all
// alignments run in parallel.
void align_to_first_views(const Problem& problem, const ViewClouds& source,
                          const std::vector<std::vector<std::size_t>>& of_landmark,
                          const ViewGroupOptions& options,
                          std::vector<std::vector<ViewGroup>>& groups) {
  const double cos_max = std::cos(options.icp_max_view_angle_deg * kRadPerDeg);
  parallel_for(problem.landmarks.size(), options.threads, [&](std::size_t j) {
    if (!of_landmark[j].empty())
      groups[j].push_back(make_group(problem, source, options, j, of_landmark[j].front()));
  });
  std::vector<std::pair<std::size_t, std::size_t>> jobs;  // (landmark, observation)
  for (std::size_t j = 0; j < of_landmark.size(); ++j)
    for (std::size_t k = 1; k < of_landmark[j].size(); ++k) jobs.emplace_back(j, of_landmark[j][k]);
  std::vector<std::optional<Pose>> aligned(jobs.size());
  parallel_for(jobs.size(), options.threads, [&](std::size_t n) {
    const auto [j, i] = jobs[n];
    const ViewGroup& g = groups[j].front();
    if (g.view.dot(view_direction(problem, i)) < cos_max) return;
    const IcpResult r = g.aligner->align(*source[i]);
    if (r.aligned) aligned[n] = r.correction;
  });
  for (std::size_t n = 0; n < jobs.size(); ++n)
    if (aligned[n]) groups[jobs[n].first].front().members.push_back({jobs[n].second, *aligned[n]});
}

void align_in_groups(const Problem& problem, const ViewClouds& source,
                     const std::vector<std::vector<std::size_t>>& of_landmark,
                     const ViewGroupOptions& options, std::vector<std::vector<ViewGroup>>& groups) {
  const double cos_max = std::cos(options.icp_max_view_angle_deg * kRadPerDeg);
  parallel_for(problem.landmarks.size(), options.threads, [&](std::size_t j) {
    auto& mine = groups[j];
    for (std::size_t i : of_landmark[j]) {
      const Vec3 view = view_direction(problem, i);
      std::vector<std::pair<double, std::size_t>> candidates;
      for (std::size_t g = 0; g < mine.size(); ++g) {
        const double c = mine[g].view.dot(view);
        if (c >= cos_max) candidates.emplace_back(-c, g);
      }
      std::sort(candidates.begin(), candidates.end());
      bool joined = false;
      for (const auto& [c, g] : candidates) {
        const IcpResult r = mine[g].aligner->align(*source[i]);
        if (!r.aligned) continue;
        mine[g].members.push_back({i, r.correction});
        joined = true;
        break;
      }
      if (!joined) mine.push_back(make_group(problem, source, options, j, i));
    }
  });
}

// View links: each observation aligned to a few earlier views of its object that look at the
// same side (the previous one, the earliest, the one between); an alignment measures the relative
// pose of the two keyframes. `source[i]` holds observation i's points (world frame, input poses),
// `of_landmark[j]` object j's observations in keyframe order; `tried` counts the alignments.
std::vector<ViewLink> view_links(const Problem& problem, const ViewClouds& source,
                                 const std::vector<std::vector<std::size_t>>& of_landmark,
                                 const ViewGroupOptions& options, std::size_t& tried_total) {
  std::vector<ViewLink> links;
  const double cos_link = std::cos(options.icp_link_max_view_angle_deg * kRadPerDeg);
  IcpOptions link_icp = options.icp;
  link_icp.max_points = options.icp_link_max_points;
  link_icp.max_model_points = options.icp_link_max_model_points;
  for (std::size_t j = 0; j < of_landmark.size(); ++j) {
    const std::vector<std::size_t>& mine = of_landmark[j];
    if (mine.size() < 2) continue;
    std::vector<Vec3> view(mine.size());
    std::vector<std::unique_ptr<ModelAligner>> aligners(mine.size());
    parallel_for(mine.size(), options.threads, [&](std::size_t p) {
      view[p] = view_direction(problem, mine[p]);
      aligners[p] = std::make_unique<ModelAligner>(*source[mine[p]], link_icp);
    });
    std::vector<std::vector<ViewLink>> found(mine.size());
    std::vector<std::size_t> tried(mine.size(), 0);
    parallel_for(mine.size(), options.threads, [&](std::size_t p) {
      const std::size_t kb = problem.observations[mine[p]].keyframe;
      std::vector<std::size_t> candidates;
      for (std::size_t q = 0; q < p; ++q)
        if (problem.observations[mine[q]].keyframe != kb && view[q].dot(view[p]) >= cos_link)
          candidates.push_back(q);
      if (candidates.empty()) return;
      std::vector<std::size_t> targets = {candidates.back(), candidates.front(),
                                          candidates[candidates.size() / 2]};
      targets.resize(std::min<std::size_t>(targets.size(), options.icp_links));
      std::sort(targets.begin(), targets.end());
      targets.erase(std::unique(targets.begin(), targets.end()), targets.end());
      const Pose& pose_b = problem.keyframes[kb].world_from_cam;
      for (std::size_t q : targets) {
        ++tried[p];
        const IcpResult r = aligners[q]->align(*source[mine[p]]);
        if (!r.aligned || !std::isfinite(r.rotation_sigma_deg)) continue;
        const std::size_t ka = problem.observations[mine[q]].keyframe;
        const Pose& pose_a = problem.keyframes[ka].world_from_cam;
        // A rotation error about the object's centre moves the camera by that angle times its
        // distance.
        const double distance = (r.centre - pose_b.translation()).norm();
        const double scale = options.icp_link_sigma_scale;
        ViewLink link{ka, kb, j, pose_a.inverse() * r.correction * pose_b};
        link.sigma_deg = scale * r.rotation_sigma_deg;
        link.sigma_m =
            scale * (r.translation_sigma_m + r.rotation_sigma_deg * M_PI / 180.0 * distance);
        if (link.sigma_deg > options.icp_link_max_sigma_deg) continue;
        found[p].push_back(link);
      }
    });
    for (std::size_t p = 0; p < mine.size(); ++p) {
      links.insert(links.end(), found[p].begin(), found[p].end());
      tried_total += tried[p];
    }
  }
  return links;
}

// One anchor per object: each aligned view observes the anchor's centroid where its alignment
// puts it; the observations it does not align keep the visible-part model.
std::size_t observe_first_views(const std::vector<std::vector<ViewGroup>>& groups,
                                Problem& problem) {
  std::size_t aligned = 0;
  for (std::size_t j = 0; j < groups.size(); ++j) {
    if (groups[j].empty() || groups[j][0].members.size() < 2) continue;
    const ViewGroup& g = groups[j][0];
    for (const GroupMember& m : g.members) {
      Observation& o = problem.observations[m.observation];
      o.centroid_in_cam = (m.correction * problem.keyframes[o.keyframe].world_from_cam).inverse() *
                          g.anchor_centroid;
      o.bias_in_world = g.anchor_centroid - problem.landmarks[j].position_in_world;
      ++aligned;
    }
  }
  return aligned;
}

// The problem of the groups: one landmark per group of >= 2 members at its anchor's centroid;
// links keep their keyframes, their landmark becomes the object's first group.
GroupedProblem problem_of_groups(const std::vector<std::vector<ViewGroup>>& groups,
                                 const std::vector<ViewLink>& links, const ViewClouds& source,
                                 const Problem& problem, const std::vector<int>& object_ids) {
  GroupedProblem out;
  out.problem.keyframes = problem.keyframes;
  out.observations_without_view = 0;
  for (std::size_t j = 0; j < groups.size(); ++j) {
    for (const ViewGroup& g : groups[j]) {
      if (g.members.size() < 2) {
        ++out.observations_without_view;
        continue;
      }
      Landmark landmark = problem.landmarks[j];
      landmark.position_in_world = g.anchor_centroid;
      for (const GroupMember& m : g.members) {
        Observation o = problem.observations[m.observation];
        o.landmark = out.problem.landmarks.size();
        o.centroid_in_cam =
            (m.correction * problem.keyframes[o.keyframe].world_from_cam).inverse() *
            g.anchor_centroid;
        o.bias_in_world = Vec3::Zero();
        out.problem.observations.push_back(o);
        ++out.observations_aligned;
      }
      out.problem.landmarks.push_back(landmark);
      out.object_ids.push_back(object_ids[j]);
    }
  }
  for (std::size_t i = 0; i < problem.observations.size(); ++i)
    if (!source[i]) ++out.observations_without_view;
  std::map<int, std::size_t> first_landmark;
  for (std::size_t k = out.object_ids.size(); k-- > 0;) first_landmark[out.object_ids[k]] = k;
  for (ViewLink l : links) {
    const auto it = first_landmark.find(object_ids[l.landmark]);
    if (it == first_landmark.end()) continue;
    l.landmark = it->second;
    out.problem.links.push_back(l);
  }
  return out;
}

}  // namespace objmap::pose
