#include "objmap/report/view3d.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <nlohmann/json.hpp>

#include "objmap/core/error.h"
#include "objmap/report/html.h"
#include "objmap/report/svg.h"

namespace objmap::report {

namespace {

using nlohmann::json;

double mm(double metres) { return std::round(metres * 1000.0) / 1000.0; }

json vec_json(const Vec3& v) { return json::array({mm(v.x()), mm(v.y()), mm(v.z())}); }

// Points as base64 of little-endian uint16 triples on a grid of `step_m` from `origin` (6 bytes a
// point instead of 12; the step is below 0.2 mm for a 10 m room).
json points_json(const std::vector<Vec3f>& points) {
  json block = {{"count", points.size()}};
  if (points.empty()) return block;
  Vec3f lo = Vec3f::Constant(std::numeric_limits<float>::max()), hi = -lo;
  for (const Vec3f& p : points) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  const double step = std::max(1e-6, static_cast<double>((hi - lo).maxCoeff()) / 65535.0);
  std::string bytes;
  bytes.reserve(points.size() * 6);
  for (const Vec3f& p : points)
    for (int k = 0; k < 3; ++k) {
      const long q = std::lround((p[k] - lo[k]) / step);
      const auto v = static_cast<std::uint16_t>(std::clamp(q, 0L, 65535L));
      bytes += static_cast<char>(v & 0xff);
      bytes += static_cast<char>(v >> 8);
    }
  block["origin"] = json::array({lo.x(), lo.y(), lo.z()});
  block["step_m"] = step;
  block["xyz"] = base64_encode(bytes);
  return block;
}

std::vector<Vec3f> every_kth(const std::vector<Vec3f>& points, std::size_t max_points) {
  if (points.size() <= max_points || max_points == 0) return points;
  const std::size_t k = (points.size() + max_points - 1) / max_points;
  std::vector<Vec3f> out;
  for (std::size_t i = 0; i < points.size(); i += k) out.push_back(points[i]);
  return out;
}

json map_json(const PointCloud& map, std::size_t total, double point_size_m,
              const View3dOptions& options) {
  const PointCloud thin = thin_points(map, options.max_map_points);
  json block = points_json(thin.points);
  std::string rgb;
  rgb.reserve(thin.size() * 3);
  for (std::size_t i = 0; i < thin.size(); ++i) {
    const Rgb col = thin.has_colors() ? thin.colors[i] : Rgb{128, 128, 128};
    rgb += static_cast<char>(col.r);
    rgb += static_cast<char>(col.g);
    rgb += static_cast<char>(col.b);
  }
  block["rgb"] = base64_encode(rgb);
  block["of"] = std::max(total, map.size());
  block["point_size_m"] = point_size_m;
  return block;
}

json object_json(const View3dObject& o, const View3dOptions& options) {
  json rotation = json::array();
  for (int r = 0; r < 3; ++r)
    for (int k = 0; k < 3; ++k) rotation.push_back(std::round(o.obb.rotation(r, k) * 1e6) / 1e6);
  json j = {{"id", o.id},
            {"class", o.class_name},
            {"color", hex_color(o.color)},
            {"center", vec_json(o.obb.center)},
            {"rotation", rotation},
            {"half_extent", vec_json(o.obb.half_extent)},
            {"observations", o.observations},
            {"views", o.views},
            {"score", std::round(o.score * 1000.0) / 1000.0},
            {"points", points_json(every_kth(o.points, options.max_object_points))},
            {"relations", o.relations}};
  if (!o.label.empty()) j["label"] = o.label;
  j["points"]["of"] = o.points.size();
  if (!o.mesh_triangles.empty()) {
    json mesh = points_json(o.mesh_vertices);
    mesh["triangles"] = o.mesh_triangles;
    j["mesh"] = mesh;
  }
  return j;
}

// JSON text made safe inside <script>: outside strings JSON has no '<', '>' or '&', and inside
// them the \u escapes read as the same characters.
std::string script_safe(const std::string& text) {
  const std::string_view special = "<>&", codes = "3c3e26";  // \u003c \u003e \u0026
  std::string out;
  out.reserve(text.size());
  for (const char ch : text) {
    const std::size_t k = special.find(ch);
    if (k == std::string_view::npos) {
      out += ch;
    } else {
      out += "\\u00";
      out += codes.substr(2 * k, 2);
    }
  }
  return out;
}

const char* kStyle = R"(
#view3d { position: relative; height: 640px; border: 1px solid #ccc; background: #f4f5f7;
          overflow: hidden; user-select: none; }
#view3d canvas { display: block; width: 100%; height: 100%; }
#view3d .toolbar { position: absolute; left: 8px; top: 8px; right: 8px; display: flex;
                   flex-wrap: wrap; gap: 4px 12px; align-items: center; font-size: 13px;
                   background: #ffffffd8; padding: 4px 8px; border-radius: 4px; }
#view3d .toolbar input[type=search] { width: 200px; }
#view3d .search-result { color: #444; }
#view3d .labels { position: absolute; left: 0; top: 0; width: 100%; height: 100%;
                  pointer-events: none; overflow: hidden; }
#view3d .label { position: absolute; transform: translate(-50%, -100%); font-size: 12px;
                 padding: 0 4px; border-radius: 3px; background: #ffffffe0; border: 1px solid;
                 white-space: nowrap; cursor: pointer; pointer-events: auto; }
#view3d .label.dim { opacity: 0.3; }
#view3d .label.hit { font-weight: 700; box-shadow: 0 0 0 2px #ffd400; }
#view3d .panel { position: absolute; right: 8px; top: 48px; width: 260px; max-height: 560px;
                 overflow: auto; background: #fff; border: 1px solid #bbb; border-radius: 4px;
                 padding: 8px 10px; font-size: 13px; display: none; }
