#pragma once
#include <opencv2/core/mat.hpp>
#include <string>

#include "objmap/core/mesh.h"
#include "objmap/core/types.h"

// A small picture of one object (RUN/objects/<id>_<class>.ply): its points seen orthographically
// from a fixed oblique view, nearest point per pixel, with a label.
namespace objmap::report {

struct ThumbnailOptions {
  int size_px = 160;              // square image side
  int up_axis = 2;                // the world axis that points up (TUM and objmap synth: z = 2)
  double azimuth_deg = -60.0;     // where the viewer stands around the up axis (0: on +a, the
                                  // first horizontal axis; 90: on +b)
  double elevation_deg = 35.0;    // the viewer's height above the horizontal plane
  double point_size_m = 0.01;     // side of the square drawn per point (the objects' voxel size)
  double clip_percent = 1.0;      // the framing ignores this % of points on each side (strays)
  int margin_px = 6;              // blank border around the object
  Rgb default_color{90, 90, 90};  // for a cloud without colours
  void check() const;             // throws InputError naming the bad field
};

// CV_8UC3 BGR, size_px × size_px, white background. Points are squares of point_size_m (at least
// one pixel, at most 9) kept where nearest to the viewer (z-buffer), darkened with depth so that
// shape reads; the label (e.g. "3 cup") is written top-left. An empty cloud gives a blank labelled
// image.
cv::Mat render_thumbnail(const PointCloud& cloud, const std::string& label,
                         const ThumbnailOptions& options = {});

// The same view of a triangle mesh, every triangle filled in `color` shaded by its facing to a
// light over the viewer's shoulder (z-buffered); an empty mesh gives a blank labelled image.
cv::Mat render_mesh_thumbnail(const TriangleMesh& mesh, Rgb color, const std::string& label,
                              const ThumbnailOptions& options = {});

}  // namespace objmap::report
