// PNG instance-ID images: <ts>.png, 8- or 16-bit single-channel label image, 0 = background, each
// other value one instance. Classes from a per-frame sidecar <ts>.instances.json
// ({"instances":[{"id":3,"class":"cup","score":0.9,"track_id":7}]},
// schemas/png_sidecar.schema.json), else from the folder's classes.txt ("<value> <class>" lines;
// then the value is also the track id), else ReadOptions.default_class with track id = value.
#include <map>
#include <opencv2/core.hpp>

#include "objmap/core/error.h"
#include "objmap/io/image.h"
#include "objmap/io/text_lines.h"
#include "objmap/segmentation/coco_classes.h"
#include "objmap/segmentation/read_internal.h"
#include "objmap/segmentation/rle.h"

namespace objmap::segmentation::detail {

// classes.txt: "# comment" lines, then "<value> <class name>" per line.
std::map<int, std::string> read_classes_txt(const fs::path& file) {
  std::map<int, std::string> classes;
  io::LineReader in(file);
  while (in.next()) {
    in.expect_fields(2, "<label value> <class name>");
    const std::int64_t value = in.integer(0, "label value");
    if (value < 1 || value > 65535) {
      throw InputError(in.where(), "label value " + std::to_string(value) +
                                       "; expected 1..65535 (0 is the background)");
    }
    if (classes.count(static_cast<int>(value))) {
      throw InputError(in.where(), "label value " + std::to_string(value) +
                                       " listed twice; expected one class per value");
    }
    classes[static_cast<int>(value)] = canonical_class(in.field(1));
  }
  return classes;
}

namespace {

using nlohmann::json;

struct SidecarEntry {
  std::string class_name;
  double score = 1.0;
  std::optional<int> track_id;
};

std::map<int, SidecarEntry> read_sidecar(const fs::path& file) {
  const json root = parse_json_file(file);
  const std::string where = file.string() + ": instances";
  const auto instances = root.is_object() ? root.find("instances") : root.end();
  if (!root.is_object() || instances == root.end() || !instances->is_array()) {
    throw InputError(where,
                     "missing or not an array; expected {\"instances\":[{\"id\":1,"
                     "\"class\":\"cup\",...}]}");
  }
  std::map<int, SidecarEntry> entries;
  for (std::size_t i = 0; i < instances->size(); ++i) {
    const json& item = (*instances)[i];
    const std::string at = where + "[" + std::to_string(i) + "]";
    if (!item.is_object()) throw InputError(at, "not an object; expected {\"id\":..,\"class\":..}");
    const auto id = item.find("id");
    if (id == item.end() || !id->is_number_integer() || id->get<std::int64_t>() < 1 ||
        id->get<std::int64_t>() > 65535) {
      throw InputError(at + ".id", (id == item.end() ? std::string("missing") : id->dump()) +
                                       "; expected the label value, an integer 1..65535");
    }
    const int value = id->get<int>();
    if (entries.count(value)) {
      throw InputError(at + ".id",
                       std::to_string(value) + " listed twice; expected one entry per id");
    }
    SidecarEntry entry;
    const auto name = item.find("class");
    if (name == item.end() || !name->is_string() ||
        canonical_class(name->get<std::string>()).empty()) {
      throw InputError(at + ".class", (name == item.end() ? std::string("missing") : name->dump()) +
                                          "; expected a class name string");
    }
    entry.class_name = canonical_class(name->get<std::string>());
    if (const auto score = item.find("score"); score != item.end()) {
      if (!score->is_number())
        throw InputError(at + ".score", score->dump() + "; expected a number in [0, 1]");
      entry.score = score->get<double>();
      check_score(entry.score, at + ".score");
    }
    if (const auto track = item.find("track_id"); track != item.end() && !track->is_null()) {
      if (!track->is_number_integer() || track->get<std::int64_t>() < 0 ||
          track->get<std::int64_t>() > 2147483647) {
        throw InputError(at + ".track_id", track->dump() + "; expected an integer >= 0 or null");
      }
      entry.track_id = track->get<int>();
    }
    entries[value] = entry;
  }
  return entries;
}

std::string list_values(const std::map<int, Mask>& masks) {
  std::string text;
  for (const auto& [value, mask] : masks)
    text += (text.empty() ? "" : ", ") + std::to_string(value);
  return text;
}

// One mask per non-zero label value, in ascending value order.
std::map<int, Mask> split_labels(const cv::Mat& labels) {
  std::map<int, Mask> masks;
  const int width = labels.cols, height = labels.rows;
  for (int v = 0; v < height; ++v) {
    for (int u = 0; u < width; ++u) {
      const int value =
          labels.depth() == CV_8U ? labels.at<std::uint8_t>(v, u) : labels.at<std::uint16_t>(v, u);
      if (value == 0) continue;
      auto it = masks.find(value);
      if (it == masks.end()) {
        Mask mask;
        mask.width = width;
        mask.height = height;
        mask.data.assign(static_cast<std::size_t>(width) * height, 0);
        it = masks.emplace(value, std::move(mask)).first;
      }
      it->second.data[static_cast<std::size_t>(v) * width + u] = 1;
    }
  }
  return masks;
}

}  // namespace

FrameSegmentation read_png_frame(const FrameEntry& entry, const fs::path& classes_file,
                                 const std::optional<std::map<int, std::string>>& classes,
                                 const ReadOptions& options) {
  const std::string where = entry.path.string();
  FrameSegmentation frame;
  frame.timestamp = entry.timestamp;
  frame.source = where;
  const cv::Mat labels = io::read_image(entry.path, /*allow_jpeg=*/false);
  if (labels.channels() != 1 || (labels.depth() != CV_8U && labels.depth() != CV_16U)) {
    throw InputError(where, std::to_string(labels.channels()) + " channel(s) of " +
                                (labels.depth() == CV_8U    ? std::string("8")
                                 : labels.depth() == CV_16U ? std::string("16")
                                                            : std::string("other")) +
                                "-bit; expected a single-channel 8- or 16-bit label image");
  }
  check_mask_size(labels.cols, labels.rows, options, where);
  std::map<int, Mask> masks = split_labels(labels);

  const fs::path sidecar_file =
      entry.path.parent_path() / (entry.path.stem().string() + ".instances.json");
  if (fs::is_regular_file(sidecar_file)) {
    const std::map<int, SidecarEntry> sidecar = read_sidecar(sidecar_file);
    for (const auto& [value, mask] : masks) {
      if (!sidecar.count(value)) {
        throw InputError(sidecar_file.string(),
                         "no entry for label value " + std::to_string(value) + " of " +
                             entry.path.filename().string() + "; expected one entry per value");
      }
    }
    for (const auto& [value, info] : sidecar) {
      if (!masks.count(value)) {
        throw InputError(
            sidecar_file.string(),
            "id " + std::to_string(value) + " has no pixel in " + entry.path.filename().string() +
                " (values present: " + list_values(masks) + "); expected ids of the label image");
      }
      Instance instance;
      instance.class_name = info.class_name;
      instance.score = info.score;
      instance.track_id = info.track_id;
      instance.mask = std::move(masks[value]);
      instance.bbox = mask_bounding_box(*instance.mask);
      frame.instances.push_back(std::move(instance));
    }
    return frame;
  }
  const std::string default_class = canonical_class(options.default_class);
  for (auto& [value, mask] : masks) {
    Instance instance;
    if (classes) {
      const auto it = classes->find(value);
      if (it == classes->end()) {
        throw InputError(where, "label value " + std::to_string(value) + " is not in " +
                                    classes_file.string() +
                                    "; expected every value of the image to have a class");
      }
      instance.class_name = it->second;
    } else {
      instance.class_name = default_class;
    }
    instance.score = 1.0;
    instance.track_id = value;  // folder-wide value = instance id across frames
    instance.mask = std::move(mask);
    instance.bbox = mask_bounding_box(*instance.mask);
    frame.instances.push_back(std::move(instance));
  }
  return frame;
}

}  // namespace objmap::segmentation::detail
