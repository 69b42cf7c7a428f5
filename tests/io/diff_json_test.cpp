// io::read_diff_json: a diff.json as objmap diff writes it reads back; every damaged field is one
// InputError line naming the file and the field.
#include <gtest/gtest.h>

#include <functional>
#include <nlohmann/json.hpp>

#include "objmap/core/error.h"
#include "objmap/io/diff_json.h"
#include "support/test_support.h"

namespace objmap::test {
namespace {

using nlohmann::json;

json evidence(int through, int lines) {
  return {{"views", 12},
          {"sightlines", lines},
          {"surface", lines - through},
          {"seen_through", through},
          {"occluded", 3},
          {"surface_share", double(lines - through) / lines}};
}

// A small diff as objmap diff writes it: B's world is A's turned 90° about z and shifted by x 1.
json valid_diff() {
  json side_a = {{"id", 3}, {"class", "cup"}, {"position", {0.5, 0.2, 0.8}}};
  json side_b = {{"id", 7},
                 {"class", "cup"},
                 {"position", {0.1, -0.5, 0.8}},
                 {"position_in_before", {1.5, 0.1, 0.8}}};
  return {{"schema_version", 1},
          {"generator", "objmap test"},
          {"before", "runA"},
          {"after", "runB"},
          {"frame", "before world"},
          {"registration",
           {{"source", "objects+icp"},
            {"before_from_after", {0, -1, 0, 1, 1, 0, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1}},
            {"yaw_deg", 90.0},
            {"tilt_deg", 0.1},
            {"translation_m", {1, 0, 0}},
            {"common_objects", 5},
            {"coarse_rms_m", 0.01},
            {"hypotheses", 40},
            {"fitness", 0.98},
            {"fitness_both", 0.9},
            {"rms_m", 0.008},
            {"icp_points", 10000},
            {"sigma_translation_m", 0.0003},
            {"sigma_yaw_deg", nullptr},
            {"uncertainty_at_objects_m", 0.03},
            {"uncertainty_yaw_deg", nullptr}}},
          {"counts",
           {{"unchanged", 0},
            {"moved", 1},
            {"removed", 1},
            {"added", 1},
            {"changed_class", 0},
            {"not_seen_again", 0},
            {"not_seen_before", 0}}},
          {"left_out", {{{"class", "person"}, {"count", 2}}}},
          {"objects",
           {{{"status", "moved"},
             {"before", side_a},
             {"after", side_b},
             {"distance_m", 1.0},
             {"displacement_m", {1.0, -0.1, 0.0}},
             {"evidence", {{"after_visit", evidence(18, 20)}, {"before_visit", nullptr}}},
             {"why", "same class 1.0 m away"}},
            {{"status", "removed"},
             {"before", {{"id", 4}, {"class", "book"}, {"position", {0, 0, 0.75}}}},
             {"after", nullptr},
             {"distance_m", nullptr},
             {"displacement_m", nullptr},
             {"evidence", {{"after_visit", evidence(25, 30)}, {"before_visit", nullptr}}},
             {"why", "its place seen empty"}},
            {{"status", "added"},
             {"before", nullptr},
             {"after", {{"id", 9}, {"class", "bowl"}, {"position", {0, 1, 0.8}}}},
             {"distance_m", nullptr},
             {"displacement_m", nullptr},
             {"evidence", {{"after_visit", nullptr}, {"before_visit", evidence(22, 24)}}},
             {"why", "its place seen empty"}}}}};
}

std::string read_error(const json& doc, const fs::path& file) {
  write_text(file, doc.dump(1));
  try {
    io::read_diff_json(file);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(DiffJson, ReadsWhatObjmapDiffWrites) {
  TempDir tmp;
  write_text(tmp / "diff.json", valid_diff().dump(1));
  const io::DiffFile d = io::read_diff_json(tmp.path());  // the folder or the file
  EXPECT_EQ(d.source, (tmp / "diff.json").string());
  EXPECT_EQ(d.before, "runA");
  EXPECT_EQ(d.registration.source, "objects+icp");
  EXPECT_NEAR(d.registration.before_from_after.translation().x(), 1.0, 1e-12);
  EXPECT_NEAR(d.registration.sigma_translation_m.value(), 0.0003, 1e-12);
  EXPECT_FALSE(d.registration.sigma_yaw_deg.has_value());
  EXPECT_NEAR(d.registration.uncertainty_at_objects_m.value(), 0.03, 1e-12);
  EXPECT_FALSE(d.registration.uncertainty_yaw_deg.has_value());
  EXPECT_EQ(d.counts.at("moved"), 1);
  ASSERT_EQ(d.left_out.size(), 1u);
  EXPECT_EQ(d.left_out[0].second, 2);
  ASSERT_EQ(d.objects.size(), 3u);
  EXPECT_EQ(d.objects[0].status, "moved");
  EXPECT_EQ(d.objects[0].after->id, 7);
  EXPECT_TRUE(d.objects[0].position_in_before().isApprox(Vec3(0.5, 0.2, 0.8)));
  EXPECT_EQ(d.objects[0].after_visit->seen_through, 18);
  EXPECT_TRUE(d.objects[0].displacement_m->isApprox(Vec3(1.0, -0.1, 0.0)));
  // An after side without position_in_before: registered with before_from_after.
  EXPECT_TRUE(d.objects[2].position_in_before().isApprox(Vec3(0.0, 0.0, 0.8)))
      << d.objects[2].position_in_before().transpose();
  EXPECT_EQ(io::read_diff_json(tmp / "diff.json").objects.size(), 3u);
}

// Each damage and the field its message must name.
struct Damage {
  std::string field;  // named in the message
  std::function<void(json&)> apply;
};

TEST(DiffJson, EveryDamagedFieldIsOneLineNamingFileAndField) {
  const std::vector<Damage> damages = {
      {"schema_version", [](json& d) { d["schema_version"] = 2; }},
      {"missing field 'generator'", [](json& d) { d.erase("generator"); }},
      {"before", [](json& d) { d["before"] = 3; }},
      {"registration.source", [](json& d) { d["registration"]["source"] = "guess"; }},
      {"registration.before_from_after",
       [](json& d) { d["registration"]["before_from_after"].erase(15); }},
      {"registration.before_from_after",  // a scale is not rigid
       [](json& d) { d["registration"]["before_from_after"][1] = -2; }},
      {"registration.before_from_after[4]",
       [](json& d) { d["registration"]["before_from_after"][4] = "1"; }},
      {"registration.fitness", [](json& d) { d["registration"]["fitness"] = 1.5; }},
      {"registration.fitness_both", [](json& d) { d["registration"]["fitness_both"] = -0.1; }},
      {"registration.tilt_deg", [](json& d) { d["registration"]["tilt_deg"] = -1; }},
      {"registration.translation_m",
       [](json& d) {
         d["registration"]["translation_m"] = {1, 2};
       }},
      {"registration.common_objects", [](json& d) { d["registration"]["common_objects"] = 1.5; }},
      {"registration.hypotheses", [](json& d) { d["registration"]["hypotheses"] = -3; }},
      {"registration: missing field 'icp_points'",
       [](json& d) { d["registration"].erase("icp_points"); }},
      {"registration.sigma_yaw_deg", [](json& d) { d["registration"]["sigma_yaw_deg"] = "x"; }},
      {"registration: missing field 'uncertainty_at_objects_m'",
       [](json& d) { d["registration"].erase("uncertainty_at_objects_m"); }},
      {"registration.uncertainty_yaw_deg",
       [](json& d) { d["registration"]["uncertainty_yaw_deg"] = -1.0; }},
      {"registration.rms_m", [](json& d) { d["registration"]["rms_m"] = nullptr; }},
      {"counts: missing field 'added'", [](json& d) { d["counts"].erase("added"); }},
      {"counts.moved", [](json& d) { d["counts"]["moved"] = -1; }},
      {"left_out[0].count", [](json& d) { d["left_out"][0]["count"] = 0; }},
      {"left_out[0]: missing field 'class'", [](json& d) { d["left_out"][0].erase("class"); }},
      {"objects", [](json& d) { d["objects"] = json::object(); }},
      {"objects[1].status", [](json& d) { d["objects"][1]["status"] = "stolen"; }},
      {"objects[0].before.position",
       [](json& d) { d["objects"][0]["before"]["position"] = "here"; }},
      {"objects[0].before.position[2]",
       [](json& d) { d["objects"][0]["before"]["position"][2] = nullptr; }},
      {"objects[0].after.id", [](json& d) { d["objects"][0]["after"]["id"] = "seven"; }},
      {"objects[0].after: missing field 'class'",
       [](json& d) { d["objects"][0]["after"].erase("class"); }},
      {"objects[0].after.position_in_before",
       [](json& d) { d["objects"][0]["after"]["position_in_before"] = {1}; }},
      {"objects[0].after", [](json& d) { d["objects"][0]["after"] = nullptr; }},
      {"objects[0].displacement_m", [](json& d) { d["objects"][0]["displacement_m"] = nullptr; }},
      {"objects[0].distance_m", [](json& d) { d["objects"][0]["distance_m"] = -1; }},
      {"objects[1].before", [](json& d) { d["objects"][1]["before"] = nullptr; }},
      {"objects[2].after", [](json& d) { d["objects"][2]["after"] = nullptr; }},
      {"objects[0].evidence.after_visit.surface_share",
       [](json& d) { d["objects"][0]["evidence"]["after_visit"]["surface_share"] = 2; }},
      {"objects[0].evidence.after_visit: missing field 'views'",
       [](json& d) { d["objects"][0]["evidence"]["after_visit"].erase("views"); }},
      {"objects[2].evidence: missing field 'before_visit'",
       [](json& d) { d["objects"][2]["evidence"].erase("before_visit"); }},
      {"objects[1].why", [](json& d) { d["objects"][1]["why"] = 1; }},
      {"objects[2]: missing field 'why'", [](json& d) { d["objects"][2].erase("why"); }},
  };
  TempDir tmp;
  const fs::path file = tmp / "diff.json";
  for (const Damage& damage : damages) {
    json doc = valid_diff();
    damage.apply(doc);
    const std::string message = read_error(doc, file);
    SCOPED_TRACE(damage.field + ": " + message);
    ASSERT_FALSE(message.empty());
    EXPECT_EQ(message.find('\n'), std::string::npos);
    EXPECT_EQ(message.rfind(file.string() + ": ", 0), 0u);
    EXPECT_NE(message.find(damage.field), std::string::npos);
  }
  // Not JSON, not an object, no file.
  write_text(file, "{\"schema_version\": 1,");
  EXPECT_THROW(io::read_diff_json(file), InputError);
  write_text(file, "[1, 2]");
  EXPECT_THROW(io::read_diff_json(file), InputError);
  EXPECT_THROW(io::read_diff_json(tmp / "none.json"), InputError);
}

}  // namespace
}  // namespace objmap::test
