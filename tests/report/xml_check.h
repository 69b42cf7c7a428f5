#pragma once
// A small XML well-formedness checker for the report's SVG and HTML: balanced and properly nested
// tags, attribute values quoted, no duplicate attribute, entities valid, no raw '<' or '&' in text.
// A leading <!DOCTYPE ...>, comments and <?...?> are skipped; <style> and <script> content is raw
// text up to its end tag, as HTML reads it (the 3D view's scripts).
#include <cctype>
#include <set>
#include <string>
#include <vector>

namespace objmap::test {

// Empty when `doc` is well-formed; otherwise what is wrong and at which offset.
inline std::string xml_problem(const std::string& doc) {
  std::vector<std::string> open;
  std::size_t i = 0, roots = 0;
  const auto fail = [&](const std::string& what) {
    return what + " at offset " + std::to_string(i) + ": '" + doc.substr(i, 40) + "'";
  };
  const auto name_char = [](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_' || c == ':' ||
           c == '.';
  };
  const auto check_entity = [&](std::size_t at, std::size_t& end) {
    end = doc.find(';', at);
    if (end == std::string::npos || end - at > 10) return false;
    const std::string e = doc.substr(at + 1, end - at - 1);
    if (e == "amp" || e == "lt" || e == "gt" || e == "quot" || e == "apos") return true;
    if (e.size() >= 2 && e[0] == '#') {
      const bool hex = e[1] == 'x';
      if (e.size() < (hex ? 3u : 2u)) return false;
      for (std::size_t k = hex ? 2 : 1; k < e.size(); ++k)
        if (!(hex ? std::isxdigit(static_cast<unsigned char>(e[k]))
                  : std::isdigit(static_cast<unsigned char>(e[k]))))
          return false;
      return true;
    }
    return false;
  };
  while (i < doc.size()) {
    const char c = doc[i];
    if (c == '&') {
      std::size_t end = 0;
      if (!check_entity(i, end)) return fail("invalid entity");
      i = end + 1;
      continue;
    }
    if (c != '<') {
      if (open.empty() && !std::isspace(static_cast<unsigned char>(c)))
        return fail("text outside the root element");
      ++i;
      continue;
    }
    if (doc.compare(i, 4, "<!--") == 0) {
      const std::size_t end = doc.find("-->", i + 4);
      if (end == std::string::npos) return fail("unterminated comment");
      i = end + 3;
      continue;
    }
    if (doc.compare(i, 2, "<?") == 0 || doc.compare(i, 9, "<!DOCTYPE") == 0) {
      if (!open.empty() || roots > 0) return fail("declaration inside the document");
      const std::size_t end = doc.find('>', i);
      if (end == std::string::npos) return fail("unterminated declaration");
      i = end + 1;
      continue;
    }
    const bool closing = i + 1 < doc.size() && doc[i + 1] == '/';
    std::size_t k = i + (closing ? 2 : 1);
    const std::size_t name_start = k;
    while (k < doc.size() && name_char(doc[k])) ++k;
    const std::string name = doc.substr(name_start, k - name_start);
    if (name.empty() || !std::isalpha(static_cast<unsigned char>(name[0])))
      return fail("bad tag name");
    if (closing) {
      while (k < doc.size() && std::isspace(static_cast<unsigned char>(doc[k]))) ++k;
      if (k >= doc.size() || doc[k] != '>') return fail("bad closing tag");
      if (open.empty() || open.back() != name)
        return fail("</" + name + "> closes " +
                    (open.empty() ? "nothing" : "<" + open.back() + ">"));
      open.pop_back();
      i = k + 1;
      continue;
    }
    std::set<std::string> attributes;
    bool self_closing = false;
    for (;;) {
      const std::size_t before = k;
      while (k < doc.size() && std::isspace(static_cast<unsigned char>(doc[k]))) ++k;
      if (k >= doc.size()) return fail("unterminated tag <" + name + ">");
      if (doc[k] == '>') {
        ++k;
        break;
      }
      if (doc.compare(k, 2, "/>") == 0) {
        self_closing = true;
        k += 2;
        break;
      }
      if (k == before) return fail("attributes of <" + name + "> not separated by space");
      const std::size_t a0 = k;
      while (k < doc.size() && name_char(doc[k])) ++k;
      const std::string attribute = doc.substr(a0, k - a0);
      if (attribute.empty()) return fail("bad attribute name in <" + name + ">");
      if (!attributes.insert(attribute).second) return fail("duplicate attribute " + attribute);
      if (k >= doc.size() || doc[k] != '=')
        return fail("attribute " + attribute + " without value");
      ++k;
      if (k >= doc.size() || (doc[k] != '"' && doc[k] != '\'')) {
        i = k;
        return fail("attribute " + attribute + " not quoted");
      }
      const char quote = doc[k++];
      while (k < doc.size() && doc[k] != quote) {
        if (doc[k] == '<') return fail("'<' in attribute " + attribute);
        if (doc[k] == '&') {
          std::size_t end = 0;
          if (!check_entity(k, end)) {
            i = k;
            return fail("invalid entity in attribute " + attribute);
          }
          k = end;
        }
        ++k;
      }
      if (k >= doc.size()) return fail("unterminated attribute " + attribute);
      ++k;
    }
    if (open.empty()) ++roots;
    if (roots > 1) return fail("a second root element <" + name + ">");
    if (!self_closing) open.push_back(name);
    i = k;
    if (!self_closing && (name == "script" || name == "style")) {  // raw text up to its end tag
      const std::size_t end = doc.find("</" + name, i);
      if (end == std::string::npos) return fail("unterminated <" + name + ">");
      i = end;
    }
  }
  if (!open.empty()) return "unclosed <" + open.back() + "> at the end";
  if (roots == 0) return "no element";
  return "";
}

// A test decoder, independent of the library's encoder.
inline std::string base64_decode(const std::string& text) {
  std::string out;
  unsigned buffer = 0;
  int bits = 0;
  for (const char c : text) {
    int v = -1;
    if (c >= 'A' && c <= 'Z')
      v = c - 'A';
    else if (c >= 'a' && c <= 'z')
      v = c - 'a' + 26;
    else if (c >= '0' && c <= '9')
      v = c - '0' + 52;
    else if (c == '+')
      v = 62;
    else if (c == '/')
      v = 63;
    else
      continue;  // padding
    buffer = buffer << 6 | v;
    bits += 6;
    if (bits >= 8) {
      bits -= 8;
      out += static_cast<char>(buffer >> bits & 0xff);
    }
  }
  return out;
}

// Occurrences of `needle` in `text`.
inline std::size_t count_of(const std::string& text, const std::string& needle) {
  std::size_t n = 0;
  for (std::size_t at = text.find(needle); at != std::string::npos;
       at = text.find(needle, at + needle.size()))
    ++n;
  return n;
}

}  // namespace objmap::test
