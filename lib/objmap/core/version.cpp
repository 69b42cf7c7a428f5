#include "objmap/core/version.h"

namespace objmap {
const char* version() { return "0.1.0"; }
}  // namespace objmap
