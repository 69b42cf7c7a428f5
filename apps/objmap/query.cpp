// objmap query: "cup on table" asked of a fused run (docs/scene.md, "Queries").
#include <cstdio>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>

#include "command.h"
#include "objmap/io/scene_json.h"
#include "objmap/scene/query.h"

namespace objmap::app {
namespace {

struct QueryOptions {
  std::string run;
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
      "nothing matches; exit 2 naming a word it does not understand.");
  cmd->add_option("--run", o->run, "run folder of objmap fuse (objects.json)")->required();
  cmd->add_option("query", o->text, "the query, e.g. \"cup on table\" (quote it)")->required();
  cmd->add_flag("--json", o->json, "print the result as JSON");
  cmd->callback([o] { run_query_command(*o); });
}

}  // namespace

OBJMAP_COMMAND(70, "query", setup_query);

}  // namespace objmap::app
