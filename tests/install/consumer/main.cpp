#include <cstdio>
#include "objmap/core/camera.h"
#include "objmap/core/version.h"
#include "objmap/io/trajectory.h"
int main() {
  auto c = objmap::camera_preset("fr1");
  std::printf("%s %g\n", objmap::version(), c.fx);
}
