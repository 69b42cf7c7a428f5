// objmap's ICP (pose::ModelAligner) against PCL's IterativeClosestPointWithNormals on two
// constructed cases: a noisy box corner moved 15 mm / 3°, a noisy plane moved 7 mm across itself.
// Prints time per alignment, the residual of the recovered motion, and the slide along the plane.
// Not part of the CMake build (it needs the PCL components registration and features, which the
// project does not configure yet). After `make build`, from the repo root, as one command line:
//   g++ -O2 -std=c++17 -Ilib -I/usr/include/pcl-1.13 -I/usr/include/eigen3
//     tests/benchmarks/compare_pcl_icp.cpp build/lib/objmap/pose/libobjmap_pose.a
//     build/lib/objmap/libobjmap_core.a -lpcl_registration -lpcl_features -lpcl_search
//     -lpcl_kdtree -lpcl_common -o /tmp/compare_pcl_icp && /tmp/compare_pcl_icp
#include <pcl/features/normal_3d.h>
#include <pcl/kdtree/kdtree_flann.h>
#include <pcl/registration/icp.h>
#include <chrono>
#include <cstdio>
#include <random>
#include "objmap/pose/icp.h"
using namespace objmap;
using Clock = std::chrono::steady_clock;
PointCloud box(double noise, unsigned seed, bool plane_only) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> n(0, noise);
  PointCloud c;
  auto add = [&](double x, double y, double z) {
    c.push_back(Vec3f(x + n(rng), y + n(rng), z + n(rng)));
  };
  for (double a = 0; a <= 0.2; a += 0.002)
    for (double b = 0; b <= 0.15; b += 0.002) add(a, b, 0.10);
  if (plane_only) return c;
  for (double a = 0; a <= 0.2; a += 0.002)
    for (double z = 0; z <= 0.1; z += 0.002) add(a, 0, z);
  for (double b = 0; b <= 0.15; b += 0.002)
    for (double z = 0; z <= 0.1; z += 0.002) add(0, b, z);
  return c;
}
PointCloud tf(const PointCloud& c, const Pose& t) {
  PointCloud o;
  for (auto& p : c.points) o.push_back((t * p.cast<double>()).cast<float>());
  return o;
}
pcl::PointCloud<pcl::PointNormal>::Ptr with_normals(const PointCloud& c) {
  pcl::PointCloud<pcl::PointXYZ>::Ptr xyz(new pcl::PointCloud<pcl::PointXYZ>);
  for (auto& p : c.points) xyz->push_back(pcl::PointXYZ(p.x(), p.y(), p.z()));
  pcl::NormalEstimation<pcl::PointXYZ, pcl::Normal> ne;
  ne.setInputCloud(xyz);
  ne.setKSearch(12);
  pcl::PointCloud<pcl::Normal> normals;
  ne.compute(normals);
  pcl::PointCloud<pcl::PointNormal>::Ptr out(new pcl::PointCloud<pcl::PointNormal>);
  pcl::concatenateFields(*xyz, normals, *out);
  return out;
}
int main() {
  for (int plane = 0; plane < 2; ++plane) {
    Pose motion = Pose::Identity();
    if (!plane)
      motion.linear() =
          Eigen::AngleAxisd(3.0 * M_PI / 180, Vec3(0.3, 1, 0.2).normalized()).toRotationMatrix();
    motion.translation() = plane ? Vec3(0, 0, 0.007) : Vec3(0.012, -0.008, 0.006);
    const PointCloud model = box(0.001, 1, plane), view = tf(box(0.001, 2, plane), motion);
    // objmap
    auto t0 = Clock::now();
    pose::ModelAligner al(model, pose::IcpOptions{});
    auto t1 = Clock::now();
    pose::IcpResult r{};
    for (int i = 0; i < 10; ++i) r = al.align(view);
    auto t2 = Clock::now();
    Pose res = r.correction * motion;
    std::printf(
        "%s objmap: build %.1f ms, align %.2f ms, residual %.2f mm %.3f deg, in-plane slide %.3f "
        "mm\n",
        plane ? "plane" : "box  ", std::chrono::duration<double, std::milli>(t1 - t0).count(),
        std::chrono::duration<double, std::milli>(t2 - t1).count() / 10,
        res.translation().norm() * 1000, Eigen::AngleAxisd(res.linear()).angle() * 180 / M_PI,
        Eigen::Vector2d(r.correction.translation().x(), r.correction.translation().y()).norm() *
            1000);
    // PCL: thinned view like ours (<= 2000 points)
    PointCloud thin;
    std::size_t stride = (view.size() + 1999) / 2000;
    for (std::size_t i = 0; i < view.size(); i += stride) thin.push_back(view.points[i]);
    t0 = Clock::now();
    auto tgt = with_normals(model), src = with_normals(thin);
    t1 = Clock::now();
    Eigen::Matrix4f T = Eigen::Matrix4f::Identity();
    for (int i = 0; i < 10; ++i) {
      pcl::IterativeClosestPointWithNormals<pcl::PointNormal, pcl::PointNormal> icp;
      icp.setInputSource(src);
      icp.setInputTarget(tgt);
      icp.setMaxCorrespondenceDistance(0.03);
      icp.setMaximumIterations(30);
      icp.setTransformationEpsilon(1e-10);
      pcl::PointCloud<pcl::PointNormal> out;
      icp.align(out);
      T = icp.getFinalTransformation();
    }
    t2 = Clock::now();
    Pose c = Pose::Identity();
    c.matrix() = T.cast<double>();
    res = c * motion;
    std::printf(
        "%s PCL   : build %.1f ms, align %.2f ms, residual %.2f mm %.3f deg, in-plane slide %.3f "
        "mm\n",
        plane ? "plane" : "box  ", std::chrono::duration<double, std::milli>(t1 - t0).count(),
        std::chrono::duration<double, std::milli>(t2 - t1).count() / 10,
        res.translation().norm() * 1000, Eigen::AngleAxisd(res.linear()).angle() * 180 / M_PI,
        Eigen::Vector2d(c.translation().x(), c.translation().y()).norm() * 1000);
  }
}
