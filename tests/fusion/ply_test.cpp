#include "objmap/io/ply.h"

#include <gtest/gtest.h>

#include <fstream>

#include "objmap/core/error.h"
#include "support/test_support.h"

namespace objmap::io {
namespace {

using objmap::test::read_text;
using objmap::test::TempDir;
using objmap::test::write_text;

PointCloud sample(bool colours) {
  PointCloud c;
  for (int i = 0; i < 1000; ++i) {
    const Vec3f p(0.001f * i, -0.5f + 1e-4f * i, 3.25f);
    if (colours)
      c.push_back(p,
                  Rgb{static_cast<std::uint8_t>(i), static_cast<std::uint8_t>(255 - i % 256), 7});
    else
      c.push_back(p);
  }
  return c;
}

TEST(Ply, BinaryRoundTripIsExact) {
  TempDir dir;
  for (bool colours : {true, false}) {
    const PointCloud c = sample(colours);
    write_ply(dir / "a.ply", c);
    const PointCloud back = read_ply(dir / "a.ply");
    EXPECT_EQ(back.points, c.points);
    EXPECT_EQ(back.colors, c.colors);
    EXPECT_EQ(std::filesystem::file_size(dir / "a.ply"),
              read_text(dir / "a.ply").find("end_header\n") + 11 + c.size() * (colours ? 15 : 12));
  }
  // No temporary file left behind.
  int files = 0;
  for (const auto& e : std::filesystem::directory_iterator(dir.path()))
    files += e.is_regular_file();
  EXPECT_EQ(files, 1);
}

TEST(Ply, LargeCloudsAndSeparateColoursRoundTrip) {
  // More points than one piece of the writer's buffer and one block of the reader (65536 each),
  // not a multiple of it.
  TempDir dir;
  PointCloud c;
  std::vector<Rgb> other;
  for (int i = 0; i < 150001; ++i) {
    c.push_back(Vec3f(1e-3f * i, -2.0f + 1e-5f * i, 0.5f * (i % 7)),
                Rgb{static_cast<std::uint8_t>(i), static_cast<std::uint8_t>(i >> 8), 9});
    other.push_back(Rgb{1, static_cast<std::uint8_t>(i % 251), static_cast<std::uint8_t>(i)});
  }
  write_ply(dir / "big.ply", c);
  PointCloud back = read_ply(dir / "big.ply");
  EXPECT_EQ(back.points, c.points);
  EXPECT_EQ(back.colors, c.colors);
  // Read a block at a time: blocks of 65536, the last one shorter, the same points in order.
  std::vector<std::size_t> sizes;
  PointCloud joined;
  read_ply_blocks(dir / "big.ply", [&](const PointCloud& block) {
    sizes.push_back(block.size());
    joined.points.insert(joined.points.end(), block.points.begin(), block.points.end());
    joined.colors.insert(joined.colors.end(), block.colors.begin(), block.colors.end());
  });
  EXPECT_EQ(sizes, (std::vector<std::size_t>{65536, 65536, 18929}));
  EXPECT_EQ(joined.points, c.points);
  EXPECT_EQ(joined.colors, c.colors);
  EXPECT_EQ(ply_vertex_count(dir / "big.ply"), 150001u);
  // The same points with other colours (the semantic map's way).
  write_ply(dir / "other.ply", c, other);
  back = read_ply(dir / "other.ply");
  EXPECT_EQ(back.points, c.points);
  EXPECT_EQ(back.colors, other);
  other.pop_back();
  try {
    write_ply(dir / "bad.ply", c, other);
    ADD_FAILURE() << "no error for a colour count that differs";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), (dir / "bad.ply").string());
    EXPECT_EQ(e.reason(), "write_ply: 150000 colours for 150001 points; expected one per point");
  }
  EXPECT_FALSE(std::filesystem::exists(dir / "bad.ply"));
}

TEST(Ply, HeaderIsTheStandardOne) {
  TempDir dir;
  write_ply(dir / "h.ply", sample(true));
  const std::string text = read_text(dir / "h.ply");
  const std::string header = text.substr(0, text.find("end_header\n") + 11);
  EXPECT_EQ(header,
            "ply\nformat binary_little_endian 1.0\ncomment objmap\nelement vertex 1000\n"
            "property float x\nproperty float y\nproperty float z\n"
            "property uchar red\nproperty uchar green\nproperty uchar blue\nend_header\n");
  write_ply(dir / "empty.ply", PointCloud{});
  EXPECT_TRUE(read_ply(dir / "empty.ply").empty());
}

