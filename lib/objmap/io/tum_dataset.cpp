#include "objmap/io/tum_dataset.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <system_error>
#include <tuple>

#include "objmap/core/error.h"
#include "objmap/io/text_lines.h"

namespace objmap::io {

namespace fs = std::filesystem;

namespace {

struct ListRow {
  double timestamp;
  fs::path file;
};

// "file: 'rgbd_dataset_freiburg1_desk.bag'" -> "rgbd_dataset_freiburg1_desk.bag".
std::string name_in_file_comment(const std::string& comment) {
  if (comment.rfind("file:", 0) != 0) return "";
  const std::size_t open = comment.find('\'');
  const std::size_t close = comment.rfind('\'');
  if (open == std::string::npos || close <= open) return "";
  return comment.substr(open + 1, close - open - 1);
}

std::vector<ListRow> read_list(const fs::path& root, const std::string& name, std::string* header) {
  const fs::path list = root / name;
  std::error_code ec;
  if (!fs::exists(list, ec))
    throw InputError(list.string(),
                     "file not found; expected a TUM RGB-D folder with rgb.txt and "
                     "depth.txt (lines 'timestamp filename')");
  LineReader in(list);
  std::vector<ListRow> rows;
  std::size_t previous_line = 0;
  while (in.next()) {
    in.expect_fields(2, "timestamp filename");
    const double t = in.number(0, "timestamp");
    if (!rows.empty() && t <= rows.back().timestamp)
      throw InputError(in.where(),
                       "timestamp " + in.field(0) +
                           (t == rows.back().timestamp ? " duplicates" : " is before that of") +
                           " line " + std::to_string(previous_line) +
                           "; expected strictly increasing timestamps");
    const fs::path image = root / in.field(1);
    if (!fs::is_regular_file(image, ec))
      throw InputError(in.where(), "listed image " + image.string() + " does not exist");
    previous_line = in.line_number();
    rows.push_back({t, image});
  }
  if (rows.empty())
    throw InputError(list.string(), "lists no image; expected lines 'timestamp filename'");
  if (header)
    for (const std::string& c : in.comments())
      if (std::string n = name_in_file_comment(c); !n.empty()) {
        *header = n;
        break;
      }
  return rows;
}

}  // namespace

void TumOptions::check() const {
  require(std::isfinite(max_diff_s) && max_diff_s > 0.0, "TumOptions.max_diff_s",
          "is " + std::to_string(max_diff_s) + "; expected a finite number of seconds > 0");
}

std::vector<std::pair<std::size_t, std::size_t>> associate_stamps(
    const std::vector<double>& rgb_stamps, const std::vector<double>& depth_stamps,
    double max_diff_s) {
  // All candidate pairs |a - b| < max_diff (a window search over the sorted depth stamps finds the
  // same set as associate.py's double loop), sorted as Python sorts (diff, a, b) tuples.
  std::vector<std::tuple<double, double, double, std::size_t, std::size_t>> candidates;
  for (std::size_t i = 0; i < rgb_stamps.size(); ++i) {
    const double a = rgb_stamps[i];
    auto j = std::lower_bound(depth_stamps.begin(), depth_stamps.end(), a - 2.0 * max_diff_s);
    for (; j != depth_stamps.end() && *j <= a + 2.0 * max_diff_s; ++j) {
      const double diff = std::abs(a - *j);
      if (diff < max_diff_s)
        candidates.emplace_back(diff, a, *j, i, static_cast<std::size_t>(j - depth_stamps.begin()));
    }
  }
  std::sort(candidates.begin(), candidates.end());
  std::vector<bool> rgb_used(rgb_stamps.size(), false), depth_used(depth_stamps.size(), false);
  std::vector<std::pair<std::size_t, std::size_t>> matches;
  for (const auto& [diff, a, b, i, j] : candidates) {
    if (rgb_used[i] || depth_used[j]) continue;
    rgb_used[i] = depth_used[j] = true;
    matches.emplace_back(i, j);
  }
  std::sort(matches.begin(), matches.end());
  return matches;
}

std::string recorded_from_header(const fs::path& list_file) {
  std::ifstream in(list_file);
  std::string line;
  while (std::getline(in, line)) {
    const std::size_t first = line.find_first_not_of(" \t");
    if (first == std::string::npos) continue;
    if (line[first] != '#') break;  // the header is over
    const std::size_t text = line.find_first_not_of(" \t", first + 1);
    if (text == std::string::npos) continue;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (std::string n = name_in_file_comment(line.substr(text)); !n.empty()) return n;
  }
  return "";
}

Dataset read_tum_dataset(const fs::path& dir, const TumOptions& options) {
  options.check();
  std::error_code ec;
  if (!fs::exists(dir, ec)) throw InputError(dir.string(), "folder not found");
  if (!fs::is_directory(dir, ec))
    throw InputError(dir.string(), "is not a folder; expected a TUM RGB-D folder");
  if (fs::is_empty(dir, ec))
    throw InputError(dir.string(),
                     "empty folder; expected a TUM RGB-D folder with rgb.txt, "
                     "depth.txt, rgb/ and depth/");
  Dataset dataset;
  dataset.root = dir;
  const std::vector<ListRow> rgb = read_list(dir, "rgb.txt", &dataset.recorded_from);
  const std::vector<ListRow> depth = read_list(dir, "depth.txt", nullptr);
  dataset.rgb_rows = rgb.size();
  dataset.depth_rows = depth.size();

  std::vector<double> rgb_stamps, depth_stamps;
  for (const ListRow& r : rgb) rgb_stamps.push_back(r.timestamp);
  for (const ListRow& r : depth) depth_stamps.push_back(r.timestamp);
  for (const auto& [i, j] : associate_stamps(rgb_stamps, depth_stamps, options.max_diff_s))
    dataset.frames.push_back({rgb[i].timestamp, depth[j].timestamp, rgb[i].file, depth[j].file});
  if (dataset.frames.empty())
    throw InputError(dir.string(), "no rgb image has a depth image within max_diff " +
                                       std::to_string(options.max_diff_s) +
                                       " s; expected rgb.txt and depth.txt of the same recording");
  return dataset;
}

}  // namespace objmap::io
