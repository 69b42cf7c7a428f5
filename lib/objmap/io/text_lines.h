#pragma once
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <string_view>
#include <vector>

// A strict line reader shared by the text parsers of objmap (trajectories, rgb.txt/depth.txt, box
// and pixel lists): line numbers for messages, comment and blank line skipping, and number parsing
// that rejects text, trailing junk, NaN and infinity.
namespace objmap::io {

// Parses the whole of `text` as a finite decimal number ("1e-3", "+2", ".5"; no hex, no "nan",
// no "inf", nothing after the number). Throws InputError(where, "<what> is '<text>'; expected a
// finite number").
double parse_double(std::string_view text, const std::string& where, const std::string& what);
// Parses the whole of `text` as a base-10 integer in the range of int64. Throws InputError.
std::int64_t parse_int(std::string_view text, const std::string& where, const std::string& what);

// Splits `line` at spaces, tabs and commas (as the TUM benchmark's associate.py does); empty fields
// are dropped.
std::vector<std::string> split_fields(std::string_view line);

// Reads a text file line by line. Lines whose first non-blank character is '#' are comments; blank
// lines are skipped; a trailing '\r' (Windows line end) is removed.
//
//   LineReader in(path);                 // throws InputError(path, "cannot open ...") if
//   unreadable while (in.next()) {
//     in.expect_fields(8, "timestamp tx ty tz qx qy qz qw");
//     double t = in.number(0, "timestamp");
//   }
class LineReader {
 public:
  explicit LineReader(const std::filesystem::path& file);

  // Advances to the next data line (not blank, not a comment); false at the end of the file.
  bool next();

  const std::filesystem::path& file() const { return file_; }
  std::size_t line_number() const { return line_number_; }  // 1-based number of the current line
  const std::string& line() const { return line_; }         // the current line, '\r' removed
  const std::vector<std::string>& fields() const { return fields_; }
  std::size_t size() const { return fields_.size(); }
  const std::string& field(std::size_t i) const;  // throws InputError when i >= size()
  // "<file>:<line>" for messages.
  std::string where() const;

  // Throws InputError(where(), "<n> fields; expected <count>: <layout>") unless the line has
  // exactly `count` fields.
  void expect_fields(std::size_t count, const std::string& layout) const;
  // Field i parsed with parse_double / parse_int, `what` names it in the message ("timestamp").
  double number(std::size_t i, const std::string& what) const;
  std::int64_t integer(std::size_t i, const std::string& what) const;

  // Comment lines met so far (text after '#', leading blanks removed), in file order.
  const std::vector<std::string>& comments() const { return comments_; }
  // Data lines read so far.
  std::size_t data_lines() const { return data_lines_; }

 private:
  std::filesystem::path file_;
  std::ifstream in_;
  std::size_t line_number_ = 0;
  std::size_t data_lines_ = 0;
  std::string line_;
  std::vector<std::string> fields_;
  std::vector<std::string> comments_;
};

}  // namespace objmap::io
