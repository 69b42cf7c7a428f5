#include "objmap/report/page.h"

#include <gtest/gtest.h>

#include "xml_check.h"

namespace objmap::report {
namespace {

using test::count_of;
using test::xml_problem;

PageContent small_page() {
  PageContent c;
  c.title = "objmap report: <run & co>";
  c.counts = RunCounts{100, 40, 300, 2, 3};
  c.topview = {"topview.png", "PNGBYTES", 10, 20, "map from above"};
  for (int id : {3, 8}) {
    PageObject o;
    o.object.id = id;
    o.object.class_name = id == 3 ? "cup" : "<script>x";
    o.object.points = 1234567;
    o.points_raw = 7654321;
    o.thumbnail = {"thumbnails/" + std::to_string(id) + ".png", "T", 160, 160, "caption"};
    c.objects.push_back(o);
  }
  c.ate.push_back({"estimated", "gt.txt", "est.txt", {}});
  c.ate.back().stats.count = 5;
  c.ate.back().stats.rmse = 0.01234;
  c.notes.push_back("a note with 'quotes'");
  return c;
}

TEST(Page, SummaryLineSaysWhatTheRunHas) {
  EXPECT_EQ(summary_line(small_page()),
            "40 keyframes of 100 frames, 300 instances; 2 objects (1 <script>x, 1 cup); ATE RMSE "
            "estimated 0.0123 m (5 pose pairs).");
  PageContent empty;
  EXPECT_EQ(summary_line(empty), "0 objects; ATE not computed (no ground-truth trajectory).");
}

TEST(Page, AnAlmostPerfectTrajectoryDoesNotReadZero) {
  PageContent c = small_page();
  c.ate.back().stats.rmse = 8.11e-6;
  c.ate.back().stats.max = 1.5e-5;
  EXPECT_NE(summary_line(c).find("ATE RMSE estimated 8.11e-06 m"), std::string::npos)
      << summary_line(c);
  EXPECT_NE(page_markdown(c).find("| estimated | 5 | 8.11e-06 | 0.0000 | 0.0000 | 0.0000 | 0.0000 "
                                  "| 1.5e-05 |"),
            std::string::npos)
      << page_markdown(c);
}

TEST(Page, HtmlIsWellFormedSelfContainedAndEscaped) {
  const std::string html = page_html(small_page());
  EXPECT_EQ(xml_problem(html), "");
  EXPECT_EQ(html.find("<script"), std::string::npos);  // the class name is text, not a tag
  EXPECT_NE(html.find("&lt;script&gt;x"), std::string::npos);
  EXPECT_EQ(count_of(html, "data-object-id=\""), 2u);
  EXPECT_EQ(count_of(html, "src=\"data:image/png;base64,"), 3u);  // top view + 2 thumbnails
  EXPECT_EQ(html.find("src=\"http"), std::string::npos);
  EXPECT_NE(html.find("1 234 567"), std::string::npos);  // points, grouped
  EXPECT_NE(html.find("Objects per class"), std::string::npos);
  EXPECT_EQ(html.find("Table 3"), std::string::npos);  // no ground-truth objects
}

TEST(Page, MarkdownReferencesTheFilesBeside) {
  const std::string md = page_markdown(small_page());
  EXPECT_NE(md.find("![top view of the semantic map](topview.png)"), std::string::npos) << md;
  EXPECT_NE(md.find("(thumbnails/3.png)"), std::string::npos) << md;
  EXPECT_NE(md.find("| estimated | 5 | 0.0123 |"), std::string::npos) << md;
  EXPECT_EQ(md.find("base64"), std::string::npos);
}

TEST(Page, SeenMovingThingsAreATableOfTheirOwn) {
  PageContent c = small_page();
  EXPECT_EQ(page_html(c).find("Seen moving things"), std::string::npos);  // none: no table
  io::Sighting s;
  s.id = 5;
  s.class_name = "person";
  s.position = Vec3(1.0, -0.5, 0.9);
  s.first_seen = 1305031234.46;
  s.last_seen = 1305031253.17;
  s.frames = 39;
  c.sightings.push_back(s);
  const std::string html = page_html(c);
  EXPECT_EQ(xml_problem(html), "");
  EXPECT_NE(html.find("<h2>Seen moving things</h2>"), std::string::npos);
  EXPECT_EQ(count_of(html, "data-object-id=\""), 2u) << "not among the objects";
  EXPECT_NE(page_markdown(c).find("| 5 | person | 1.00, -0.50, 0.90 | 1305031234.460 | "
                                  "1305031253.170 | 39 |"),
            std::string::npos)
      << page_markdown(c);
}

TEST(Page, SuspectedDuplicatesAreATableWithTheReason) {
  PageContent c = small_page();
  EXPECT_EQ(page_html(c).find("Suspected duplicates"), std::string::npos);  // no section: none
  c.duplicates.emplace();
  EXPECT_NE(page_html(c).find("No suspected duplicates"), std::string::npos);
  EXPECT_NE(page_markdown(c).find("No suspected duplicates"), std::string::npos);
  PageDuplicate d;
  d.a = 3;
  d.b = 8;
  d.class_name = "cup";
  d.obb_overlap = 0.884;
  d.surface_distance_m = 0.0004;
  d.touching_share = 0.5;
  d.merge_refused = "score";
  d.merge_reason = "score P 0.39 <= 0.40 (same track no, centroids 0.25 m apart, containment 0.73)";
  c.duplicates->push_back(d);
  const std::string html = page_html(c);
  EXPECT_EQ(xml_problem(html), "");
  EXPECT_NE(html.find("<h2>Suspected duplicates</h2>"), std::string::npos);
  EXPECT_NE(html.find("why not merged"), std::string::npos);
  EXPECT_NE(html.find("P 0.39 &lt;= 0.40"), std::string::npos);  // escaped
  EXPECT_EQ(html.find("No suspected duplicates"), std::string::npos);
  const std::string md = page_markdown(c);
  // Markdown passes HTML on: '<' as an entity there too (it renders as "<=").
  EXPECT_NE(md.find("| 3 + 8 | cup | 88.4% | 0.000 | 50.0% | score P 0.39 &lt;= 0.40"),
            std::string::npos)
      << md;
}

}  // namespace
}  // namespace objmap::report
