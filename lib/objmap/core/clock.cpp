#include "objmap/core/clock.h"

#include <sys/resource.h>

namespace objmap {

long peak_rss_kb() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return usage.ru_maxrss;
}

}  // namespace objmap
