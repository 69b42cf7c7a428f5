#include "objmap/pipeline/segmentation_frames.h"

#include <algorithm>
#include <cmath>

namespace objmap::pipeline {

namespace fs = std::filesystem;

SegmentationSource list_segmentation_frames(const fs::path& dir, const std::string& format,
                                            const segmentation::ReadOptions& read) {
  SegmentationSource seg_source;
  if (format == "json") {
    for (const auto& entry : fs::directory_iterator(dir)) {
      const fs::path& file = entry.path();
      double t = 0;
      if (entry.is_regular_file() && file.extension() == ".json" &&
          segmentation::parse_timestamp(file.stem().string(), t))
        seg_source.files.emplace_back(t, file);
    }
    std::sort(seg_source.files.begin(), seg_source.files.end());
    for (const auto& [t, file] : seg_source.files) seg_source.stamps.push_back(t);
  } else {
    seg_source.whole = segmentation::read_segmentation(dir, read);
    for (const auto& frame : seg_source.whole.frames) seg_source.stamps.push_back(frame.timestamp);
  }
  return seg_source;
}

std::vector<std::ptrdiff_t> match_segmentation_frames(const std::vector<double>& stamps,
                                                      const std::vector<Keyframe>& keyframes,
                                                      std::size_t& with_seg) {
  std::vector<std::ptrdiff_t> seg_of(keyframes.size(), -1);
  with_seg = 0;
  std::size_t j = 0;
  for (std::size_t i = 0; i < keyframes.size(); ++i) {
    const double t = keyframes[i].timestamp;
    while (j < stamps.size() && stamps[j] < t - 1e-3) ++j;
    if (j < stamps.size() && std::abs(stamps[j] - t) <= 1e-3) {
      seg_of[i] = static_cast<std::ptrdiff_t>(j);
      ++with_seg;
    }
  }
  return seg_of;
}

const segmentation::FrameSegmentation* segmentation_frame(const SegmentationSource& source,
                                                          const segmentation::ReadOptions& read,
                                                          std::ptrdiff_t index,
                                                          segmentation::FrameSegmentation& lazy) {
  if (index < 0) return nullptr;
  if (source.files.empty()) return &source.whole.frames[index];
  lazy = segmentation::read_frame_json(source.files[index].second, read);
  return &lazy;
}

}  // namespace objmap::pipeline
