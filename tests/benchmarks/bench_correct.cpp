// bench_correct: objmap's pose correction (lib/objmap/pose) on a synthetic 200-keyframe problem —
// a camera orbiting 12 object landmarks, every landmark observed from every keyframe with 5 mm
// noise, the input trajectory drifting (yaw and translation growing along the path). Reports the
// time of correct_poses for "graph" (one Ceres problem, plus its two held-out solves and one
// reweighting round each) and "paper" (eq 20 per keyframe), and the gain in keyframe position RMS.
#include <benchmark/benchmark.h>

#include <cmath>
#include <random>

#include "objmap/pose/correct.h"

namespace {

using objmap::Pose;
using objmap::Vec3;
namespace pose = objmap::pose;

struct Case {
  std::vector<Pose> truth;
  pose::Problem problem;
};

Case make_case(int keyframes) {
  Case c;
  std::vector<Vec3> landmarks;
  for (int j = 0; j < 12; ++j)
    landmarks.push_back(Vec3(0.5 * std::cos(0.9 * j), 0.4 * std::sin(1.3 * j), 0.05 * (j % 4)));
  std::mt19937 rng(1);
  std::normal_distribution<double> noise(0.0, 0.005);
  for (int k = 0; k < keyframes; ++k) {
    const double a = 6.0 * k / keyframes;  // most of a circle
    const Vec3 position(1.5 * std::cos(a), 1.5 * std::sin(a), 0.6);
    const Vec3 z = (-position).normalized();
    const Vec3 x = z.cross(Vec3::UnitZ()).normalized();
    Pose p = Pose::Identity();
    p.linear().col(0) = x;
    p.linear().col(1) = z.cross(x);
    p.linear().col(2) = z;
    p.translation() = position;
    c.truth.push_back(p);
    Pose drift = Pose::Identity();
    drift.linear() = Eigen::AngleAxisd(0.0002 * k, Vec3::UnitZ()).toRotationMatrix();
    drift.translation() = Vec3(0.0002 * k, 0.0001 * k, 0.0);
    c.problem.keyframes.push_back({0.1 * k, drift * p});
  }
  for (int j = 0; j < 12; ++j) c.problem.landmarks.push_back({j, landmarks[j]});
  for (int k = 0; k < keyframes; ++k)
    for (int j = 0; j < 12; ++j) {
      pose::Observation o;
      o.keyframe = k;
      o.landmark = j;
      o.centroid_in_cam =
          c.truth[k].inverse() * landmarks[j] + Vec3(noise(rng), noise(rng), noise(rng));
      c.problem.observations.push_back(o);
    }
  return c;
}

double position_rms(const std::vector<Pose>& a, const std::vector<Pose>& b) {
  double sum = 0.0;
  for (std::size_t k = 0; k < a.size(); ++k)
    sum += (a[k].translation() - b[k].translation()).squaredNorm();
  return std::sqrt(sum / a.size());
}

void BM_Correct(benchmark::State& state, const std::string& method) {
  const Case c = make_case(static_cast<int>(state.range(0)));
  pose::CorrectionOptions options;
  options.method = method;
  pose::CorrectionResult result;
  for (auto _ : state) {
    result = pose::correct_poses(c.problem, options);
    benchmark::DoNotOptimize(result);
  }
  std::vector<Pose> input;
  for (const auto& k : c.problem.keyframes) input.push_back(k.world_from_cam);
  state.counters["keyframes"] = static_cast<double>(c.problem.keyframes.size());
  state.counters["observations"] = static_cast<double>(c.problem.observations.size());
  state.counters["accepted"] = result.accepted;
  state.counters["rms_in_mm"] = 1000.0 * position_rms(input, c.truth);
  state.counters["rms_out_mm"] = 1000.0 * position_rms(result.proposed, c.truth);
}

BENCHMARK_CAPTURE(BM_Correct, graph, std::string("graph"))
    ->Arg(50)
    ->Arg(200)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Correct, paper, std::string("paper"))
    ->Arg(50)
    ->Arg(200)
    ->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
