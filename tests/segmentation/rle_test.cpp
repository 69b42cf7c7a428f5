#include "objmap/segmentation/rle.h"

#include <gtest/gtest.h>

#include <random>

#include "objmap/core/error.h"
#include "support/test_support.h"

namespace objmap::segmentation {
namespace {

using test::error_of;

// A mask from rows of '0'/'1' (row-major, top row first).
Mask from_rows(const std::vector<std::string>& rows) {
  Mask mask;
  mask.height = static_cast<int>(rows.size());
  mask.width = rows.empty() ? 0 : static_cast<int>(rows[0].size());
  for (const auto& row : rows) {
    for (char c : row) mask.data.push_back(c == '1' ? 1 : 0);
  }
  return mask;
}

// 3x3, column-major order reads col 0: 0 0 0, col 1: 1 1 1, col 2: 0 0 1
//   -> runs [3 zeros, 3 ones, 2 zeros, 1 one] = counts [3, 3, 2, 1].
// String: counts 0..2 as they are: '3' '3' '2' (48 + n, each < 16 so one char, no sign bit).
// Count 3 is written as the difference to count 1: 1 - 3 = -2 -> two's complement ...11110,
// low 5 bits 11110 = 30; shifted right by 5 the rest is -1 and bit 4 of 30 is set (the sign), so it
// is the last char: 30 + 48 = 78 = 'N'.   => "332N"
TEST(Rle, HandVector3x3WithNegativeDelta) {
  const Mask mask = from_rows({"010", "010", "011"});
  EXPECT_EQ(rle_counts(mask), (std::vector<std::uint32_t>{3, 3, 2, 1}));
  EXPECT_EQ(rle_encode(mask), "332N");
  EXPECT_EQ(rle_decode("332N", 3, 3).data, mask.data);
}

// 8 rows x 6 columns (h = 8, w = 6, 48 pixels); 1-pixels: column 4 rows 3..7 and column 5
// rows 2..3. Column-major index = u*8 + v: ones at 35..39 and 42..43 -> counts [35, 5, 2, 2, 4]. 35
// = 0b100011: low 5 bits 00011 = 3, rest 1 != 0 -> more: 3 | 0x20 = 35, +48 = 83 'S';
//                then 1, rest 0 and bit 4 clear -> last: 1 + 48 = 49 '1'            => "S1"
// 5 -> '5', 2 -> '2' (first three counts are written as they are)
// count 3: 2 - 5 = -3 -> low 5 bits 11101 = 29, rest -1, bit 4 set -> last: 29 + 48 = 77 'M'
// count 4: 4 - 2 = 2 -> '2'                                                         => "S152M2"
TEST(Rle, HandVector8x6WithCountAbove32AndNegativeDelta) {
  Mask mask;
  mask.width = 6;
  mask.height = 8;
  mask.data.assign(48, 0);
  for (int v = 3; v <= 7; ++v) mask.data[v * 6 + 4] = 1;
  for (int v = 2; v <= 3; ++v) mask.data[v * 6 + 5] = 1;
  EXPECT_EQ(rle_counts(mask), (std::vector<std::uint32_t>{35, 5, 2, 2, 4}));
  EXPECT_EQ(rle_encode(mask), "S152M2");
  const Mask decoded = rle_decode("S152M2", 8, 6);
  EXPECT_EQ(decoded.data, mask.data);
  const Box box = mask_bounding_box(decoded);
  EXPECT_EQ(box.x, 4);
  EXPECT_EQ(box.y, 2);
  EXPECT_EQ(box.w, 2);
  EXPECT_EQ(box.h, 6);
  EXPECT_EQ(decoded.area(), 7u);
}

// 1 x 17, only the last pixel set: counts [16, 1]. 16 = 0b10000: low 5 bits 16 has bit 4 set, which
// would read as a negative number, so another char must follow although the rest is 0:
// 16 | 0x20 = 48, +48 = 96 '`'; then 0 -> '0'; then 1 -> '1'.   => "`01"
TEST(Rle, HandVectorPositiveCountWithBit4Set) {
  Mask mask = from_rows({"00000000000000001"});
  EXPECT_EQ(rle_counts(mask), (std::vector<std::uint32_t>{16, 1}));
  EXPECT_EQ(rle_encode(mask), "`01");
  EXPECT_EQ(rle_decode("`01", 1, 17).data, mask.data);
}

// An empty 480 x 640 mask: counts [307200]. 307200 = 9600*32 -> 0 (more) 'P'; 9600 = 300*32 -> 0
// (more) 'P'; 300 = 9*32 + 12 -> 12|0x20 = 44, +48 = 92 '\'; 9 -> '9'.   => "PP\9"
TEST(Rle, HandVectorEmptyVgaMask) {
  Mask mask;
  mask.width = 640;
  mask.height = 480;
  mask.data.assign(640 * 480, 0);
  EXPECT_EQ(rle_encode(mask), "PP\\9");
  EXPECT_EQ(rle_decode("PP\\9", 480, 640).area(), 0u);
}

TEST(Rle, FirstPixelSetStartsWithZeroRun) {
  const Mask mask = from_rows({"11"});
  EXPECT_EQ(rle_counts(mask), (std::vector<std::uint32_t>{0, 2}));
  EXPECT_EQ(rle_encode(mask), "02");
}

TEST(Rle, RoundTripsRandomMasks) {
  std::mt19937 random(42);
  for (int trial = 0; trial < 300; ++trial) {
    Mask mask;
    mask.width = std::uniform_int_distribution<int>(0, 70)(random);
    mask.height = std::uniform_int_distribution<int>(0, 50)(random);
    // Blobs of varying density so that runs range from 1 to the whole mask.
    const double density = std::uniform_real_distribution<double>(0.0, 1.0)(random);
    const int stickiness = std::uniform_int_distribution<int>(0, 40)(random);
    std::bernoulli_distribution flip(1.0 / (1 + stickiness));
    std::bernoulli_distribution on(density);
    std::uint8_t value = 0;
    for (int i = 0; i < mask.width * mask.height; ++i) {
      if (flip(random)) value = on(random) ? 1 : 0;
      mask.data.push_back(value);
    }
    const std::string text = rle_encode(mask);
    for (char c : text) ASSERT_TRUE(c >= '0' && c <= 'o') << text;
    const Mask decoded = rle_decode(text, mask.height, mask.width);
    ASSERT_EQ(decoded.data, mask.data) << mask.width << "x" << mask.height << " " << text;
    ASSERT_EQ(rle_counts_from_string(text), rle_counts(mask));
  }
}

TEST(Rle, LargeCountsRoundTrip) {
  const std::vector<std::uint32_t> counts = {0, 4000000000u, 1, 3, 2000000000u, 7};
  EXPECT_EQ(rle_counts_from_string(rle_counts_to_string(counts)), counts);
}

TEST(Rle, RejectsCharacterOutsideAlphabet) {
  EXPECT_EQ(error_of([] { rle_decode("33!N", 3, 3); }),
            "RLE counts: character '!' at position 2; expected '0'..'o'");
  EXPECT_NE(error_of([] { rle_decode("33p", 3, 3); }).find("character 'p'"), std::string::npos);
}

TEST(Rle, RejectsStringEndingInsideANumber) {
  // 'S' = 35 has the "more" bit set: a number continues after it.
  EXPECT_NE(error_of([] { rle_decode("33S", 3, 3); }).find("string ends inside a number"),
            std::string::npos);
}

TEST(Rle, RejectsNegativeRun) {
  // '0' then 'M' (= -3 as the 2nd count, which is not delta coded).
  EXPECT_NE(error_of([] { rle_decode("0M", 1, 3); }).find("run 1 (at character 1) is -3"),
            std::string::npos);
}

TEST(Rle, RejectsCountsNotSummingToImageSize) {
  EXPECT_EQ(error_of([] { rle_decode("332N", 3, 4); }),
            "RLE counts: 4 runs summing to 9 pixels; expected h*w = 3*4 = 12");
}

TEST(Rle, BoundingBoxOfEmptyMaskIsZero) {
  const Box box = mask_bounding_box(from_rows({"000", "000"}));
  EXPECT_EQ(box.w, 0);
  EXPECT_EQ(box.h, 0);
}

}  // namespace
}  // namespace objmap::segmentation
