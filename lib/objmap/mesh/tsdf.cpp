#include "objmap/mesh/tsdf.h"

#include <dlfcn.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <numeric>
#include <utility>

#include "objmap/core/error.h"
#include "objmap/mesh/vdb_backend.h"

namespace objmap::mesh {

MeshSelection parse_mesh_selection(const std::string& text, const std::string& where) {
  if (text == "none") return {false, false};
  if (text == "objects") return {true, false};
  if (text == "scene") return {false, true};
  if (text == "all") return {true, true};
  throw InputError(where,
                   "'" + text + "' is not a mesh selection; expected none, objects, scene or all");
}

void TsdfOptions::check() const {
  auto positive = [](double v, const char* field) {
    require(std::isfinite(v) && v > 0.0, field, "must be > 0 (got " + std::to_string(v) + ")");
  };
  require(std::isfinite(voxel_m) && voxel_m >= 0.0, "voxel_m", "must be >= 0 (0: from the size)");
  positive(voxel_fraction, "voxel_fraction");
  positive(min_voxel_m, "min_voxel_m");
  require(min_voxel_m <= 0.5, "min_voxel_m", "must be <= 0.5 m");
  positive(max_voxel_m, "max_voxel_m");
  require(max_voxel_m >= min_voxel_m, "max_voxel_m", "must be >= min_voxel_m");
  positive(truncation_voxels, "truncation_voxels");
  require(std::isfinite(min_voxel_pixels) && min_voxel_pixels >= 0.0, "min_voxel_pixels",
          "must be >= 0");
  require(std::isfinite(min_truncation_m) && min_truncation_m >= 0.0, "min_truncation_m",
          "must be >= 0");
  positive(reference_depth_m, "reference_depth_m");
  require(std::isfinite(min_weight) && min_weight >= 0.0, "min_weight", "must be >= 0");
  require(std::isfinite(carving_depth_m) && carving_depth_m >= 0.0, "carving_depth_m",
          "must be >= 0 (0: to the box's side)");
  require(min_component_share >= 0.0 && min_component_share < 1.0, "min_component_share",
          "must be in [0, 1)");
}

using detail::fast_floor;

PointCloud voxel_means(const PointCloud& points, double voxel_m) {
  // An open-addressing table of the voxels met (twice as many slots as points, a power of two);
  // voxels are numbered in the order they are first met.
  struct Sum {
    Vec3 point = Vec3::Zero(), rgb = Vec3::Zero();
    std::uint32_t count = 0;
  };
  std::size_t slots = 16;
  while (slots < 2 * points.size()) slots *= 2;
  std::vector<std::int64_t> slot_key(slots, -1);
  std::vector<std::uint32_t> slot_sum(slots);
  std::vector<Sum> sums;
  const bool colour = points.has_colors();
  const double inverse = 1.0 / voxel_m;
  auto cell = [&](float x) { return fast_floor(x * inverse) + (std::int64_t{1} << 20); };
  std::int64_t last_key = -1;
  std::uint32_t last = 0;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const Vec3f& p = points.points[i];
    const std::int64_t key = (cell(p.x()) << 42) | (cell(p.y()) << 21) | cell(p.z());
    if (key != last_key) {  // neighbouring pixels mostly share a voxel: one probe per run
      std::size_t s =
          static_cast<std::size_t>(static_cast<std::uint64_t>(key) * 0x9e3779b97f4a7c15ULL >> 17) &
          (slots - 1);
      while (slot_key[s] != -1 && slot_key[s] != key) s = (s + 1) & (slots - 1);
      if (slot_key[s] == -1) {
        slot_key[s] = key;
        slot_sum[s] = static_cast<std::uint32_t>(sums.size());
        sums.emplace_back();
      }
      last = slot_sum[s];
      last_key = key;
    }
    Sum& sum = sums[last];
    sum.point += p.cast<double>();
    if (colour) sum.rgb += Vec3(points.colors[i].r, points.colors[i].g, points.colors[i].b);
    ++sum.count;
  }
  PointCloud out;
  out.points.reserve(sums.size());
  for (const Sum& sum : sums) {
    out.points.push_back((sum.point / sum.count).cast<float>());
    if (colour) {
      const Vec3 c = sum.rgb / sum.count;
      out.colors.push_back(Rgb{static_cast<std::uint8_t>(std::lround(c.x())),
                               static_cast<std::uint8_t>(std::lround(c.y())),
                               static_cast<std::uint8_t>(std::lround(c.z()))});
    }
  }
  return out;
}

