// No command writes over what it reads: an output that is an input, or a folder that
// holds one, is exit 2 naming both flags, and the input is left as it was.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "support/test_support.h"

namespace objmap::test {
namespace {

struct Case {
  std::vector<std::string> args;
  std::string message;  // the start of the error after "objmap: error: "
  fs::path kept;        // the input that must be unchanged
};

void expect_refused(const Case& c) {
  const std::string before = fs::is_regular_file(c.kept) ? read_text(c.kept) : "";
  const auto count = [&] {
    std::size_t n = 0;
    if (fs::is_directory(c.kept))
      for (const auto& e : fs::recursive_directory_iterator(c.kept)) n += e.is_regular_file();
    return n;
  };
  const std::size_t files = count();
  const RunResult r = run_objmap(c.args);
  EXPECT_EQ(r.exit_code, 2) << c.message << "\n" << r.err;
  EXPECT_EQ(r.err.rfind("objmap: error: " + c.message, 0), 0u) << r.err;
  EXPECT_NE(r.err.find("objmap never writes over what it reads"), std::string::npos) << r.err;
  if (fs::is_regular_file(c.kept)) {
    EXPECT_EQ(read_text(c.kept), before) << c.kept;
  }
  EXPECT_EQ(count(), files) << c.kept;
}

TEST(InputsCli, NoCommandWritesOverWhatItReads) {
  OBJMAP_DATA_OR_SKIP(data, "tum/fr1_desk_9");
  OBJMAP_DATA_OR_SKIP(models, "../models/yolo-fastest-1.1_coco");
  TempDir tmp;
  const std::string d = data.string(), gt = (data / "groundtruth.txt").string();
  const fs::path seg = tmp / "seg", run = tmp / "run", traj = tmp / "gt.txt";
  ASSERT_EQ(run_objmap({"detect", "--dataset", d, "--model",
                        (models / "yolo-fastest-1.1-xl.weights").string(), "--out", seg.string()})
                .exit_code,
            0);
  ASSERT_EQ(run_objmap({"fuse", "--dataset", d, "--trajectory", gt, "--segmentation", seg.string(),
                        "--out", run.string()})
                .exit_code,
            0);
  write_text(traj, read_text(data / "groundtruth.txt"));
  fs::create_directory_symlink(seg, tmp / "seg-link");
  const std::string t = traj.string();
  const std::vector<Case> cases{
      {{"track", "--dataset", d, "--segmentation", seg.string(), "--out", seg.string()},
       "--out: " + seg.string() + " is the input of --segmentation",
       seg},
      {{"track", "--dataset", d, "--segmentation", seg.string(), "--out",
        (tmp / "seg-link").string()},
       "--out: " + (tmp / "seg-link").string() + " is the input of --segmentation",
       seg},
      {{"track", "--dataset", d, "--segmentation", seg.string(), "--out",
        (tmp / "x" / ".." / "seg").string()},
       "--out: ",
       seg},
      {{"correct", "--run", run.string(), "--out", run.string()},
       "--out: " + run.string() + " is the input of --run",
       run},
      {{"fuse", "--dataset", d, "--trajectory", gt, "--segmentation", seg.string(), "--out",
        seg.string()},
       "--out: " + seg.string() + " is the input of --segmentation",
       seg},
      {{"eval", "ate", "--gt", t, "--est", t, "--json", t},
       "--json: " + t + " is the input of --gt",
       traj},
      {{"eval", "ate", "--gt", gt, "--est", t, "--save-aligned", t},
       "--save-aligned: " + t + " is the input of --est",
       traj},
      {{"eval", "rpe", "--gt", gt, "--est", t, "--json", t},
       "--json: " + t + " is the input of --est",
       traj},
      {{"eval", "objects", "--map", (run / "objects.json").string(), "--reference",
        (run / "objects.json").string(), "--json", (run / "objects.json").string()},
       "--json: ",
       run / "objects.json"},
      {{"eval", "tracks", "--gt", seg.string(), "--est", seg.string(), "--json", seg.string()},
       "--json: " + seg.string() + " is the input of --gt",
       seg},
      {{"eval", "masks", "--run", run.string(), "--json", run.string()},
       "--json: " + run.string() + " is the input of --run",
       run},
      // A folder that holds an input is never replaced either.
      {{"correct", "--run", run.string(), "--out", tmp.path().string()}, "--out: ", run},
  };
  for (const Case& c : cases) expect_refused(c);
}

TEST(InputsCli, AnOutputThatCannotBeWrittenIsRefusedBeforeTheWork) {
  // --out inside a regular file: refused before any work, naming the output and the file in its
  // way (not the temporary folder at the final rename).
  OBJMAP_DATA_OR_SKIP(data, "tum/fr1_desk_9");
  TempDir tmp;
  write_text(tmp / "a_file", "x");
  const RunResult r = run_objmap({"fuse", "--dataset", data.string(), "--trajectory",
                                  (data / "groundtruth.txt").string(), "--segmentation",
                                  (data / "detections_yolofastest").string(), "--out",
                                  (tmp / "a_file" / "run").string()});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(r.err, "objmap: error: " + (tmp / "a_file" / "run").string() +
                       ": cannot be written: " + (tmp / "a_file").string() +
                       " is not a folder; expected an output inside a folder\n");
  EXPECT_EQ(r.out, "") << "no work was done";
}

}  // namespace
}  // namespace objmap::test
