#pragma once
// The short synthetic walk-through the live tests replay (objmap synth --preset walkthrough at
// half size), made once per objmap binary in the test cache.
#include <string>

#include "support/test_support.h"

namespace objmap::test {

// The walk-through of seed 5 with `frames` frames; empty (and a test failure) when synth failed.
inline fs::path live_scene(int frames) {
  RunResult why;
  const fs::path scene =
      cached_output("live-walk" + std::to_string(frames),
                    {"synth", "--out", "{OUT}", "--preset", "walkthrough", "--frames",
                     std::to_string(frames), "--scale", "0.5", "--seed", "5", "--threads", "2"},
                    &why);
  if (!fs::exists(scene)) {
    ADD_FAILURE() << "objmap synth: " << why.err;
    return {};
  }
  return scene;
}

}  // namespace objmap::test
