#include "objmap/segmentation/write.h"

#include <cstdio>
#include <nlohmann/json.hpp>
#include <set>

#include "objmap/core/error.h"
#include "objmap/io/atomic.h"
#include "objmap/segmentation/rle.h"

namespace objmap::segmentation {

std::string frame_file_name(double timestamp) {
  char name[64];
  std::snprintf(name, sizeof name, "%.6f.json", timestamp);
  return name;
}

std::string frame_json(const FrameSegmentation& frame) {
  // ordered_json keeps the documented key order: class, score, track_id, bbox, mask.
  nlohmann::ordered_json instances = nlohmann::ordered_json::array();
  for (const Instance& instance : frame.instances) {
    nlohmann::ordered_json item;
    item["class"] = instance.class_name;
    item["score"] = instance.score;
    if (instance.track_id) item["track_id"] = *instance.track_id;
    item["bbox"] = {instance.bbox.x, instance.bbox.y, instance.bbox.w, instance.bbox.h};
    if (instance.mask) {
      item["mask"]["size"] = {instance.mask->height, instance.mask->width};
      item["mask"]["counts"] = rle_encode(*instance.mask);
    }
    instances.push_back(std::move(item));
  }
  nlohmann::ordered_json root;
  root["instances"] = std::move(instances);
  return root.dump() + "\n";
}

void write_frame_json(const std::filesystem::path& file, const FrameSegmentation& frame) {
  io::write_file_atomic(file, frame_json(frame));
}

void require_distinct_frame_names(const std::filesystem::path& dir,
                                  const std::vector<double>& timestamps) {
  std::set<std::string> names;
  for (const double timestamp : timestamps) {
    const std::string name = frame_file_name(timestamp);
    if (!names.insert(name).second) {
      throw InputError((dir / name).string(),
                       "two frames have this file name; expected timestamps that differ at 6 "
                       "decimals");
    }
  }
}

void write_segmentation(const std::filesystem::path& dir, const Segmentation& segmentation) {
  std::vector<double> timestamps;
  for (const FrameSegmentation& frame : segmentation.frames) timestamps.push_back(frame.timestamp);
  require_distinct_frame_names(dir, timestamps);
  io::create_output_folders(dir);
  for (const FrameSegmentation& frame : segmentation.frames) {
    write_frame_json(dir / frame_file_name(frame.timestamp), frame);
  }
}

}  // namespace objmap::segmentation
