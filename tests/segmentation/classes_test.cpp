#include <gtest/gtest.h>

#include <fstream>

#include "objmap/segmentation/coco_classes.h"
#include "support/test_support.h"

namespace objmap::segmentation {
namespace {

TEST(Classes, CanonicalSpellings) {
  EXPECT_EQ(canonical_class("tv"), "tv monitor");
  EXPECT_EQ(canonical_class("tvmonitor"), "tv monitor");
  EXPECT_EQ(canonical_class("TV Monitor"), "tv monitor");
  EXPECT_EQ(canonical_class("tv_monitor"), "tv monitor");
  EXPECT_EQ(canonical_class("teddy_bear"), "teddy bear");
  EXPECT_EQ(canonical_class("  Teddy   Bear "), "teddy bear");
  EXPECT_EQ(canonical_class("cell_phone"), "cell phone");
  EXPECT_EQ(canonical_class("diningtable"), "dining table");
  EXPECT_EQ(canonical_class("sofa"), "couch");
  EXPECT_EQ(canonical_class("motorbike"), "motorcycle");
  EXPECT_EQ(canonical_class("aeroplane"), "airplane");
  EXPECT_EQ(canonical_class("pottedplant"), "potted plant");
  EXPECT_EQ(canonical_class("009_gelatin_box"), "009 gelatin box");  // not COCO: normalised only
  EXPECT_EQ(canonical_class("Chair"), "chair");
}

TEST(Classes, PaperClassesAreCoco) {
  for (const std::string name :
       {"chair", "cup", "tv monitor", "teddy bear", "bottle", "book", "keyboard", "mouse"}) {
    EXPECT_GE(coco80_id(name), 0) << name;
    EXPECT_EQ(canonical_class(name), name);
  }
  EXPECT_EQ(coco80_id("tvmonitor"), 62);
  EXPECT_EQ(coco80_id("gelatin box"), -1);
}

TEST(Classes, Coco80MatchesDarknetCocoNames) {
  const auto& names = coco80_names();
  ASSERT_EQ(names.size(), 80u);
  EXPECT_EQ(names[0], "person");
  EXPECT_EQ(names[56], "chair");
  EXPECT_EQ(names[62], "tv monitor");
  EXPECT_EQ(names[79], "toothbrush");
  const auto file = test::data_dir() / ".." / "models" / "yolo-fastest-1.1_coco" / "coco.names";
  if (!test::fs::exists(file)) GTEST_SKIP() << "missing " << file;
  std::ifstream in(file);
  std::string line;
  std::size_t id = 0;
  while (std::getline(in, line)) {
    if (line.empty()) continue;
    ASSERT_LT(id, names.size());
    EXPECT_EQ(canonical_class(line), names[id]) << "id " << id << " '" << line << "'";
    ++id;
  }
  EXPECT_EQ(id, 80u);
  // Every name is already canonical.
  for (const auto& name : names) EXPECT_EQ(canonical_class(name), name);
}

}  // namespace
}  // namespace objmap::segmentation
