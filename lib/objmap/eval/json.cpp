#include "objmap/eval/json.h"

#include <nlohmann/json.hpp>

namespace objmap::eval {

namespace {

using nlohmann::ordered_json;

void put_stats(ordered_json& out, const ErrorStats& stats) {
  out["rmse"] = stats.rmse;
  out["mean"] = stats.mean;
  out["median"] = stats.median;
  out["std"] = stats.stddev;
  out["min"] = stats.min;
  out["max"] = stats.max;
}

}  // namespace

ordered_json stats_json(const ErrorStats& s) {
  ordered_json out;
  out["count"] = s.count;
  put_stats(out, s);
  return out;
}

std::string ate_json(const AteResult& result, const AteOptions& options) {
  ordered_json out;
  out["pairs"] = result.stats.count;
  put_stats(out, result.stats);
  out["unit"] = "m";
  out["gt"] = result.gt_source;
  out["est"] = result.est_source;
  out["max_diff_s"] = options.max_diff_s;
  out["offset_s"] = options.offset_s;
  ordered_json alignment;
  alignment["type"] = options.with_scale ? "sim3" : "se3";
  ordered_json rotation = ordered_json::array();
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) rotation.push_back(result.gt_from_est.rotation(r, c));
  alignment["rotation"] = rotation;
  const Vec3& t = result.gt_from_est.translation;
  alignment["translation"] = {t.x(), t.y(), t.z()};
  alignment["scale"] = result.gt_from_est.scale;
  out["gt_from_est"] = alignment;
  return out.dump(2) + "\n";
}

std::string rpe_json(const RpeResult& result, const RpeOptions& options) {
  ordered_json out;
  out["pairs"] = result.pairs.size();
  ordered_json translational, rotational;
  put_stats(translational, result.translational_m);
  translational["unit"] = "m";
  put_stats(rotational, result.rotational_deg);
  rotational["unit"] = "deg";
  out["translational"] = translational;
  out["rotational"] = rotational;
  out["delta"] = options.delta;
  out["delta_unit"] = to_string(options.delta_unit);
  out["offset_s"] = options.offset_s;
  out["max_diff_s"] = result.max_diff_s;
  out["gt"] = result.gt_source;
  out["est"] = result.est_source;
  return out.dump(2) + "\n";
}

}  // namespace objmap::eval
