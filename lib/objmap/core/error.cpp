#include "objmap/core/error.h"

namespace objmap {

namespace {
std::string join(const std::string& where, const std::string& reason) {
  return where.empty() ? reason : where + ": " + reason;
}
}  // namespace

InputError::InputError(std::string where, std::string reason)
    : std::runtime_error(join(where, reason)),
      where_(std::move(where)),
      reason_(std::move(reason)) {}

void require(bool condition, const std::string& where, const std::string& reason) {
  if (!condition) throw InputError(where, reason);
}

}  // namespace objmap
