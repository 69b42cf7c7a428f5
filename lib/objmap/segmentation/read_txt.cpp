// Text formats: the paper's pixel lists <ts>/<class>/<track_id>.txt ("u v" per line) and the
// per-frame box files <ts>.txt in three layouts (boxes-named, boxes-coco, boxes-xywh).
#include <algorithm>
#include <cmath>

#include "objmap/core/error.h"
#include "objmap/io/text_lines.h"
#include "objmap/segmentation/coco_classes.h"
#include "objmap/segmentation/read_internal.h"
#include "objmap/segmentation/rle.h"

namespace objmap::segmentation::detail {

namespace {

constexpr const char* kNamedLayout = "class_id class_name score x1 y1 x2 y2";
constexpr const char* kCocoLayout = "coco80_id x y w h score";
constexpr const char* kXywhLayout = "x y w h score";

bool is_number(const std::string& text) {
  try {
    io::parse_double(text, "", "");
    return true;
  } catch (const InputError&) {
    return false;
  }
}

int coco_id(const io::LineReader& in, std::size_t field, const std::string& what) {
  const std::int64_t id = in.integer(field, what);
  if (id < 0 || id > 79) {
    throw InputError(in.where(), what + " " + std::to_string(id) +
                                     "; expected a COCO-80 class id 0..79 (coco.names order)");
  }
  return static_cast<int>(id);
}

std::vector<fs::path> sorted_entries(const fs::path& dir) {
  std::vector<fs::path> entries;
  for (const auto& entry : fs::directory_iterator(dir)) {
    if (entry.path().filename().string().rfind('.', 0) == 0) continue;  // hidden files
    entries.push_back(entry.path());
  }
  std::sort(entries.begin(), entries.end());
  return entries;
}

}  // namespace

// ---- the paper's pixel lists -----------------------------------------------------------------

FrameSegmentation read_paper_frame(const FrameEntry& entry, const ReadOptions& options) {
  // The pixel lists carry no image size: the image size of the options, else TUM's 640 x 480.
  const int width = options.image_width > 0 ? options.image_width : 640;
  const int height = options.image_height > 0 ? options.image_height : 480;
  FrameSegmentation frame;
  frame.timestamp = entry.timestamp;
  frame.source = entry.path.string();
  for (const fs::path& class_dir : sorted_entries(entry.path)) {
    if (!fs::is_directory(class_dir)) {
      throw InputError(class_dir.string(),
                       "not a folder; expected <timestamp>/<class>/<track_id>.txt");
    }
    const std::string class_name = canonical_class(class_dir.filename().string());
    // Track files in numeric order of their ids.
    std::vector<std::pair<std::int64_t, fs::path>> tracks;
    for (const fs::path& file : sorted_entries(class_dir)) {
      std::int64_t id = -1;
      try {
        if (file.extension() == ".txt" && fs::is_regular_file(file)) {
          id = io::parse_int(file.stem().string(), "", "");
        }
      } catch (const InputError&) {
      }
      if (id < 0 || id > 2147483647) {
        throw InputError(file.string(),
                         "not a track file; expected <track_id>.txt with an "
                         "integer track id >= 0");
      }
      tracks.emplace_back(id, file);
    }
    std::sort(tracks.begin(), tracks.end());
    for (const auto& [id, file] : tracks) {
      Instance instance;
      instance.class_name = class_name;
      instance.score = 1.0;
      instance.track_id = static_cast<int>(id);
      Mask mask;
      mask.width = width;
      mask.height = height;
      mask.data.assign(static_cast<std::size_t>(width) * height, 0);
      io::LineReader in(file);
      while (in.next()) {
        in.expect_fields(2, "u v");
        const std::int64_t u = in.integer(0, "u"), v = in.integer(1, "v");
        if (u < 0 || u >= width || v < 0 || v >= height) {
          throw InputError(in.where(), "pixel (" + std::to_string(u) + ", " + std::to_string(v) +
                                           ") outside the " + std::to_string(width) + "x" +
                                           std::to_string(height) +
                                           " image; expected 0 <= u < width, 0 <= v < height");
        }
        mask.data[static_cast<std::size_t>(v) * width + u] = 1;
      }
      if (in.data_lines() == 0) {
        throw InputError(file.string(), "no pixel; expected one \"u v\" pixel per line");
      }
      instance.bbox = mask_bounding_box(mask);
      instance.mask = std::move(mask);
      frame.instances.push_back(std::move(instance));
    }
  }
  return frame;
}

// ---- box files -------------------------------------------------------------------------------

std::string detect_box_layout(const FolderScan& scan) {
  for (const auto& entry : scan.txt) {
    io::LineReader in(entry.path);
    if (!in.next()) continue;  // a frame without detections; look at the next file
    const auto& fields = in.fields();
    const bool all_numbers = std::all_of(fields.begin(), fields.end(), is_number);
    if (fields.size() == 7 && !is_number(fields[1])) return "boxes-named";
    if (fields.size() == 6 && all_numbers) return "boxes-coco";
    if (fields.size() == 5 && all_numbers) return "boxes-xywh";
    throw InputError(in.where(), std::to_string(fields.size()) + " fields \"" + in.line() +
                                     "\"; cannot tell the box layout, expected \"" + kNamedLayout +
                                     "\", \"" + kCocoLayout + "\" or \"" + kXywhLayout + "\"");
  }
  throw InputError(scan.txt.front().path.parent_path().string(),
                   std::to_string(scan.txt.size()) +
                       " <timestamp>.txt files without a data line; cannot tell the box layout "
                       "(choose one with --seg-format, config segmentation.format)");
}

FrameSegmentation read_box_frame(const FrameEntry& entry, const std::string& format,
                                 const ReadOptions& options) {
  const std::string default_class = canonical_class(options.default_class);
  const auto& names = coco80_names();
  FrameSegmentation frame;
  frame.timestamp = entry.timestamp;
  frame.source = entry.path.string();
  io::LineReader in(entry.path);
  while (in.next()) {
    Instance instance;
    Box box;
    if (format == "boxes-named") {  // class_id class_name score x1 y1 x2 y2
      in.expect_fields(7, kNamedLayout);
      const int id = coco_id(in, 0, "class_id");
      instance.class_name = canonical_class(in.field(1));
      if (instance.class_name != names[id]) {
        throw InputError(in.where(), "class_name '" + in.field(1) + "' does not match class_id " +
                                         std::to_string(id) + "; expected '" + names[id] + "'");
      }
      instance.score = in.number(2, "score");
      const double x1 = in.number(3, "x1"), y1 = in.number(4, "y1");
      const double x2 = in.number(5, "x2"), y2 = in.number(6, "y2");
      if (x2 < x1 || y2 < y1) {
        throw InputError(in.where(), "corners (" + format_number(x1) + ", " + format_number(y1) +
                                         ") (" + format_number(x2) + ", " + format_number(y2) +
                                         "); expected x1 <= x2 and y1 <= y2");
      }
      box = Box{x1, y1, x2 - x1, y2 - y1};
    } else if (format == "boxes-coco") {  // coco80_id x y w h score; (x, y) = top-left corner
      in.expect_fields(6, kCocoLayout);
      instance.class_name = names[coco_id(in, 0, "coco80_id")];
      box = Box{in.number(1, "x"), in.number(2, "y"), in.number(3, "w"), in.number(4, "h")};
      instance.score = in.number(5, "score");
    } else if (format == "boxes-xywh") {  // x y w h score; (x, y) = top-left corner
      in.expect_fields(5, kXywhLayout);
      instance.class_name = default_class;
      box = Box{in.number(0, "x"), in.number(1, "y"), in.number(2, "w"), in.number(3, "h")};
      instance.score = in.number(4, "score");
    } else {
      throw InputError("ReadOptions.format", "'" + format + "' is not a box format");
    }
    check_score(instance.score, in.where());
    instance.bbox = check_box(box, options, in.where());
    frame.instances.push_back(std::move(instance));
  }
  return frame;
}

}  // namespace objmap::segmentation::detail
