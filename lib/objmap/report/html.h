#pragma once
#include <string>
#include <string_view>
#include <vector>

// Building blocks of the report's pages: base64 data URIs for embedded pictures and tables that
// render both as HTML and as Markdown.
namespace objmap::report {

// RFC 4648 base64 with padding ("foobar" → "Zm9vYmFy").
std::string base64_encode(std::string_view bytes);
// "data:image/png;base64,..." for a PNG file's bytes.
std::string png_data_uri(std::string_view png_bytes);

// Plain text for Markdown: '<', '>' and '&' as entities (no HTML of a run's names gets into a
// rendered report.md), line breaks as spaces.
std::string markdown_text(std::string_view text);

// A table of text cells; cells are plain text (escaped when rendered).
struct Table {
  std::string caption;                         // shown above the table (may be empty)
  std::vector<std::string> header;             // one per column
  std::vector<bool> numeric;                   // per column: right-aligned (missing entries: false)
  std::vector<std::vector<std::string>> rows;  // each as many cells as the header
  // Per row, an optional CSS colour ("#rrggbb") drawn as a small swatch before the first cell
  // (HTML only); empty or shorter than `rows`: none.
  std::vector<std::string> swatches;
  // Rows whose first cell equals this are set in bold (a total row), e.g. "overall".
  std::string total_row;
};

std::string html_table(const Table& table);
// A GitHub-flavoured Markdown table, "**caption**" above it; '|' in cells escaped.
std::string markdown_table(const Table& table);

}  // namespace objmap::report
