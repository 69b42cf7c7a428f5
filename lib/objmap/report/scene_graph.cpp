#include "objmap/report/scene_graph.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <vector>

#include "objmap/core/error.h"
#include "objmap/core/format.h"
#include "objmap/fusion/palette.h"
#include "objmap/report/html.h"
#include "objmap/report/svg.h"

namespace objmap::report {

void SceneGraphOptions::check() const {
  require(std::isfinite(width_px) && width_px >= 320 && width_px <= 20000,
          "SceneGraphOptions.width_px", "must be in [320, 20000]");
}

std::optional<double> floor_height_m(const io::SceneDescription& scene) {
  const io::SceneSurface* floor = nullptr;
  for (const io::SceneSurface& s : scene.surfaces)
    if (s.label == "floor" && (!floor || s.area_m2 > floor->area_m2 ||
                               (s.area_m2 == floor->area_m2 && s.height_m < floor->height_m)))
      floor = &s;
  if (!floor) return std::nullopt;
  return floor->height_m;
}

std::string height_text(const io::SceneSurface& surface, const std::optional<double>& floor_m) {
  if (!floor_m) return "no floor found";
  std::string h = fixed_text(surface.height_m - *floor_m, 2);
  if (h == "-0.00") h = "0.00";
  return h + " m above the floor";
}

namespace {

// The scene as a tree: per surface (in reading order) the objects standing on it; under each
// object the objects standing on it.
struct Group {
  const io::SceneSurface* surface = nullptr;  // nullptr: the objects on no listed surface
  std::vector<int> roots;                     // object indices
};
struct SceneTree {
  std::vector<Group> groups;                   // surfaces with objects, then "on no surface"
  std::vector<const io::SceneSurface*> empty;  // surfaces with nothing on them
  std::map<int, std::vector<int>> children;    // object index -> indices of the objects on it
};

// Floor pieces first, then by height (the order of the file among equals).
std::vector<const io::SceneSurface*> reading_order(const io::SceneDescription& s) {
  std::vector<const io::SceneSurface*> surfaces;
  for (const auto& f : s.surfaces) surfaces.push_back(&f);
  std::stable_sort(surfaces.begin(), surfaces.end(), [](const auto* a, const auto* b) {
    return (a->label == "floor") != (b->label == "floor") ? a->label == "floor"
                                                          : a->height_m < b->height_m;
  });
  return surfaces;
}

// Places `i` and, under it, everything on it that is not placed yet: the tree has each object
// once (a cycle in the file is cut where it closes).
void place(int i, const std::map<int, std::vector<int>>& on_object, SceneTree& tree,
           std::set<int>& placed) {
  placed.insert(i);
  const auto it = on_object.find(i);
  if (it == on_object.end()) return;
  for (const int c : it->second)
    if (!placed.count(c)) {
      tree.children[i].push_back(c);
      place(c, on_object, tree, placed);
    }
}

SceneTree build_tree(const io::SceneDescription& s) {
  SceneTree tree;
  std::map<int, int> index_of;  // object id -> index
  for (std::size_t i = 0; i < s.objects.size(); ++i)
    index_of[s.objects[i].id] = static_cast<int>(i);
  std::map<int, std::vector<int>> on_surface, on_object;
  std::vector<int> on_nothing;
  for (std::size_t i = 0; i < s.objects.size(); ++i) {
    const auto& on = s.objects[i].on;
    const int me = static_cast<int>(i);
    if (on && on->kind == io::SceneRelation::Kind::kObject && index_of.count(on->id) &&
        index_of[on->id] != me)
      on_object[index_of[on->id]].push_back(me);
    else if (on && on->kind == io::SceneRelation::Kind::kSurface && s.surface(on->id))
      on_surface[on->id].push_back(me);
    else
      on_nothing.push_back(me);
  }
  std::set<int> placed;
  for (const io::SceneSurface* f : reading_order(s)) {
    if (!on_surface.count(f->id)) {
      tree.empty.push_back(f);
      continue;
    }
    tree.groups.push_back({f, on_surface[f->id]});
    for (const int i : on_surface[f->id]) place(i, on_object, tree, placed);
  }
  for (const int i : on_nothing) place(i, on_object, tree, placed);
  for (std::size_t i = 0; i < s.objects.size(); ++i)  // a cycle of objects on each other
    if (!placed.count(static_cast<int>(i))) {
      on_nothing.push_back(static_cast<int>(i));
      place(static_cast<int>(i), on_object, tree, placed);
    }
  if (!on_nothing.empty()) tree.groups.push_back({nullptr, on_nothing});
  return tree;
}

std::string surface_title(const io::SceneSurface& f, const std::optional<double>& floor_m) {
  std::string t = "S" + std::to_string(f.id) + " " + f.label + ", " + height_text(f, floor_m);
  if (f.area_m2 > 0) t += ", " + fixed_text(f.area_m2, f.area_m2 < 1 ? 2 : 1) + " m²";
  return t;
}

std::string object_label(const io::SceneObject& o) {
  return std::to_string(o.id) + " " + o.class_name;
}

std::string edge_name(const io::SceneObject& o) {
  return "on object " + std::to_string(o.id) +
         (o.on->kind == io::SceneRelation::Kind::kSurface ? " surface " : " object ") +
         std::to_string(o.on->id);
}

// ---- layout -------------------------------------------------------------------------------

constexpr double kMargin = 8, kPad = 10, kGap = 12, kChipH = 22, kRowGap = 6, kIndent = 22,
                 kTitleH = 26, kCharW = 6.8;

double text_width(const std::string& text, double char_w = kCharW) {
  std::size_t glyphs = 0;  // UTF-8: count the first byte of each character only
  for (const char c : text) glyphs += (static_cast<unsigned char>(c) & 0xC0) != 0x80;
  return static_cast<double>(glyphs) * char_w;
}

// The text cut to `max_w` (an ellipsis at the end) at whole UTF-8 characters.
std::string fit(const std::string& text, double max_w, double char_w = kCharW) {
  if (text_width(text, char_w) <= max_w) return text;
  const auto keep = static_cast<std::size_t>(std::max(1.0, std::floor(max_w / char_w) - 1));
  std::string out;
  std::size_t glyphs = 0;
  for (const char c : text) {
    const bool starts = (static_cast<unsigned char>(c) & 0xC0) != 0x80;
    if (starts && ++glyphs > keep) break;
    out += c;
  }
  return out + "…";
}

struct Chip {
  int object = -1;  // object index; -1: a surface chip (the card of empty ones)
  const io::SceneSurface* surface = nullptr;
  std::string label;
  double x = 0, y = 0, w = 0;  // in the card
  int parent_chip = -1;        // the chip of what it stands on (an object), for the connector
};

struct Card {
  std::string title;
  const io::SceneSurface* surface = nullptr;  // its title is the surface's node
  std::vector<Chip> chips;
  double w = 0, h = 0, x = 0, y = 0;
};

// Lays out the chips of a card row by row, at most `inner_w` wide: an object with others on it
// gets a row of its own and they follow one level indented; the others flow along rows.
struct CardLayout {
  const io::SceneDescription& scene;
  const SceneTree& tree;
  double inner_w;
  Card& card;
  double y = kTitleH + kRowGap;  // top of the next row
  double x = 0;                  // in the current row; 0: the row is empty

