#include "objmap/pipeline/run_json.h"

#include <array>

#include "objmap/io/json_file.h"

namespace objmap::pipeline::run_json {

namespace fs = std::filesystem;

json read_file(const fs::path& file) {
  return io::read_json_file(file, "cannot be read; expected a file of a fuse run");
}

Vec3 vec3(const json& a, const fs::path& file, const std::string& where) {
  require(a.is_array() && a.size() == 3 && a[0].is_number() && a[1].is_number() && a[2].is_number(),
          file.string() + ": " + where, "expected an array of 3 numbers");
  return {a[0].get<double>(), a[1].get<double>(), a[2].get<double>()};
}

Camera camera(const json& run, const fs::path& file) {
  const json cam = field<json>(field<json>(run, "inputs", file, ""), "camera", file, "inputs");
  Camera c;
  c.name = field<std::string>(cam, "name", file, "inputs.camera");
  c.width = field<int>(cam, "width", file, "inputs.camera");
  c.height = field<int>(cam, "height", file, "inputs.camera");
  c.fx = field<double>(cam, "fx", file, "inputs.camera");
  c.fy = field<double>(cam, "fy", file, "inputs.camera");
  c.cx = field<double>(cam, "cx", file, "inputs.camera");
  c.cy = field<double>(cam, "cy", file, "inputs.camera");
  c.distortion = field<std::array<double, 5>>(cam, "distortion", file, "inputs.camera");
  c.depth_factor = field<double>(cam, "depth_factor", file, "inputs.camera");
  c.check(file.string() + ": inputs.camera");
  return c;
}

std::string input_path(const json& run, const fs::path& file, const std::string& which) {
  const json inputs = field<json>(run, "inputs", file, "");
  return field<std::string>(field<json>(inputs, which, file, "inputs"), "path", file,
                            "inputs." + which);
}

std::string input_layout(const json& run, const fs::path& file) {
  const json inputs = field<json>(run, "inputs", file, "");
  const json dataset = field<json>(inputs, "dataset", file, "inputs");
  if (!dataset.contains("layout")) return "auto";
  return field<std::string>(dataset, "layout", file, "inputs.dataset");
}

io::Dataset dataset(const json& run, const fs::path& file) {
  io::DatasetOptions options;
  options.layout = input_layout(run, file);
  options.max_diff_s = field<json>(run, "options", file, "").value("max_diff_s", 0.02);
  const json inputs = field<json>(run, "inputs", file, "");
  const json recording = field<json>(inputs, "dataset", file, "inputs");
  if (recording.contains("topics"))
    options.topics = field<std::string>(recording, "topics", file, "inputs.dataset");
  return io::read_dataset(input_path(run, file, "dataset"), options);
}

}  // namespace objmap::pipeline::run_json
