#include "objmap/report/topview.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <opencv2/imgproc.hpp>

#include "objmap/core/error.h"

namespace objmap::report {

void TopViewOptions::check() const {
  require(up_axis >= 0 && up_axis <= 2, "TopViewOptions.up_axis", "must be 0, 1 or 2 (x, y, z)");
  require(std::isfinite(pixel_m) && pixel_m > 0, "TopViewOptions.pixel_m", "must be > 0");
  require(max_size_px >= 64 && max_size_px <= 20000, "TopViewOptions.max_size_px",
          "must be in [64, 20000]");
  require(margin_px >= 0 && margin_px <= 1000, "TopViewOptions.margin_px", "must be in [0, 1000]");
  require(clip_percent >= 0 && clip_percent < 50, "TopViewOptions.clip_percent",
          "must be in [0, 50)");
  require(std::isfinite(point_size_m) && point_size_m >= 0, "TopViewOptions.point_size_m",
          "must be >= 0");
  require(fade >= 0 && fade <= 0.9, "TopViewOptions.fade", "must be in [0, 0.9]");
  require(label_scale > 0.1 && label_scale <= 3, "TopViewOptions.label_scale",
          "must be in (0.1, 3]");
}

namespace {

// The two horizontal axes for an up axis, so that the view is right-handed seen from above.
void horizontal_axes(int up, int& a, int& b) {
  a = (up + 1) % 3;
  b = (up + 2) % 3;
}

double percentile(std::vector<float>& v, double p) {
  if (v.empty()) return 0.0;
  const std::size_t k = std::min(v.size() - 1, static_cast<std::size_t>(p / 100.0 * v.size()));
  std::nth_element(v.begin(), v.begin() + k, v.end());
  return v[k];
}

// Where a point of the two horizontal axes falls in the view, in pixels (not rounded).
cv::Point2d to_pixel(const TopView& view, double pa, double pb) {
  return cv::Point2d((pa - view.origin_a) / view.pixel_m, (view.origin_b - pb) / view.pixel_m);
}

// The extent of a view on its two horizontal axes a and b, in metres.
struct Extent {
  double a0 = 0, a1 = 0, b0 = 0, b1 = 0;
};

// Step 1: the extent of the map on the two horizontal axes (stray points clipped), widened so that
// every object and every path is in view.
Extent map_extent(const PointBlocks& blocks, std::size_t points,
                  const std::vector<TopViewObject>& objects, const std::vector<TopViewPath>& paths,
                  const TopViewOptions& options, int a, int b) {
  // One axis at a time, so that the map's coordinates are held once: one float a point.
  std::vector<float> v;
  auto clipped = [&](int axis, double& lo, double& hi) {
    v.clear();
    v.reserve(points);
    blocks([&](const PointCloud& block) {
      for (const Vec3f& p : block.points) v.push_back(p[axis]);
    });
    lo = percentile(v, options.clip_percent);
    hi = percentile(v, 100 - options.clip_percent);
  };
  double a0 = 0, a1 = 0, b0 = 0, b1 = 0;
  clipped(a, a0, a1);
  clipped(b, b0, b1);
  for (const auto& o : objects) {  // objects always in view
    a0 = std::min(a0, o.obb.center[a] - 0.2);
    a1 = std::max(a1, o.obb.center[a] + 0.2);
    b0 = std::min(b0, o.obb.center[b] - 0.2);
    b1 = std::max(b1, o.obb.center[b] + 0.2);
  }
  for (const TopViewPath& path : paths)
    for (const Vec3& p : path.points_in_world) {
      a0 = std::min(a0, p[a] - 0.05);
      a1 = std::max(a1, p[a] + 0.05);
      b0 = std::min(b0, p[b] - 0.05);
      b1 = std::max(b1, p[b] + 0.05);
    }
  if (a1 - a0 < 0.1) a1 = a0 + 0.1;
  if (b1 - b0 < 0.1) b1 = b0 + 0.1;
  return {a0, a1, b0, b1};
}

// A white view of the extent with its margins: the pixel size grows when the extent would
// exceed max_size_px.
TopView blank_view(const Extent& e, const TopViewOptions& options) {
  const double extent = std::max(e.a1 - e.a0, e.b1 - e.b0);
  const double pixel_m = std::max(options.pixel_m, extent / options.max_size_px);
  const int width = static_cast<int>(std::ceil((e.a1 - e.a0) / pixel_m)) + 2 * options.margin_px;
  const int height = static_cast<int>(std::ceil((e.b1 - e.b0) / pixel_m)) + 2 * options.margin_px;
  TopView view;
  view.pixel_m = pixel_m;
  view.origin_a = e.a0 - options.margin_px * pixel_m;
  view.origin_b =
      e.b1 + options.margin_px * pixel_m;  // image rows go toward -b (b up in the image)
  view.image = cv::Mat(height, width, CV_8UC3, cv::Scalar(255, 255, 255));
  return view;
}

// Step 2: z-buffer: the highest point of each pixel; each point a square of point_size_m. Then
// faded towards white, so that boxes, labels and paths stand out.
void draw_points(TopView& view, const PointBlocks& blocks, const TopViewOptions& options, int a,
                 int b, int up) {
  const int width = view.image.cols, height = view.image.rows;
  cv::Mat top(height, width, CV_32F, cv::Scalar(-std::numeric_limits<float>::infinity()));
  const int half =
      std::clamp(static_cast<int>(std::lround(options.point_size_m / view.pixel_m / 2)), 0, 8);
  blocks([&](const PointCloud& cloud) {
    const bool colors = cloud.has_colors();
    for (std::size_t i = 0; i < cloud.size(); ++i) {
      const auto& p = cloud.points[i];
      const cv::Point2d px = to_pixel(view, p[a], p[b]);
      const int u = static_cast<int>(px.x), v = static_cast<int>(px.y);
      if (u + half < 0 || v + half < 0 || u - half >= width || v - half >= height) continue;
      const Rgb c = colors ? cloud.colors[i] : Rgb{90, 90, 90};
      for (int vv = std::max(0, v - half); vv <= std::min(height - 1, v + half); ++vv)
        for (int uu = std::max(0, u - half); uu <= std::min(width - 1, u + half); ++uu) {
          float& z = top.at<float>(vv, uu);
          if (p[up] <= z) continue;
          z = p[up];
          view.image.at<cv::Vec3b>(vv, uu) = cv::Vec3b(c.b, c.g, c.r);
        }
    }
  });
  if (options.fade > 0)
    view.image.convertTo(view.image, CV_8UC3, 1.0 - options.fade, 255.0 * options.fade);
}

// Step 4: the outline of each oriented box seen from above; returns the centres in pixels.
std::vector<cv::Point> draw_object_boxes(TopView& view, const std::vector<TopViewObject>& objects,
                                         int a, int b) {
  std::vector<cv::Point> centers;
  for (const auto& o : objects) {
    std::vector<cv::Point2f> corners;
    for (int i = 0; i < 8; ++i) {
      const Vec3 local((i & 1 ? 1 : -1) * o.obb.half_extent.x(),
                       (i & 2 ? 1 : -1) * o.obb.half_extent.y(),
                       (i & 4 ? 1 : -1) * o.obb.half_extent.z());
      const Vec3 w = o.obb.center + o.obb.rotation * local;
      corners.push_back(to_pixel(view, w[a], w[b]));
    }
    std::vector<cv::Point2f> hull;
    cv::convexHull(corners, hull);
    std::vector<cv::Point> poly(hull.begin(), hull.end());
    const cv::Scalar color(o.color.b, o.color.g, o.color.r);
    cv::polylines(view.image, poly, true, cv::Scalar(0, 0, 0), 4, cv::LINE_AA);
    cv::polylines(view.image, poly, true, color, 2, cv::LINE_AA);
    const cv::Point2d c = to_pixel(view, o.obb.center[a], o.obb.center[b]);
    centers.emplace_back(static_cast<int>(std::lround(c.x)), static_cast<int>(std::lround(c.y)));
  }
  return centers;
}

// The scale bar's white box in the bottom-left corner (step 6), kept free of labels.
cv::Rect scale_bar_box(const TopView& view, const TopViewOptions& options) {
  const int bar = static_cast<int>(1.0 / view.pixel_m);
  const cv::Point s0(options.margin_px / 2 + 4, view.image.rows - 8);
  return cv::Rect(s0.x - 4, s0.y - 22, bar + 8, 28);
}

// Whether `rect` lies inside a width × height image and keeps 2 px from every box of `taken`.
bool free_place(const cv::Rect& rect, const std::vector<cv::Rect>& taken, int width, int height) {
  if (rect.x < 0 || rect.y < 0 || rect.x + rect.width > width || rect.y + rect.height > height)
    return false;
  for (const cv::Rect& q : taken)
    if ((rect & cv::Rect(q.x - 2, q.y - 2, q.width + 4, q.height + 4)).area() > 0) return false;
  return true;
}

// A label box's place: the first free place on rings around the centre c (right of it first, then
// round it, further out ring by ring); an empty rect when there is none within `rings` rings.
cv::Rect place_label(const cv::Point& c, const cv::Size& box, const std::vector<cv::Rect>& taken,
                     int width, int height, int rings) {
  for (int ring = 0; ring <= rings; ++ring) {
    const int r = ring * (box.height + 2);
    const int steps = ring == 0 ? 1 : 8 + 4 * ring;
    for (int s = 0; s < steps; ++s) {
      const double angle = -M_PI / 4 + 2 * M_PI * s / steps;
      const cv::Point p(c.x + 7 + static_cast<int>(std::lround(r * std::cos(angle))),
                        c.y - box.height / 2 + static_cast<int>(std::lround(r * std::sin(angle))));
      const bool left = std::cos(angle) < -0.3;
      const cv::Rect rect(left ? p.x - 14 - box.width : p.x, p.y, box.width, box.height);
      if (free_place(rect, taken, width, height)) return rect;
    }
  }
  return {};
}

// A label's box: the text's size with a 4 px border.
cv::Size label_box(const std::string& text, double font_scale, int* text_height) {
  int baseline = 0;
  const cv::Size size = cv::getTextSize(text, cv::FONT_HERSHEY_SIMPLEX, font_scale, 1, &baseline);
  *text_height = size.height;
  return {size.width + 8, size.height + baseline + 6};
}

void draw_label(TopView& view, const cv::Point& c, const cv::Rect& chosen, const std::string& text,
                const cv::Scalar& color, double font_scale) {
  int text_height = 0;
  label_box(text, font_scale, &text_height);
  const cv::Point near(std::clamp(c.x, chosen.x, chosen.x + chosen.width),
                       std::clamp(c.y, chosen.y, chosen.y + chosen.height));
  if (cv::norm(near - c) > 9) cv::line(view.image, c, near, cv::Scalar(40, 40, 40), 1, cv::LINE_AA);
  cv::rectangle(view.image, chosen, cv::Scalar(255, 255, 255), cv::FILLED);
  cv::rectangle(view.image, chosen, color, 2);
  cv::putText(view.image, text, cv::Point(chosen.x + 4, chosen.y + 3 + text_height),
              cv::FONT_HERSHEY_SIMPLEX, font_scale, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
}

// Step 5: a dot at each centre, then the labels: "id class" at the first free place around its
// centre (no label over another label or another object's dot), with a leader line when moved
// away; when there is none, the id alone, and the label goes to the list beside the map.
void draw_labels(TopView& view, const std::vector<TopViewObject>& objects,
                 const std::vector<cv::Point>& centers, const TopViewOptions& options) {
  std::vector<cv::Rect> dots;
  const cv::Rect bar = scale_bar_box(view, options);
  for (std::size_t k = 0; k < objects.size(); ++k) {
    cv::circle(view.image, centers[k], 4, cv::Scalar(0, 0, 0), -1, cv::LINE_AA);
    cv::circle(view.image, centers[k], 2,
               cv::Scalar(objects[k].color.b, objects[k].color.g, objects[k].color.r), -1,
               cv::LINE_AA);
    dots.emplace_back(centers[k].x - 4, centers[k].y - 4, 9, 9);
  }
  std::vector<cv::Rect> placed;
  for (std::size_t k = 0; k < objects.size(); ++k) {
    const auto& o = objects[k];
    // Free of the placed labels and of every other object's dot.
    std::vector<cv::Rect> taken = placed;
    taken.push_back(bar);
    for (std::size_t d = 0; d < dots.size(); ++d)
      if (d != k) taken.push_back(dots[d]);
    TopViewLabel label{o.id, {}, false};
    std::string text = o.label;
    for (const bool whole : {true, false}) {
      if (!whole) text = std::to_string(o.id);
      int text_height = 0;
      const cv::Size box = label_box(text, options.label_scale, &text_height);
      // The whole label near its object (a short leader line), the id a little further.
      label.box =
          place_label(centers[k], box, taken, view.image.cols, view.image.rows, whole ? 4 : 8);
      label.listed = !whole;
      if (label.box.area() > 0) break;
    }
    if (label.box.area() > 0) {
      placed.push_back(label.box);
      draw_label(view, centers[k], label.box, text, cv::Scalar(o.color.b, o.color.g, o.color.r),
                 options.label_scale);
    }
    view.labels.push_back(label);
  }
}

// Step 7: the labels that did not fit on the map, listed in columns on its right: a swatch in the
// class colour and "id class" per line.
void draw_label_list(TopView& view, const std::vector<TopViewObject>& objects,
                     const TopViewOptions& options) {
  std::vector<std::size_t> listed;
  for (std::size_t k = 0; k < objects.size(); ++k)
    if (view.labels[k].listed) listed.push_back(k);
  if (listed.empty()) return;
  const std::string title = "labels of crowded objects:";
  int text_height = 0, line_w = 0;
  const int title_w = label_box(title, options.label_scale, &text_height).width;
  for (const std::size_t k : listed)
    line_w =
        std::max(line_w, label_box(objects[k].label, options.label_scale, &text_height).width + 16);
  // As many columns as the map's height needs, at most as many as make the list as wide as the
  // map; then the list runs below the map's bottom (the picture grows white below the map).
  const int line_h = text_height + 10, top = options.margin_px + line_h + 4;
  const int n = static_cast<int>(listed.size());
  const int fit_rows = std::max(1, (view.image.rows - top - options.margin_px) / line_h);
  const int columns =
      std::clamp((n + fit_rows - 1) / fit_rows, 1, std::max(1, view.image.cols / (line_w + 12)));
  const int rows = (n + columns - 1) / columns;
  cv::Mat out(std::max(view.image.rows, top + rows * line_h + options.margin_px),
              view.image.cols + std::max(title_w, columns * (line_w + 12)) + options.margin_px,
              CV_8UC3, cv::Scalar(255, 255, 255));
  view.image.copyTo(out(cv::Rect(0, 0, view.image.cols, view.image.rows)));
  const int x0 = view.image.cols + 8;
  cv::putText(out, title, cv::Point(x0, options.margin_px + text_height), cv::FONT_HERSHEY_SIMPLEX,
              options.label_scale, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
  for (std::size_t i = 0; i < listed.size(); ++i) {
    const TopViewObject& o = objects[listed[i]];
    const int x = x0 + static_cast<int>(i / rows) * (line_w + 12);
    const int y = top + static_cast<int>(i % rows) * line_h;
    cv::rectangle(out, cv::Rect(x, y + 2, 10, text_height),
                  cv::Scalar(o.color.b, o.color.g, o.color.r), cv::FILLED);
    cv::putText(out, o.label, cv::Point(x + 16, y + 2 + text_height), cv::FONT_HERSHEY_SIMPLEX,
                options.label_scale, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
  }
  view.image = out;
}

// Step 6: a 1 m scale bar in the bottom-left corner.
void draw_scale_bar(TopView& view, const TopViewOptions& options) {
  const int bar = static_cast<int>(1.0 / view.pixel_m);
  const cv::Point s0(options.margin_px / 2 + 4, view.image.rows - 8);
  cv::rectangle(view.image, scale_bar_box(view, options), cv::Scalar(255, 255, 255), cv::FILLED);
  cv::line(view.image, s0, s0 + cv::Point(bar, 0), cv::Scalar(0, 0, 0), 2);
  cv::putText(view.image, "1 m", s0 + cv::Point(4, -6), cv::FONT_HERSHEY_SIMPLEX, 0.45,
              cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
}

}  // namespace

TopView render_top_view(const PointCloud& cloud, const std::vector<TopViewObject>& objects,
                        const TopViewOptions& options, const std::vector<TopViewPath>& paths) {
  return render_top_view([&](const std::function<void(const PointCloud&)>& take) { take(cloud); },
                         cloud.size(), objects, options, paths);
}

TopView render_top_view(const PointBlocks& blocks, std::size_t points,
                        const std::vector<TopViewObject>& objects, const TopViewOptions& options,
                        const std::vector<TopViewPath>& paths) {
  options.check();
  int a = 0, b = 1;
  horizontal_axes(options.up_axis, a, b);
  const int up = options.up_axis;

  // 1. Extent of the map on the two horizontal axes (stray points clipped), objects and paths in.
  TopView view = blank_view(map_extent(blocks, points, objects, paths, options, a, b), options);
  // 2. Z-buffer: the highest point of each pixel, faded towards white.
  draw_points(view, blocks, options, a, b, up);
  // 3. Paths (the camera), under the objects.
  for (const TopViewPath& path : paths) draw_path(view, path.points_in_world, path.color, up);
  if (options.draw_objects) {
    // 4. Objects: the outline of each oriented box seen from above.
    const std::vector<cv::Point> centers = draw_object_boxes(view, objects, a, b);
    // 5. Labels: a dot at each centre, each label at the first free place around it.
    draw_labels(view, objects, centers, options);
  }
  // 6. A 1 m scale bar in the bottom-left corner.
  draw_scale_bar(view, options);
  view.map_width_px = view.image.cols;
  // 7. The labels that did not fit on the map, listed on its right.
  if (options.draw_objects) draw_label_list(view, objects, options);
  return view;
}

void draw_path(TopView& view, const std::vector<Vec3>& points_in_world, const Rgb& color,
               int up_axis) {
  require(up_axis >= 0 && up_axis <= 2, "draw_path.up_axis", "must be 0, 1 or 2 (x, y, z)");
  require(view.pixel_m > 0 && !view.image.empty(), "draw_path.view", "must be a rendered view");
  int a = 0, b = 1;
  horizontal_axes(up_axis, a, b);
  std::vector<cv::Point> poly;
  for (const Vec3& p : points_in_world) {
    const cv::Point px(static_cast<int>(std::lround((p[a] - view.origin_a) / view.pixel_m)),
                       static_cast<int>(std::lround((view.origin_b - p[b]) / view.pixel_m)));
    if (poly.empty() || px != poly.back()) poly.push_back(px);
  }
  if (poly.empty()) return;
  const cv::Scalar bgr(color.b, color.g, color.r);
  cv::polylines(view.image, poly, false, cv::Scalar(255, 255, 255), 4, cv::LINE_AA);
  cv::polylines(view.image, poly, false, bgr, 2, cv::LINE_AA);
  cv::circle(view.image, poly.front(), 6, cv::Scalar(255, 255, 255), 3, cv::LINE_AA);
  cv::circle(view.image, poly.front(), 6, bgr, 2, cv::LINE_AA);
}

}  // namespace objmap::report
