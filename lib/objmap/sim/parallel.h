#pragma once
#include "objmap/core/parallel.h"

// The scene generator's threads: the shared loop of objmap/core.
namespace objmap::sim {
using objmap::parallel_for;
using objmap::resolve_threads;
}  // namespace objmap::sim
