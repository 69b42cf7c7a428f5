// Outputs unchanged: objects.json and run.json of `objmap fuse` on the synthetic scene of seed 3
// and on fr1_rpy_every4 (Yolo-Fastest boxes, ground-truth trajectory), less timings
// (run.json "performance") and with the run's and the inputs' folders replaced by {RUN}, {SCENE}
// and {DATA}, compared with tests/regression/outputs_reference.json section by section: a section
// that is small (counts, points, inputs with their checksums) as it is, a large one (each object,
// each sighting, the options, the duplicates, the scene) by the FNV-1a digest of its JSON, so that
// a failure names the section and the object that changed. A restructuring must leave every
// section as it was.
//
// A change that is meant to change the outputs (or the synthetic scene: see run.json's input
// checksums) rewrites the reference with OBJMAP_UPDATE_OUTPUT_REFERENCE=1 in the environment
// (`OBJMAP_UPDATE_OUTPUT_REFERENCE=1 ctest -R regression_outputs`) and says why in its commit.
//
// The runs are those of the test cache (support/test_support.h) that tests/regression and
// tests/integration/diff_test.cpp make with the same arguments: "seed3-orbit60-scene",
// "seed3-orbit60-fuse" and "diff-real-fr1_rpy_every4".
#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "objmap/core/checksum.h"
#include "support/test_support.h"

namespace objmap::test {
namespace {

using nlohmann::json;

fs::path output_reference_file() {
  return fs::path(OBJMAP_SOURCE_DIR_FOR_TESTS) / "tests" / "regression" / "outputs_reference.json";
}

bool update_output_reference() {
  const char* v = std::getenv("OBJMAP_UPDATE_OUTPUT_REFERENCE");
  return v && std::string(v) == "1";
}

// Every string with `from` replaced by `to`, recursively.
void replace_in_strings(json& node, const std::string& from, const std::string& to) {
  if (node.is_string()) {
    std::string s = node.get<std::string>();
    for (std::size_t at = s.find(from); at != std::string::npos; at = s.find(from, at + to.size()))
      s.replace(at, from.size(), to);
    node = s;
  } else if (node.is_structured()) {
    for (auto& child : node) replace_in_strings(child, from, to);
  }
}

// A value as it is when its JSON is short, else as the digest of its JSON.
json section_value(const json& value) {
  const std::string text = value.dump();
  if (text.size() <= 600) return value;
  return json{{"fnv1a", hex64(fnv1a(text))}, {"bytes", text.size()}};
}

// The sections of one output file: its top-level fields, arrays of records one entry per record
// ("objects[3] id 4 chair").
json output_sections(const fs::path& file, const std::map<std::string, std::string>& folders) {
  std::ifstream in(file);
  json doc = json::parse(in, nullptr, /*allow_exceptions=*/false);
  if (!doc.is_object()) return json();
  doc.erase("performance");  // timings and memory: the one part that differs between two runs
  for (const auto& [folder, name] : folders) replace_in_strings(doc, folder, name);
  json sections = json::object();
  for (const auto& [key, value] : doc.items()) {
    if (value.is_array() && !value.empty() && value.front().is_object()) {
      sections[key + ".size"] = value.size();
      for (std::size_t i = 0; i < value.size(); ++i) {
        std::string name = key + "[" + std::to_string(i) + "]";
        if (value[i].contains("id")) name += " id " + value[i]["id"].dump();
        if (value[i].contains("class")) name += " " + value[i]["class"].get<std::string>();
        sections[name] = section_value(value[i]);
      }
    } else {
      sections[key] = section_value(value);
    }
  }
  return sections;
}

// Compares the sections of `run`'s objects.json and run.json with the reference's entry `name`
// (or writes them there with OBJMAP_UPDATE_OUTPUT_REFERENCE=1).
void expect_outputs_as_recorded(const std::string& name, const fs::path& run,
                                const std::map<std::string, std::string>& folders) {
  json got = json::object();
  for (const char* file : {"objects.json", "run.json"}) {
    got[file] = output_sections(run / file, folders);
    ASSERT_TRUE(got[file].is_object()) << run / file << " is not a JSON object";
  }
  json reference;
  {
    std::ifstream in(output_reference_file());
    reference = json::parse(in, nullptr, /*allow_exceptions=*/false);
  }
  if (!reference.is_object()) reference = json::object();
  if (update_output_reference()) {
    reference[name] = got;
    std::ofstream(output_reference_file()) << reference.dump(1) << "\n";
    std::cout << "[ outputs ] wrote " << name << " into " << output_reference_file() << std::endl;
    return;
  }
  ASSERT_TRUE(reference.contains(name)) << "no entry " << name << " in " << output_reference_file()
                                        << "; record it with OBJMAP_UPDATE_OUTPUT_REFERENCE=1";
  for (const char* file : {"objects.json", "run.json"}) {
    const json& want = reference[name][file];
    const json& have = got[file];
    std::vector<std::string> keys;
    for (const auto& [key, value] : want.items()) keys.push_back(key);
    for (const auto& [key, value] : have.items())
      if (!want.contains(key)) keys.push_back(key);
    for (const std::string& key : keys) {
      const json recorded = want.contains(key) ? want[key] : json("(absent)");
      const json now = have.contains(key) ? have[key] : json("(absent)");
      EXPECT_EQ(recorded, now) << name << " " << file << " section \"" << key
                               << "\" changed:\n  recorded " << recorded.dump() << "\n  now      "
                               << now.dump()
                               << "\n(a deliberate change: OBJMAP_UPDATE_OUTPUT_REFERENCE=1, see "
                                  "the head of tests/regression/outputs_test.cpp)";
    }
  }
}

TEST(Outputs, FuseOnASyntheticSceneAsRecorded) {
  RunResult synth, fuse;
  const fs::path scene =
      cached_output("seed3-orbit60-scene",
                    {"synth", "--out", "{OUT}", "--seed", "3", "--orbit-speed", "60"}, &synth);
  ASSERT_TRUE(fs::exists(scene)) << synth.err;
  const fs::path run = cached_output(
      "seed3-orbit60-fuse",
      {"fuse", "--dataset", scene.string(), "--trajectory", (scene / "groundtruth.txt").string(),
       "--segmentation", (scene / "segmentation").string(), "--out", "{OUT}"},
      &fuse);
  ASSERT_TRUE(fs::exists(run)) << fuse.err;
  expect_outputs_as_recorded("synthetic_seed3_orbit60", run,
                             {{run.string(), "{RUN}"}, {scene.string(), "{SCENE}"}});
}

TEST(Outputs, FuseOnFr1RpyAsRecorded) {
  OBJMAP_DATA_OR_SKIP(data, "tum/fr1_rpy_every4");
  RunResult fuse;
  const fs::path run = cached_output(
      "diff-real-fr1_rpy_every4",
      {"fuse", "--dataset", data.string(), "--trajectory", (data / "groundtruth.txt").string(),
       "--segmentation", (data / "detections_yolofastest").string(), "--out", "{OUT}"},
      &fuse);
  ASSERT_TRUE(fs::exists(run)) << fuse.err;
  expect_outputs_as_recorded("fr1_rpy_every4", run,
                             {{run.string(), "{RUN}"}, {data.string(), "{DATA}"}});
}

}  // namespace
}  // namespace objmap::test