TEST(Ply, ReadsAsciiWithExtraPropertiesAndDoubles) {
  TempDir dir;
  write_text(dir / "a.ply",
             "ply\nformat ascii 1.0\ncomment from somewhere\nelement vertex 2\n"
             "property double x\nproperty double y\nproperty double z\nproperty float nx\n"
             "property uchar red\nproperty uchar green\nproperty uchar blue\n"
             "element face 0\nproperty list uchar int vertex_indices\nend_header\n"
             "1 2 3 0.5 10 20 30\n-1.5 0 2.25 0 255 0 1\n");
  const PointCloud c = read_ply(dir / "a.ply");
  ASSERT_EQ(c.size(), 2u);
  EXPECT_EQ(c.points[1], Vec3f(-1.5f, 0.f, 2.25f));
  EXPECT_EQ(c.colors[0], (Rgb{10, 20, 30}));
}

TEST(Ply, ReadsEveryBinaryTypeWithItsSign) {
  // x: short -2, y: int -70000, z: double 1.25, red: char -1 (clamped to 0), green: ushort 300
  // (clamped to 255), blue: uint8 7.
  TempDir dir;
  std::string bytes =
      "ply\nformat binary_little_endian 1.0\nelement vertex 1\nproperty short x\n"
      "property int y\nproperty double z\nproperty char red\nproperty ushort green\n"
      "property uint8 blue\nend_header\n";
  const auto put = [&bytes](const void* v, std::size_t n) {
    bytes.append(static_cast<const char*>(v), n);
  };
  const std::int16_t x = -2;
  const std::int32_t y = -70000;
  const double z = 1.25;
  const std::int8_t r = -1;
  const std::uint16_t g = 300;
  const std::uint8_t b = 7;
  put(&x, 2);
  put(&y, 4);
  put(&z, 8);
  put(&r, 1);
  put(&g, 2);
  put(&b, 1);
  write_text(dir / "types.ply", bytes);
  const PointCloud c = read_ply(dir / "types.ply");
  ASSERT_EQ(c.size(), 1u);
  EXPECT_EQ(c.points[0], Vec3f(-2.f, -70000.f, 1.25f));
  EXPECT_EQ(c.colors[0], (Rgb{0, 255, 7}));
}

TEST(Ply, MalformedFilesSayWhatIsWrong) {
  TempDir dir;
  write_text(dir / "be.ply",
             "ply\nformat binary_big_endian 1.0\nelement vertex 1\nproperty float x\nend_header\n");
  try {
    read_ply(dir / "be.ply");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), (dir / "be.ply").string() + ":2");
    EXPECT_NE(e.reason().find("binary_big_endian"), std::string::npos);
  }
  EXPECT_THROW(read_ply_blocks(dir / "be.ply", [](const PointCloud&) {}), InputError);
  EXPECT_THROW(ply_vertex_count(dir / "be.ply"), InputError);
  write_ply(dir / "t.ply", sample(true));
  const std::string full = read_text(dir / "t.ply");
  write_text(dir / "t.ply", full.substr(0, full.size() - 100));
  try {
    read_ply(dir / "t.ply");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(e.reason().find("truncated"), std::string::npos) << e.what();
  }
  // A count no file of this size can hold is an error before anything is allocated (it was
  // std::bad_alloc, exit 1).
  for (const char* format : {"binary_little_endian", "ascii"}) {
    write_text(dir / "huge.ply", std::string("ply\nformat ") + format +
                                     " 1.0\nelement vertex 4000000000\nproperty float x\n"
                                     "property float y\nproperty float z\nend_header\n1 2 3\n");
    try {
      read_ply(dir / "huge.ply");
      FAIL() << format;
    } catch (const InputError& e) {
      EXPECT_NE(e.reason().find("the header says 4000000000 vertices, but only 6 bytes follow it"),
                std::string::npos)
          << e.what();
    }
  }
  write_text(dir / "noxyz.ply",
             "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nend_header\n1\n");
  EXPECT_THROW(read_ply(dir / "noxyz.ply"), InputError);
  EXPECT_THROW(read_ply(dir / "missing.ply"), InputError);
  write_text(dir / "a_file", "x");  // a file where the folder should be
  EXPECT_THROW(write_ply(dir / "a_file" / "x.ply", sample(false)), InputError);
}

}  // namespace
}  // namespace objmap::io
