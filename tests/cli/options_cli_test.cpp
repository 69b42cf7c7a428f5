// A bad option of track or synth is named by the flag the user gave (not a library struct member),
// and a negative number for an unsigned one is refused, not wrapped round.
#include <gtest/gtest.h>

#include "support/test_support.h"

namespace objmap::test {
namespace {

TEST(TrackCli, BadOptionNamesItsFlag) {
  TempDir dir;
  const std::pair<std::string, std::string> cases[] = {
      {"--max-age", "-1"},           {"--n-init", "0"},         {"--lambda", "2"},
      {"--gate-3d-m", "-1"},         {"--gate-3d-speed", "-1"}, {"--gate-3d-history", "0"},
      {"--max-cosine-distance", "3"}, {"--max-iou-distance", "5"}, {"--std-position", "0"},
      {"--std-velocity", "0"},       {"--min-score", "nan"}};
  for (const auto& [flag, value] : cases) {
    const RunResult r =
        run_objmap({"track", "--dataset", (dir / "d").string(), "--segmentation",
                    (dir / "s").string(), "--out", (dir / "o").string(), flag, value});
    EXPECT_EQ(r.exit_code, 2) << flag;
    EXPECT_EQ(r.err.rfind("objmap: error: " + flag + ": must be ", 0), 0u) << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  }
}

TEST(SynthCli, NegativeSeedIsRefused) {
  TempDir dir;
  const RunResult r = run_objmap({"synth", "--out", (dir / "s").string(), "--seed", "-1"});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(r.err, "objmap: usage error: --seed: must be a whole number >= 0, got '-1' (see "
                   "'objmap --help')\n");
  EXPECT_FALSE(fs::exists(dir / "s"));
}

}  // namespace
}  // namespace objmap::test
