#include "objmap/report/scene_graph.h"

#include <gtest/gtest.h>

#include <regex>
#include <string>

#include "objmap/core/error.h"
#include "xml_check.h"

namespace objmap::report {
namespace {

using test::count_of;
using test::xml_problem;

io::SceneSurface surface(int id, const std::string& label, double height_m, double area_m2) {
  io::SceneSurface s;
  s.id = id;
  s.label = label;
  s.height_m = height_m;
  s.area_m2 = area_m2;
  return s;
}

io::SceneObject object(int id, const std::string& class_name, io::SceneRelation::Kind kind,
                       int on) {
  io::SceneObject o;
  o.id = id;
  o.class_name = class_name;
  o.on = io::SceneRelation{kind, on, "", 0.0};
  return o;
}

constexpr auto kSurface = io::SceneRelation::Kind::kSurface;
constexpr auto kObject = io::SceneRelation::Kind::kObject;

// A desk scene in a first camera's frame (heights negative): the floor at -1.59 m (and a small
// floor piece at -1.60 m), a desk at -0.86 m, a shelf board nothing stands on; a keyboard and a
// book on the desk, a second book on the first, a chair on the floor, a lamp on nothing.
io::SceneDescription desk_scene() {
  io::SceneDescription s;
  s.surfaces = {surface(1, "table", -0.86, 2.72), surface(0, "floor", -1.59, 5.7),
                surface(4, "floor", -1.60, 0.5), surface(3, "surface", -0.40, 0.3)};
  s.objects = {object(1, "keyboard", kSurface, 1), object(2, "book", kSurface, 1),
               object(3, "book", kObject, 2), object(5, "chair", kSurface, 0), io::SceneObject{}};
  s.objects.back().id = 6;
  s.objects.back().class_name = "lamp";
  return s;
}

// The numbers of the attribute `name` of the root <svg>.
double svg_size(const std::string& svg, const std::string& name) {
  std::smatch m;
  const std::regex re("<svg[^>]* " + name + "=\"([0-9.]+)\"");
  if (!std::regex_search(svg, m, re)) return -1;
  return std::stod(m[1]);
}

TEST(SceneGraph, HeightsAreAboveTheLargestFloorPiece) {
  const io::SceneDescription s = desk_scene();
  ASSERT_TRUE(floor_height_m(s));
  EXPECT_DOUBLE_EQ(*floor_height_m(s), -1.59);  // 5.7 m2, not the lower 0.5 m2 piece
  EXPECT_EQ(height_text(s.surfaces[0], floor_height_m(s)), "0.73 m above the floor");
  EXPECT_EQ(height_text(s.surfaces[1], floor_height_m(s)), "0.00 m above the floor");
  const std::string svg = scene_graph_svg(s);
  EXPECT_EQ(xml_problem(svg), "") << svg;
  EXPECT_NE(svg.find("S1 table, 0.73 m above the floor, 2.7 m²"), std::string::npos) << svg;
  EXPECT_EQ(svg.find("-0.86"), std::string::npos) << "a height in the SLAM frame";
}

TEST(SceneGraph, WithoutAFloorSaysNoFloorFound) {
  io::SceneDescription s = desk_scene();
  s.surfaces[1].label = s.surfaces[2].label = "surface";
  EXPECT_FALSE(floor_height_m(s));
  const std::string svg = scene_graph_svg(s);
  EXPECT_NE(svg.find("S1 table, no floor found"), std::string::npos) << svg;
  EXPECT_EQ(svg.find("above the floor"), std::string::npos) << svg;
}

TEST(SceneGraph, MarkdownIsTheTreeAsNestedLists) {
  EXPECT_EQ(scene_graph_markdown(desk_scene()),
            "- S0 floor, 0.00 m above the floor, 5.7 m²\n"
            "  - 5 chair\n"
            "- S1 table, 0.73 m above the floor, 2.7 m²\n"
            "  - 1 keyboard\n"
            "  - 2 book\n"
            "    - 3 book\n"
            "- on no surface\n"
            "  - 6 lamp\n"
            "- surfaces with nothing on them\n"
            "  - S4 floor, -0.01 m above the floor, 0.50 m²\n"
            "  - S3 surface, 1.19 m above the floor, 0.30 m²\n\n");
}

TEST(SceneGraph, EveryObjectSurfaceAndOnEdgeIsThereOnce) {
  const std::string svg = scene_graph_svg(desk_scene());
  for (const char* node : {"object 1", "object 2", "object 3", "object 5", "object 6", "surface 0",
                           "surface 1", "surface 3", "surface 4"})
    EXPECT_EQ(count_of(svg, std::string("data-node=\"") + node + "\""), 1u) << node;
  for (const char* edge : {"on object 1 surface 1", "on object 2 surface 1", "on object 3 object 2",
                           "on object 5 surface 0"})
    EXPECT_EQ(count_of(svg, std::string("data-edge=\"") + edge + "\""), 1u) << edge;
  EXPECT_EQ(count_of(svg, "data-edge=\""), 4u);  // the lamp stands on nothing
  EXPECT_EQ(count_of(svg, "<polyline"), 1u);     // the one connector: book on book
}

TEST(SceneGraph, ManySurfacesAndObjectsWrapToThePageWidth) {
  // 40 surfaces, 31 chairs on the floor and two objects on each other surface: one row of
  // columns would be thousands of pixels wide.
  io::SceneDescription s;
  s.surfaces.push_back(surface(0, "floor", 0.0, 20.0));
  for (int i = 1; i < 40; ++i) s.surfaces.push_back(surface(i, "table", 0.5 + 0.01 * i, 1.0));
  int id = 0;
  for (int i = 0; i < 31; ++i) s.objects.push_back(object(id++, "chair", kSurface, 0));
  for (int i = 1; i < 40; ++i)
    for (const char* c : {"cup", "laptop"}) s.objects.push_back(object(id++, c, kSurface, i));
  for (const double width : {1180.0, 600.0}) {
    SceneGraphOptions options;
    options.width_px = width;
    const std::string svg = scene_graph_svg(s, options);
    EXPECT_EQ(xml_problem(svg), "");
    EXPECT_LE(svg_size(svg, "width"), width);
    EXPECT_GT(svg_size(svg, "width"), width * 0.8) << "the cards fill the width";
    EXPECT_EQ(count_of(svg, "data-node=\"object "), s.objects.size());
    // Every box lies inside the picture.
    const std::regex rect("<rect x=\"([0-9.]+)\" y=\"[0-9.]+\" width=\"([0-9.]+)\"");
    for (auto it = std::sregex_iterator(svg.begin(), svg.end(), rect); it != std::sregex_iterator();
         ++it)
      EXPECT_LE(std::stod((*it)[1]) + std::stod((*it)[2]), svg_size(svg, "width"));
  }
}

TEST(SceneGraph, RunNamesAreEscapedAndLongOnesCut) {
  io::SceneDescription s = desk_scene();
  s.objects[0].class_name = "<script>alert(1)</script>";
  s.objects[1].class_name = "a\"b&c";
  s.surfaces[0].label = "<b>";
  s.objects[3].class_name = std::string(500, 'x');
  const std::string svg = scene_graph_svg(s);
  EXPECT_EQ(xml_problem(svg), "") << svg;
  EXPECT_EQ(svg.find("<script"), std::string::npos);
  EXPECT_EQ(svg.find("<b>"), std::string::npos);
  EXPECT_NE(svg.find("1 &lt;script&gt;alert(1)&lt;/script&gt;"), std::string::npos) << svg;
  EXPECT_NE(svg.find("2 a&quot;b&amp;c"), std::string::npos) << svg;
  EXPECT_LE(svg_size(svg, "width"), 1180);
  const std::string md = scene_graph_markdown(s);
  EXPECT_EQ(md.find("<script"), std::string::npos);
  EXPECT_NE(md.find("  - 1 &lt;script&gt;alert(1)&lt;/script&gt;\n"), std::string::npos) << md;
  EXPECT_NE(md.find("  - 2 a\"b&amp;c\n"), std::string::npos) << md;
}

TEST(SceneGraph, ObjectsOnEachOtherInACycleAppearOnce) {
  io::SceneDescription s;
  s.objects = {object(1, "book", kObject, 2), object(2, "book", kObject, 1)};
  const std::string svg = scene_graph_svg(s);
  EXPECT_EQ(count_of(svg, "data-node=\"object 1\""), 1u);
  EXPECT_EQ(count_of(svg, "data-node=\"object 2\""), 1u);
  EXPECT_EQ(scene_graph_markdown(s), "- on no surface\n  - 1 book\n    - 2 book\n\n");
  EXPECT_EQ(scene_graph_svg(io::SceneDescription{}), "");
}

TEST(SceneGraph, BadOptionsAreNamed) {
  SceneGraphOptions options;
  options.width_px = 10;
  try {
    scene_graph_svg(desk_scene(), options);
    FAIL() << "no throw";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("SceneGraphOptions.width_px"), std::string::npos);
  }
}

}  // namespace
}  // namespace objmap::report
