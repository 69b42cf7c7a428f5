#pragma once
#include <filesystem>
#include <string>

#include <nlohmann/json.hpp>

#include "objmap/core/camera.h"
#include "objmap/core/error.h"
#include "objmap/core/types.h"
#include "objmap/io/dataset.h"

// Reading what `objmap fuse` wrote into a run folder (run.json, objects.json) for the stages that
// start from a run (objmap correct, objmap eval masks): every missing or mistyped field is an
// InputError naming the file and the field.
namespace objmap::pipeline::run_json {

using json = nlohmann::json;

// The parsed JSON file; InputError when it cannot be read or parsed.
json read_file(const std::filesystem::path& file);

// A field of a JSON document, with a message naming the file and the field when it is missing or
// of the wrong type.
template <typename T>
T field(const json& node, const std::string& key, const std::filesystem::path& file,
        const std::string& where) {
  const std::string name = where.empty() ? key : where + "." + key;
  require(node.is_object() && node.contains(key), file.string() + ": " + name,
          "missing; expected the field that objmap fuse writes");
  try {
    return node.at(key).get<T>();
  } catch (const json::exception&) {
    throw InputError(file.string() + ": " + name, "has the wrong type");
  }
}

// An array of 3 numbers.
Vec3 vec3(const json& a, const std::filesystem::path& file, const std::string& where);

// run.json's inputs.camera.
Camera camera(const json& run, const std::filesystem::path& file);

// run.json's inputs.<which>.path (dataset, trajectory, segmentation).
std::string input_path(const json& run, const std::filesystem::path& file,
                       const std::string& which);

// The recording of the run, read again in the layout fuse read it in (inputs.dataset.layout;
// detected for runs that do not name it), with the run's options.max_diff_s.
io::Dataset dataset(const json& run, const std::filesystem::path& file);

// inputs.dataset.layout, or "auto" for runs that do not name it.
std::string input_layout(const json& run, const std::filesystem::path& file);

}  // namespace objmap::pipeline::run_json
