#pragma once
#include <cstddef>
#include <cstdint>
#include <opencv2/core.hpp>
#include <vector>

#include "objmap/core/types.h"
#include "objmap/geometry/backproject.h"

// A back-projection's points kept as the pixels they came from (objmap follow keeps every
// keyframe's observations for a loop closure): runs of pixels of one row, `stride` apart, with
// each pixel's raw depth and colour. 5 bytes a point and 8 a run, against 15 a point for the
// points themselves; made again into points with any pose, they are the points backproject() makes
// of the same pixels with that pose, bit for bit.
namespace objmap::geometry {

struct PixelRuns {
  int stride = 1;                    // the back-projection's: pixels of a run are stride apart
  std::vector<std::uint32_t> first;  // each run's first pixel, v * width + u
  std::vector<std::uint32_t> end;    // each run's end: its last point's index + 1
  std::vector<std::uint16_t> raw;    // each point's raw depth-image value
  std::vector<Rgb> colors;           // each point's colour (empty: none)

  std::size_t size() const { return raw.size(); }
  std::size_t bytes() const;  // what the runs hold (their vectors' sizes)
};

// The runs of backproject()'s points (made with options.pixel_indices and `stride`): their pixel
// indices (ascending, as backproject gives them), the depth image they were read from (CV_16UC1)
// and their colours (`colors` empty or one per point). Throws InputError when the sizes disagree
// or an index lies outside `depth`.
PixelRuns make_pixel_runs(const std::vector<std::uint32_t>& pixel_index, const cv::Mat& depth,
                          const std::vector<Rgb>& colors, int stride);

// The points of `runs` in the world with `world_from_cam` (eqs 11-15 as backproject() computes
// them, through `rays`), with their colours. Throws InputError when a run's pixels lie outside the
// ray table.
PointCloud points_from_runs(const RayTable& rays, const PixelRuns& runs,
                            const Pose& world_from_cam);

}  // namespace objmap::geometry
