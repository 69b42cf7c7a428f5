// The 3D view's data and section (lib/objmap/report/view3d.h); the page in a browser is
// tests/report/view3d_browser_test.mjs.
#include "objmap/report/view3d.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <functional>
#include <nlohmann/json.hpp>

#include "objmap/core/error.h"
#include "objmap/report/page.h"
#include "xml_check.h"

namespace objmap::report {
namespace {

using test::base64_decode;
using test::count_of;
using test::xml_problem;

const char* kHostile = "</script><script>alert(1)</script><!-- & \"x\"";

View3dContent small_view() {
  View3dContent c;
  for (int i = 0; i < 50; ++i)
    c.map.push_back(Vec3f(0.01f * i, -0.02f * i, 1.0f + 0.003f * i), Rgb{10, 20, 30});
  View3dObject o;
  o.id = 4;
  o.class_name = kHostile;
  o.obb.center = Vec3(1, 2, 3);
  o.obb.half_extent = Vec3(0.1, 0.2, 0.3);
  o.points = {Vec3f(0.9f, 1.8f, 2.7f), Vec3f(1.1f, 2.2f, 3.3f), Vec3f(1.0f, 2.0f, 3.0f)};
  o.relations = {std::string("on surface 1 (") + kHostile + ")"};
  c.objects.push_back(o);
  c.surfaces.push_back(
      {1, "table", std::nullopt, {Vec3(0, 0, 0.7), Vec3(1, 0, 0.7), Vec3(1, 1, 0.7)}});
  c.camera_path = {Vec3(0, 0, 1.5), Vec3(0.1, 0, 1.5)};
  c.queries["cup on table"] = {4};
  return c;
}

nlohmann::json data_of(const std::string& section) {
  const std::string open = "<script type=\"application/json\" id=\"view3d-data\">";
  const std::size_t at = section.find(open) + open.size();
  return nlohmann::json::parse(section.substr(at, section.find("</script>", at) - at));
}

// The uint16 grid of a points block back in metres.
std::vector<Vec3f> decoded(const nlohmann::json& block) {
  const std::string bytes = base64_decode(block["xyz"].get<std::string>());
  std::vector<Vec3f> out;
  for (std::size_t i = 0; i + 6 <= bytes.size(); i += 6) {
    Vec3f p;
    for (int k = 0; k < 3; ++k) {
      const unsigned q = static_cast<std::uint8_t>(bytes[i + 2 * k]) |
                         static_cast<std::uint8_t>(bytes[i + 2 * k + 1]) << 8;
      p[k] =
          static_cast<float>(block["origin"][k].get<double>() + q * block["step_m"].get<double>());
    }
    out.push_back(p);
  }
  return out;
}

TEST(View3d, RunTextCannotEndTheScriptAndReadsBackExactly) {
  const std::string section = view3d_html(small_view(), {});
  EXPECT_EQ(count_of(section, "<script"), 2u);   // the data and the viewer
  EXPECT_EQ(count_of(section, "</script"), 2u);  // none from the class name
  EXPECT_EQ(section.find("<!--"), std::string::npos);
  EXPECT_EQ(section.find("alert(1)</"), std::string::npos);
  const nlohmann::json data = data_of(section);
  EXPECT_EQ(data["objects"][0]["class"], kHostile);  // \u003c reads back as '<'
  EXPECT_EQ(data["objects"][0]["relations"][0], std::string("on surface 1 (") + kHostile + ")");
  EXPECT_EQ(data["queries"]["cup on table"], nlohmann::json::array({4}));
  EXPECT_EQ(data["surfaces"][0]["above_floor_m"], nullptr);  // no floor found
}

TEST(View3d, PointsReadBackWithinHalfAGridStep) {
  const View3dContent c = small_view();
  const nlohmann::json data = data_of(view3d_html(c, {}));
  const std::vector<Vec3f> map = decoded(data["map"]);
  ASSERT_EQ(map.size(), c.map.size());
  const double half_step = data["map"]["step_m"].get<double>() / 2 + 1e-6;
  for (std::size_t i = 0; i < map.size(); ++i)
    EXPECT_LE((map[i] - c.map.points[i]).cwiseAbs().maxCoeff(), half_step) << i;
  EXPECT_EQ(base64_decode(data["map"]["rgb"].get<std::string>()).substr(0, 3),
            std::string("\x0a\x14\x1e"));
  const std::vector<Vec3f> object = decoded(data["objects"][0]["points"]);
  ASSERT_EQ(object.size(), 3u);
  EXPECT_NEAR(object[1].z(), 3.3f, 1e-4);
}

TEST(View3d, TheMapIsThinnedToTheLimit) {
  PointCloud big;
  for (int i = 0; i < 250000; ++i) big.push_back(Vec3f(i * 1e-5f, 0, 0), Rgb{1, 2, 3});
  const PointCloud thin = thin_points(big, 200000);
  EXPECT_LE(thin.size(), 200000u);
  EXPECT_GE(thin.size(), 100000u);  // every 2nd point
  EXPECT_TRUE(thin.has_colors());
  EXPECT_EQ(thin_points(big, 300000).size(), big.size());
  // Read in blocks of 65536 (not a multiple of the step 2... nor of 3 at 100000): the same points.
  const PointBlocks blocks = [&](const std::function<void(const PointCloud&)>& take) {
    for (std::size_t first = 0; first < big.size(); first += 65536) {
      PointCloud block;
      for (std::size_t i = first; i < std::min(big.size(), first + 65536); ++i)
        block.push_back(big.points[i], big.colors[i]);
      take(block);
    }
  };
  for (std::size_t limit : {200000u, 100000u, 300000u}) {
    const PointCloud whole = thin_points(big, limit), read = thin_points(blocks, big.size(), limit);
    EXPECT_EQ(read.points, whole.points) << limit;
    EXPECT_EQ(read.colors, whole.colors) << limit;
  }
  View3dOptions options;
  options.max_map_points = 10;
  EXPECT_THROW(options.check(), InputError);
}

TEST(View3d, ThePageWithTheViewIsWellFormed) {
  PageContent page;
  page.title = "run";
  page.view3d = small_view();
  const std::string html = page_html(page);
  EXPECT_EQ(xml_problem(html), "");
  EXPECT_NE(html.find("<h2>The map in 3D</h2>"), std::string::npos);
  EXPECT_EQ(html.find("src=\"http"), std::string::npos);
  EXPECT_NE(html.find("const THREE=(()=>{"), std::string::npos);  // three.js inlined
}

}  // namespace
}  // namespace objmap::report
