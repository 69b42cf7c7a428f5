#include "objmap/io/run_path.h"

#include <gtest/gtest.h>

#include <fstream>

#include "objmap/core/error.h"
#include "support/test_support.h"

namespace objmap::io {
namespace {

namespace fs = std::filesystem;
using test::TempDir;

// The message of path_in_run's refusal; "" when it accepts.
std::string refusal(const fs::path& run, const std::string& relative) {
  try {
    path_in_run(run, relative, run / "objects.json", "objects[3].ply");
    return "";
  } catch (const InputError& e) {
    return e.what();
  }
}

TEST(RunPath, PathsInsideTheRunAreJoinedToIt) {
  TempDir dir;
  const fs::path run = dir / "run";
  fs::create_directories(run / "objects");
  std::ofstream(run / "objects" / "1_cup.ply") << "ply\n";
  EXPECT_EQ(path_in_run(run, "objects/1_cup.ply", run / "objects.json", "objects[0].ply"),
            run / "objects/1_cup.ply");
  EXPECT_EQ(refusal(run, "objects/2_not_yet_written.ply"), "");  // need not exist
  EXPECT_EQ(refusal(run, "objects/../objects/1_cup.ply"), "");
  EXPECT_EQ(refusal(run, "./objects/1_cup.ply"), "");
  EXPECT_EQ(refusal(fs::path(run.string() + "/"), "objects/1_cup.ply"), "");
  // A link that stays inside.
  fs::create_symlink(run / "objects" / "1_cup.ply", run / "objects" / "alias.ply");
  EXPECT_EQ(refusal(run, "objects/alias.ply"), "");
}

TEST(RunPath, PathsLeadingOutAreRefusedNamingTheFileFieldAndPath) {
  TempDir dir;
  const fs::path run = dir / "run";
  fs::create_directories(run / "objects");
  std::ofstream(dir / "outside.ply") << "ply\n";
  EXPECT_EQ(refusal(run, "../outside.ply"),
            (run / "objects.json").string() +
                ": objects[3].ply: '../outside.ply' resolves outside "
                "the run folder " +
                run.string() + "; expected a path inside it");
  EXPECT_NE(refusal(run, "objects/../../outside.ply"), "");
  EXPECT_NE(refusal(run, (dir / "outside.ply").string()), "");  // absolute
  EXPECT_NE(refusal(run, "/etc/passwd"), "");
  EXPECT_NE(refusal(run, ".."), "");
  EXPECT_NE(refusal(run, "."), "");  // the folder itself is no file in it
  EXPECT_NE(refusal(run, ""), "");
  // A sibling folder whose name starts like the run's.
  fs::create_directories(dir / "run2");
  EXPECT_NE(refusal(run, "../run2/x.ply"), "");
  // Links that lead out: a file, and a folder of the run.
  fs::create_symlink(dir / "outside.ply", run / "objects" / "link.ply");
  EXPECT_NE(refusal(run, "objects/link.ply"), "");
  fs::create_directory_symlink(dir.path(), run / "up");
  EXPECT_NE(refusal(run, "up/outside.ply"), "");
  EXPECT_EQ(refusal(run, "up/run/objects/missing.ply"), "") << "out and back in: resolves inside";
}

}  // namespace
}  // namespace objmap::io
