#pragma once
#include <cstddef>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include <opencv2/core/mat.hpp>

#include "objmap/io/dataset.h"
#include "objmap/segmentation/read.h"
#include "objmap/segmentation/types.h"
#include "objmap/track/position_3d.h"
#include "objmap/track/tracker.h"

// Offline tracking of a segmentation (`objmap track`): the frames in time order through the
// DeepSORT tracker, each written out with its track ids once they are final (a window of frames,
// not the whole recording, in memory).
namespace objmap::track {

struct TrackOptions {
  TrackerOptions tracker;
  // Input track ids are ignored (the tracker gives its own); instances of tracks that are never
  // confirmed keep no track id. Offline, a confirmed track's first n_init - 1 (tentative)
  // detections are given its id too (true); false: only the detections made while the track was
  // confirmed, as DeepSORT's online output.
  bool label_tentative_history = true;
  void check() const { tracker.check(); }
};

struct TrackSummary {
  int id = 0;              // output track id (1, 2, ... in order of confirmation)
  std::string class_name;  // majority class of its detections
  std::size_t first_frame = 0, last_frame = 0;  // indices into the segmentation's frames
  double first_timestamp = 0, last_timestamp = 0;
  std::size_t length = 0;  // instances labelled with this id
};

struct TrackResult {
  // The input with track_id set (or cleared) per instance (track_segmentation; track_stream hands
  // the frames to its output instead).
  segmentation::Segmentation tracked;
  std::vector<TrackSummary> tracks;  // confirmed tracks, by id
  std::size_t frames = 0;
  std::size_t instances = 0;          // all instances
  std::size_t instances_tracked = 0;  // instances given a track id
  std::size_t tracks_started = 0;     // tentative tracks created (confirmed or not)
  bool used_appearance = false;
  // 3D gate (options.tracker.use_gate_3d): frames with a pose (and depth), frames without one
  // (tracked without the gate), instances given a 3D position, and of the others why not.
  bool used_gate_3d = false;
  std::size_t frames_with_pose = 0;
  std::size_t frames_without_pose = 0;
  std::size_t instances_with_position = 0;
  std::size_t instances_mask_from_box = 0;     // positions made through box_mask.h
  std::size_t instances_no_mask_from_box = 0;  // box-only instances whose box gave no mask
  std::size_t instances_few_depth_pixels = 0;  // masks with too few valid depth pixels
};

// The rgb image (CV_8UC3 BGR) of frame `index` of the segmentation; called once per frame, in
// order, only when options.tracker.use_appearance.
using FrameImage = std::function<cv::Mat(std::size_t index)>;
using TrackProgress = std::function<void(std::size_t done, std::size_t total)>;

// The frames of a segmentation, read one at a time (a segmentation::FrameReader on a folder).
struct FrameStream {
  std::string source;    // the folder, for messages
  std::size_t size = 0;  // frames, sorted by timestamp
  // Frame `index`; called once per frame, in order 0, 1, ..., size - 1.
  std::function<segmentation::FrameSegmentation(std::size_t index)> read;
};

// Receives frame `index` with its track ids (set or cleared per instance), in order, as soon as
// they are final. A detection of a tentative track waits until the track is confirmed or deleted
// (a tentative track is deleted at its first miss: at most n_init - 1 frames later), so at most
// n_init frames are held at once, whatever the length of the recording.
using TrackedFrameFn =
    std::function<void(std::size_t index, segmentation::FrameSegmentation&& frame)>;

// Tracks the frames of `input` as they are read, one time step per frame (its timestamp the
// tracker's time), and hands each tracked frame to `output`; result.tracked stays empty.
// `positions` gives the instances' 3D positions, required when options.tracker.use_gate_3d (see
// depth_positions). Throws InputError when the segmentation has no frame or (after the last frame)
// no instance at all, for bad options, and whatever input.read throws.
TrackResult track_stream(const FrameStream& input, const TrackedFrameFn& output,
                         const TrackOptions& options, const FrameImage& image = {},
                         const TrackProgress& progress = {},
                         const FramePositionsFn& positions = {});

// track_stream over a segmentation in memory; result.tracked holds the tracked frames.
TrackResult track_segmentation(const segmentation::Segmentation& input, const TrackOptions& options,
                               const FrameImage& image = {}, const TrackProgress& progress = {},
                               const FramePositionsFn& positions = {});

// tracks.json: {"frames":N,"instances":N,"instances_tracked":N,"tracks_started":N,
// "appearance":bool,"tracks":[{"id","class","first_frame","last_frame","first_timestamp",
// "last_timestamp","length"}]} (deterministic); with the 3D gate also
// "gate_3d":{"frames_with_pose",
// "frames_without_pose","instances_with_position","instances_mask_from_box",
// "instances_no_mask_from_box","instances_few_depth_pixels"} before "tracks".
std::string tracks_json(const TrackResult& result);

// Length statistics of the confirmed tracks (frames labelled per track).
struct LengthStats {
  std::size_t count = 0;
  double mean = 0;
  std::size_t min = 0, median = 0, max = 0;
};
LengthStats length_stats(const std::vector<TrackSummary>& tracks);

// --- Inputs of `objmap track` -------------------------------------------------------------------

// The rgb images of a TUM folder for the frames of a segmentation. A folder whose rgb.txt lists
// images that are not there (a detection stream without images, such as the fr3_long_office
// annotations) has none: has_images is false.
struct FrameImages {
  bool has_images = false;
  std::vector<std::filesystem::path> files;  // one per segmentation frame, when has_images
  std::vector<std::size_t> rows;  // its row of rgb.txt / frame of the dataset, when has_images
  std::size_t listed = 0;         // rows of rgb.txt
};

// Reads `dataset`/rgb.txt (strict: `timestamp filename` lines, increasing stamps) and finds the
// image of each segmentation frame of `frames` (segmentation::FrameReader::frames(); the rgb stamp
// within max_diff_s). Throws InputError for a missing folder or rgb.txt, a bad line, or (when the
// images exist) a segmentation frame without an rgb image (naming the frame's file).
FrameImages find_frame_images(const std::filesystem::path& dataset,
                              const std::vector<segmentation::FrameEntry>& frames,
                              double max_diff_s = 1e-4);
// The same over the frames of a recording read in any layout (io/dataset.h).
FrameImages find_frame_images(const io::Dataset& dataset,
                              const std::vector<segmentation::FrameEntry>& frames,
                              double max_diff_s = 1e-4);

}  // namespace objmap::track
