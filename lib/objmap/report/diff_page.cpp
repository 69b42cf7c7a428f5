#include "objmap/report/diff_page.h"

#include "objmap/report/svg.h"

namespace objmap::report {

namespace {

const char* kDiffStyle = R"(
table.changes img { width: 120px; height: 120px; display: block; }
table.changes td { vertical-align: top; }
table.changes div.why { font-size: 12px; color: #555; max-width: 160px; }
tr[data-status=moved] td:first-child { color: #b02020; font-weight: 600; }
tr[data-status=removed] td:first-child, tr[data-status=added] td:first-child { font-weight: 600; }
)";

const char* kChangesCaption =
    "Every object whose status is not unchanged: as the before visit (A) saw it and as the after "
    "visit (B) saw it, both drawn from the same oblique view in A's frame; a side without an "
    "object says why. Positions in A's world, metres.";

std::string cell(const std::string& text) { return "<td>" + xml_escape(text) + "</td>"; }

// The picture and, under it, what it shows or why there is no object to show.
std::string thumbnail_cell(const PagePicture& p, const std::string& alt) {
  return "<td>" + (p.bytes.empty() ? std::string() : image_tag(p, "thumb", alt)) +
         "<div class=\"why\">" + xml_escape(p.caption) + "</div></td>";
}

std::string changes_html(const DiffPageContent& c) {
  std::string h = "<table class=\"changes\">\n<caption>" + xml_escape(kChangesCaption) +
                  "</caption>\n<tr><th>status</th><th>before (A)</th><th>after (B)</th>"
                  "<th>position in A</th><th>change</th><th>why</th><th>A</th><th>B</th></tr>\n";
  for (const DiffPageChange& r : c.changes)
    h += "<tr data-status=\"" + xml_escape(r.status) + "\">" + cell(r.status) + cell(r.before) +
         cell(r.after) + cell(r.position) + cell(r.change) + cell(r.why) +
         thumbnail_cell(r.before_thumbnail, "before: " + r.before) +
         thumbnail_cell(r.after_thumbnail, "after: " + r.after) + "</tr>\n";
  return h + "</table>\n";
}

}  // namespace

std::string diff_page_html(const DiffPageContent& c) {
  std::string h;
  h += "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\"/>\n";
  h += "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\"/>\n";
  h += "<title>" + xml_escape(c.title) + "</title>\n<style>" + page_style() + kDiffStyle +
       "</style>\n</head>\n<body>\n";
  h += "<h1>" + xml_escape(c.title) + "</h1>\n";
  h += "<p class=\"summary\">" + xml_escape(c.summary) + "</p>\n";
  if (!c.notes.empty()) {
    h += "<ul class=\"notes\">\n";
    for (const std::string& n : c.notes) h += "<li>" + xml_escape(n) + "</li>\n";
    h += "</ul>\n";
  }
  // 1. The registration, 2. the changes, 3. both maps in 3D.
  h += "<h2>Registration</h2>\n" + html_table(c.registration);
  h += "<h2>Changes</h2>\n";
  h += c.changes.empty() ? std::string("<p>No changes: every object is unchanged.</p>\n")
                         : changes_html(c);
  if (!c.unchanged.empty()) {
    std::string list;
    for (const std::string& u : c.unchanged) list += (list.empty() ? "" : ", ") + u;
    h += "<p class=\"unchanged\">Unchanged (" + std::to_string(c.unchanged.size()) +
         "): " + xml_escape(list) + ".</p>\n";
  }
  if (c.view3d) h += "<h2>Both maps in 3D</h2>\n" + view3d_html(*c.view3d, c.view3d_options);
  h += "<footer>\n";
  for (const std::string& line : c.inputs) h += xml_escape(line) + "<br/>\n";
  h += "Written by objmap report --diff.\n</footer>\n</body>\n</html>\n";
  return h;
}

std::string diff_page_markdown(const DiffPageContent& c) {
  std::string m = "# " + markdown_text(c.title) + "\n\n" + markdown_text(c.summary) + "\n\n";
  for (const std::string& n : c.notes) m += "- note: " + markdown_text(n) + "\n";
  if (!c.notes.empty()) m += "\n";
  m += markdown_table(c.registration) + "\n";
  Table t;
  t.caption = kChangesCaption;
  t.header = {"status", "before (A)", "after (B)", "position in A", "change", "why", "A", "B"};
  const auto picture = [](const PagePicture& p, const std::string& alt) {
    return (p.bytes.empty() ? "" : "![" + alt + "](" + p.file + ") ") + p.caption;
  };
  for (const DiffPageChange& r : c.changes)
    t.rows.push_back({r.status, r.before, r.after, r.position, r.change, r.why,
                      picture(r.before_thumbnail, "before"), picture(r.after_thumbnail, "after")});
  m += markdown_table(t) + "\n";
  if (!c.unchanged.empty()) {
    m += "Unchanged (" + std::to_string(c.unchanged.size()) + "):";
    for (const std::string& u : c.unchanged) m += " " + markdown_text(u) + ";";
    m += "\n\n";
  }
  for (const std::string& line : c.inputs) m += markdown_text(line) + "  \n";
  return m;
}

}  // namespace objmap::report
