#pragma once
#include <cstddef>
#include <functional>
#include <opencv2/core/mat.hpp>
#include <string>
#include <vector>

#include "objmap/core/types.h"

// An orthographic top view of a map (e.g. map_semantic.ply) with the objects drawn on it: what a
// person looks at first to judge an object map.
namespace objmap::report {

struct TopViewOptions {
  int up_axis = 2;         // the world axis that points up (TUM and objmap synth: z = 2)
  double pixel_m = 0.005;  // metres per pixel (5 mm), made coarser when the map is larger than...
  int max_size_px = 1600;  // ... this many pixels on its longer side
  int margin_px = 24;      // blank border around the map
  double clip_percent = 0.5;  // the extent ignores this % of points on each side (stray points)
  bool draw_objects = true;   // object footprints (OBB seen from above) with "id class" labels
  double point_size_m = 0.0;  // side of the square drawn per point (0: one pixel); the map's voxel
                              // size fills the gaps between points
  double fade = 0.0;          // the map blended this much towards white (0..0.9), so that boxes
                              // and labels stand out
  double label_scale = 0.5;   // label font scale (OpenCV Hershey simplex)
  void check() const;         // throws InputError naming the bad field
};

struct TopViewObject {
  int id = -1;
  std::string label;  // e.g. "7 cup"
  Obb obb;
  Rgb color;
};

// A path to draw, e.g. the camera positions of the run's trajectory (in the map's frame).
struct TopViewPath {
  std::vector<Vec3> points_in_world;
  Rgb color{20, 20, 20};
};

// Where an object's label went: each label is placed where it overlaps no other label and no
// other object's centre dot; when "id class" finds no such place near its object, the id alone is
// tried, and the label is listed beside the map (a column on the right) instead.
struct TopViewLabel {
  int id = -1;
  cv::Rect box;         // on the map, in pixels; empty: no room even for the id
  bool listed = false;  // the whole label is in the list beside the map (the map shows the id)
};

struct TopView {
  cv::Mat image;  // CV_8UC3 BGR: the map, and the list of labels on its right when there is one
  double pixel_m = 0.0;
  // World coordinates (the two horizontal axes) of the image's top-left pixel centre.
  double origin_a = 0.0, origin_b = 0.0;
  int map_width_px = 0;              // the map's columns (the list, if any, is to their right)
  std::vector<TopViewLabel> labels;  // one per object, in the objects' order
};

// Each pixel shows the highest point above it (z-buffer along up_axis); empty pixels are white.
// The view covers the map (clip_percent aside), every object and every path; paths are drawn over
// the points and under the objects.
TopView render_top_view(const PointCloud& cloud, const std::vector<TopViewObject>& objects,
                        const TopViewOptions& options = {},
                        const std::vector<TopViewPath>& paths = {});

// A map handed over a block of points at a time: each call hands every block (points, with their
// colours or none) to `take`, in the same order every time (io::read_ply_blocks of a file).
using PointBlocks = std::function<void(const std::function<void(const PointCloud&)>& take)>;

// The same view of a map of `points` points read from `blocks` three times (each horizontal axis
// for the extent, then the drawing), holding one float a point instead of the map.
TopView render_top_view(const PointBlocks& blocks, std::size_t points,
                        const std::vector<TopViewObject>& objects,
                        const TopViewOptions& options = {},
                        const std::vector<TopViewPath>& paths = {});

// Draws a path of world points (e.g. the camera positions of the run's trajectory, in the map's
// frame) on the view: a line with a dark casing and a ring at its first point.
void draw_path(TopView& view, const std::vector<Vec3>& points_in_world, const Rgb& color,
               int up_axis = 2);

}  // namespace objmap::report