#view3d .panel.open { display: block; }
#view3d .panel h3 { margin: 0 0 4px; font-size: 15px; }
#view3d .panel img { width: 120px; height: 120px; float: right; margin: 0 0 4px 6px; }
#view3d .panel ul { padding-left: 16px; margin: 4px 0; }
p.view3d-caption { font-size: 13px; color: #555; margin: 4px 0 0; }
#view3d .help { position: absolute; left: 8px; bottom: 6px; font-size: 12px; color: #555; }
)";

}  // namespace

void View3dOptions::check() const {
  require(max_map_points >= 1000, "max_map_points",
          std::to_string(max_map_points) + "; expected at least 1000");
  require(max_object_points >= 10, "max_object_points",
          std::to_string(max_object_points) + "; expected at least 10");
}

PointCloud thin_points(const PointCloud& cloud, std::size_t max_points) {
  if (cloud.size() <= max_points || max_points == 0) return cloud;
  return thin_points([&](const std::function<void(const PointCloud&)>& take) { take(cloud); },
                     cloud.size(), max_points);
}

PointCloud thin_points(const PointBlocks& blocks, std::size_t points, std::size_t max_points) {
  const std::size_t k =
      points <= max_points || max_points == 0 ? 1 : (points + max_points - 1) / max_points;
  PointCloud out;
  out.reserve(points / k + 1);
  std::size_t i = 0;  // the map's index of the block's first point
  blocks([&](const PointCloud& block) {
    for (std::size_t j = (k - i % k) % k; j < block.size(); j += k) {
      if (block.has_colors())
        out.push_back(block.points[j], block.colors[j]);
      else
        out.push_back(block.points[j]);
    }
    i += block.size();
  });
  return out;
}

std::string view3d_json(const View3dContent& c, const View3dOptions& options) {
  options.check();
  json doc;
  doc["map"] = map_json(c.map, c.map_points_total, c.map_point_size_m, options);
  if (!c.second_map.empty())
    doc["second_map"] =
        map_json(c.second_map, c.second_map_points_total, c.map_point_size_m, options);
  if (!c.arrows.empty()) {
    doc["arrows"] = json::array();
    for (const View3dArrow& a : c.arrows)
      doc["arrows"].push_back({{"from", vec_json(a.from)},
                               {"to", vec_json(a.to)},
                               {"color", hex_color(a.color)},
                               {"label", a.label}});
  }
  doc["objects"] = json::array();
  for (const View3dObject& o : c.objects) doc["objects"].push_back(object_json(o, options));
  doc["surfaces"] = json::array();
  for (const View3dSurface& s : c.surfaces) {
    json outline = json::array();
    for (const Vec3& p : s.outline) outline.push_back(vec_json(p));
    json j = {{"id", s.id}, {"label", s.label}, {"outline", outline}};
    j["above_floor_m"] = s.above_floor_m ? json(mm(*s.above_floor_m)) : json(nullptr);
    doc["surfaces"].push_back(j);
  }
  doc["path"] = json::array();
  for (const Vec3& p : c.camera_path) doc["path"].push_back(vec_json(p));
  doc["queries"] = c.queries;
  doc["known_classes"] = c.known_classes;
  doc["class_aliases"] = c.class_aliases;
  return script_safe(doc.dump());
}

std::string view3d_html(const View3dContent& c, const View3dOptions& options) {
  std::string h = "<style>" + std::string(kStyle) + "</style>\n";
  h += "<div id=\"view3d\">\n<canvas></canvas>\n<div class=\"labels\"></div>\n";
  h += "<div class=\"toolbar\">\n";
  std::vector<std::string> layers = {"map"};
  if (!c.second_map.empty()) layers.push_back("second_map");
  for (const char* layer : {"objects", "boxes", "labels", "surfaces", "path"})
    layers.push_back(layer);
  if (!c.arrows.empty()) layers.push_back("arrows");
  for (const std::string& layer : layers)
    h += "<label><input type=\"checkbox\" data-layer=\"" + layer + "\" checked=\"checked\"/> " +
         (layer == "second_map" ? std::string("after map") : layer) + "</label>\n";
  h += "<input type=\"search\" placeholder=\"cup on table\" aria-label=\"search objects\"/>\n";
  h += "<span class=\"search-result\"></span>\n</div>\n";
  h += "<div class=\"panel\"></div>\n";
  h += "<div class=\"help\">drag: orbit · right-drag or shift-drag: pan · wheel: zoom · click an "
       "object or its label: details</div>\n</div>\n";
  const std::size_t drawn = std::min(c.map.size(), options.max_map_points);
  const std::size_t total = std::max(c.map_points_total, c.map.size());
  const std::string caption =
      !c.caption.empty()
          ? c.caption
          : "The run in its gravity frame (z up): the semantic map (" + std::to_string(drawn) +
                " of its " + std::to_string(total) +
                " points), each object's points in its class colour with its oriented box and "
                "label (where labels crowd, the nearest; zoom in for the others), the support "
                "surfaces (floor grey, tables brown, other surfaces violet) and the camera path "
                "in magenta. The search takes objmap query's phrases: CLASS "
                "[on|near|above|under CLASS|floor|table|seat|surface].";
  h += "<p class=\"view3d-caption\">" + xml_escape(caption) + "</p>\n";
  h += "<script type=\"application/json\" id=\"view3d-data\">" + view3d_json(c, options) +
       "</script>\n";
  // three.js (MIT, lib/objmap/report/three/LICENSE; its licence header is kept in the text) and the
  // viewer, one classic script so that it runs from file://.
  h += "<script>\n\"use strict\";\n" + std::string(three_js()) + "\n" + std::string(view3d_js()) +
       "\n</script>\n";
  return h;
}

}  // namespace objmap::report
