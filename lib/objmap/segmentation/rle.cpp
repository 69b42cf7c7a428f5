#include "objmap/segmentation/rle.h"

#include <algorithm>
#include <cstdint>
#include <limits>

#include "objmap/core/error.h"

namespace objmap::segmentation {

namespace {

void check_mask_shape(const Mask& mask) {
  require(mask.width >= 0 && mask.height >= 0 &&
              mask.data.size() == static_cast<std::size_t>(mask.width) * mask.height,
          "Mask",
          "data has " + std::to_string(mask.data.size()) + " bytes; expected width*height = " +
              std::to_string(mask.width) + "*" + std::to_string(mask.height));
}

std::string show_char(char c) {
  if (c >= 32 && c < 127) return std::string("'") + c + "'";
  return "byte " + std::to_string(static_cast<unsigned char>(c));
}

}  // namespace

std::vector<std::uint32_t> rle_counts(const Mask& mask) {
  check_mask_shape(mask);
  std::vector<std::uint32_t> counts;
  std::uint8_t previous = 0;  // the first run is a 0-run, possibly of length 0
  std::uint32_t run = 0;
  for (int u = 0; u < mask.width; ++u) {     // column-major: down each column,
    for (int v = 0; v < mask.height; ++v) {  // then the next column
      const std::uint8_t value = mask.at(u, v) ? 1 : 0;
      if (value != previous) {
        counts.push_back(run);
        run = 0;
        previous = value;
      }
      ++run;
    }
  }
  counts.push_back(run);
  return counts;
}

Mask rle_counts_decode(const std::vector<std::uint32_t>& counts, int height, int width) {
  require(height >= 0 && width >= 0, "RLE size",
          "[" + std::to_string(height) + "," + std::to_string(width) + "]; expected [h,w] >= 0");
  const std::uint64_t pixels =
      static_cast<std::uint64_t>(height) * static_cast<std::uint64_t>(width);
  std::uint64_t sum = 0;
  for (std::uint32_t count : counts) sum += count;
  if (sum != pixels) {
    throw InputError("RLE counts", std::to_string(counts.size()) + " runs summing to " +
                                       std::to_string(sum) +
                                       " pixels; expected h*w = " + std::to_string(height) + "*" +
                                       std::to_string(width) + " = " + std::to_string(pixels));
  }
  Mask mask;
  mask.width = width;
  mask.height = height;
  mask.data.assign(pixels, 0);
  std::uint64_t position = 0;  // column-major index: u * height + v
  for (std::size_t i = 0; i < counts.size(); ++i) {
    if (i % 2 == 1) {  // odd runs are 1-runs
      for (std::uint64_t j = position; j < position + counts[i]; ++j) {
        const std::uint64_t u = j / height, v = j % height;
        mask.data[v * width + u] = 1;
      }
    }
    position += counts[i];
  }
  return mask;
}

std::string rle_counts_to_string(const std::vector<std::uint32_t>& counts) {
  std::string text;
  for (std::size_t i = 0; i < counts.size(); ++i) {
    // From the 4th count on, the difference to the count two before (the previous run of the
    // same value), which is small and may be negative.
    std::int64_t x = counts[i];
    if (i > 2) x -= static_cast<std::int64_t>(counts[i - 2]);
    bool more = true;
    while (more) {
      int group = static_cast<int>(x & 0x1f);  // 5 bits, least significant first
      x >>= 5;                                 // arithmetic shift: keeps the sign
      // Done when the rest is all sign bits and bit 4 of this group already carries that sign.
      more = (group & 0x10) ? x != -1 : x != 0;
      if (more) group |= 0x20;
      text.push_back(static_cast<char>(group + 48));
    }
  }
  return text;
}

std::vector<std::uint32_t> rle_counts_from_string(const std::string& text) {
  std::vector<std::uint32_t> counts;
  std::size_t p = 0;
  while (p < text.size()) {
    const std::size_t start = p;
    std::int64_t x = 0;
    int k = 0;
    bool more = true;
    while (more) {
      if (p >= text.size()) {
        throw InputError("RLE counts", "string ends inside a number (at character " +
                                           std::to_string(start) +
                                           "); expected a last character below 'P'");
      }
      const int group = static_cast<int>(static_cast<unsigned char>(text[p])) - 48;
      if (group < 0 || group > 63) {
        throw InputError("RLE counts", "character " + show_char(text[p]) + " at position " +
                                           std::to_string(p) + "; expected '0'..'o'");
      }
      if (k >= 7) {
        throw InputError("RLE counts", "number at position " + std::to_string(start) +
                                           " has more than 7 characters; expected a run length "
                                           "below 2^32");
      }
      x |= static_cast<std::int64_t>(group & 0x1f) << (5 * k);
      more = (group & 0x20) != 0;
      ++p;
      ++k;
      if (!more && (group & 0x10)) {  // negative: sign-extend above the 5k bits read
        x = static_cast<std::int64_t>(static_cast<std::uint64_t>(x) |
                                      (~std::uint64_t{0} << (5 * k)));
      }
    }
    if (counts.size() > 2) x += counts[counts.size() - 2];
    if (x < 0 || x > std::numeric_limits<std::uint32_t>::max()) {
      throw InputError("RLE counts", "run " + std::to_string(counts.size()) + " (at character " +
                                         std::to_string(start) + ") is " + std::to_string(x) +
                                         "; expected a length >= 0");
    }
    counts.push_back(static_cast<std::uint32_t>(x));
  }
  return counts;
}

std::string rle_encode(const Mask& mask) { return rle_counts_to_string(rle_counts(mask)); }

Mask rle_decode(const std::string& counts, int height, int width) {
  return rle_counts_decode(rle_counts_from_string(counts), height, width);
}

Box mask_bounding_box(const Mask& mask) {
  check_mask_shape(mask);
  int u_min = mask.width, v_min = mask.height, u_max = -1, v_max = -1;
  for (int v = 0; v < mask.height; ++v) {
    const std::uint8_t* row = mask.data.data() + static_cast<std::size_t>(v) * mask.width;
    for (int u = 0; u < mask.width; ++u) {
      if (!row[u]) continue;
      u_min = std::min(u_min, u);
      u_max = std::max(u_max, u);
      v_min = std::min(v_min, v);
      v_max = std::max(v_max, v);
    }
  }
  if (u_max < 0) return Box{};
  return Box{static_cast<double>(u_min), static_cast<double>(v_min),
             static_cast<double>(u_max - u_min + 1), static_cast<double>(v_max - v_min + 1)};
}

}  // namespace objmap::segmentation
