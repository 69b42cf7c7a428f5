// objmap's statistical outlier removal (filters::remove_outliers, eq 18) against PCL's
// StatisticalOutlierRemoval on bench_fusion's 100k-point cloud, K = 20, k = 1.0: the kept sets
// compared flag by flag, and the wall time per call (best of 10) of each, objmap's on 1 and 2
// threads. Not part of the CMake build (PCL is not a dependency of objmap). After `make build`,
// from the repo root, as one command line:
//   g++ -O2 -std=c++17 -Ilib -Itests/benchmarks -I/usr/include/pcl-1.13 -I/usr/include/eigen3
//     tests/benchmarks/compare_pcl_sor.cpp build/lib/objmap/filters/libobjmap_filters.a
//     build/lib/objmap/libobjmap_core.a -lpcl_filters -lpcl_search -lpcl_kdtree -lpcl_common
//     -llz4 -lpthread -o /tmp/compare_pcl_sor && /tmp/compare_pcl_sor
#include <pcl/filters/statistical_outlier_removal.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <vector>

#include "objmap/filters/outlier.h"
#include "surface_cloud.h"

namespace {

double now_ms() {
  return std::chrono::duration<double, std::milli>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

template <typename F>
double best_of_10(F&& f) {
  double best = 1e300;
  for (int i = 0; i < 10; ++i) {
    const double t0 = now_ms();
    f();
    best = std::min(best, now_ms() - t0);
  }
  return best;
}

}  // namespace

int main() {
  using namespace objmap;
  const PointCloud cloud = bench::surface_cloud(100000);
  auto pcl_cloud = std::make_shared<pcl::PointCloud<pcl::PointXYZ>>();
  for (const Vec3f& p : cloud.points) pcl_cloud->push_back(pcl::PointXYZ(p.x(), p.y(), p.z()));

  filters::OutlierResult ours;
  const double ours_ms = best_of_10([&] { ours = filters::remove_outliers(cloud, {}); });
  filters::OutlierOptions two_threads;
  two_threads.threads = 2;
  const double ours_2_ms = best_of_10([&] { filters::remove_outliers(cloud, two_threads); });
  pcl::Indices kept;
  const double pcl_ms = best_of_10([&] {
    pcl::StatisticalOutlierRemoval<pcl::PointXYZ> sor;
    sor.setInputCloud(pcl_cloud);
    sor.setMeanK(20);
    sor.setStddevMulThresh(1.0);
    sor.filter(kept);
  });

  std::vector<bool> pcl_keeps(cloud.size(), false);
  for (const auto i : kept) pcl_keeps[static_cast<std::size_t>(i)] = true;
  std::size_t differing = 0;
  for (std::size_t i = 0; i < cloud.size(); ++i) differing += pcl_keeps[i] != ours.keep_mask[i];
  std::printf("objmap remove_outliers: %zu kept, %.1f ms (1 thread), %.1f ms (2 threads)\n",
              ours.kept.size(), ours_ms, ours_2_ms);
  std::printf("PCL StatisticalOutlierRemoval: %zu kept, %.1f ms\n", kept.size(), pcl_ms);
  std::printf("points kept by one and not the other: %zu\n", differing);
  return differing == 0 ? 0 : 1;
}
