// An interrupted command (Ctrl-C, kill) leaves nothing half-written: its unfinished output is
// removed, an earlier output stays as it was, and the exit status says which signal ended it.
#include <gtest/gtest.h>

#include <csignal>

#include "support/test_support.h"

namespace objmap::test {
namespace {

// True when `dir` holds an entry whose name starts with `prefix`.
bool holds(const fs::path& dir, const std::string& prefix) {
  std::error_code ec;
  for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec))
    if (it->path().filename().string().rfind(prefix, 0) == 0) return true;
  return false;
}

// objmap synth writes into its temporary folder from the start (frame by frame): interrupted once
// that folder is there, it removes it and ends by the signal; the earlier sequence stays.
TEST(Interrupt, SynthRemovesItsUnfinishedFolderAndKeepsTheEarlierOne) {
  TempDir dir;
  const fs::path scene = dir / "scene";
  write_text(scene / "synth.json", "{\"earlier\": true}");  // an earlier sequence
  for (int sig : {SIGINT, SIGTERM}) {
    const RunResult r = run_objmap_interrupted(
        {"synth", "--out", scene.string(), "--frames", "300", "--threads", "1"},
        [&] { return holds(dir.path(), "scene.tmp-"); }, sig);
    EXPECT_EQ(r.exit_code, 128 + sig) << r.err;
    EXPECT_NE(r.err.find("objmap: interrupted ("), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("; removed the unfinished " + scene.string() + ".tmp-"), std::string::npos)
        << r.err;
    EXPECT_FALSE(holds(dir.path(), "scene.")) << "a temporary folder is left";
    EXPECT_EQ(read_text(scene / "synth.json"), "{\"earlier\": true}");
  }
}

}  // namespace
}  // namespace objmap::test
