#pragma once
// Internal to objmap_segmentation: helpers shared by the readers of read.cpp, read_png.cpp and
// read_txt.cpp. Not installed API.
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "objmap/segmentation/read.h"
#include "objmap/segmentation/types.h"

namespace objmap::segmentation::detail {

namespace fs = std::filesystem;

// What a segmentation folder holds, by kind; each list sorted by timestamp.
struct FolderScan {
  std::vector<FrameEntry> json;     // <ts>.json (not *.instances.json)
  std::vector<FrameEntry> png;      // <ts>.png
  std::vector<FrameEntry> txt;      // <ts>.txt
  std::vector<FrameEntry> folders;  // <ts>/
  std::vector<std::string> other;   // every other name (for messages), sorted
  std::size_t entries = 0;          // all entries of the folder
};

// Lists `dir`; throws InputError when it is missing, not a folder, or two files of one kind have
// the same timestamp ("1.5.txt" and "1.50.txt").
FolderScan scan_folder(const fs::path& dir);

// "<what> files: 'a', 'b', ... (N entries)" for messages.
std::string describe(const FolderScan& scan);
// What detect_format accepts, for messages.
extern const char* const kAccepted;

// Validates a box against the image (options.image_width/height when > 0, the tolerance
// options.box_tolerance_px) and returns it clamped to the image. Throws InputError(where, ...).
Box check_box(const Box& box, const ReadOptions& options, const std::string& where);
// Throws InputError(where, ...) unless 0 <= score <= 1.
void check_score(double score, const std::string& where);
// Throws InputError(where, ...) when image_width/height are set and the mask has another size.
void check_mask_size(int width, int height, const ReadOptions& options, const std::string& where);

std::string format_number(double value);

// Whole file as text; throws InputError when it cannot be opened.
std::string read_file_text(const fs::path& file);
// Parses a JSON file; throws InputError("<file>:<line>", "malformed JSON at column C: ...").
nlohmann::json parse_json_file(const fs::path& file);

// The readers of one frame, one per format (canonical JSON: read_frame_json of read.h).
// `classes`: the folder's classes.txt (png without a sidecar), when it has one.
FrameSegmentation read_png_frame(const FrameEntry& entry, const fs::path& classes_file,
                                 const std::optional<std::map<int, std::string>>& classes,
                                 const ReadOptions& options);
FrameSegmentation read_paper_frame(const FrameEntry& entry, const ReadOptions& options);
FrameSegmentation read_box_frame(const FrameEntry& entry, const std::string& format,
                                 const ReadOptions& options);
// classes.txt of a png folder: "<value> <class name>" lines.
std::map<int, std::string> read_classes_txt(const fs::path& file);
// "boxes-named" | "boxes-coco" | "boxes-xywh" from the first data line of the box files.
std::string detect_box_layout(const FolderScan& scan);

}  // namespace objmap::segmentation::detail
