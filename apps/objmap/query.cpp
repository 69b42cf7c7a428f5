// objmap query: "cup on table" asked of a fused run (docs/scene.md, "Queries"), or "what moved"
// asked of a diff (docs/change.md, "Questions").
#include <cstdio>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "command.h"
#include "objmap/change/diff_query.h"
#include "objmap/core/error.h"
#include "objmap/io/diff_json.h"
#include "objmap/io/scene_json.h"
#include "objmap/scene/query.h"

namespace objmap::app {
namespace {

struct QueryOptions {
  std::string run;
  std::string diff;
  std::string text;
  bool json = false;
};

nlohmann::ordered_json match_json(const scene::QueryMatch& m, const scene::MapScene& map) {
  const Vec3& p = m.object->position;
  nlohmann::ordered_json j = {
      {"id", m.object->id}, {"class", m.object->class_name}, {"position", {p.x(), p.y(), p.z()}},
      {"why", m.why},       {"distance_m", m.distance_m},    {"surface", nullptr}};
  if (const scene::MapSurface* s = m.surface ? map.surface(*m.surface) : nullptr)
    j["surface"] = {{"id", s->id}, {"label", s->label}, {"height_m", s->height_m}};
  return j;
}

// "1 table" or "-": the surface a match stands on.
std::string surface_text(const scene::QueryMatch& m, const scene::MapScene& map) {
  const scene::MapSurface* s = m.surface ? map.surface(*m.surface) : nullptr;
  return s ? std::to_string(s->id) + " " + s->label : "-";
}

void print_matches(const std::vector<scene::QueryMatch>& matches, const scene::MapScene& map) {
  std::printf("  %-4s %-16s %-27s %-12s %s\n", "id", "class", "position (m)", "surface",
              "relation");
  for (const auto& m : matches) {
    const Vec3& p = m.object->position;
    std::printf("  %-4d %-16s (%7.3f, %7.3f, %7.3f)  %-12s %s\n", m.object->id,
                m.object->class_name.c_str(), p.x(), p.y(), p.z(), surface_text(m, map).c_str(),
                m.why.c_str());
  }
}

void run_query_command(const QueryOptions& o) {
  const scene::MapScene map = io::read_map_scene(std::filesystem::path(o.run) / "objects.json");
  const scene::Query q = scene::parse_query(o.text, map);
  const scene::QueryResult r = scene::run_query(q, map);
  if (o.json) {
    nlohmann::ordered_json out = {{"query", o.text},
                                  {"subject", q.subject},
                                  {"relation", q.relation},
                                  {"target", q.target},
                                  {"matches", nlohmann::ordered_json::array()},
                                  {"candidates", nlohmann::ordered_json::array()}};
    for (const auto& m : r.matches) out["matches"].push_back(match_json(m, map));
    for (const auto& m : r.candidates) out["candidates"].push_back(match_json(m, map));
    std::printf("%s\n", out.dump(2).c_str());
    return;
  }
  if (!r.matches.empty()) {
    std::printf("%zu match%s for \"%s\":\n", r.matches.size(), r.matches.size() == 1 ? "" : "es",
                o.text.c_str());
    print_matches(r.matches, map);
    return;
  }
  std::printf("no match for \"%s\"\n", o.text.c_str());
  if (!r.candidates.empty()) {
    std::printf("nearest candidates:\n");
    print_matches(r.candidates, map);
  }
}

// ---- --diff: the objects of a diff.json that answer "what moved"

nlohmann::ordered_json vec_json(const Vec3& v) { return {v.x(), v.y(), v.z()}; }

nlohmann::ordered_json side_json(const std::optional<io::DiffSide>& s) {
  if (!s) return nullptr;
  return {{"id", s->id},
          {"class", s->class_name},
          {"position", vec_json(s->position)},
          {"position_in_before", vec_json(s->position_in_before)}};
}

nlohmann::ordered_json diff_match_json(const io::DiffObject& o) {
  return {{"status", o.status},
          {"before", side_json(o.before)},
          {"after", side_json(o.after)},
          {"position_in_before", vec_json(o.position_in_before())},
          {"distance_m", o.distance_m ? nlohmann::ordered_json(*o.distance_m) : nullptr},
          {"displacement_m", o.displacement_m ? vec_json(*o.displacement_m) : nullptr},
          {"why", o.why}};
}

// "3 cup" or "-".
std::string side_text(const std::optional<io::DiffSide>& s) {
  return s ? std::to_string(s->id) + " " + s->class_name : "-";
}

std::string point_text(const Vec3& p) {
  char text[64];
  std::snprintf(text, sizeof text, "(%7.3f, %7.3f, %7.3f)", p.x(), p.y(), p.z());
  return text;
}

void print_diff_matches(const std::vector<const io::DiffObject*>& matches) {
  std::printf("  %-15s %-16s %-16s %-27s %-27s %s\n", "status", "before (A)", "after (B)",
              "position in A (m)", "after, in A (m)", "displacement (m)");
  for (const io::DiffObject* o : matches) {
    const std::string after = o->after ? point_text(o->after->position_in_before) : "-";
    std::string moved = "-";
    if (o->displacement_m) {
      char norm[32];
      std::snprintf(norm, sizeof norm, " %.3f", o->displacement_m->norm());
      moved = point_text(*o->displacement_m) + norm;
    }
    std::printf("  %-15s %-16s %-16s %-27s %-27s %s\n", o->status.c_str(),
                side_text(o->before).c_str(), side_text(o->after).c_str(),
                point_text(o->position_in_before()).c_str(), after.c_str(), moved.c_str());
  }
}

void run_diff_query_command(const QueryOptions& o) {
  const io::DiffFile diff = io::read_diff_json(o.diff);
  const change::DiffQuery q = change::parse_diff_query(o.text, diff);
  const std::vector<const io::DiffObject*> matches = change::run_diff_query(q, diff);
  if (o.json) {
    nlohmann::ordered_json out = {{"query", o.text},
                                  {"diff", diff.source},
                                  {"statuses", q.statuses},
                                  {"class", q.class_name},
                                  {"matches", nlohmann::ordered_json::array()}};
    for (const io::DiffObject* m : matches) out["matches"].push_back(diff_match_json(*m));
    std::printf("%s\n", out.dump(2).c_str());
    return;
  }
  if (matches.empty()) {
    std::printf("no match for \"%s\"\n", o.text.c_str());
    return;
  }
  std::printf("%zu match%s for \"%s\" (positions in the before run's world, A):\n", matches.size(),
              matches.size() == 1 ? "" : "es", o.text.c_str());
  print_diff_matches(matches);
}

void setup_query(CLI::App& app) {
  auto o = std::make_shared<QueryOptions>();
  auto* cmd = app.add_subcommand(
      "query",
      "Ask a fused run for objects: QUERY = CLASS [on|near|above|under CLASS|floor|table|seat|"
      "surface]. Class names as fuse writes them (any COCO spelling; plurals too). Examples:\n"
      "  objmap query --run RUN \"cup on table\"\n"
      "  objmap query --run RUN \"keyboards\"\n"
      "  objmap query --run RUN \"mouse near keyboard\"\n"
      "  objmap query --run RUN \"book on chair\" --json\n"
      "Prints each match with its id, class, position (world frame) and the relation's figures "
      "(gap to the support, distance); exit 0 with \"no match\" and the nearest candidates when "
      "nothing matches; exit 2 naming a word it does not understand.\n"
      "With --diff DIFF (objmap diff's folder or its diff.json): QUERY = STATUS... [CLASS] or "
      "CLASS, STATUS = moved|added|removed|changed class|not seen again|not seen before|"
      "unchanged|changed (the first four together); other words (what, which, is, are, ...) are "
      "ignored. Examples:\n"
      "  objmap query --diff DIFF \"what moved\"\n"
      "  objmap query --diff DIFF \"moved cup\"\n"
      "  objmap query --diff DIFF \"removed chair\" --json\n"
      "Prints each object with its status, ids and classes in both runs, its position in the "
      "before run's world and, moved, its displacement.");
  auto* run = cmd->add_option("--run", o->run, "run folder of objmap fuse (objects.json)");
  cmd->add_option("--diff", o->diff, "folder of objmap diff (diff.json), or the file")
      ->excludes(run);
  cmd->add_option("query", o->text, "the query, e.g. \"cup on table\" (quote it)")->required();
  cmd->add_flag("--json", o->json, "print the result as JSON");
  cmd->callback([o] {
    require(!o->run.empty() || !o->diff.empty(), "query",
            "no input; expected --run RUN (objmap fuse) or --diff DIFF (objmap diff)");
    if (o->diff.empty())
      run_query_command(*o);
    else
      run_diff_query_command(*o);
  });
}

}  // namespace

OBJMAP_COMMAND(70, "query", setup_query);

}  // namespace objmap::app
