#include "objmap/io/text_lines.h"

#include <charconv>
#include <cmath>
#include <system_error>

#include "objmap/core/error.h"

namespace objmap::io {

namespace {

std::string quoted(std::string_view text) {
  constexpr std::size_t kMax = 40;
  std::string s(text.substr(0, kMax));
  if (text.size() > kMax) s += "...";
  return "'" + s + "'";
}

}  // namespace

double parse_double(std::string_view text, const std::string& where, const std::string& what) {
  std::string_view body = text;
  if (!body.empty() && body.front() == '+') body.remove_prefix(1);  // from_chars takes no '+'
  double value = 0.0;
  bool ok = !body.empty() && (body.size() == text.size() || body.front() != '-');
  if (ok) {
    const char* end = body.data() + body.size();
    const auto [ptr, ec] = std::from_chars(body.data(), end, value, std::chars_format::general);
    ok = ec == std::errc() && ptr == end && std::isfinite(value);  // rejects nan, inf, 1e999
  }
  if (!ok) throw InputError(where, what + " is " + quoted(text) + "; expected a finite number");
  return value;
}

std::int64_t parse_int(std::string_view text, const std::string& where, const std::string& what) {
  std::string_view body = text;
  if (!body.empty() && body.front() == '+') body.remove_prefix(1);
  std::int64_t value = 0;
  const char* end = body.data() + body.size();
  const auto [ptr, ec] = std::from_chars(body.data(), end, value, 10);
  if (body.empty() || (body.size() != text.size() && body.front() == '-') || ec != std::errc() ||
      ptr != end)
    throw InputError(where, what + " is " + quoted(text) + "; expected an integer");
  return value;
}

std::vector<std::string> split_fields(std::string_view line) {
  std::vector<std::string> fields;
  std::size_t i = 0;
  auto is_sep = [](char c) {
    return c == ' ' || c == '\t' || c == ',' || c == '\r' || c == '\v' || c == '\f';
  };
  while (i < line.size()) {
    while (i < line.size() && is_sep(line[i])) ++i;
    const std::size_t start = i;
    while (i < line.size() && !is_sep(line[i])) ++i;
    if (i > start) fields.emplace_back(line.substr(start, i - start));
  }
  return fields;
}

LineReader::LineReader(const std::filesystem::path& file) : file_(file) {
  std::error_code ec;
  if (!std::filesystem::exists(file_, ec)) throw InputError(file_.string(), "file not found");
  if (std::filesystem::is_directory(file_, ec))
    throw InputError(file_.string(), "is a folder; expected a text file");
  in_.open(file_, std::ios::in | std::ios::binary);
  if (!in_) throw InputError(file_.string(), "cannot open the file for reading");
}

bool LineReader::next() {
  fields_.clear();
  while (std::getline(in_, line_)) {
    ++line_number_;
    if (!line_.empty() && line_.back() == '\r') line_.pop_back();
    const std::size_t first = line_.find_first_not_of(" \t\v\f");
    if (first == std::string::npos) continue;  // blank
    if (line_[first] == '#') {
      const std::size_t text = line_.find_first_not_of(" \t", first + 1);
      comments_.push_back(text == std::string::npos ? std::string() : line_.substr(text));
      continue;
    }
    fields_ = split_fields(line_);
    if (fields_.empty()) continue;  // only separators (e.g. ",,,")
    ++data_lines_;
    return true;
  }
  if (in_.bad()) throw InputError(where(), "read error");
  line_.clear();
  return false;
}

const std::string& LineReader::field(std::size_t i) const {
  if (i >= fields_.size())
    throw InputError(where(), std::to_string(fields_.size()) + " fields; expected at least " +
                                  std::to_string(i + 1));
  return fields_[i];
}

std::string LineReader::where() const {
  return file_.string() + ":" + std::to_string(line_number_);
}

void LineReader::expect_fields(std::size_t count, const std::string& layout) const {
  if (fields_.size() != count)
    throw InputError(where(), std::to_string(fields_.size()) + " fields; expected " +
                                  std::to_string(count) + ": " + layout);
}

double LineReader::number(std::size_t i, const std::string& what) const {
  return parse_double(field(i), where(), what);
}

std::int64_t LineReader::integer(std::size_t i, const std::string& what) const {
  return parse_int(field(i), where(), what);
}

}  // namespace objmap::io
