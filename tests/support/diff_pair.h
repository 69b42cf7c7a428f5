#pragma once
// The synthetic pair of visits the diff tests share (tests/integration diff_test.cpp and
// diff_outputs_test.cpp): objmap synth, its second visit with known changes, both fused, each
// cached (tests/support cached_output) under a key of its own.
#include <string>
#include <vector>

#include "support/test_support.h"

namespace objmap::test {

// A synthetic first visit, its second visit (2 moved, 1 removed, 1 added) and both fused with the
// ground-truth trajectory and the noisy segmentation; small: 60 frames at half size, a full orbit.
struct SynthPair {
  fs::path first, second, run_a, run_b;
  RunResult why;
};

inline SynthPair diff_synth_pair(const std::string& seed) {
  SynthPair p;
  const std::vector<std::string> common{"--frames",      "60",  "--scale", "0.5",
                                        "--orbit-speed", "180", "--seed",  seed};
  std::vector<std::string> a{"synth", "--out", "{OUT}"};
  a.insert(a.end(), common.begin(), common.end());
  p.first = cached_output("diff-first-" + seed, a, &p.why);
  if (!fs::exists(p.first)) return p;
  std::vector<std::string> b{
      "synth", "--out", "{OUT}", "--second-visit-of", p.first.string(), "--move", "2", "--remove",
      "1",     "--add", "1"};
  b.insert(b.end(), common.begin(), common.end());
  b.back() = std::to_string(std::stoi(seed) + 100);  // the second visit's own seed
  p.second = cached_output("diff-second-" + seed, b, &p.why);
  if (!fs::exists(p.second)) return p;
  const auto fuse = [&](const fs::path& scene, const std::string& key) {
    return cached_output(
        key,
        {"fuse", "--dataset", scene.string(), "--trajectory", (scene / "groundtruth.txt").string(),
         "--segmentation", (scene / "segmentation").string(), "--out", "{OUT}"},
        &p.why);
  };
  p.run_a = fuse(p.first, "diff-first-fuse-" + seed);
  p.run_b = fuse(p.second, "diff-second-fuse-" + seed);
  return p;
}

// objmap diff of the pair (cached too): DIFF/diff.json.
inline fs::path diff_synth_diff(const SynthPair& p, const std::string& seed, RunResult* why) {
  return cached_output(
      "diff-out-" + seed,
      {"diff", "--before", p.run_a.string(), "--after", p.run_b.string(), "--out", "{OUT}"}, why);
}

}  // namespace objmap::test
