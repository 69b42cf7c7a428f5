// The agreement of two segmentations of the same frames (a detect backend or option against the
// reference path): instances matched one-to-one within a class by mask IoU
// (segmentation/detect_compare.h), over every frame of both folders.
//   build/bin/detect_agreement REFERENCE_SEG OTHER_SEG
// Prints the instances of each, the matched pairs, the smallest and median IoU, the share of pairs
// with IoU >= 0.95, and the instances left unmatched on either side. Exit 1 when a frame is
// missing.
#include <cstdio>
#include <map>

#include "objmap/core/error.h"
#include "objmap/segmentation/detect_compare.h"
#include "objmap/segmentation/read.h"

using namespace objmap::segmentation;

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: detect_agreement REFERENCE_SEG OTHER_SEG\n");
    return 2;
  }
  Segmentation reference, other;
  try {
    reference = read_segmentation(argv[1]);
    other = read_segmentation(argv[2]);
  } catch (const objmap::InputError& e) {
    std::fprintf(stderr, "detect_agreement: %s\n", e.what());
    return 2;
  }
  std::map<double, const FrameSegmentation*> by_time;
  for (const auto& f : other.frames) by_time[f.timestamp] = &f;
  MaskAgreement all;
  std::size_t missing = 0;
  for (const auto& f : reference.frames) {
    const auto it = by_time.find(f.timestamp);
    if (it == by_time.end()) {
      ++missing;
      continue;
    }
    all.add(compare_masks(f.instances, it->second->instances));
  }
  std::size_t good = 0;
  for (double iou : all.ious) good += iou >= 0.95;
  std::printf(
      "frames %zu (%zu missing in the other)\ninstances reference %zu, other %zu, matched %zu\n"
      "mask IoU of matched pairs: min %.4f, median %.4f, >= 0.95: %zu of %zu\n"
      "unmatched: reference %zu, other %zu\n",
      reference.frames.size(), missing, all.reference, all.other, all.ious.size(), all.min_iou(),
      all.median_iou(), good, all.ious.size(), all.unmatched_reference, all.unmatched_other);
  return missing ? 1 : 0;
}
