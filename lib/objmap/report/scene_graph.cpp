#include "objmap/report/scene_graph.h"

#include <algorithm>
#include <cstdio>
#include <map>
#include <vector>

#include "objmap/fusion/palette.h"
#include "objmap/report/svg.h"

namespace objmap::report {
namespace {

constexpr int kNodeW = 120, kNodeH = 26, kGapX = 12, kRowH = 56, kMargin = 16;

struct Node {
  double x = 0, y = 0;  // centre
};

// Depth of an object above its surface: 0 on a surface, 1 + its support's depth on an object
// (cycles and chains longer than 8 stop there).
int depth_of(const io::SceneObject& o, const io::SceneDescription& s, int hops = 0) {
  if (!o.on || o.on->kind != io::SceneRelation::Kind::kObject || hops > 8) return 0;
  const io::SceneObject* below = s.object(o.on->id);
  return below ? 1 + depth_of(*below, s, hops + 1) : 0;
}

// The surface an object's chain of supports ends on; -1 when none.
int base_surface(const io::SceneObject& o, const io::SceneDescription& s, int hops = 0) {
  if (!o.on || hops > 8) return -1;
  if (o.on->kind == io::SceneRelation::Kind::kSurface) return o.on->id;
  const io::SceneObject* below = s.object(o.on->id);
  return below ? base_surface(*below, s, hops + 1) : -1;
}

// A node's box and label; `node` ("object 3", "surface 1") names it for programs (data-node).
std::string rect(const Node& n, const std::string& node, const std::string& fill,
                 const std::string& label) {
  char buf[512];
  std::snprintf(buf, sizeof buf,
                "<rect data-node=\"%s\" x=\"%.1f\" y=\"%.1f\" width=\"%d\" height=\"%d\" rx=\"5\" "
                "fill=\"%s\" stroke=\"#333\"/><text x=\"%.1f\" y=\"%.1f\" font-size=\"11\" "
                "text-anchor=\"middle\" font-family=\"sans-serif\">",
                node.c_str(), n.x - kNodeW / 2.0, n.y - kNodeH / 2.0, kNodeW, kNodeH, fill.c_str(),
                n.x, n.y + 4);
  return buf + xml_escape(label) + "</text>\n";
}

std::string colour(const std::string& class_name) {
  const Rgb c = fusion::class_color(class_name);
  char buf[16];
  std::snprintf(buf, sizeof buf, "#%02x%02x%02x", c.r, c.g, c.b);
  return buf;
}

}  // namespace

std::string scene_graph_svg(const io::SceneDescription& s) {
  if (s.objects.empty()) return "";
  // Columns: one per surface (floor first, then by height), then one for unsupported objects.
  std::vector<const io::SceneSurface*> surfaces;
  for (const auto& f : s.surfaces) surfaces.push_back(&f);
  std::stable_sort(surfaces.begin(), surfaces.end(), [](const auto* a, const auto* b) {
    return (a->label == "floor") != (b->label == "floor") ? a->label == "floor"
                                                          : a->height_m < b->height_m;
  });
  std::map<int, int> column_of_surface;
  for (std::size_t i = 0; i < surfaces.size(); ++i)
    column_of_surface[surfaces[i]->id] = static_cast<int>(i);
  const int free_column = static_cast<int>(surfaces.size());
  // Objects per (column, depth), in id order.
  std::map<std::pair<int, int>, std::vector<const io::SceneObject*>> cells;
  int max_depth = 0;
  for (const auto& o : s.objects) {
    const int base = base_surface(o, s);
    const int column =
        base >= 0 && column_of_surface.count(base) ? column_of_surface[base] : free_column;
    const int depth = depth_of(o, s);
    max_depth = std::max(max_depth, depth);
    cells[{column, depth}].push_back(&o);
  }
  std::vector<int> width(free_column + 1, 1);
  for (const auto& [key, list] : cells)
    width[key.first] = std::max(width[key.first], static_cast<int>(list.size()));
  std::vector<double> left(free_column + 2, kMargin);
  for (int c = 0; c <= free_column; ++c)
    left[c + 1] = left[c] + width[c] * (kNodeW + kGapX) + 2 * kGapX;
  const double height = kMargin * 2 + (max_depth + 2) * kRowH;
  const auto row_y = [&](int row) { return height - kMargin - kNodeH / 2.0 - row * kRowH; };
  std::map<int, Node> object_node, surface_node;
  for (const auto& [key, list] : cells)
    for (std::size_t i = 0; i < list.size(); ++i)
      object_node[list[i]->id] = {left[key.first] + kNodeW / 2.0 + i * (kNodeW + kGapX),
                                  row_y(key.second + 1)};
  for (std::size_t c = 0; c < surfaces.size(); ++c)
    surface_node[surfaces[c]->id] = {left[c] + kNodeW / 2.0, row_y(0)};
  std::string body;
  for (const auto& o : s.objects) {  // edges first, under the boxes
    if (!o.on) continue;
    const auto& to = o.on->kind == io::SceneRelation::Kind::kSurface ? surface_node : object_node;
    if (!to.count(o.on->id)) continue;
    const Node a = object_node[o.id], b = to.at(o.on->id);
    char buf[320];
    std::snprintf(buf, sizeof buf,
                  "<line data-edge=\"on object %d %s %d\" x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" "
                  "y2=\"%.1f\" stroke=\"#777\" stroke-width=\"1.5\"/>\n",
                  o.id, o.on->kind == io::SceneRelation::Kind::kSurface ? "surface" : "object",
                  o.on->id, a.x, a.y + kNodeH / 2.0, b.x, b.y - kNodeH / 2.0);
    body += buf;
  }
  for (const auto* f : surfaces) {
    char label[128];
    std::snprintf(label, sizeof label, "S%d %s %.2f m", f->id, f->label.c_str(), f->height_m);
    body += rect(surface_node[f->id], "surface " + std::to_string(f->id), "#e8e2d0", label);
  }
  for (const auto& o : s.objects)
    body += rect(object_node[o.id], "object " + std::to_string(o.id), colour(o.class_name),
                 std::to_string(o.id) + " " + o.class_name);
  char head[256];
  std::snprintf(head, sizeof head,
                "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"%.0f\" height=\"%.0f\" "
                "viewBox=\"0 0 %.0f %.0f\">\n",
                left[free_column + 1] + kMargin, height, left[free_column + 1] + kMargin, height);
  return head + body + "</svg>\n";
}

}  // namespace objmap::report
