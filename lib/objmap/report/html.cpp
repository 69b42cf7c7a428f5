#include "objmap/report/html.h"

#include "objmap/report/svg.h"

namespace objmap::report {

std::string base64_encode(std::string_view bytes) {
  static const char kAlphabet[] =
      "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((bytes.size() + 2) / 3 * 4);
  std::size_t i = 0;
  for (; i + 3 <= bytes.size(); i += 3) {
    const unsigned v = static_cast<unsigned char>(bytes[i]) << 16 |
                       static_cast<unsigned char>(bytes[i + 1]) << 8 |
                       static_cast<unsigned char>(bytes[i + 2]);
    out += kAlphabet[v >> 18 & 63];
    out += kAlphabet[v >> 12 & 63];
    out += kAlphabet[v >> 6 & 63];
    out += kAlphabet[v & 63];
  }
  const std::size_t rest = bytes.size() - i;
  if (rest > 0) {
    unsigned v = static_cast<unsigned char>(bytes[i]) << 16;
    if (rest == 2) v |= static_cast<unsigned char>(bytes[i + 1]) << 8;
    out += kAlphabet[v >> 18 & 63];
    out += kAlphabet[v >> 12 & 63];
    out += rest == 2 ? kAlphabet[v >> 6 & 63] : '=';
    out += '=';
  }
  return out;
}

std::string png_data_uri(std::string_view png_bytes) {
  return "data:image/png;base64," + base64_encode(png_bytes);
}

namespace {

bool is_numeric(const Table& t, std::size_t column) {
  return column < t.numeric.size() && t.numeric[column];
}

std::string markdown_cell(const std::string& text) {
  std::string out;
  for (const char c : markdown_text(text)) {
    if (c == '|')
      out += "\\|";
    else
      out += c;
  }
  return out;
}

}  // namespace

std::string markdown_text(std::string_view text) {
  std::string out;
  for (const char c : text) {
    if (c == '<')
      out += "&lt;";
    else if (c == '>')
      out += "&gt;";
    else if (c == '&')
      out += "&amp;";
    else if (c == '\n' || c == '\r')
      out += ' ';
    else
      out += c;
  }
  return out;
}

std::string html_table(const Table& table) {
  std::string out = "<table>\n";
  if (!table.caption.empty()) out += "<caption>" + xml_escape(table.caption) + "</caption>\n";
  out += "<thead><tr>";
  for (std::size_t c = 0; c < table.header.size(); ++c)
    out += std::string(is_numeric(table, c) ? "<th class=\"num\">" : "<th>") +
           xml_escape(table.header[c]) + "</th>";
  out += "</tr></thead>\n<tbody>\n";
  for (std::size_t r = 0; r < table.rows.size(); ++r) {
    const auto& row = table.rows[r];
    const bool total = !table.total_row.empty() && !row.empty() && row[0] == table.total_row;
    out += total ? "<tr class=\"total\">" : "<tr>";
    for (std::size_t c = 0; c < row.size(); ++c) {
      out += is_numeric(table, c) ? "<td class=\"num\">" : "<td>";
      if (c == 0 && r < table.swatches.size() && !table.swatches[r].empty())
        out += "<span class=\"swatch\" style=\"background:" + xml_escape(table.swatches[r]) +
               "\"></span>";
      out += xml_escape(row[c]) + "</td>";
    }
    out += "</tr>\n";
  }
  out += "</tbody>\n</table>\n";
  return out;
}

std::string markdown_table(const Table& table) {
  std::string out;
  if (!table.caption.empty()) out += "**" + markdown_cell(table.caption) + "**\n\n";
  out += "|";
  for (const auto& h : table.header) out += " " + markdown_cell(h) + " |";
  out += "\n|";
  for (std::size_t c = 0; c < table.header.size(); ++c)
    out += is_numeric(table, c) ? "---:|" : "---|";
  out += "\n";
  for (const auto& row : table.rows) {
    const bool total = !table.total_row.empty() && !row.empty() && row[0] == table.total_row;
    out += "|";
    for (const auto& cell : row)
      out += " " +
             (total && !cell.empty() ? "**" + markdown_cell(cell) + "**" : markdown_cell(cell)) +
             " |";
    out += "\n";
  }
  return out + "\n";
}

}  // namespace objmap::report
