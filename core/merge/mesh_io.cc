#include "core/merge/mesh_io.h"

#include <algorithm>
#include <cctype>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <string>

#include "core/common/atomic_file.h"

namespace scanreg::merge {

namespace {

template <typename T>
void Append(std::string& out, const T& value) {
  out.append(reinterpret_cast<const char*>(&value), sizeof(T));  // little-endian hosts only (x86, arm)
}

std::string OriginComment(const Eigen::Vector3d& o) {
  char buf[160];
  std::snprintf(buf, sizeof buf, "comment scanreg_origin %.6f %.6f %.6f\n", o.x(), o.y(), o.z());
  return buf;
}

Status WriteAll(const std::filesystem::path& path, const std::string& bytes) {
  AtomicFile file(path);
  if (Status s = file.Open(); !s) return s;
  if (Status s = file.Write(bytes); !s) return s;
  return file.Commit();
}

}  // namespace

Status WriteMeshPly(const std::filesystem::path& path, const Mesh& mesh) {
  std::string out = "ply\nformat binary_little_endian 1.0\ncomment scanreg merged mesh\n" + OriginComment(mesh.origin);
  out += "element vertex " + std::to_string(mesh.vertices.size()) +
         "\nproperty float x\nproperty float y\nproperty float z\n";
  out += "element face " + std::to_string(mesh.triangles.size()) + "\nproperty list uchar int vertex_indices\nend_header\n";
  out.reserve(out.size() + mesh.vertices.size() * 12 + mesh.triangles.size() * 13);
  for (const auto& v : mesh.vertices) Append(out, v.x()), Append(out, v.y()), Append(out, v.z());
  for (const auto& t : mesh.triangles) {
    Append(out, std::uint8_t(3));
    Append(out, std::int32_t(t[0])), Append(out, std::int32_t(t[1])), Append(out, std::int32_t(t[2]));
  }
  return WriteAll(path, out);
}

Status WriteMeshObj(const std::filesystem::path& path, const Mesh& mesh) {
  std::string out = "# scanreg merged mesh: " + std::to_string(mesh.vertices.size()) + " vertices, " +
                    std::to_string(mesh.triangles.size()) + " triangles, absolute coordinates (metres)\n";
  char buf[128];
  for (const auto& v : mesh.vertices) {
    const Eigen::Vector3d p = mesh.origin + v.cast<double>();
    out.append(buf, std::snprintf(buf, sizeof buf, "v %.6f %.6f %.6f\n", p.x(), p.y(), p.z()));
  }
  for (const auto& t : mesh.triangles) {
    out.append(buf, std::snprintf(buf, sizeof buf, "f %d %d %d\n", t[0] + 1, t[1] + 1, t[2] + 1));
  }
  return WriteAll(path, out);
}

Status WriteMeshStl(const std::filesystem::path& path, const Mesh& mesh) {
  std::string out(80, ' ');
  const std::string title = "scanreg merged mesh, coordinates relative to its origin";
  std::memcpy(out.data(), title.data(), title.size());
  Append(out, std::uint32_t(mesh.triangles.size()));
  for (const auto& t : mesh.triangles) {
    const Eigen::Vector3f &a = mesh.vertices[t[0]], &b = mesh.vertices[t[1]], &c = mesh.vertices[t[2]];
    Eigen::Vector3f n = (b - a).cross(c - a);
    if (n.norm() > 0) n.normalize();
    const Eigen::Vector3f* corners[4] = {&n, &a, &b, &c};
    for (const Eigen::Vector3f* p : corners) Append(out, p->x()), Append(out, p->y()), Append(out, p->z());
    Append(out, std::uint16_t(0));
  }
  return WriteAll(path, out);
}

Status WriteMeshFile(const std::filesystem::path& path, const Mesh& mesh) {
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  if (ext == ".ply") return WriteMeshPly(path, mesh);
  if (ext == ".obj") return WriteMeshObj(path, mesh);
  if (ext == ".stl") return WriteMeshStl(path, mesh);
  return MakeError(ErrorCode::kInvalidArgument,
                   "cannot write mesh '" + path.string() + "': use a .ply, .obj or .stl file name");
}

Status WritePointCloudPly(const std::filesystem::path& path, const Eigen::Vector3d& origin,
                          const std::vector<Eigen::Vector3f>& points) {
  std::string out = "ply\nformat binary_little_endian 1.0\ncomment scanreg merged points\n" + OriginComment(origin);
  out += "element vertex " + std::to_string(points.size()) + "\nproperty float x\nproperty float y\nproperty float z\nend_header\n";
  out.reserve(out.size() + points.size() * 12);
  for (const auto& v : points) Append(out, v.x()), Append(out, v.y()), Append(out, v.z());
  return WriteAll(path, out);
}

}  // namespace scanreg::merge
