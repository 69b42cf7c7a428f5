// objmap report on a fuse run of a synthetic scene.
#include <gtest/gtest.h>

#include <opencv2/imgcodecs.hpp>

#include "objmap/io/objects_json.h"
#include "support/test_support.h"

namespace objmap::test {
namespace {

TEST(ReportCli, WritesATopViewAndOneTableRowPerObject) {
  RunResult r;
  const fs::path scene = cached_output(
      "seed3-orbit60-scene", {"synth", "--out", "{OUT}", "--seed", "3", "--orbit-speed", "60"}, &r);
  ASSERT_TRUE(fs::exists(scene)) << r.err;
  const fs::path run = cached_output(
      "seed3-orbit60-fuse",
      {"fuse", "--dataset", scene.string(), "--trajectory", (scene / "groundtruth.txt").string(),
       "--segmentation", (scene / "segmentation").string(), "--out", "{OUT}"},
      &r);
  ASSERT_TRUE(fs::exists(run)) << r.err;
  TempDir dir;
  r = run_objmap({"report", "--run", run.string(), "--out", (dir / "rep").string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const cv::Mat image = cv::imread((dir / "rep" / "topview.png").string(), cv::IMREAD_COLOR);
  ASSERT_FALSE(image.empty());
  EXPECT_GT(image.cols, 200);
  const auto objects = io::read_objects_json(run / "objects.json");
  const std::string md = read_text(dir / "rep" / "report.md");
  std::size_t rows = 0;
  for (const auto& o : objects)
    rows += md.find("| " + std::to_string(o.id) + " | " + o.class_name + " |") != std::string::npos;
  EXPECT_EQ(rows, objects.size());
}

TEST(ReportCli, MissingRunIsExit2) {
  TempDir dir;
  const auto r = run_objmap({"report", "--run", (dir / "nothing").string()});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("objects.json"), std::string::npos) << r.err;
}

TEST(ObjectsJson, MissingFieldIsNamed) {
  TempDir dir;
  write_text(dir / "objects.json", R"({"objects":[{"id":1,"class":"cup"}]})");
  try {
    io::read_objects_json(dir / "objects.json");
    FAIL() << "no throw";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("objects[0]"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("score"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace objmap::test
