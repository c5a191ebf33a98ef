#include "core/merge/mesh_io.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <limits>
#include <string>

#include "core/common/atomic_file.h"
#include "core/common/log.h"

namespace scanreg::merge {

namespace {

template <typename T>
void Append(std::string& out, const T& value) {
  out.append(reinterpret_cast<const char*>(&value), sizeof(T));  // little-endian hosts only (x86, arm)
}

// World coordinates in double: every reader (VTK, PCL, CloudCompare, MeshLab, Blender, Open3D)
// places them without knowing anything of ours.
void AppendWorld(std::string& out, const Eigen::Vector3d& origin, const Eigen::Vector3f& v) {
  const Eigen::Vector3d p = origin + v.cast<double>();
  Append(out, p.x()), Append(out, p.y()), Append(out, p.z());
}

const char* kDoubleVertex = "property double x\nproperty double y\nproperty double z\n";


// An atomic output appended a few megabytes at a time: a mesh of tens of millions of triangles is
// never held a second time as its file's bytes.
class ChunkedOutput {
 public:
  explicit ChunkedOutput(const std::filesystem::path& path) : file_(path) {}
  Status Open() { return file_.Open(); }
  std::string& bytes() { return bytes_; }
  // Call after each element: hands the bytes to the file once they pass a chunk.
  Status Drain() {
    if (bytes_.size() < kChunk) return Status::Ok();
    Status s = file_.Write(bytes_);
    bytes_.clear();
    return s;
  }
  Status Commit() {
    if (Status s = file_.Write(bytes_); !s) return s;
    bytes_ = std::string();
    return file_.Commit();
  }