double model_voxel_m(const Vec3& box_size, const TsdfOptions& options, double pixel_footprint_m) {
  if (options.voxel_m > 0.0) return options.voxel_m;
  const double v = options.voxel_fraction * box_size.maxCoeff();
  return std::max(std::clamp(v, options.min_voxel_m, options.max_voxel_m),
                  options.min_voxel_pixels * pixel_footprint_m);
}

double pixel_footprint_m(const std::vector<DepthView>& views, double focal_px) {
  std::vector<double> range;
  for (const DepthView& v : views) {
    if (!v.points) continue;
    const std::size_t step = std::max<std::size_t>(1, v.points->size() / 64);
    for (std::size_t i = 0; i < v.points->size(); i += step)
      range.push_back((v.points->points[i].cast<double>() - v.camera_in_world).norm());
  }
  if (range.empty() || !(focal_px > 0.0)) return 0.0;
  std::nth_element(range.begin(), range.begin() + static_cast<std::ptrdiff_t>(range.size() / 2),
                   range.end());
  return range[range.size() / 2] / focal_px;
}

namespace {

// The places libobjmap_vdb.so is looked for: OBJMAP_VDB_MODULE alone when set; else beside the
// program (<bin>/../lib/objmap/, the build tree's and an installed tree's layout), then the
// install prefix's lib/objmap/.
std::vector<std::string> vdb_module_places() {
  if (const char* env = std::getenv("OBJMAP_VDB_MODULE"); env && *env) return {env};
  std::vector<std::string> places;
  std::error_code error;
  const std::filesystem::path exe = std::filesystem::read_symlink("/proc/self/exe", error);
  if (!error)
    places.push_back((exe.parent_path().parent_path() / "lib/objmap/libobjmap_vdb.so").string());
#ifdef OBJMAP_VDB_INSTALLED
  places.push_back(OBJMAP_VDB_INSTALLED);
#endif
  return places;
}

const detail::VdbBackend* load_vdb_backend() {
  std::string tried;
  for (const std::string& place : vdb_module_places()) {
    void* handle = dlopen(place.c_str(), RTLD_NOW | RTLD_LOCAL);
    if (handle == nullptr) {
      const char* error = dlerror();
      tried += "; " + (error ? std::string(error) : place + ": cannot be loaded");
      continue;
    }
    using Get = const detail::VdbBackend* (*)();
    const auto get = reinterpret_cast<Get>(dlsym(handle, "objmap_vdb_backend"));
    const detail::VdbBackend* backend = get ? get() : nullptr;
    if (backend != nullptr && backend->abi == detail::kVdbBackendAbi) return backend;
    tried += "; " + place + ": not this build's module";
    dlclose(handle);
  }
  throw InputError("meshes", "the OpenVDB module libobjmap_vdb.so is not found (" +
                                 tried.substr(std::min<std::size_t>(2, tried.size())) +
                                 "); build it (make build) or name it in OBJMAP_VDB_MODULE");
}

}  // namespace

const detail::VdbBackend& vdb_backend() {
  static const detail::VdbBackend* backend = load_vdb_backend();  // once; a failure retries
  return *backend;
}

void require_meshes() { vdb_backend(); }

struct TsdfModel::Impl {
  const detail::VdbBackend& backend;
  void* model;
  double voxel_m;
  Impl(const detail::VdbBackend& b, const Aabb& box, double voxel, const TsdfOptions& options)
      : backend(b), model(b.create(box, voxel, options)), voxel_m(voxel) {}
  ~Impl() { backend.destroy(model); }
  Impl(const Impl&) = delete;
  Impl& operator=(const Impl&) = delete;
};

TsdfModel::TsdfModel(const Aabb& box, double voxel_m, const TsdfOptions& options) {
  require(std::isfinite(voxel_m) && voxel_m > 0.0, "mesh.voxel_m", "must be > 0");
  impl_ = std::make_unique<Impl>(vdb_backend(), box, voxel_m, options);
}
TsdfModel::~TsdfModel() = default;
TsdfModel::TsdfModel(TsdfModel&&) noexcept = default;
TsdfModel& TsdfModel::operator=(TsdfModel&&) noexcept = default;

void TsdfModel::add(const DepthView& view) {
  if (!view.points) return;
  impl_->backend.add(impl_->model, view.camera_in_world, voxel_means(*view.points, impl_->voxel_m));
}

ModelResult TsdfModel::mesh() const {
  ModelResult result;
  impl_->backend.mesh(impl_->model, result);
  return result;
}

ModelResult fuse_model(const std::vector<DepthView>& views, const Aabb& box, double voxel_m,
                       const TsdfOptions& options) {
  TsdfModel model(box, voxel_m, options);
  for (const DepthView& view : views) model.add(view);
  return model.mesh();
}

}  // namespace objmap::mesh
