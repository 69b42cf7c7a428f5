#include "objmap/segmentation/read.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>

#include "objmap/core/error.h"
#include "objmap/io/json_file.h"
#include "objmap/segmentation/coco_classes.h"
#include "objmap/segmentation/read_internal.h"
#include "objmap/segmentation/rle.h"

namespace objmap::segmentation {

namespace {

using nlohmann::json;
namespace fs = std::filesystem;

const std::vector<std::string>& known_formats() {
  static const std::vector<std::string> formats = {"json",        "png",        "txt-paper",
                                                   "boxes-named", "boxes-coco", "boxes-xywh"};
  return formats;
}

std::string join(const std::vector<std::string>& items, const std::string& separator) {
  std::string text;
  for (const auto& item : items) text += (text.empty() ? "" : separator) + item;
  return text;
}

bool ends_with(const std::string& text, const std::string& suffix) {
  return text.size() >= suffix.size() &&
         text.compare(text.size() - suffix.size(), suffix.size(), suffix) == 0;
}

}  // namespace

void ReadOptions::check() const {
  const auto& formats = known_formats();
  require(format == "auto" || std::find(formats.begin(), formats.end(), format) != formats.end(),
          "ReadOptions.format", "'" + format + "'; expected auto, " + join(formats, ", "));
  require(image_width >= 0 && image_height >= 0 && (image_width > 0) == (image_height > 0),
          "ReadOptions.image_width/image_height",
          std::to_string(image_width) + "x" + std::to_string(image_height) +
              "; expected both > 0 (the image size) or both 0 (not checked)");
  require(!canonical_class(default_class).empty(), "ReadOptions.default_class",
          "empty; expected a class name such as \"object\"");
  require(std::isfinite(box_tolerance_px) && box_tolerance_px >= 0, "ReadOptions.box_tolerance_px",
          detail::format_number(box_tolerance_px) + "; expected a number of pixels >= 0");
}

bool parse_timestamp(const std::string& stem, double& timestamp) {
  if (stem.empty()) return false;
  const char* end = stem.data() + stem.size();
  double value = 0.0;
  const auto [ptr, ec] = std::from_chars(stem.data(), end, value, std::chars_format::fixed);
  if (ec != std::errc() || ptr != end || !std::isfinite(value)) return false;
  timestamp = value;
  return true;
}

namespace detail {

const char* const kAccepted =
    "<timestamp>.json (canonical), <timestamp>.png label images (with <timestamp>.instances.json "
    "or classes.txt), <timestamp>/<class>/<track_id>.txt pixel lists (paper), or <timestamp>.txt "
    "box files (class_id class_name score x1 y1 x2 y2 | coco80_id x y w h score | x y w h score)";

std::string format_number(double value) {
  char text[64];
  std::snprintf(text, sizeof text, "%.10g", value);
  return text;
}

namespace {

void sort_unique(std::vector<FrameEntry>& entries) {
  std::sort(entries.begin(), entries.end(), [](const FrameEntry& a, const FrameEntry& b) {
    return a.timestamp != b.timestamp ? a.timestamp < b.timestamp : a.path < b.path;
  });
  for (std::size_t i = 1; i < entries.size(); ++i) {
    if (entries[i].timestamp == entries[i - 1].timestamp) {
      throw InputError(entries[i].path.string(), "same timestamp as " +
                                                     entries[i - 1].path.filename().string() +
                                                     "; expected one file per frame");
    }
  }
}

}  // namespace

FolderScan scan_folder(const fs::path& dir) {
  std::error_code error;
  if (!fs::exists(dir, error)) {
    throw InputError(dir.string(), "no such folder; expected a segmentation folder");
  }
  if (!fs::is_directory(dir, error)) {
    throw InputError(dir.string(), "not a folder; expected a segmentation folder");
  }
  FolderScan scan;
  for (const auto& entry : fs::directory_iterator(dir)) {
    ++scan.entries;
    const fs::path& path = entry.path();
    const std::string name = path.filename().string();
    double timestamp = 0.0;
    if (entry.is_directory()) {
      if (parse_timestamp(name, timestamp)) {
        scan.folders.push_back({timestamp, path});
        continue;
      }
    } else if (entry.is_regular_file()) {
      const std::string extension = path.extension().string();
      const std::string stem = path.stem().string();
      if (!ends_with(name, ".instances.json") && parse_timestamp(stem, timestamp)) {
        if (extension == ".json") {
          scan.json.push_back({timestamp, path});
          continue;
        }
        if (extension == ".png") {
          scan.png.push_back({timestamp, path});
          continue;
        }
        if (extension == ".txt") {
          scan.txt.push_back({timestamp, path});
          continue;
        }
      }
    }
    scan.other.push_back(name + (entry.is_directory() ? "/" : ""));
  }
  sort_unique(scan.json);
  sort_unique(scan.png);
  sort_unique(scan.txt);
  sort_unique(scan.folders);
  std::sort(scan.other.begin(), scan.other.end());
  return scan;
}

std::string describe(const FolderScan& scan) {
  std::vector<std::string> parts;
  auto add = [&](std::size_t n, const std::string& what) {
    if (n > 0) parts.push_back(std::to_string(n) + " " + what);
  };
  add(scan.json.size(), "<timestamp>.json");
  add(scan.png.size(), "<timestamp>.png");
  add(scan.txt.size(), "<timestamp>.txt");
  add(scan.folders.size(), "<timestamp>/ folders");
  if (!scan.other.empty()) {
    std::vector<std::string> names(
        scan.other.begin(), scan.other.begin() + std::min<std::size_t>(scan.other.size(), 4));
    for (auto& name : names) name = "'" + name + "'";
    if (scan.other.size() > names.size()) names.push_back("...");
    parts.push_back(std::to_string(scan.other.size()) + " other (" + join(names, ", ") + ")");
  }
  return "found " + join(parts, ", ");
}

Box check_box(const Box& box, const ReadOptions& options, const std::string& where) {
  const std::string text = "box [" + format_number(box.x) + ", " + format_number(box.y) + ", " +
                           format_number(box.w) + ", " + format_number(box.h) + "] (x y w h)";
  if (!std::isfinite(box.x) || !std::isfinite(box.y) || !std::isfinite(box.w) ||
      !std::isfinite(box.h) || box.w < 0 || box.h < 0) {
    throw InputError(where, text + "; expected finite numbers with width and height >= 0");
  }
  const double tolerance = options.box_tolerance_px;
  const std::string within = " by more than " + format_number(tolerance) + " px";
  if (box.x < -tolerance) throw InputError(where, text + " starts left of the image" + within);
  if (box.y < -tolerance) throw InputError(where, text + " starts above the image" + within);
  const double width = options.image_width, height = options.image_height;
  if (width > 0 && box.x + box.w > width + tolerance) {
    throw InputError(where, text + " ends at x = " + format_number(box.x + box.w) +
                                ", past the image width " + format_number(width) + within);
  }
  if (height > 0 && box.y + box.h > height + tolerance) {
    throw InputError(where, text + " ends at y = " + format_number(box.y + box.h) +
                                ", past the image height " + format_number(height) + within);
  }
  // Within the tolerance: clamp to the image.
  double x0 = std::max(box.x, 0.0), y0 = std::max(box.y, 0.0);
  double x1 = box.x + box.w, y1 = box.y + box.h;
  if (width > 0) x0 = std::min(x0, width), x1 = std::min(x1, width);
  if (height > 0) y0 = std::min(y0, height), y1 = std::min(y1, height);
  return Box{x0, y0, std::max(0.0, x1 - x0), std::max(0.0, y1 - y0)};
}

void check_score(double score, const std::string& where) {
  if (!(score >= 0.0 && score <= 1.0)) {
    throw InputError(where, "score " + format_number(score) + "; expected a number in [0, 1]");
  }
}

void check_mask_size(int width, int height, const ReadOptions& options, const std::string& where) {
  if (options.image_width <= 0) return;
  if (width != options.image_width || height != options.image_height) {
    throw InputError(where, "mask is " + std::to_string(width) + "x" + std::to_string(height) +
                                " (w x h); expected the image size " +
                                std::to_string(options.image_width) + "x" +
                                std::to_string(options.image_height));
  }
}

// ---- canonical JSON --------------------------------------------------------------------------

std::string read_file_text(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw InputError(file.string(), "cannot open for reading");
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

namespace {
// nlohmann's parse error without its "[json.exception...] parse error at line L, column C: "
// prefix.
std::string parse_error_reason(const std::string& what) {
  const std::size_t colon = what.find(": ");
  return colon == std::string::npos ? what : what.substr(colon + 2);
}
}  // namespace

nlohmann::json parse_json_file(const fs::path& file) {
  const std::string text = read_file_text(file);
  try {
    return json::parse(text);
  } catch (const json::parse_error& e) {
    // Line and column of the byte where parsing stopped (e.byte is 1-based).
    const std::size_t byte = std::min<std::size_t>(e.byte == 0 ? 0 : e.byte - 1, text.size());
    std::size_t line = 1, column = 1;
    for (std::size_t i = 0; i < byte; ++i) {
      if (text[i] == '\n') {
        ++line;
        column = 1;
      } else {
        ++column;
      }
    }
    throw InputError(
        file.string() + ":" + std::to_string(line),
        "malformed JSON at column " + std::to_string(column) + ": " + parse_error_reason(e.what()));
  } catch (const json::exception& e) {  // a number beyond a double's range (1e999): name its field
    const std::string field = io::json_failing_field(text);
    const bool score = field.size() >= 6 && field.compare(field.size() - 6, 6, ".score") == 0;
    throw InputError(file.string() + (field.empty() ? "" : ": " + field),
                     "malformed JSON: " + parse_error_reason(e.what()) + "; expected a finite " +
                         (score ? "number in [0, 1]" : "number (one a double can hold)"));
  }
}

namespace {

std::string type_name(const json& value) { return value.type_name(); }

double get_number(const json& value, const std::string& where, const std::string& expected) {
  if (!value.is_number()) {
    throw InputError(where, type_name(value) + " " + value.dump() + "; expected " + expected);
  }
  return value.get<double>();
}

Mask read_mask(const json& mask, const std::string& where) {
  if (!mask.is_object()) {
    throw InputError(where,
                     type_name(mask) + "; expected {\"size\":[h,w],\"counts\":\"<COCO RLE>\"}");
  }
  const auto size = mask.find("size");
  if (size == mask.end() || !size->is_array() || size->size() != 2 ||
      !(*size)[0].is_number_integer() || !(*size)[1].is_number_integer() ||
      (*size)[0].get<std::int64_t>() < 0 || (*size)[1].get<std::int64_t>() < 0 ||
      (*size)[0].get<std::int64_t>() > 100000 || (*size)[1].get<std::int64_t>() > 100000) {
    throw InputError(where + ".size", (size == mask.end() ? std::string("missing") : size->dump()) +
                                          "; expected [height, width], two integers >= 0");
  }
  const int height = (*size)[0].get<int>(), width = (*size)[1].get<int>();
  const auto counts = mask.find("counts");
  try {
    if (counts != mask.end() && counts->is_string()) {
      return rle_decode(counts->get<std::string>(), height, width);
    }
    if (counts != mask.end() && counts->is_array()) {  // uncompressed RLE, as COCO's iscrowd
      std::vector<std::uint32_t> runs;
      for (const auto& run : *counts) {
        if (!run.is_number_unsigned() || run.get<std::uint64_t>() > 0xffffffffULL) {
          throw InputError("", "run " + run.dump() + "; expected an integer >= 0");
        }
        runs.push_back(run.get<std::uint32_t>());
      }
      return rle_counts_decode(runs, height, width);
    }
  } catch (const InputError& e) {
    throw InputError(where + ".counts", e.reason());
  }
  throw InputError(where + ".counts",
                   (counts == mask.end() ? std::string("missing") : type_name(*counts)) +
                       "; expected a COCO RLE string (or a list of run lengths)");
}

Instance read_instance(const json& item, const std::string& where, const ReadOptions& options) {
  if (!item.is_object()) {
    throw InputError(where,
                     type_name(item) + "; expected an object {\"class\":..,\"score\":..,...}");
  }
  Instance instance;
  const auto name = item.find("class");
  if (name == item.end() || !name->is_string() ||
      canonical_class(name->get<std::string>()).empty()) {
    throw InputError(where + ".class",
                     (name == item.end() ? std::string("missing") : name->dump()) +
                         "; expected a class name string");
  }
  instance.class_name = canonical_class(name->get<std::string>());
  if (const auto score = item.find("score"); score != item.end()) {
    instance.score = get_number(*score, where + ".score", "a number in [0, 1]");
    check_score(instance.score, where + ".score");
  }
  if (const auto track = item.find("track_id"); track != item.end() && !track->is_null()) {
    if (!track->is_number_integer() || track->get<std::int64_t>() < 0 ||
        track->get<std::int64_t>() > 2147483647) {
      throw InputError(where + ".track_id", track->dump() + "; expected an integer >= 0 or null");
    }
    instance.track_id = track->get<int>();
  }
  if (const auto mask = item.find("mask"); mask != item.end() && !mask->is_null()) {
    instance.mask = read_mask(*mask, where + ".mask");
    check_mask_size(instance.mask->width, instance.mask->height, options, where + ".mask.size");
  }
  const auto bbox = item.find("bbox");
  if (bbox != item.end() && !bbox->is_null()) {
    if (!bbox->is_array() || bbox->size() != 4) {
      throw InputError(where + ".bbox", bbox->dump() + "; expected [x, y, w, h]");
    }
    Box box;
    box.x = get_number((*bbox)[0], where + ".bbox[0]", "a number (x)");
    box.y = get_number((*bbox)[1], where + ".bbox[1]", "a number (y)");
    box.w = get_number((*bbox)[2], where + ".bbox[2]", "a number (w)");
    box.h = get_number((*bbox)[3], where + ".bbox[3]", "a number (h)");
    instance.bbox = check_box(box, options, where + ".bbox");
  } else if (instance.mask) {
    instance.bbox = mask_bounding_box(*instance.mask);
  } else {
    throw InputError(where, "neither bbox nor mask; expected at least one of them");
  }
  return instance;
}

}  // namespace

}  // namespace detail

FrameSegmentation read_frame_json(const fs::path& file, const ReadOptions& options) {
  FrameSegmentation frame;
  frame.source = file.string();
  if (!parse_timestamp(file.stem().string(), frame.timestamp)) {
    throw InputError(file.string(), "file name is not a timestamp; expected <timestamp>.json");
  }
  const json root = detail::parse_json_file(file);
  const auto instances = root.is_object() ? root.find("instances") : root.end();
  if (!root.is_object() || instances == root.end() || !instances->is_array()) {
    throw InputError(
        file.string() + ": instances",
        std::string(root.is_object() ? (instances == root.end() ? "missing" : "not an array")
                                     : root.type_name()) +
            "; expected {\"instances\":[...]}");
  }
  for (std::size_t i = 0; i < instances->size(); ++i) {
    frame.instances.push_back(detail::read_instance(
        (*instances)[i], file.string() + ": instances[" + std::to_string(i) + "]", options));
  }
  return frame;
}

// ---- detection and dispatch ------------------------------------------------------------------

std::string detect_format(const fs::path& dir) {
  const detail::FolderScan scan = detail::scan_folder(dir);
  if (scan.entries == 0) {
    throw InputError(dir.string(), std::string("empty folder; expected ") + detail::kAccepted);
  }
  const int kinds =
      !scan.json.empty() + !scan.png.empty() + !scan.txt.empty() + !scan.folders.empty();
  if (kinds > 1) {
    throw InputError(dir.string(),
                     detail::describe(scan) +
                         "; cannot tell which is the segmentation, expected one kind "
                         "(or choose one with --seg-format, config segmentation.format)");
  }
  if (!scan.png.empty()) return "png";
  if (!scan.json.empty()) return "json";
  if (!scan.folders.empty()) return "txt-paper";
  if (!scan.txt.empty()) return detail::detect_box_layout(scan);
  throw InputError(dir.string(), "nothing recognisable: " + detail::describe(scan) + "; expected " +
                                     detail::kAccepted);
}

FrameReader::FrameReader(const fs::path& dir, const ReadOptions& options)
    : dir_(dir), options_(options) {
  options.check();
  format_ = options.format == "auto" ? detect_format(dir) : options.format;
  const detail::FolderScan scan = detail::scan_folder(dir);
  std::string expected;
  if (format_ == "json") {
    frames_ = scan.json, expected = "<timestamp>.json files";
  } else if (format_ == "png") {
    frames_ = scan.png, expected = "<timestamp>.png label images";
  } else if (format_ == "txt-paper") {
    frames_ = scan.folders, expected = "<timestamp>/ folders of <class>/<track_id>.txt";
  } else {
    frames_ = scan.txt, expected = "<timestamp>.txt box files";
  }
  if (frames_.empty()) {
    throw InputError(dir.string(), "no frame for format " + format_ + ": " +
                                       (scan.entries == 0 ? std::string("empty folder")
                                                          : detail::describe(scan)) +
                                       "; expected " + expected);
  }
  if (format_ == "png" && fs::is_regular_file(dir / "classes.txt"))
    png_classes_ = detail::read_classes_txt(dir / "classes.txt");
}

FrameSegmentation FrameReader::read(std::size_t index) const {
  const FrameEntry& entry = frames_.at(index);
  if (format_ == "json") return read_frame_json(entry.path, options_);
  if (format_ == "png")
    return detail::read_png_frame(entry, dir_ / "classes.txt", png_classes_, options_);
  if (format_ == "txt-paper") return detail::read_paper_frame(entry, options_);
  return detail::read_box_frame(entry, format_, options_);
}

Segmentation read_segmentation(const fs::path& dir, const ReadOptions& options) {
  const FrameReader reader(dir, options);
  Segmentation segmentation;
  segmentation.source = dir.string();
  segmentation.format = reader.format();
  segmentation.frames.reserve(reader.size());
  for (std::size_t i = 0; i < reader.size(); ++i) segmentation.frames.push_back(reader.read(i));
  return segmentation;
}

}  // namespace objmap::segmentation
