#pragma once

namespace objmap {
// The library's version, "MAJOR.MINOR.PATCH"; written into run.json and the outputs.
const char* version();
}  // namespace objmap
