#pragma once
#include <cstddef>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "objmap/segmentation/types.h"

// Readers of every segmentation format into the one in-memory form of types.h (formats:
// docs/formats.md, "Segmentation"). A frame's timestamp is its file or folder name without the
// extension; frames come out sorted by timestamp.
namespace objmap::segmentation {

struct ReadOptions {
  // "auto" (detect_format) | "json" | "png" | "txt-paper" | "boxes-named" | "boxes-coco" |
  // "boxes-xywh"
  std::string format = "auto";
  // When > 0: every mask must have this size and every box must lie in the image (within
  // box_tolerance_px). The txt-paper layout has no image size of its own: its masks get this size,
  // 640 x 480 (TUM) when not set.
  int image_width = 0, image_height = 0;
  // Class of the instances of formats without one (boxes-xywh, e.g. fr3_cabinet's YOLOv2 boxes; png
  // without sidecar or classes.txt).
  std::string default_class = "object";
  // Detector boxes may overshoot the image border a little: a box edge up to this many pixels
  // outside the image (x < 0, or x + w > width when the width is known) is clamped to the border;
  // further out is an error. 10 px: the real YOLO stream of fr3_long_office_household has a box 7
  // px past the right border.
  double box_tolerance_px = 10.0;
  // Throws InputError naming the bad field.
  void check() const;
};

// The format of a segmentation folder, from the files present and the first data line of the box
// files: "json" | "png" | "txt-paper" | "boxes-named" | "boxes-coco" | "boxes-xywh". Throws
// InputError when the folder is missing or empty, or when it cannot tell (the message says what was
// found and what is accepted).
std::string detect_format(const std::filesystem::path& dir);

// One frame of a segmentation folder before it is read: its timestamp and its file or folder.
struct FrameEntry {
  double timestamp = 0.0;
  std::filesystem::path path;
};

// A segmentation folder read one frame at a time, so that a long recording need not be in memory
// at once (objmap track streams its frames through it).
class FrameReader {
 public:
  // Lists `dir` and finds its format (options.format, or detect_format when "auto"). Throws
  // InputError for bad options, a missing or empty folder, a format it cannot tell, no frame of the
  // format, and (png) a bad classes.txt.
  explicit FrameReader(const std::filesystem::path& dir, const ReadOptions& options = {});

  const std::string& format() const { return format_; }
  const std::filesystem::path& dir() const { return dir_; }
  const std::vector<FrameEntry>& frames() const { return frames_; }  // sorted by timestamp
  std::size_t size() const { return frames_.size(); }
  // Reads frame `index` (in any order; the files are read again on each call). Throws InputError
  // naming the file (and line or field) and what was expected.
  FrameSegmentation read(std::size_t index) const;

 private:
  std::filesystem::path dir_;
  ReadOptions options_;
  std::string format_;
  std::vector<FrameEntry> frames_;
  std::optional<std::map<int, std::string>> png_classes_;  // png: the folder's classes.txt
};

// Reads the whole folder (FrameReader, every frame). Throws InputError naming the file (and line
// or field) and what was expected.
Segmentation read_segmentation(const std::filesystem::path& dir, const ReadOptions& options = {});

// One canonical JSON frame file (<timestamp>.json); the timestamp is taken from the file name.
FrameSegmentation read_frame_json(const std::filesystem::path& file,
                                  const ReadOptions& options = {});

// A file or folder name without extension parsed as a timestamp ("1305031453.359684"); false
// when it is not a number.
bool parse_timestamp(const std::string& stem, double& timestamp);

}  // namespace objmap::segmentation
