#include "objmap/io/ply.h"

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <functional>
#include <sstream>
#include <string>
#include <vector>

#include "objmap/core/error.h"
#include "objmap/io/atomic.h"

namespace objmap::io {

namespace fs = std::filesystem;

namespace {

// `colors`: one per point, or nullptr for none.
void write_ply_points(const fs::path& path, const PointCloud& cloud, const std::vector<Rgb>* colors,
                      const PlyWriteOptions& options) {
  const bool colour = colors != nullptr;
  std::ostringstream header;
  header << "ply\nformat binary_little_endian 1.0\n";
  if (!options.comment.empty()) header << "comment " << options.comment << "\n";
  header << "element vertex " << cloud.size() << "\n"
         << "property float x\nproperty float y\nproperty float z\n";
  if (colour) header << "property uchar red\nproperty uchar green\nproperty uchar blue\n";
  header << "end_header\n";

  // The body in pieces of up to 64k points through one reused buffer (bytes written as the format
  // says, whatever the host order), into a temporary file renamed when complete (io/atomic.h).
  static_assert(sizeof(float) == 4, "PLY float is 4 bytes");
  AtomicFile file(path);
  const std::string head = header.str();
  file.write(head.data(), head.size());
  const std::size_t stride = 12 + (colour ? 3 : 0);
  constexpr std::size_t kPiece = 65536;
  std::vector<char> buffer(std::min(cloud.size(), kPiece) * stride);
  for (std::size_t begin = 0; begin < cloud.size(); begin += kPiece) {
    const std::size_t end = std::min(cloud.size(), begin + kPiece);
    char* out = buffer.data();
    for (std::size_t i = begin; i < end; ++i) {
      const Vec3f& p = cloud.points[i];
      const float xyz[3] = {p.x(), p.y(), p.z()};
      for (int a = 0; a < 3; ++a) {
        std::uint32_t bits;
        std::memcpy(&bits, &xyz[a], 4);
        for (int b = 0; b < 4; ++b) *out++ = static_cast<char>((bits >> (8 * b)) & 0xff);
      }
      if (colour) {
        *out++ = static_cast<char>((*colors)[i].r);
        *out++ = static_cast<char>((*colors)[i].g);
        *out++ = static_cast<char>((*colors)[i].b);
      }
    }
    file.write(buffer.data(), static_cast<std::size_t>(out - buffer.data()));
  }
  file.commit();
}

}  // namespace

void write_ply(const fs::path& path, const PointCloud& cloud, const PlyWriteOptions& options) {
  write_ply_points(path, cloud, cloud.has_colors() ? &cloud.colors : nullptr, options);
}

void write_ply(const fs::path& path, const PointCloud& cloud, const std::vector<Rgb>& colors,
               const PlyWriteOptions& options) {
  require(colors.size() == cloud.size(), path.string(),
          "write_ply: " + std::to_string(colors.size()) + " colours for " +
              std::to_string(cloud.size()) + " points; expected one per point");
  write_ply_points(path, cloud, &colors, options);
}

namespace {

enum class Kind { kSigned, kUnsigned, kFloat, kDouble };

struct Property {
  std::string type;  // normalised: char uchar short ushort int uint float double
  std::string name;
  int size = 0;
  Kind kind = Kind::kUnsigned;  // how the `size` bytes of a binary value read
};

Kind kind_of(const std::string& t) {
  if (t == "float") return Kind::kFloat;
  if (t == "double") return Kind::kDouble;
  if (t == "char" || t == "short" || t == "int") return Kind::kSigned;
  return Kind::kUnsigned;
}

int type_size(const std::string& t) {
  if (t == "char" || t == "uchar") return 1;
  if (t == "short" || t == "ushort") return 2;
  if (t == "int" || t == "uint" || t == "float") return 4;
  if (t == "double") return 8;
  return 0;
}

std::string normalise_type(const std::string& t) {
  if (t == "int8") return "char";
  if (t == "uint8") return "uchar";
  if (t == "int16") return "short";
  if (t == "uint16") return "ushort";
  if (t == "int32") return "int";
  if (t == "uint32") return "uint";
  if (t == "float32") return "float";
  if (t == "float64") return "double";
  return t;
}

// A little-endian binary value of property `p` (its kind and size parsed once from the header).
double read_binary(const char* bytes, const Property& p) {
  std::uint64_t bits = 0;
  for (int b = 0; b < p.size; ++b)
    bits |= static_cast<std::uint64_t>(static_cast<unsigned char>(bytes[b])) << (8 * b);
  switch (p.kind) {
    case Kind::kFloat: {
      const std::uint32_t b32 = static_cast<std::uint32_t>(bits);
      float f;
      std::memcpy(&f, &b32, 4);
      return f;
    }
    case Kind::kDouble: {
      double d;
      std::memcpy(&d, &bits, 8);
      return d;
    }
    case Kind::kSigned:  // sign-extend from p.size bytes
      return static_cast<double>(static_cast<std::int64_t>(bits << (64 - 8 * p.size)) >>
                                 (64 - 8 * p.size));
    case Kind::kUnsigned:
      break;
  }
  return static_cast<double>(bits);
}

}  // namespace

namespace {

// A PLY file being read: the stream, its current line and line number.
struct PlyReader {
  std::ifstream f;
  std::string where, line;
  int line_no = 0;
  bool next_line() {
    if (!std::getline(f, line)) return false;
    ++line_no;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    return true;
  }
};

// What the header says: the format, the vertex count and the vertex properties with their
// offsets in a binary row; the indices of x, y, z and of the colour (-1: absent).
struct PlyHeader {
  std::string format;
  std::size_t vertices = 0;
  std::vector<Property> props;
  std::vector<std::size_t> offset;
  std::size_t stride = 0;
  int ix = -1, iy = -1, iz = -1, ir = -1, ig = -1, ib = -1, inx = -1, iny = -1, inz = -1;
  bool colour() const { return ir >= 0 && ig >= 0 && ib >= 0; }
  bool normals() const { return inx >= 0 && iny >= 0 && inz >= 0; }
  // The `face` element right after `vertex` (meshes): its count and its one list property, or
  // face_props other than that list (not read).
  std::size_t faces = 0;
  bool face_list = false;
  int face_other_props = 0;
  Property face_count, face_index;
};

// A property line of the `face` element after its type word: the vertex index list is kept.
void read_face_property(std::istringstream& ls, const std::string& type, const std::string& at,
                        PlyHeader& h) {
  if (type != "list") {
    ++h.face_other_props;
    return;
  }
  std::string count_type, index_type, name;
  ls >> count_type >> index_type >> name;
  count_type = normalise_type(count_type);
  index_type = normalise_type(index_type);
  const int count_size = type_size(count_type), index_size = type_size(index_type);
  if (count_size == 0 || index_size == 0 || count_type == "float" || count_type == "double" ||
      index_type == "float" || index_type == "double")
    throw InputError(at, "bad face list '" + count_type + " " + index_type +
                             "'; expected integer count and index types");
  if (name != "vertex_indices" && name != "vertex_index") {
    ++h.face_other_props;
    return;
  }
  h.face_list = true;
  h.face_count = {count_type, "count", count_size, kind_of(count_type)};
  h.face_index = {index_type, name, index_size, kind_of(index_type)};
}

// Step 1: the header lines up to end_header.
PlyHeader read_header(PlyReader& r) {
  if (!r.next_line() || r.line != "ply")
    throw InputError(r.where + ":1", "not a PLY file; expected 'ply'");
  PlyHeader h;
  bool in_vertex = false, seen_vertex = false, vertex_first = true;
  std::string element;
  while (true) {
    if (!r.next_line()) throw InputError(r.where, "header has no 'end_header'");
    std::istringstream ls(r.line);
    std::string word;
    ls >> word;
    const std::string at = r.where + ":" + std::to_string(r.line_no);
    if (word == "end_header") break;
    if (word == "comment" || word == "obj_info" || word.empty()) continue;
    if (word == "format") {
      ls >> h.format;
      if (h.format != "binary_little_endian" && h.format != "ascii")
        throw InputError(
            at, "format '" + h.format + "' not supported; expected binary_little_endian or ascii");
    } else if (word == "element") {
      std::string name;
      std::size_t count = 0;
      ls >> name >> count;
      if (!ls) throw InputError(at, "bad element line; expected 'element <name> <count>'");
      in_vertex = name == "vertex";
      element = name;
      if (name == "face" && seen_vertex) h.faces = count;
      if (in_vertex) {
        seen_vertex = true;
        h.vertices = count;
      } else if (!seen_vertex && count > 0) {
        vertex_first = false;
      }
    } else if (word == "property") {
      std::string type, name;
      ls >> type;
      if (element == "face" && seen_vertex) {
        read_face_property(ls, type, at, h);
        continue;
      }
      if (!in_vertex) continue;
      if (type == "list") throw InputError(at, "list property in 'vertex' is not supported");
      ls >> name;
      type = normalise_type(type);
      const int size = type_size(type);
      if (size == 0 || name.empty()) throw InputError(at, "unknown property type '" + type + "'");
      h.props.push_back({type, name, size, kind_of(type)});
    } else {
      throw InputError(at, "unexpected header line '" + r.line + "'");
    }
  }
  if (h.format.empty()) throw InputError(r.where, "header has no 'format' line");
  if (!seen_vertex) throw InputError(r.where, "no 'element vertex'; expected a point cloud");
  if (!vertex_first) throw InputError(r.where, "'vertex' is not the first element; not supported");
  return h;
}

// Step 2: where x, y, z and the colour are, and each property's offset in a binary row.
void locate_properties(const std::string& where, PlyHeader& h) {
  h.offset.resize(h.props.size());
  for (std::size_t i = 0; i < h.props.size(); ++i) {
    h.offset[i] = h.stride;
    h.stride += h.props[i].size;
    const std::string& n = h.props[i].name;
    const int k = static_cast<int>(i);
    if (n == "x") h.ix = k;
    if (n == "y") h.iy = k;
    if (n == "z") h.iz = k;
    if (n == "red" || n == "r") h.ir = k;
    if (n == "green" || n == "g") h.ig = k;
    if (n == "blue" || n == "b") h.ib = k;
    if (n == "nx") h.inx = k;
    if (n == "ny") h.iny = k;
    if (n == "nz") h.inz = k;
  }
  if (h.ix < 0 || h.iy < 0 || h.iz < 0)
    throw InputError(where, "vertex has no x, y and z properties");
}

// Step 3: the count against the bytes that follow the header, before anything is allocated: a
// header's count is not to be trusted (a 4-billion-vertex header on a small file).
void check_count(PlyReader& r, const PlyHeader& h) {
  const std::streamoff body_start = r.f.tellg();
  r.f.seekg(0, std::ios::end);
  const auto remaining =
      static_cast<std::size_t>(std::max<std::streamoff>(0, r.f.tellg() - body_start));
  r.f.seekg(body_start);
  const bool binary = h.format == "binary_little_endian";
  const std::size_t least_per_vertex = binary ? h.stride : 2 * h.props.size();  // ascii: "0 "
  if (least_per_vertex > 0 && h.vertices > remaining / least_per_vertex)
    throw InputError(r.where, "the header says " + std::to_string(h.vertices) +
                                  " vertices, but only " + std::to_string(remaining) +
                                  " bytes follow it (at least " + std::to_string(least_per_vertex) +
                                  " per vertex): truncated, or a wrong count; expected the file "
                                  "to hold every vertex it counts");
}

std::uint8_t to_byte(double v) { return static_cast<std::uint8_t>(v < 0 ? 0 : v > 255 ? 255 : v); }

// The vertices read so far: a block of at most kBlockRows of them (its points, colours when the
// file has them, normals when asked for and present), handed on to a BlockSink with the index of
// its first vertex. Read a block at a time, a large map never sits in memory twice (its bytes and
// its points).
constexpr std::size_t kBlockRows = 65536;
struct VertexBlock {
  PointCloud cloud;
  std::vector<Vec3f> normals;
  void resize(const PlyHeader& h, std::size_t rows, bool with_normals) {
    cloud.points.resize(rows);
    cloud.colors.resize(h.colour() ? rows : 0);
    normals.resize(with_normals ? rows : 0);
  }
};
using BlockSink = std::function<void(const VertexBlock& block, std::size_t first)>;

// Step 4, binary: the rows, a block at a time.
void read_binary_body(PlyReader& r, const PlyHeader& h, bool with_normals, const BlockSink& sink) {
  std::vector<char> body(std::min(h.vertices, kBlockRows) * h.stride);
  VertexBlock block;
  for (std::size_t first = 0; first < h.vertices; first += kBlockRows) {
    const std::size_t rows = std::min(kBlockRows, h.vertices - first);
    r.f.read(body.data(), static_cast<std::streamsize>(rows * h.stride));
    if (static_cast<std::size_t>(r.f.gcount()) != rows * h.stride)
      throw InputError(
          r.where, "file ends after " +
                       std::to_string(first + static_cast<std::size_t>(r.f.gcount()) / h.stride) +
                       " of " + std::to_string(h.vertices) + " vertices (truncated)");
    block.resize(h, rows, with_normals);
    for (std::size_t j = 0; j < rows; ++j) {
      const char* row = body.data() + j * h.stride;
      auto value = [&](int k) { return read_binary(row + h.offset[k], h.props[k]); };
      block.cloud.points[j] =
          Vec3f(static_cast<float>(value(h.ix)), static_cast<float>(value(h.iy)),
                static_cast<float>(value(h.iz)));
      if (h.colour())
        block.cloud.colors[j] =
            Rgb{to_byte(value(h.ir)), to_byte(value(h.ig)), to_byte(value(h.ib))};
      if (with_normals)
        block.normals[j] = Vec3f(static_cast<float>(value(h.inx)), static_cast<float>(value(h.iny)),
                                 static_cast<float>(value(h.inz)));
    }
    sink(block, first);
  }
}

// Step 4, ascii: a line per vertex, a block of lines at a time.
void read_ascii_body(PlyReader& r, const PlyHeader& h, bool with_normals, const BlockSink& sink) {
  std::vector<double> v(h.props.size());
  VertexBlock block;
  for (std::size_t first = 0; first < h.vertices; first += kBlockRows) {
    const std::size_t rows = std::min(kBlockRows, h.vertices - first);
    block.resize(h, rows, with_normals);
    for (std::size_t j = 0; j < rows; ++j) {
      if (!r.next_line())
        throw InputError(r.where, "file ends after " + std::to_string(first + j) + " of " +
                                      std::to_string(h.vertices) + " vertices (truncated)");
      std::istringstream ls(r.line);
      for (double& x : v) ls >> x;
      if (!ls)
        throw InputError(r.where + ":" + std::to_string(r.line_no),
                         "expected " + std::to_string(h.props.size()) + " numbers per vertex");
      block.cloud.points[j] = Vec3f(static_cast<float>(v[h.ix]), static_cast<float>(v[h.iy]),
                                    static_cast<float>(v[h.iz]));
      if (h.colour())
        block.cloud.colors[j] = Rgb{to_byte(v[h.ir]), to_byte(v[h.ig]), to_byte(v[h.ib])};
      if (with_normals)
        block.normals[j] = Vec3f(static_cast<float>(v[h.inx]), static_cast<float>(v[h.iny]),
                                 static_cast<float>(v[h.inz]));
    }
    sink(block, first);
  }
}

// One face's vertex indices as a fan of triangles, each index checked against the vertex count.
void add_face(const std::vector<std::int64_t>& index, const PlyHeader& h, const std::string& where,
              std::size_t face, TriangleMesh& mesh) {
  for (std::int64_t i : index)
    if (i < 0 || static_cast<std::size_t>(i) >= h.vertices)
      throw InputError(where, "face " + std::to_string(face) + " names vertex " +
                                  std::to_string(i) + " of " + std::to_string(h.vertices) +
                                  "; expected indices of the vertex element");
  for (std::size_t k = 2; k < index.size(); ++k)
    mesh.triangles.push_back({static_cast<std::uint32_t>(index[0]),
                              static_cast<std::uint32_t>(index[k - 1]),
                              static_cast<std::uint32_t>(index[k])});
}

// Step 5 of a mesh: the faces, binary (count, then the indices) or a line each.
void read_faces(PlyReader& r, const PlyHeader& h, TriangleMesh& mesh) {
  const bool binary = h.format == "binary_little_endian";
  std::vector<std::int64_t> index;
  std::vector<char> bytes(8);
  for (std::size_t f = 0; f < h.faces; ++f) {
    std::int64_t n = 0;
    if (binary) {
      r.f.read(bytes.data(), h.face_count.size);
      n = static_cast<std::int64_t>(read_binary(bytes.data(), h.face_count));
      if (n < 0 || n > 1000) n = -1;
      if (n > 0) {
        bytes.resize(std::max<std::size_t>(8, static_cast<std::size_t>(n * h.face_index.size)));
        r.f.read(bytes.data(), n * h.face_index.size);
      }
      if (!r.f || n < 0)
        throw InputError(r.where, "file ends or breaks in face " + std::to_string(f) + " of " +
                                      std::to_string(h.faces) + " (truncated)");
      index.resize(static_cast<std::size_t>(n));
      for (std::int64_t k = 0; k < n; ++k)
        index[k] = static_cast<std::int64_t>(
            read_binary(bytes.data() + k * h.face_index.size, h.face_index));
    } else {
      if (!r.next_line())
        throw InputError(r.where, "file ends after " + std::to_string(f) + " of " +
                                      std::to_string(h.faces) + " faces (truncated)");
      std::istringstream ls(r.line);
      ls >> n;
      index.resize(n > 0 && n <= 1000 ? static_cast<std::size_t>(n) : 0);
      for (auto& i : index) ls >> i;
      if (!ls || n < 0 || n > 1000)
        throw InputError(r.where + ":" + std::to_string(r.line_no), "bad face line");
    }
    add_face(index, h, r.where, f, mesh);
  }
}

}  // namespace

namespace {

// Steps 1-3 of every reader: the header checked; the reader is left at the vertices.
void open_vertices(PlyReader& r, PlyHeader& h, const fs::path& path, bool mesh) {
  r.where = path.string();
  r.f.open(path, std::ios::binary);
  if (!r.f) throw InputError(r.where, "cannot open for reading");
  h = read_header(r);
  locate_properties(r.where, h);
  if (mesh && h.faces > 0 && !h.face_list)
    throw InputError(r.where, "element face has no vertex_indices list; expected a mesh");
  if (mesh && h.face_other_props > 0)
    throw InputError(r.where, "element face has properties besides vertex_indices; not supported");
  check_count(r, h);
}

void read_body(PlyReader& r, const PlyHeader& h, bool with_normals, const BlockSink& sink) {
  if (h.format == "binary_little_endian")
    read_binary_body(r, h, with_normals, sink);
  else
    read_ascii_body(r, h, with_normals, sink);
}

// Steps 1-4 of both whole readers: the header, then the vertices (points, colours, and `normals`
// when given and the file has them); the reader is left at the elements after `vertex`.
PointCloud read_vertices(PlyReader& r, PlyHeader& h, const fs::path& path, bool mesh,
                         std::vector<Vec3f>* normals) {
  open_vertices(r, h, path, mesh);
  PointCloud cloud;
  cloud.points.resize(h.vertices);
  if (h.colour()) cloud.colors.resize(h.vertices);
  if (normals && h.normals())
    normals->resize(h.vertices);
  else
    normals = nullptr;
  read_body(r, h, normals != nullptr, [&](const VertexBlock& block, std::size_t first) {
    std::copy(block.cloud.points.begin(), block.cloud.points.end(), cloud.points.begin() + first);
    std::copy(block.cloud.colors.begin(), block.cloud.colors.end(), cloud.colors.begin() + first);
    if (normals) std::copy(block.normals.begin(), block.normals.end(), normals->begin() + first);
  });
  return cloud;
}

}  // namespace

PointCloud read_ply(const fs::path& path) {
  PlyReader r;
  PlyHeader h;
  return read_vertices(r, h, path, false, nullptr);
}

std::size_t ply_vertex_count(const fs::path& path) {
  PlyReader r;
  PlyHeader h;
  open_vertices(r, h, path, false);
  return h.vertices;
}

void read_ply_blocks(const fs::path& path, const std::function<void(const PointCloud&)>& take) {
  PlyReader r;
  PlyHeader h;
  open_vertices(r, h, path, false);
  read_body(r, h, false, [&](const VertexBlock& block, std::size_t) { take(block.cloud); });
}

void write_mesh_ply(const fs::path& path, const TriangleMesh& mesh,
                    const PlyWriteOptions& options) {
  const bool normals = mesh.has_normals(), colour = mesh.has_colors();
  std::ostringstream header;
  header << "ply\nformat binary_little_endian 1.0\n";
  if (!options.comment.empty()) header << "comment " << options.comment << "\n";
  header << "element vertex " << mesh.vertices.size() << "\n"
         << "property float x\nproperty float y\nproperty float z\n";
  if (normals) header << "property float nx\nproperty float ny\nproperty float nz\n";
  if (colour) header << "property uchar red\nproperty uchar green\nproperty uchar blue\n";
  header << "element face " << mesh.triangles.size() << "\n"
         << "property list uchar int vertex_indices\nend_header\n";
  std::string body = header.str();
  body.reserve(body.size() + mesh.vertices.size() * (12 + (normals ? 12 : 0) + (colour ? 3 : 0)) +
               mesh.triangles.size() * 13);
  auto put32 = [&](std::uint32_t bits) {
    for (int b = 0; b < 4; ++b) body.push_back(static_cast<char>((bits >> (8 * b)) & 0xff));
  };
  auto put_vec = [&](const Vec3f& v) {
    for (int a = 0; a < 3; ++a) {
      std::uint32_t bits;
      std::memcpy(&bits, &v[a], 4);
      put32(bits);
    }
  };
  for (std::size_t i = 0; i < mesh.vertices.size(); ++i) {
    put_vec(mesh.vertices[i]);
    if (normals) put_vec(mesh.normals[i]);
    if (colour) {
      body.push_back(static_cast<char>(mesh.colors[i].r));
      body.push_back(static_cast<char>(mesh.colors[i].g));
      body.push_back(static_cast<char>(mesh.colors[i].b));
    }
  }
  for (const auto& t : mesh.triangles) {
    body.push_back(3);
    for (std::uint32_t i : t) put32(i);
  }
  write_file_atomic(path, body);
}

TriangleMesh read_mesh_ply(const fs::path& path) {
  PlyReader r;
  PlyHeader h;
  TriangleMesh mesh;
  PointCloud cloud = read_vertices(r, h, path, true, &mesh.normals);
  mesh.vertices = std::move(cloud.points);
  mesh.colors = std::move(cloud.colors);
  read_faces(r, h, mesh);
  return mesh;
}

}  // namespace objmap::io