  void new_row() {
    if (x > 0) y += kChipH + kRowGap;
    x = 0;
  }
  int add(int object, int depth, int parent_chip) {
    Chip c;
    c.object = object;
    const double left = kPad + std::min(depth, 10) * kIndent;
    c.label = fit(object_label(scene.objects[object]), kPad + inner_w - left - 14);
    c.w = text_width(c.label) + 14;
    if (x > 0 && left + x + c.w > kPad + inner_w) new_row();
    c.x = left + x, c.y = y, c.parent_chip = parent_chip;
    x += c.w + kGap;
    card.chips.push_back(c);
    return static_cast<int>(card.chips.size()) - 1;
  }
  void siblings(const std::vector<int>& objects, int depth, int parent_chip) {
    std::vector<int> leaves;
    for (const int i : objects) {
      const auto it = tree.children.find(i);
      if (it == tree.children.end()) {
        leaves.push_back(i);
        continue;
      }
      new_row();
      const int chip = add(i, depth, parent_chip);
      new_row();
      siblings(it->second, depth + 1, chip);
      new_row();
    }
    if (!leaves.empty()) new_row();
    for (const int i : leaves) add(i, depth, parent_chip);
  }
  void finish() {
    new_row();
    double right = kPad + text_width(card.title, kCharW * 1.05);
    for (const Chip& c : card.chips) right = std::max(right, c.x + c.w);
    card.w = right + kPad;
    card.h = y + kPad - kRowGap;
  }
};

std::vector<Card> make_cards(const io::SceneDescription& s, const SceneTree& tree, double inner_w) {
  const std::optional<double> floor_m = floor_height_m(s);
  std::vector<Card> cards;
  for (const Group& g : tree.groups) {
    Card card;
    card.surface = g.surface;
    card.title = fit(g.surface ? surface_title(*g.surface, floor_m) : "on no surface", inner_w,
                     kCharW * 1.05);
    CardLayout layout{s, tree, inner_w, card};
    layout.siblings(g.roots, 0, -1);
    layout.finish();
    cards.push_back(std::move(card));
  }
  if (!tree.empty.empty()) {
    Card card;
    card.title = "surfaces with nothing on them";
    CardLayout layout{s, tree, inner_w, card};
    layout.new_row();
    for (const io::SceneSurface* f : tree.empty) {
      Chip c;
      c.surface = f;
      c.label = fit("S" + std::to_string(f->id) + " " + f->label + ", " +
                        (floor_m ? fixed_text(f->height_m - *floor_m, 2) + " m" : "no floor"),
                    inner_w - 14);
      c.w = text_width(c.label) + 14;
      if (layout.x > 0 && kPad + layout.x + c.w > kPad + inner_w) layout.new_row();
      c.x = kPad + layout.x, c.y = layout.y;
      layout.x += c.w + kGap;
      card.chips.push_back(c);
    }
    layout.finish();
    cards.push_back(std::move(card));
  }
  return cards;
}

// Cards left to right, a new shelf when the next does not fit; returns the total height.
double pack(std::vector<Card>& cards, double width) {
  double x = kMargin, y = kMargin, shelf_h = 0;
  for (Card& c : cards) {
    if (x > kMargin && x + c.w > width - kMargin) {
      x = kMargin;
      y += shelf_h + kGap;
      shelf_h = 0;
    }
    c.x = x, c.y = y;
    x += c.w + kGap;
    shelf_h = std::max(shelf_h, c.h);
  }
  return y + shelf_h + kMargin;
}

std::string light(const Rgb& c) {  // the class colour 70% towards white
  const auto mix = [](std::uint8_t v) {
    return static_cast<std::uint8_t>(std::lround(v + 0.7 * (255 - v)));
  };
  return hex_color(Rgb{mix(c.r), mix(c.g), mix(c.b)});
}

void draw_card(Svg& svg, const io::SceneDescription& s, const Card& card) {
  svg.rect(card.x, card.y, card.w, card.h,
           {{"rx", "6"}, {"fill", "#faf8f2"}, {"stroke", "#b9b2a0"}});
  if (card.surface)
    svg.open_group({{"data-node", "surface " + std::to_string(card.surface->id)}});
  else
    svg.open_group({});
  svg.rect(card.x, card.y, card.w, kTitleH, {{"rx", "6"}, {"fill", "#e8e2d0"}});
  svg.text(card.x + kPad, card.y + 17, card.title, {{"font-weight", "600"}, {"fill", "#333"}});
  svg.close_group();
  // The connectors first, under the boxes: down from what an object stands on, then along the
  // row of the objects on it.
  for (const Chip& c : card.chips) {
    if (c.parent_chip < 0) continue;
    const Chip& p = card.chips[c.parent_chip];
    const double px = card.x + p.x + 8, y = card.y + c.y + kChipH / 2;
    svg.polyline({{px, card.y + p.y + kChipH}, {px, y}, {card.x + c.x, y}},
                 {{"stroke", "#777"}, {"stroke-width", "1.5"}});
  }
  for (const Chip& c : card.chips) {
    const double x = card.x + c.x, y = card.y + c.y;
    if (c.surface) {
      svg.open_group({{"data-node", "surface " + std::to_string(c.surface->id)}});
      svg.rect(x, y, c.w, kChipH, {{"rx", "4"}, {"fill", "#e8e2d0"}, {"stroke", "#8a8270"}});
    } else {
      const io::SceneObject& o = s.objects[c.object];
      SvgAttributes group = {{"data-node", "object " + std::to_string(o.id)}};
      if (o.on) group.push_back({"data-edge", edge_name(o)});
      svg.open_group(group);
      const Rgb colour = fusion::class_color(o.class_name);
      svg.rect(x, y, c.w, kChipH,
               {{"rx", "4"},
                {"fill", light(colour)},
                {"stroke", hex_color(colour)},
                {"stroke-width", "1.5"}});
    }
    svg.text(x + 7, y + 15, c.label, {{"font-size", "11"}, {"fill", "#222"}});
    svg.close_group();
  }
}

void markdown_objects(const io::SceneDescription& s, const SceneTree& tree,
                      const std::vector<int>& objects, int depth, std::string& out) {
  for (const int i : objects) {
    out +=
        std::string(2 * (depth + 1), ' ') + "- " + markdown_text(object_label(s.objects[i])) + "\n";
    const auto it = tree.children.find(i);
    if (it != tree.children.end()) markdown_objects(s, tree, it->second, depth + 1, out);
  }
}

}  // namespace

std::string scene_graph_svg(const io::SceneDescription& s, const SceneGraphOptions& options) {
  options.check();
  if (s.objects.empty()) return "";
  const SceneTree tree = build_tree(s);
  std::vector<Card> cards = make_cards(s, tree, options.width_px - 2 * kMargin - 2 * kPad);
  double width = 0;
  const double height = pack(cards, options.width_px);
  for (const Card& c : cards) width = std::max(width, c.x + c.w + kMargin);
  Svg svg(std::ceil(width), std::ceil(height));
  for (const Card& c : cards) draw_card(svg, s, c);
  return svg.str();
}

std::string scene_graph_markdown(const io::SceneDescription& s) {
  if (s.objects.empty()) return "";
  const SceneTree tree = build_tree(s);
  const std::optional<double> floor_m = floor_height_m(s);
  std::string out;
  for (const Group& g : tree.groups) {
    out += "- " +
           (g.surface ? markdown_text(surface_title(*g.surface, floor_m)) : "on no surface") + "\n";
    markdown_objects(s, tree, g.roots, 0, out);
  }
  if (!tree.empty.empty()) {
    out += "- surfaces with nothing on them\n";
    for (const io::SceneSurface* f : tree.empty)
      out += "  - " + markdown_text(surface_title(*f, floor_m)) + "\n";
  }
  return out + "\n";
}

}  // namespace objmap::report
