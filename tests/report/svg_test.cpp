#include "objmap/report/svg.h"

#include <gtest/gtest.h>

#include "objmap/report/html.h"
#include "xml_check.h"

namespace objmap::report {
namespace {

using test::count_of;
using test::xml_problem;

TEST(XmlCheck, RejectsWhatIsNotWellFormed) {
  EXPECT_EQ(xml_problem("<a x=\"1\"><b/>t &amp; &#39; &#x27;</a>"), "");
  EXPECT_NE(xml_problem("<a><b></a></b>"), "");        // crossed
  EXPECT_NE(xml_problem("<a><b></a>"), "");            // unclosed
  EXPECT_NE(xml_problem("<a x=1/>"), "");              // unquoted
  EXPECT_NE(xml_problem("<a x=\"1\" x=\"2\"/>"), "");  // duplicate
  EXPECT_NE(xml_problem("<a>x & y</a>"), "");          // raw &
  EXPECT_NE(xml_problem("<a>&nbsp;</a>"), "");         // not an XML entity
  EXPECT_NE(xml_problem("<a x=\"<\"/>"), "");          // '<' in a value
  EXPECT_NE(xml_problem("<a/><b/>"), "");              // two roots
  EXPECT_EQ(xml_problem("<!DOCTYPE html>\n<html><meta charset=\"utf-8\"/></html>\n"), "");
}

TEST(Svg, EscapesTextAndAttributes) {
  EXPECT_EQ(xml_escape("a<b & \"c\" 'd'>"), "a&lt;b &amp; &quot;c&quot; &#39;d&#39;&gt;");
  EXPECT_EQ(xml_escape(std::string("x\x01y\tz")), "xy\tz");  // control characters dropped
  Svg svg(100, 50);
  svg.open_group({{"stroke", "#000"}});
  svg.text(10, 20, "cup <7> & \"mug\"", {{"fill", "a\"b"}});
  svg.polyline({{0, 0}, {1.25, 2.5}}, {{"stroke", "red"}});
  svg.title("tooltip <x>");
  // the group is left open: str() closes it
  const std::string doc = svg.str();
  EXPECT_EQ(xml_problem(doc), "") << doc;
  EXPECT_NE(doc.find("cup &lt;7&gt; &amp; &quot;mug&quot;"), std::string::npos) << doc;
  EXPECT_NE(doc.find("fill=\"a&quot;b\""), std::string::npos) << doc;
  EXPECT_NE(doc.find("points=\"0,0 1.25,2.5\""), std::string::npos) << doc;
  EXPECT_EQ(count_of(doc, "<polyline"), 1u);
  EXPECT_NE(doc.find("viewBox=\"0 0 100 50\""), std::string::npos);
}

TEST(Svg, NumbersAndColours) {
  EXPECT_EQ(svg_number(1.5), "1.5");
  EXPECT_EQ(svg_number(2.0), "2");
  EXPECT_EQ(svg_number(-0.001), "0");
  EXPECT_EQ(svg_number(3.14159, 3), "3.142");
  EXPECT_EQ(hex_color(Rgb{255, 16, 0}), "#ff1000");
}

TEST(Html, Base64MatchesRfc4648) {
  EXPECT_EQ(base64_encode(""), "");
  EXPECT_EQ(base64_encode("f"), "Zg==");
  EXPECT_EQ(base64_encode("fo"), "Zm8=");
  EXPECT_EQ(base64_encode("foo"), "Zm9v");
  EXPECT_EQ(base64_encode("foob"), "Zm9vYg==");
  EXPECT_EQ(base64_encode("fooba"), "Zm9vYmE=");
  EXPECT_EQ(base64_encode("foobar"), "Zm9vYmFy");
  EXPECT_EQ(base64_encode(std::string("\xff\xfe\x00", 3)), "//4A");
  EXPECT_EQ(png_data_uri("foo"), "data:image/png;base64,Zm9v");
}

TEST(Html, TablesEscapeTheirCells) {
  Table t;
  t.caption = "A & B";
  t.header = {"class", "n"};
  t.numeric = {false, true};
  t.rows = {{"a|b <c>", "3"}, {"overall", "3"}};
  t.swatches = {"#ff0000"};
  t.total_row = "overall";
  const std::string html = html_table(t);
  EXPECT_EQ(xml_problem(html), "") << html;
  EXPECT_NE(html.find("a|b &lt;c&gt;"), std::string::npos) << html;
  EXPECT_NE(html.find("<td class=\"num\">3</td>"), std::string::npos) << html;
  EXPECT_EQ(count_of(html, "class=\"swatch\""), 1u);
  EXPECT_EQ(count_of(html, "<tr class=\"total\">"), 1u);
  const std::string md = markdown_table(t);
  EXPECT_NE(md.find("| a\\|b &lt;c&gt; | 3 |"), std::string::npos) << md;  // no HTML in Markdown
  EXPECT_NE(md.find("|---|---:|"), std::string::npos) << md;
  EXPECT_NE(md.find("| **overall** | **3** |"), std::string::npos) << md;
}

}  // namespace
}  // namespace objmap::report
