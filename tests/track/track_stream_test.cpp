// track_stream: the frames flow through the tracker (read, tracked, written, dropped) with at most
// n_init frames held at once, and get the labels that the whole recording gives them.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <optional>
#include <utility>
#include <vector>

#include "objmap/core/error.h"
#include "objmap/track/track_segmentation.h"
#include "objmap/track/tracker.h"

namespace objmap::track {
namespace {

constexpr int kWidth = 160, kHeight = 120;

segmentation::Instance instance_at(double x, double y, const char* class_name) {
  segmentation::Instance inst;
  inst.class_name = class_name;
  inst.bbox = {x, y, 12, 16};
  segmentation::Mask mask;  // a full-image mask, as the detectors give
  mask.width = kWidth;
  mask.height = kHeight;
  mask.data.assign(static_cast<std::size_t>(kWidth) * kHeight, 0);
  for (int v = static_cast<int>(y); v < static_cast<int>(y) + 16; ++v)
    for (int u = static_cast<int>(x); u < static_cast<int>(x) + 12; ++u)
      mask.data[static_cast<std::size_t>(v) * kWidth + u] = 1;
  inst.mask = std::move(mask);
  return inst;
}

// Frame f of a walk-through: four objects drifting right, each out of view for a while (its track
// is lost, a new one starts), and short false positives of 1..n_init-1 frames (tentative tracks
// deleted) and of n_init frames (confirmed at their last detection, so that their first ones wait
// for it).
segmentation::FrameSegmentation walkthrough_frame(int f) {
  segmentation::FrameSegmentation frame;
  frame.timestamp = 100.0 + f / 30.0;
  static const char* const kClasses[] = {"cup", "book", "chair", "tv"};
  for (int k = 0; k < 4; ++k) {
    if ((f / 25 + k) % 4 == 3) continue;  // out of view
    const double x = std::fmod(5.0 + 0.7 * f + 35 * k, 140.0);
    frame.instances.push_back(instance_at(x, 10.0 + 25 * k, kClasses[k]));
  }
  const int phase = f % 11;  // a ghost seen for 1, 2 or 3 frames in every 11
  const int seen = 1 + (f / 11) % 3;
  if (phase < seen) frame.instances.push_back(instance_at(70 + 3 * phase, 100, "cup"));
  return frame;
}

// The labels the whole recording gives: every frame's associations first, then the confirmed
// tracks numbered 1, 2, ... in order of confirmation (frame, then internal id), a detection made
// while its track was tentative labelled when the track is confirmed later (option on).
std::vector<std::vector<std::optional<int>>> labels_of_whole_recording(int frames,
                                                                       const TrackOptions& o) {
  Tracker tracker(o.tracker);
  std::vector<std::vector<Association>> all;
  for (int f = 0; f < frames; ++f) {
    const segmentation::FrameSegmentation frame = walkthrough_frame(f);
    std::vector<Detection> detections;
    for (const auto& inst : frame.instances) {
      Detection d;
      d.box = inst.bbox;
      d.class_name = inst.class_name;
      detections.push_back(d);
    }
    all.push_back(tracker.step(detections, frame.timestamp));
  }
  std::vector<std::pair<int, int>> order;  // (frame of confirmation, internal id)
  std::map<int, bool> seen;
  for (int f = 0; f < frames; ++f)
    for (const Association& a : all[f])
      if (a.confirmed && !seen[a.track_id]) {
        seen[a.track_id] = true;
        order.emplace_back(f, a.track_id);
      }
  std::sort(order.begin(), order.end());
  std::map<int, int> output_id;
  for (std::size_t i = 0; i < order.size(); ++i)
    output_id[order[i].second] = static_cast<int>(i) + 1;
  std::vector<std::vector<std::optional<int>>> labels(frames);
  for (int f = 0; f < frames; ++f)
    for (const Association& a : all[f]) {
      const auto it = output_id.find(a.track_id);
      const bool labelled = it != output_id.end() && (a.confirmed || o.label_tentative_history);
      labels[f].push_back(labelled ? std::optional<int>(it->second) : std::nullopt);
    }
  return labels;
}

struct StreamRun {
  TrackResult result;
  std::vector<segmentation::FrameSegmentation> written;
  std::size_t most_held = 0;  // frames read and not yet written, at most
};

StreamRun stream_walkthrough(int frames, const TrackOptions& o) {
  StreamRun run;
  std::size_t read = 0;
  FrameStream input;
  input.source = "walkthrough";
  input.size = static_cast<std::size_t>(frames);
  input.read = [&](std::size_t index) {
    EXPECT_EQ(index, read);  // in order, once each
    ++read;
    run.most_held = std::max(run.most_held, read - run.written.size());
    return walkthrough_frame(static_cast<int>(index));
  };
  run.result = track_stream(
      input,
      [&](std::size_t index, segmentation::FrameSegmentation&& frame) {
        EXPECT_EQ(index, run.written.size());  // in order, once each
        run.written.push_back(std::move(frame));
      },
      o);
  return run;
}

TEST(TrackStream, HoldsAtMostNInitFramesAndLabelsAsTheWholeRecording) {
  const int frames = 300;
  for (const int n_init : {3, 5}) {
    for (const bool history : {true, false}) {
      TrackOptions o;
      o.tracker.use_appearance = false;
      o.tracker.n_init = n_init;
      o.label_tentative_history = history;
      const StreamRun run = stream_walkthrough(frames, o);
      // The window: a frame waits for its tentative tracks, at most n_init - 1 frames; without the
      // tentative history nothing waits.
      EXPECT_LE(run.most_held, history ? static_cast<std::size_t>(n_init) : 1u) << n_init;
      EXPECT_GE(run.most_held, history ? static_cast<std::size_t>(n_init) : 1u)
          << "the stream never waited: the test does not exercise the window";
      ASSERT_EQ(run.written.size(), static_cast<std::size_t>(frames));
      const auto expected = labels_of_whole_recording(frames, o);
      std::size_t labelled = 0;
      for (int f = 0; f < frames; ++f) {
        const auto& instances = run.written[f].instances;
        ASSERT_EQ(instances.size(), expected[f].size()) << f;
        for (std::size_t i = 0; i < instances.size(); ++i) {
          EXPECT_EQ(instances[i].track_id, expected[f][i]) << "frame " << f << " instance " << i;
          labelled += expected[f][i].has_value();
          EXPECT_TRUE(instances[i].mask.has_value());
        }
      }
      EXPECT_EQ(run.result.instances_tracked, labelled);
      EXPECT_GT(run.result.tracks.size(), 10u);  // tracks restart after each time out of view
    }
  }
}

// A frame that cannot be read stops the stream: the frames before it were handed out, none after.
TEST(TrackStream, ReadErrorStopsTheStream) {
  FrameStream input;
  input.source = "walkthrough";
  input.size = 50;
  input.read = [](std::size_t index) {
    if (index == 20) throw InputError("walkthrough/20.json:1", "malformed JSON at column 3");
    return walkthrough_frame(static_cast<int>(index));
  };
  TrackOptions o;
  o.tracker.use_appearance = false;
  std::size_t written = 0;
  try {
    track_stream(
        input, [&](std::size_t, segmentation::FrameSegmentation&&) { ++written; }, o);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()), "walkthrough/20.json:1: malformed JSON at column 3");
  }
  EXPECT_LE(written, 20u);
  EXPECT_GE(written, 20u - 3u);  // all but the frames waiting for tentative tracks
}

}  // namespace
}  // namespace objmap::track
