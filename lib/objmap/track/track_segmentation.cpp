#include "objmap/track/track_segmentation.h"

#include <algorithm>
#include <cmath>
#include <deque>
#include <map>
#include <optional>
#include <set>
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

// A tracked frame not yet written: a detection of a tentative track waits for the track's fate.
struct HeldFrame {
  std::size_t index = 0;
  segmentation::FrameSegmentation frame;
  std::vector<Association> associations;  // one per instance
};

// Output ids (the confirmed tracks numbered 1, 2, ... in order of confirmation), the instances'
// labels and the per-track summaries, frame by frame; a frame is written once its labels are final.
class Labeller {
 public:
  Labeller(const TrackOptions& options, const TrackedFrameFn& output, TrackResult& result)
      : options_(options), output_(output), result_(result) {}

  // Frame `held` after the tracker's step: numbers the tracks it confirmed, then writes the held
  // frames, oldest first, while their labels are final.
  void add(HeldFrame&& held, const Tracker& tracker) {
    std::vector<int> confirmed;  // internal ids confirmed in this frame
    for (const Association& a : held.associations) {
      result_.tracks_started =
          std::max(result_.tracks_started, static_cast<std::size_t>(a.track_id));
      if (a.confirmed && !output_id_.count(a.track_id)) confirmed.push_back(a.track_id);
    }
    std::sort(confirmed.begin(), confirmed.end());
    for (const int id : confirmed) {
      const int output_id = static_cast<int>(output_id_.size()) + 1;
      output_id_[id] = output_id;
      result_.tracks.emplace_back();
      votes_.emplace_back();
    }
    held_.push_back(std::move(held));
    std::set<int> tentative;  // live tracks that may still be confirmed
    for (const Track& t : tracker.tracks())
      if (t.track_state == TrackState::kTentative) tentative.insert(t.id);
    while (!held_.empty() && is_final(held_.front(), tentative)) write_front();
  }

  // Writes the frames still held: their tentative tracks are never confirmed now.
  void finish() {
    while (!held_.empty()) write_front();
  }

  // A track's class is the majority vote of its instances (ties: the first name).
  void name_tracks() {
    for (std::size_t i = 0; i < result_.tracks.size(); ++i) {
      int best = -1;
      for (const auto& [name, n] : votes_[i])
        if (n > best) {
          best = n;
          result_.tracks[i].class_name = name;
        }
    }
  }

 private:
  // Whether every instance's label is known: untracked, of a numbered track, or of a tentative
  // track that is gone (or whose tentative detections are not labelled anyway).
  bool is_final(const HeldFrame& held, const std::set<int>& tentative) const {
    if (!options_.label_tentative_history) return true;
    for (const Association& a : held.associations)
      if (a.track_id != 0 && !output_id_.count(a.track_id) && tentative.count(a.track_id))
        return false;
    return true;
  }

  // Track ids into the oldest held frame's instances, and its tracks' frames and class votes; then
  // the frame goes to the output.
  void write_front() {
    HeldFrame& held = held_.front();
    segmentation::FrameSegmentation& frame = held.frame;
    for (std::size_t i = 0; i < frame.instances.size(); ++i) {
      auto& inst = frame.instances[i];
      inst.track_id.reset();
      const Association& a = held.associations[i];
      const auto it = output_id_.find(a.track_id);
      if (it == output_id_.end() || (!a.confirmed && !options_.label_tentative_history)) continue;
      inst.track_id = it->second;
      ++result_.instances_tracked;
      TrackSummary& s = result_.tracks[it->second - 1];
      if (s.length == 0) {
        s.id = it->second;
        s.first_frame = held.index;
        s.first_timestamp = frame.timestamp;
      }
      s.last_frame = held.index;
      s.last_timestamp = frame.timestamp;
      ++s.length;
      ++votes_[it->second - 1][inst.class_name];
    }
    output_(held.index, std::move(frame));
    held_.pop_front();
  }

  const TrackOptions& options_;
  const TrackedFrameFn& output_;
  TrackResult& result_;
  std::map<int, int> output_id_;                   // internal id -> output id
  std::vector<std::map<std::string, int>> votes_;  // class votes per output id - 1
  std::deque<HeldFrame> held_;                     // tracked, not yet written, oldest first
};

}  // namespace

