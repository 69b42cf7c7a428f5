#include "objmap/pipeline/packed_pixels.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>

#include "objmap/core/error.h"
#include "objmap/geometry/backproject.h"
#include "objmap/io/deflate.h"
#include "objmap/io/image.h"
#include "support/test_support.h"

namespace objmap::pipeline {
namespace {

// The runs of the pixels of `depth` inside a disc of radius 150 px about the image centre (an
// object-sized region), with `bgr`'s colours when given.
geometry::PixelRuns disc_runs(const cv::Mat& depth, const cv::Mat* bgr, int stride) {
  Mask mask{depth.cols, depth.rows,
            std::vector<std::uint8_t>(static_cast<std::size_t>(depth.total()))};
  for (int v = 0; v < depth.rows; ++v)
    for (int u = 0; u < depth.cols; ++u) {
      const int du = u - depth.cols / 2, dv = v - depth.rows / 2;
      mask.data[static_cast<std::size_t>(v) * depth.cols + u] = du * du + dv * dv < 150 * 150;
    }
  const geometry::RayTable rays = geometry::make_ray_table(camera_preset("fr1"));
  geometry::BackprojectOptions options;
  options.stride = stride;
  options.pixel_indices = true;
  const geometry::DepthFrame frame(depth, Pose::Identity(), bgr, &mask,
                                   geometry::mask_bounds(mask));
  const geometry::BackprojectResult made = geometry::backproject(rays, frame, options);
  return geometry::make_pixel_runs(made.pixel_index, depth, made.points_in_world.colors, stride);
}

// The files a TUM list (rgb.txt, depth.txt) names, in its order.
std::vector<std::filesystem::path> listed_files(const std::filesystem::path& dir,
                                                const std::string& list) {
  std::vector<std::filesystem::path> files;
  std::ifstream in(dir / list);
  for (std::string line; std::getline(in, line);)
    if (!line.empty() && line[0] != '#') files.push_back(dir / line.substr(line.find(' ') + 1));
  return files;
}

void expect_same_runs(const geometry::PixelRuns& a, const geometry::PixelRuns& b) {
  EXPECT_EQ(a.stride, b.stride);
  EXPECT_EQ(a.first, b.first);
  EXPECT_EQ(a.end, b.end);
  EXPECT_EQ(a.raw, b.raw);
  EXPECT_EQ(a.colors, b.colors);
}

TEST(PackedPixelRuns, RealFramesComeBackBitForBitInLessThanHalfTheBytes) {
  OBJMAP_DATA_OR_SKIP(dir, "tum/fr1_rpy_every4");
  const std::vector<std::filesystem::path> depths = listed_files(dir, "depth.txt");
  const std::vector<std::filesystem::path> rgbs = listed_files(dir, "rgb.txt");
  ASSERT_GT(depths.size(), 120u);
  ASSERT_GT(rgbs.size(), 120u);
  std::size_t points = 0, packed_bytes = 0, run_bytes = 0;
  for (std::size_t i = 3; i < 120; i += 36) {  // 4 frames of the clip
    const cv::Mat depth = io::read_image(depths[i], false);
    const cv::Mat bgr = io::read_image(rgbs[i], true);
    for (int stride : {1, 2}) {
      const geometry::PixelRuns runs = disc_runs(depth, &bgr, stride);
      ASSERT_GT(runs.size(), 10000u / stride);
      const PackedPixelRuns packed = pack_pixel_runs(runs);
      expect_same_runs(unpack_pixel_runs(packed), runs);
      points += runs.size();
      packed_bytes += packed.bytes();
      run_bytes += runs.bytes();
    }
  }
  // Measured: 2.18 bytes a point against the runs' 5.10 (Kinect depth and colour noise).
  EXPECT_LT(static_cast<double>(packed_bytes) / points, 3.0);
  EXPECT_LT(packed_bytes, run_bytes / 2 + run_bytes / 10);
}

TEST(PackedPixelRuns, WithoutColoursEmptyAndWrapping) {
  // Depths that jump by more than a byte and wrap around 0 and 65535 between points; no colours.
  cv::Mat depth(480, 640, CV_16UC1);
  for (int v = 0; v < 480; ++v)
    for (int u = 0; u < 640; ++u)
      depth.at<std::uint16_t>(v, u) = static_cast<std::uint16_t>((u * 997 + v * 31) % 9000 + 1);
  geometry::PixelRuns runs = disc_runs(depth, nullptr, 1);
  ASSERT_GT(runs.size(), 50000u);
  runs.raw[0] = 65535;
  runs.raw[1] = 1;
  expect_same_runs(unpack_pixel_runs(pack_pixel_runs(runs)), runs);
  const geometry::PixelRuns none;
  const PackedPixelRuns packed_none = pack_pixel_runs(none);
  EXPECT_EQ(packed_none.points, 0u);
  expect_same_runs(unpack_pixel_runs(packed_none), none);
}

TEST(PackedPixelRuns, PlanesThatDoNotInflateToTheirPointsAreRefused) {
  cv::Mat depth(480, 640, CV_16UC1, cv::Scalar(2000));
  PackedPixelRuns packed = pack_pixel_runs(disc_runs(depth, nullptr, 1));
  PackedPixelRuns longer = packed;
  ++longer.points;
  EXPECT_THROW(unpack_pixel_runs(longer), std::logic_error);
  packed.planes.resize(packed.planes.size() / 2);
  EXPECT_THROW(unpack_pixel_runs(packed), std::logic_error);
  std::vector<std::uint8_t> out(10);
  EXPECT_FALSE(io::inflate_bytes({0xff, 0xff, 0xff}, out.data(), out.size()));
  const std::uint8_t ten[10] = {1, 2, 3, 4, 5, 6, 7, 8, 9, 10};
  EXPECT_TRUE(io::inflate_bytes(io::deflate_bytes(ten, 10), out.data(), out.size()));
  EXPECT_EQ(out, std::vector<std::uint8_t>(ten, ten + 10));
  EXPECT_FALSE(io::inflate_bytes(io::deflate_bytes(ten, 10), out.data(), 9));
}

TEST(PackedPixelFile, RunsComeBackFromTheFileAsWrittenAndTheFolderShowsNoFile) {
  test::TempDir dir;
  cv::Mat depth(480, 640, CV_16UC1), bgr(480, 640, CV_8UC3);
  for (int v = 0; v < 480; ++v)
    for (int u = 0; u < 640; ++u) {
      depth.at<std::uint16_t>(v, u) = static_cast<std::uint16_t>(1000 + (u * 7 + v * 3) % 4000);
      bgr.at<cv::Vec3b>(v, u) = cv::Vec3b(u % 256, v % 256, (u + v) % 256);
    }
  std::vector<PackedPixelRuns> packed = {pack_pixel_runs(disc_runs(depth, &bgr, 1)),
                                         pack_pixel_runs(geometry::PixelRuns{}),
                                         pack_pixel_runs(disc_runs(depth, nullptr, 2))};
  std::vector<PackedPixelFile::Entry> entries;
  std::uint64_t bytes = 0;
  {
    PackedPixelFile file(dir.path());
    for (const PackedPixelRuns& p : packed) {
      entries.push_back(file.append(p));
      bytes += p.bytes();
    }
    EXPECT_EQ(file.bytes(), bytes);
    EXPECT_TRUE(std::filesystem::is_empty(dir.path()));  // unnamed
    // In any order, bit for bit.
    for (std::size_t i = packed.size(); i-- > 0;) {
      const PackedPixelRuns back = file.read(entries[i]);
      EXPECT_EQ(back.stride, packed[i].stride);
      EXPECT_EQ(back.points, packed[i].points);
      EXPECT_EQ(back.colors, packed[i].colors);
      EXPECT_EQ(back.first, packed[i].first);
      EXPECT_EQ(back.end, packed[i].end);
      EXPECT_EQ(back.planes, packed[i].planes);
      expect_same_runs(unpack_pixel_runs(back), unpack_pixel_runs(packed[i]));
    }
    // An entry past the file's end.
    PackedPixelFile::Entry beyond = entries[0];
    beyond.offset = file.bytes() - 10;
    try {
      file.read(beyond);
      ADD_FAILURE() << "read past the end";
    } catch (const InputError& e) {
      EXPECT_EQ(std::string(e.what()),
                dir.path().string() + ": cannot read the kept pixels' file back: it ends early");
    }
  }
  EXPECT_TRUE(std::filesystem::is_empty(dir.path()));
}

TEST(PackedPixelFile, AFolderThatIsNotThereIsNamed) {
  test::TempDir dir;
  try {
    PackedPixelFile file(dir.path() / "gone");
    ADD_FAILURE() << "made a file in a missing folder";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()),
              (dir.path() / "gone").string() +
                  ": cannot make the file of the kept pixels there: No such file or directory; "
                  "expected a writable folder");
  }
}

}  // namespace
}  // namespace objmap::pipeline
