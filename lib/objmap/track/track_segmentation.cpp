#include "objmap/track/track_segmentation.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <optional>
#include <string>
#include <utility>

#include <nlohmann/json.hpp>

#include "objmap/core/error.h"
#include "objmap/io/text_lines.h"

namespace objmap::track {

namespace fs = std::filesystem;

namespace {

// The frame's instances as detections, with their colour descriptors when appearance is on.
std::vector<Detection> detections_of(const segmentation::FrameSegmentation& frame,
                                     const cv::Mat& bgr, bool appearance,
                                     const TrackOptions& options) {
  std::vector<Detection> detections;
  detections.reserve(frame.instances.size());
  for (const auto& inst : frame.instances) {
    Detection d;
    d.box = inst.bbox;
    d.class_name = inst.class_name;
    d.score = inst.score;
    if (appearance) d.descriptor = colour_descriptor(bgr, inst, options.tracker.appearance);
    detections.push_back(std::move(d));
  }
  return detections;
}

// The 3D gate's input: each detection's point in the world (when the frame has a pose), counted.
void add_positions(const FramePositions& p, std::vector<Detection>& detections,
                   TrackResult& result) {
  ++(p.has_pose ? result.frames_with_pose : result.frames_without_pose);
  if (!p.has_pose) return;
  require(p.instances.size() == detections.size(), "track_segmentation",
          "the position source gave " + std::to_string(p.instances.size()) +
              " positions for a frame of " + std::to_string(detections.size()) +
              " instances; expected one per instance");
  for (std::size_t i = 0; i < detections.size(); ++i) {
    const InstancePosition& ip = p.instances[i];
    detections[i].point_in_world = ip.point_in_world;
    if (ip.point_in_world) {
      ++result.instances_with_position;
      if (ip.mask_from_box) ++result.instances_mask_from_box;
    }
    if (ip.status == PositionStatus::kNoMaskFromBox) ++result.instances_no_mask_from_box;
    if (ip.status == PositionStatus::kTooFewDepthPixels) ++result.instances_few_depth_pixels;
  }
}

// Online DeepSORT over the frames in time order: each frame's associations.
std::vector<std::vector<Association>> run_tracker(
    const segmentation::Segmentation& input, const TrackOptions& options, const FrameImage& image,
    const TrackProgress& progress, const FramePositionsFn& positions, TrackResult& result) {
  const bool appearance = options.tracker.use_appearance;
  Tracker tracker(options.tracker);
  std::vector<std::vector<Association>> associations(input.frames.size());
  for (std::size_t f = 0; f < input.frames.size(); ++f) {
    const auto& frame = input.frames[f];
    cv::Mat bgr;
    if (appearance && !frame.instances.empty()) bgr = image(f);
    std::vector<Detection> detections = detections_of(frame, bgr, appearance, options);
    if (options.tracker.use_gate_3d) add_positions(positions(f), detections, result);
    associations[f] = tracker.step(detections, frame.timestamp);
    if (progress) progress(f + 1, input.frames.size());
  }
  return associations;
}

// Output ids: the confirmed tracks numbered 1, 2, ... in order of confirmation (internal id ->
// output id); `started`: the tracks started (the largest internal id).
std::map<int, int> output_ids(const std::vector<std::vector<Association>>& associations,
                              int& started) {
  std::map<int, std::pair<std::size_t, int>> confirmed_at;  // internal id -> (frame, internal id)
  started = 0;
  for (std::size_t f = 0; f < associations.size(); ++f)
    for (const Association& a : associations[f]) {
      if (a.track_id == 0) continue;
      started = std::max(started, a.track_id);
      if (a.confirmed && !confirmed_at.count(a.track_id))
        confirmed_at[a.track_id] = {f, a.track_id};
    }
  std::vector<std::pair<std::size_t, int>> order;
  for (const auto& [id, at] : confirmed_at) order.push_back(at);
  std::sort(order.begin(), order.end());
  std::map<int, int> output_id;
  for (std::size_t i = 0; i < order.size(); ++i)
    output_id[order[i].second] = static_cast<int>(i) + 1;
  return output_id;
}

// Track ids into result.tracked's instances, and each track's frames and class votes.
std::vector<std::map<std::string, int>> label_instances(
    const std::vector<std::vector<Association>>& associations, const std::map<int, int>& output_id,
    const TrackOptions& options, TrackResult& result) {
  std::vector<std::map<std::string, int>> votes(result.tracks.size());
  for (std::size_t f = 0; f < associations.size(); ++f) {
    auto& frame = result.tracked.frames[f];
    for (std::size_t i = 0; i < frame.instances.size(); ++i) {
      auto& inst = frame.instances[i];
      inst.track_id.reset();
      const Association& a = associations[f][i];
      const auto it = output_id.find(a.track_id);
      if (it == output_id.end() || (!a.confirmed && !options.label_tentative_history)) continue;
      inst.track_id = it->second;
      ++result.instances_tracked;
      TrackSummary& s = result.tracks[it->second - 1];
      if (s.length == 0) {
        s.id = it->second;
        s.first_frame = f;
        s.first_timestamp = frame.timestamp;
      }
      s.last_frame = f;
      s.last_timestamp = frame.timestamp;
      ++s.length;
      ++votes[it->second - 1][inst.class_name];
    }
  }
  return votes;
}

}  // namespace

TrackResult track_segmentation(const segmentation::Segmentation& input, const TrackOptions& options,
                               const FrameImage& image, const TrackProgress& progress,
                               const FramePositionsFn& positions) {
  options.check();
  const std::string where = input.source.empty() ? "segmentation" : input.source;
  require(!input.frames.empty(), where, "no frame; expected at least one frame of detections");
  std::size_t instances = 0;
  for (const auto& f : input.frames) instances += f.instances.size();
  require(instances > 0, where,
          "no instance in any of the " + std::to_string(input.frames.size()) +
              " frames; expected detections to track");
  const bool appearance = options.tracker.use_appearance;
  require(!appearance || static_cast<bool>(image), "track_segmentation",
          "appearance is on but no image source was given; expected rgb images or "
          "use_appearance = false");
  const bool gate_3d = options.tracker.use_gate_3d;
  require(!gate_3d || static_cast<bool>(positions), "track_segmentation",
          "the 3D gate is on but no position source was given; expected depth and a trajectory "
          "or use_gate_3d = false");
  TrackResult result;

  // 1. Online DeepSORT over the frames in time order.
  const std::vector<std::vector<Association>> associations =
      run_tracker(input, options, image, progress, positions, result);

  // 2. Output ids: the confirmed tracks numbered 1, 2, ... in order of confirmation.
  int started = 0;
  const std::map<int, int> output_id = output_ids(associations, started);

  // 3. Track ids into the instances, and the per-track summary; a track's class is the majority
  //    vote of its instances.
  result.tracked = input;
  result.frames = input.frames.size();
  result.instances = instances;
  result.tracks_started = static_cast<std::size_t>(started);
  result.used_appearance = appearance;
  result.used_gate_3d = gate_3d;
  result.tracks.resize(output_id.size());
  const std::vector<std::map<std::string, int>> votes =
      label_instances(associations, output_id, options, result);
  for (std::size_t i = 0; i < result.tracks.size(); ++i) {
    int best = -1;
    for (const auto& [name, n] : votes[i])
      if (n > best) {
        best = n;
        result.tracks[i].class_name = name;
      }
  }
  return result;
}

std::string tracks_json(const TrackResult& r) {
  nlohmann::ordered_json out;
  out["frames"] = r.frames;
  out["instances"] = r.instances;
  out["instances_tracked"] = r.instances_tracked;
  out["tracks_started"] = r.tracks_started;
  out["appearance"] = r.used_appearance;
  if (r.used_gate_3d) {
    nlohmann::ordered_json g;
    g["frames_with_pose"] = r.frames_with_pose;
    g["frames_without_pose"] = r.frames_without_pose;
    g["instances_with_position"] = r.instances_with_position;
    g["instances_mask_from_box"] = r.instances_mask_from_box;
    g["instances_no_mask_from_box"] = r.instances_no_mask_from_box;
    g["instances_few_depth_pixels"] = r.instances_few_depth_pixels;
    out["gate_3d"] = g;
  }
  nlohmann::ordered_json tracks = nlohmann::ordered_json::array();
  for (const TrackSummary& s : r.tracks) {
    nlohmann::ordered_json t;
    t["id"] = s.id;
    t["class"] = s.class_name;
    t["first_frame"] = s.first_frame;
    t["last_frame"] = s.last_frame;
    t["first_timestamp"] = s.first_timestamp;
    t["last_timestamp"] = s.last_timestamp;
    t["length"] = s.length;
    tracks.push_back(t);
  }
  out["tracks"] = tracks;
  return out.dump(2) + "\n";
}

LengthStats length_stats(const std::vector<TrackSummary>& tracks) {
  LengthStats s;
  if (tracks.empty()) return s;
  std::vector<std::size_t> lengths;
  for (const auto& t : tracks) lengths.push_back(t.length);
  std::sort(lengths.begin(), lengths.end());
  s.count = lengths.size();
  double sum = 0;
  for (std::size_t n : lengths) sum += static_cast<double>(n);
  s.mean = sum / static_cast<double>(lengths.size());
  s.min = lengths.front();
  s.max = lengths.back();
  s.median = lengths[lengths.size() / 2];
  return s;
}

namespace {

// The image of each segmentation frame among `rows` (timestamp, image), sorted by timestamp.
// has_images: whether the images are there (else none is matched).
FrameImages match_frame_images(const std::vector<std::pair<double, fs::path>>& rows,
                               const segmentation::Segmentation& segmentation, double max_diff_s,
                               const std::string& list, bool has_images) {
  FrameImages out;
  out.listed = rows.size();
  out.has_images = has_images && !rows.empty();
  if (!out.has_images) return out;
  for (const auto& frame : segmentation.frames) {
    const auto it = std::lower_bound(
        rows.begin(), rows.end(), frame.timestamp,
        [](const std::pair<double, fs::path>& row, double t) { return row.first < t; });
    std::optional<std::size_t> best;
    double best_diff = max_diff_s;
    for (auto c = it == rows.begin() ? it : it - 1; c != rows.end() && c <= it; ++c) {
      const double diff = std::abs(c->first - frame.timestamp);
      if (diff <= best_diff) {
        best_diff = diff;
        best = static_cast<std::size_t>(c - rows.begin());
      }
    }
    require(best.has_value(), frame.source.empty() ? segmentation.source : frame.source,
            "no rgb image of " + list +
                " at this frame's timestamp; expected the "
                "segmentation's frames to be rgb frames of the dataset (or use --no-appearance)");
    out.files.push_back(rows[*best].second);
    out.rows.push_back(*best);
  }
  return out;
}

}  // namespace

FrameImages find_frame_images(const fs::path& dataset,
                              const segmentation::Segmentation& segmentation, double max_diff_s) {
  require(fs::is_directory(dataset), dataset.string(),
          "no such folder; expected a TUM RGB-D folder with rgb.txt");
  const fs::path list = dataset / "rgb.txt";
  require(fs::exists(list), list.string(), "missing; expected 'timestamp filename' lines");
  std::vector<std::pair<double, fs::path>> rows;
  io::LineReader in(list);
  while (in.next()) {
    in.expect_fields(2, "timestamp filename");
    const double t = in.number(0, "timestamp");
    require(rows.empty() || t > rows.back().first, in.where(),
            "timestamp not after the previous one; expected increasing timestamps");
    rows.emplace_back(t, dataset / in.field(1));
  }
  require(!rows.empty(), list.string(), "no image listed; expected lines 'timestamp filename'");
  // The images are there when the first listed one is; the folder is then a full recording.
  return match_frame_images(rows, segmentation, max_diff_s, list.string(),
                            fs::exists(rows.front().second));
}

FrameImages find_frame_images(const io::Dataset& dataset,
                              const segmentation::Segmentation& segmentation, double max_diff_s) {
  std::vector<std::pair<double, fs::path>> rows;
  for (const io::FramePair& f : dataset.frames) rows.emplace_back(f.rgb_timestamp, f.rgb_file);
  const bool has_images =
      dataset.source != nullptr || (!rows.empty() && fs::exists(rows.front().second));
  return match_frame_images(rows, segmentation, max_diff_s,
                            dataset.root.string() + " (" + dataset.layout + " layout)", has_images);
}

}  // namespace objmap::track
