#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "objmap/segmentation/types.h"

// COCO run-length encoding of binary masks, compressed string form, byte-compatible with
// pycocotools (mask.encode(np.asfortranarray(m))["counts"]).
//
// Runs are taken in column-major (Fortran) order, i.e. down the first column, then the second, ...,
// alternating 0-runs and 1-runs and always starting with a 0-run (which may be 0 long). The counts
// are then written as a string: from the 4th count on (0-based index i > 2) the difference to the
// count two before is written instead of the count itself; each number is cut into 5-bit groups,
// least significant first, each group goes in one character (bit 5 = "more groups follow", bit 4 of
// the last group = sign), and 48 is added so that every character is in '0'..'o'.
namespace objmap::segmentation {

// Run lengths (uncompressed RLE) of `mask` in column-major order, starting with a 0-run.
std::vector<std::uint32_t> rle_counts(const Mask& mask);
// The mask of size height x width for uncompressed run lengths. Throws InputError when the counts
// do not sum to height*width.
Mask rle_counts_decode(const std::vector<std::uint32_t>& counts, int height, int width);

// Compressed string of run lengths (pycocotools rleToString) and back (rleFrString). The decoder
// throws InputError on a character outside '0'..'o', a string that ends inside a number, a run
// that would be negative or too long.
std::string rle_counts_to_string(const std::vector<std::uint32_t>& counts);
std::vector<std::uint32_t> rle_counts_from_string(const std::string& counts);

// Mask -> compressed string and back.
std::string rle_encode(const Mask& mask);
// Throws InputError on a bad string or counts that do not sum to height*width.
Mask rle_decode(const std::string& counts, int height, int width);

// Tight bounding box of the 1-pixels, {x, y, w, h} with w = x_max - x_min + 1 (as pycocotools
// toBbox); {0, 0, 0, 0} for a mask without 1-pixels.
Box mask_bounding_box(const Mask& mask);

}  // namespace objmap::segmentation
