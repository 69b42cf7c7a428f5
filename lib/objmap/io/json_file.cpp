#include "objmap/io/json_file.h"

#include <fstream>
#include <string>
#include <system_error>
#include <vector>

#include "objmap/core/error.h"
#include "objmap/io/library_errors.h"

namespace objmap::io {

namespace {

using json = nlohmann::json;

// A SAX pass that only follows where it is ("objects[3].ply"): where a parse fails, the field
// that holds the failing value (a number beyond a double, a broken string).
class FieldTracker : public nlohmann::json_sax<json> {
 public:
  std::string where() const {
    std::string out;
    for (const Level& l : levels_) {
      if (l.array) {
        out += "[" + std::to_string(l.index == 0 ? 0 : l.index - 1) + "]";
      } else if (!l.key.empty()) {
        out += (out.empty() ? "" : ".") + l.key;
      }
    }
    return out;
  }
  bool null() override { return value(); }
  bool boolean(bool) override { return value(); }
  bool number_integer(number_integer_t) override { return value(); }
  bool number_unsigned(number_unsigned_t) override { return value(); }
  bool number_float(number_float_t, const string_t&) override { return value(); }
  bool string(string_t&) override { return value(); }
  bool binary(binary_t&) override { return value(); }
  bool start_object(std::size_t) override {
    value();
    levels_.push_back({false, 0, ""});
    return true;
  }
  bool key(string_t& k) override {
    levels_.back().key = k;
    return true;
  }
  bool end_object() override {
    levels_.pop_back();
    return true;
  }
  bool start_array(std::size_t) override {
    value();
    levels_.push_back({true, 0, ""});
    return true;
  }
  bool end_array() override {
    levels_.pop_back();
    return true;
  }
  bool parse_error(std::size_t, const std::string&, const nlohmann::detail::exception&) override {
    if (!levels_.empty() && levels_.back().array) ++levels_.back().index;
    return false;
  }

 private:
  struct Level {
    bool array = false;
    std::size_t index = 0;  // values met so far in an array
    std::string key;        // the current key of an object
  };
  bool value() {
    if (!levels_.empty() && levels_.back().array) ++levels_.back().index;
    return true;
  }
  std::vector<Level> levels_;
};

}  // namespace

std::string json_failing_field(const std::string& text) {
  FieldTracker tracker;
  json::sax_parse(text, &tracker);
  return tracker.where();
}

nlohmann::json read_json_file(const std::filesystem::path& file, const std::string& cannot_open) {
  // A folder opens as a stream on Linux; reading it would then throw std::ios_base::failure.
  std::error_code ec;
  if (std::filesystem::is_directory(file, ec))
    throw InputError(file.string(), "is a folder; expected a JSON file");
  std::ifstream in(file);
  if (!in) throw InputError(file.string(), cannot_open);
  try {
    return nlohmann::json::parse(in);
  } catch (const nlohmann::json::out_of_range& e) {
    // A number beyond a double: name the field it belongs to.
    std::ifstream again(file);
    FieldTracker tracker;
    json::sax_parse(again, &tracker);
    const std::string field = tracker.where();
    throw InputError(file.string() + (field.empty() ? "" : ": " + field),
                     std::string("malformed JSON: ") + e.what());
  } catch (const nlohmann::json::exception& e) {
    throw InputError(file.string(), std::string("malformed JSON: ") + e.what());
  } catch (...) {
    rethrow_naming_file(file.string());
  }
}

}  // namespace objmap::io
