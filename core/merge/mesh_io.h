// Mesh and merged point-cloud export, each written atomically (a failed or interrupted write
// leaves no partial file). Every format holds world coordinates (mesh.origin + vertex), so any
// other program places the mesh on the registered clouds: PLY as doubles, OBJ as text with 1 µm
// digits, STL as the 32-bit floats the format allows (a warning is logged when that rounds a
// coordinate by more than kFloatWarningM: beyond ~1.7 km from the origin).
#pragma once

#include <Eigen/Geometry>
#include <filesystem>
#include <functional>
#include <vector>

#include "core/common/expected.h"
#include "core/merge/mesh.h"

namespace scanreg::merge {

constexpr double kFloatWarningM = 1e-4;  // 0.1 mm
// Largest rounding error of a coordinate of this magnitude stored as a 32-bit float (metres).
double FloatRoundingError(double magnitude);

// What the writers read: a mesh in memory (InMemoryMesh) or streamed from disk (MeshSpill).
class MeshSource {
 public:
  virtual ~MeshSource() = default;
  virtual Eigen::Vector3d origin() const = 0;
  virtual std::size_t vertex_count() const = 0;
  virtual std::size_t triangle_count() const = 0;
  // The vertices carry what the measurements say of them (VertexInfo; a default one when not).
  virtual bool described() const = 0;
  virtual bool coloured() const = 0;  // described with the scans' colour
  // f on every vertex (relative to the origin) / triangle, in order; stops at f's first error.
  using VertexVisitor = std::function<Status(const Eigen::Vector3f&, const VertexInfo&)>;
  virtual Status ForEachVertex(const VertexVisitor& f) const = 0;
  virtual Status ForEachTriangle(const std::function<Status(const Eigen::Vector3i&)>& f) const = 0;
};

class InMemoryMesh : public MeshSource {
 public:
  explicit InMemoryMesh(const Mesh& mesh) : mesh_(mesh) {}
  Eigen::Vector3d origin() const override { return mesh_.origin; }
  std::size_t vertex_count() const override { return mesh_.vertices.size(); }
  std::size_t triangle_count() const override { return mesh_.triangles.size(); }
  bool described() const override { return !mesh_.info.empty(); }
  bool coloured() const override { return described() && mesh_.coloured; }
  Status ForEachVertex(const VertexVisitor& f) const override;
  Status ForEachTriangle(const std::function<Status(const Eigen::Vector3i&)>& f) const override;

 private:
  const Mesh& mesh_;
};

// PLY writes each vertex's colour as uchar red green blue (when coloured) and its gap (VertexInfo)
// as float scalar_gap, in metres (when described; CloudCompare reads it as the scalar field "gap",
// PCL as a field); OBJ the colour after x y z (0..1, as MeshLab reads it); STL neither.
// Streamed: PLY and OBJ hold a few megabytes of the file at a time; STL holds the vertices (it
// writes each triangle's corners).
Status WriteMeshPly(const std::filesystem::path& path, const MeshSource& mesh);  // binary little-endian
Status WriteMeshObj(const std::filesystem::path& path, const MeshSource& mesh);
Status WriteMeshStl(const std::filesystem::path& path, const MeshSource& mesh);  // binary
// By extension: .ply, .obj or .stl (case-insensitive); other extensions are an error.
Status WriteMeshFile(const std::filesystem::path& path, const MeshSource& mesh);
Status WriteMeshFile(const std::filesystem::path& path, const Mesh& mesh);
// The mesh's vertices (world = origin + vertex) as a binary PLY vertex list of doubles.
Status WritePointCloudPly(const std::filesystem::path& path, const MeshSource& mesh);

}  // namespace scanreg::merge
