#pragma once
#include <stdexcept>
#include <string>

namespace objmap {

// The one exception type of the library: bad input (a file, a field, an option). `what()` is the
// whole line that the user sees: "<where>: <what is wrong>; expected <what was expected>". `where`
// is a file path, optionally with ":<line>" or a field name; it may be empty for an option of a
// struct. apps/objmap turns it into exit code 2 and that one line on stderr.
class InputError : public std::runtime_error {
 public:
  InputError(std::string where, std::string reason);
  const std::string& where() const { return where_; }
  const std::string& reason() const { return reason_; }

 private:
  std::string where_;
  std::string reason_;
};

// Throws InputError(where, reason) when `condition` is false. For option checks: `require(k > 0,
// "OutlierOptions.std_ratio", "must be > 0, got " + std::to_string(k))`.
void require(bool condition, const std::string& where, const std::string& reason);

}  // namespace objmap
