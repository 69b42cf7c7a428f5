#pragma once
#include <nlohmann/json.hpp>
#include <string>

#include "objmap/eval/ate.h"
#include "objmap/eval/rpe.h"

// The JSON documents of `objmap eval ate` and `objmap eval rpe` (schemas/eval_ate.schema.json,
// schemas/eval_rpe.schema.json). Deterministic: the same result gives the same bytes.
namespace objmap::eval {

// {"count":N,"rmse":..,"mean":..,"median":..,"std":..,"min":..,"max":..} of an error list.
nlohmann::ordered_json stats_json(const ErrorStats& stats);

// {"pairs":N,"rmse":..,"mean":..,"median":..,"std":..,"min":..,"max":.., "unit":"m",
//  "gt":..,"est":..,"max_diff_s":..,"offset_s":..,"gt_from_est":{"type":"se3"|"sim3",
//  "rotation":[9, row-major],"translation":[3],"scale":..}} — metres.
std::string ate_json(const AteResult& result, const AteOptions& options);

// {"pairs":N,"translational":{"rmse",..,"unit":"m"},"rotational":{..,"unit":"deg"},
//  "delta":..,"delta_unit":"s|m|rad|deg|f","offset_s":..,"max_diff_s":..,"gt":..,"est":..}
std::string rpe_json(const RpeResult& result, const RpeOptions& options);

}  // namespace objmap::eval