 private:
  static constexpr std::size_t kChunk = std::size_t(8) << 20;
  AtomicFile file_;
  std::string bytes_;
};

// The PLY vertex properties WriteWorldVertices writes.
std::string VertexProperties(const MeshSource& mesh) {
  std::string out = kDoubleVertex;
  if (mesh.coloured()) out += "property uchar red\nproperty uchar green\nproperty uchar blue\n";
  if (mesh.described()) out += "property float scalar_gap\n";
  return out;
}

// The vertices in world coordinates, as PLY doubles, with their colour and gap (VertexProperties).
Status WriteWorldVertices(const MeshSource& mesh, ChunkedOutput& output) {
  const Eigen::Vector3d origin = mesh.origin();
  const bool coloured = mesh.coloured(), described = mesh.described();
  return mesh.ForEachVertex([&](const Eigen::Vector3f& v, const VertexInfo& info) {
    AppendWorld(output.bytes(), origin, v);
    if (coloured) Append(output.bytes(), info.colour);
    if (described) Append(output.bytes(), info.gap_m);
    return output.Drain();
  });
}

const char* kGapComment =
    "comment scalar_gap: metres from the vertex to the nearest scan point (beyond 1.5 voxels: surface the merge "
    "interpolated, not measured; at least 2 voxels on a filled hole)\n";

}  // namespace

double FloatRoundingError(double magnitude) {
  const float f = static_cast<float>(std::abs(magnitude));
  return 0.5 * (std::nextafter(f, std::numeric_limits<float>::infinity()) - f);
}

Status InMemoryMesh::ForEachVertex(const VertexVisitor& f) const {
  const VertexInfo none;
  for (std::size_t i = 0; i < mesh_.vertices.size(); ++i)
    if (Status s = f(mesh_.vertices[i], mesh_.info.empty() ? none : mesh_.info[i]); !s) return s;
  return Status::Ok();
}

Status InMemoryMesh::ForEachTriangle(const std::function<Status(const Eigen::Vector3i&)>& f) const {
  for (const auto& t : mesh_.triangles)
    if (Status s = f(t); !s) return s;
  return Status::Ok();
}

Status WriteMeshPly(const std::filesystem::path& path, const MeshSource& mesh) {
  ChunkedOutput output(path);
  if (Status s = output.Open(); !s) return s;
  std::string& out = output.bytes();
  out = "ply\nformat binary_little_endian 1.0\ncomment scanreg merged mesh, world coordinates (metres)\n";
  if (mesh.described()) out += kGapComment;
  out += "element vertex " + std::to_string(mesh.vertex_count()) + "\n" + VertexProperties(mesh);
  out += "element face " + std::to_string(mesh.triangle_count()) +
         "\nproperty list uchar int vertex_indices\nend_header\n";
  if (Status s = WriteWorldVertices(mesh, output); !s) return s;
  if (Status s = mesh.ForEachTriangle([&](const Eigen::Vector3i& t) {
        Append(out, std::uint8_t(3));
        Append(out, std::int32_t(t[0])), Append(out, std::int32_t(t[1])), Append(out, std::int32_t(t[2]));
        return output.Drain();
      });
      !s)
    return s;
  return output.Commit();
}

Status WriteMeshObj(const std::filesystem::path& path, const MeshSource& mesh) {
  ChunkedOutput output(path);
  if (Status s = output.Open(); !s) return s;
  std::string& out = output.bytes();
  out = "# scanreg merged mesh: " + std::to_string(mesh.vertex_count()) + " vertices, " +
        std::to_string(mesh.triangle_count()) + " triangles, absolute coordinates (metres)\n";
  char buf[128];
  const Eigen::Vector3d origin = mesh.origin();
  const bool coloured = mesh.coloured();
  if (Status s = mesh.ForEachVertex([&](const Eigen::Vector3f& v, const VertexInfo& info) {
        const Eigen::Vector3d p = origin + v.cast<double>();
        if (coloured) {
          out.append(buf, std::snprintf(buf, sizeof buf, "v %.6f %.6f %.6f %.4f %.4f %.4f\n", p.x(), p.y(), p.z(),
                                        info.colour[0] / 255.0, info.colour[1] / 255.0, info.colour[2] / 255.0));
          return output.Drain();
        }
        out.append(buf, std::snprintf(buf, sizeof buf, "v %.6f %.6f %.6f\n", p.x(), p.y(), p.z()));
        return output.Drain();
      });
      !s)
    return s;
  if (Status s = mesh.ForEachTriangle([&](const Eigen::Vector3i& t) {
        out.append(buf, std::snprintf(buf, sizeof buf, "f %d %d %d\n", t[0] + 1, t[1] + 1, t[2] + 1));
        return output.Drain();
      });
      !s)
    return s;
  return output.Commit();
}

Status WriteMeshStl(const std::filesystem::path& path, const MeshSource& mesh) {
  std::vector<Eigen::Vector3f> vertices;  // each triangle's corners are written
  vertices.reserve(mesh.vertex_count());
  if (Status s = mesh.ForEachVertex([&](const Eigen::Vector3f& v, const VertexInfo&) {
        vertices.push_back(v);
        return Status::Ok();
      });
      !s)
    return s;
  const Eigen::Vector3d origin = mesh.origin();
  ChunkedOutput output(path);
  if (Status s = output.Open(); !s) return s;
  std::string& out = output.bytes();
  out.assign(80, ' ');
  const std::string title = "scanreg merged mesh, world coordinates (metres)";
  std::memcpy(out.data(), title.data(), title.size());
  Append(out, std::uint32_t(mesh.triangle_count()));
  if (Status s = mesh.ForEachTriangle([&](const Eigen::Vector3i& t) {
        Eigen::Vector3f corners[4];
        for (int k = 0; k < 3; ++k) corners[k + 1] = (origin + vertices[t[k]].cast<double>()).cast<float>();
        // The normal from the local (origin-relative) vertices: exact even where world floats are coarse.
        const Eigen::Vector3f &a = vertices[t[0]], &b = vertices[t[1]], &c = vertices[t[2]];
        corners[0] = (b - a).cross(c - a);
        if (corners[0].norm() > 0) corners[0].normalize();
        for (const Eigen::Vector3f& p : corners) Append(out, p.x()), Append(out, p.y()), Append(out, p.z());
        Append(out, std::uint16_t(0));
        return output.Drain();
      });
      !s)
    return s;
  double largest = 0.0;
  for (const auto& v : vertices) largest = std::max(largest, (origin + v.cast<double>()).cwiseAbs().maxCoeff());
  if (FloatRoundingError(largest) > kFloatWarningM) {
    char buf[320];
    std::snprintf(buf, sizeof buf,
                  "STL stores 32-bit floats: '%s' has world coordinates up to %.0f m, rounded by up to %.2f mm; "
                  "write .ply or .obj for exact coordinates",
                  path.string().c_str(), largest, FloatRoundingError(largest) * 1000);
    LogWarning(buf);
  }
  return output.Commit();
}

Status WriteMeshFile(const std::filesystem::path& path, const MeshSource& mesh) {
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  if (ext == ".ply") return WriteMeshPly(path, mesh);
  if (ext == ".obj") return WriteMeshObj(path, mesh);
  if (ext == ".stl") return WriteMeshStl(path, mesh);
  return MakeError(ErrorCode::kInvalidArgument,
                   "cannot write mesh '" + path.string() + "': use a .ply, .obj or .stl file name");
}

Status WriteMeshFile(const std::filesystem::path& path, const Mesh& mesh) {
  return WriteMeshFile(path, InMemoryMesh(mesh));
}

Status WritePointCloudPly(const std::filesystem::path& path, const MeshSource& mesh) {
  ChunkedOutput output(path);
  if (Status s = output.Open(); !s) return s;
  std::string& out = output.bytes();
  out = "ply\nformat binary_little_endian 1.0\ncomment scanreg merged points, world coordinates (metres)\n";
  if (mesh.described()) out += kGapComment;
  out += "element vertex " + std::to_string(mesh.vertex_count()) + "\n" + VertexProperties(mesh) + "end_header\n";
  if (Status s = WriteWorldVertices(mesh, output); !s) return s;
  return output.Commit();
}

}  // namespace scanreg::merge
