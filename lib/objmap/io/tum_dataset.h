#pragma once
#include <cstddef>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "objmap/io/dataset.h"

// The tum layout: a TUM RGB-D folder: rgb.txt and depth.txt list `timestamp filename` (filename
// relative to the folder; '#' comments and blank lines allowed), the images are in rgb/ and depth/.
namespace objmap::io {

struct TumOptions {
  double max_diff_s = 0.02;  // rgb and depth stamps pair when |t_rgb - t_depth| < max_diff_s
                             // (strictly, as associate.py); finite, > 0
  void check() const;        // throws InputError naming the bad field
};

// Reads rgb.txt and depth.txt of `dir` and associates them one to one exactly as the TUM
// benchmark's associate.py: every candidate pair with |a - b| < max_diff_s, sorted by (difference,
// rgb time, depth time), taken greedily when both are still free, then sorted by rgb time.
// Every listed image must exist. Throws InputError for a missing folder, rgb.txt or depth.txt, a
// line that is not `timestamp filename`, timestamps not strictly increasing, a listed image that
// does not exist, a list with no image, and no associated pair at all.
Dataset read_tum_dataset(const std::filesystem::path& dir, const TumOptions& options = {});

// The association alone, on two increasing lists of stamps: pairs of indices (rgb, depth), sorted
// by rgb index.
std::vector<std::pair<std::size_t, std::size_t>> associate_stamps(
    const std::vector<double>& rgb_stamps, const std::vector<double>& depth_stamps,
    double max_diff_s);

// The name inside a "file: '<name>'" comment of a TUM list (rgb.txt, groundtruth.txt), or "".
std::string recorded_from_header(const std::filesystem::path& list_file);

}  // namespace objmap::io