TrackResult track_stream(const FrameStream& input, const TrackedFrameFn& output,
                         const TrackOptions& options, const FrameImage& image,
                         const TrackProgress& progress, const FramePositionsFn& positions) {
  options.check();
  const std::string where = input.source.empty() ? "segmentation" : input.source;
  require(input.size > 0, where, "no frame; expected at least one frame of detections");
  const bool appearance = options.tracker.use_appearance;
  require(!appearance || static_cast<bool>(image), "track_segmentation",
          "appearance is on but no image source was given; expected rgb images or "
          "use_appearance = false");
  const bool gate_3d = options.tracker.use_gate_3d;
  require(!gate_3d || static_cast<bool>(positions), "track_segmentation",
          "the 3D gate is on but no position source was given; expected depth and a trajectory "
          "or use_gate_3d = false");
  TrackResult result;
  result.frames = input.size;
  result.used_appearance = appearance;
  result.used_gate_3d = gate_3d;
  Tracker tracker(options.tracker);
  Labeller labeller(options, output, result);

  // 1. Online DeepSORT over the frames in time order; each frame is written with its track ids as
  //    soon as they are final (the confirmed tracks numbered 1, 2, ... in order of confirmation).
  for (std::size_t f = 0; f < input.size; ++f) {
    HeldFrame held{f, input.read(f), {}};
    const segmentation::FrameSegmentation& frame = held.frame;
    result.instances += frame.instances.size();
    cv::Mat bgr;
    if (appearance && !frame.instances.empty()) bgr = image(f);
    std::vector<Detection> detections = detections_of(frame, bgr, appearance, options);
    if (gate_3d) add_positions(positions(f, frame), detections, result);
    held.associations = tracker.step(detections, frame.timestamp);
    labeller.add(std::move(held), tracker);
    if (progress) progress(f + 1, input.size);
  }
  labeller.finish();
  require(result.instances > 0, where,
          "no instance in any of the " + std::to_string(input.size) +
              " frames; expected detections to track");

  // 2. A track's class is the majority vote of its instances.
  labeller.name_tracks();
  return result;
}

TrackResult track_segmentation(const segmentation::Segmentation& input, const TrackOptions& options,
                               const FrameImage& image, const TrackProgress& progress,
                               const FramePositionsFn& positions) {
  FrameStream stream;
  stream.source = input.source;
  stream.size = input.frames.size();
  stream.read = [&input](std::size_t i) { return input.frames[i]; };
  segmentation::Segmentation tracked;
  tracked.format = input.format;
  tracked.source = input.source;
  TrackResult result = track_stream(
      stream,
      [&tracked](std::size_t, segmentation::FrameSegmentation&& frame) {
        tracked.frames.push_back(std::move(frame));
      },
      options, image, progress, positions);
  result.tracked = std::move(tracked);
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
                               const std::vector<segmentation::FrameEntry>& frames,
                               double max_diff_s, const std::string& list, bool has_images) {
  FrameImages out;
  out.listed = rows.size();
  out.has_images = has_images && !rows.empty();
  if (!out.has_images) return out;
  for (const auto& frame : frames) {
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
    require(best.has_value(), frame.path.string(),
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
                              const std::vector<segmentation::FrameEntry>& frames,
                              double max_diff_s) {
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
  return match_frame_images(rows, frames, max_diff_s, list.string(),
                            fs::exists(rows.front().second));
}

FrameImages find_frame_images(const io::Dataset& dataset,
                              const std::vector<segmentation::FrameEntry>& frames,
                              double max_diff_s) {
  std::vector<std::pair<double, fs::path>> rows;
  for (const io::FramePair& f : dataset.frames) rows.emplace_back(f.rgb_timestamp, f.rgb_file);
  const bool has_images =
      dataset.source != nullptr || (!rows.empty() && fs::exists(rows.front().second));
  return match_frame_images(rows, frames, max_diff_s,
                            dataset.root.string() + " (" + dataset.layout + " layout)", has_images);
}

}  // namespace objmap::track
