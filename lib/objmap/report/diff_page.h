#pragma once
#include <optional>
#include <string>
#include <vector>

#include "objmap/report/html.h"
#include "objmap/report/page.h"
#include "objmap/report/view3d.h"

// The report page of a diff (`objmap report --diff`, docs/change.md "The report"): the
// registration, a table of every change with the object as each visit saw it, and the 3D view
// with both maps. Gathered by lib/objmap/pipeline/report_diff.cpp; rendered here as one
// self-contained HTML file and a Markdown summary that references the thumbnails beside it.
namespace objmap::report {

// One row: an object of the diff whose status is not "unchanged".
struct DiffPageChange {
  std::string status;            // diff.json status
  std::string before, after;     // "3 cup", or "-" where that visit has none
  std::string position;          // in the before world, "(x, y, z)" m
  std::string change;            // "0.42 m (dx, dy, dz)" for moved; else "" or a distance
  std::string why;               // diff.json why
  PagePicture before_thumbnail;  // PNG; without an object, a blank picture saying why
  PagePicture after_thumbnail;   // PNG, the after object registered into the before world
};

struct DiffPageContent {
  std::string title;    // "objmap diff report: d11"
  std::string summary;  // one line: the counts per status
  Table registration;   // the registration: transform, fitness, uncertainty
  std::vector<DiffPageChange> changes;
  std::vector<std::string> unchanged;  // "3 cup" per unchanged object
  std::optional<View3dContent> view3d;
  View3dOptions view3d_options;
  std::vector<std::string> notes;   // what could not be shown and why
  std::vector<std::string> inputs;  // "label: path" lines for the footer
};

// The page, self-contained (pictures as data URIs), well-formed XML apart from the doctype; each
// change is a row <tr data-status="...">.
std::string diff_page_html(const DiffPageContent& content);

// The Markdown summary; thumbnails referenced by their `file` names.
std::string diff_page_markdown(const DiffPageContent& content);

}  // namespace objmap::report
