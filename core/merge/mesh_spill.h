// A merged mesh kept on disk while it is built and written (issue 13, item 5: a merge's memory does
// not grow with its mesh). A tiled merge appends each tile's vertices and triangles to two
// temporary files and tracks the connected pieces as they come (union-find, 4 bytes a vertex);
// small pieces are then dropped by renumbering, and the writers (mesh_io.h) stream the files —
// the whole mesh is never in memory. The files are removed with the spill.
#pragma once

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <vector>

#include "core/common/expected.h"
#include "core/merge/mesh.h"
#include "core/merge/mesh_io.h"

namespace scanreg::merge {

class MeshSpill : public MeshSource {
 public:
  // Two temporary files in `dir` (where the output goes: the space the mesh needs is there).
  static Expected<std::unique_ptr<MeshSpill>> Create(const std::filesystem::path& dir);
  ~MeshSpill() override;
  MeshSpill(const MeshSpill&) = delete;
  MeshSpill& operator=(const MeshSpill&) = delete;

  // Appends a piece (MeshBuilder::Take: its triangles index every vertex appended so far and its
  // own) and empties it.
  Status Append(Mesh& piece);
  // Drops the pieces with fewer triangles than min_fraction x the largest piece's (as
  // RemoveSmallPieces does in memory). Returns the number of triangles removed.
  Expected<std::size_t> RemoveSmallPieces(double min_fraction);

  // The folder of its files.
  std::filesystem::path directory() const { return vertex_path_.parent_path(); }

  Eigen::Vector3d origin() const override { return origin_; }
  std::size_t vertex_count() const override { return kept_vertices_; }
  std::size_t triangle_count() const override { return kept_triangles_; }
  bool described() const override { return vertices_ > 0 && !undescribed_; }
  bool coloured() const override { return described() && coloured_; }
  Status ForEachVertex(const VertexVisitor& f) const override;
  Status ForEachTriangle(const std::function<Status(const Eigen::Vector3i&)>& f) const override;

 private:
  MeshSpill() = default;
  std::uint32_t Find(std::uint32_t v);
  Status Flush(std::FILE* file, const std::filesystem::path& path, const void* data, std::size_t bytes);

  Eigen::Vector3d origin_ = Eigen::Vector3d::Zero();
  std::filesystem::path vertex_path_, triangle_path_;
  std::FILE* vertex_file_ = nullptr;
  std::FILE* triangle_file_ = nullptr;
  std::size_t vertices_ = 0, triangles_ = 0;            // appended
  std::size_t kept_vertices_ = 0, kept_triangles_ = 0;  // after RemoveSmallPieces
  std::vector<std::uint32_t> parent_;  // union-find over vertices; after RemoveSmallPieces: new ids
  bool renumbered_ = false;
  bool undescribed_ = false;  // a piece came without VertexInfo for each vertex
  bool coloured_ = false;     // a piece came coloured
};

}  // namespace scanreg::merge
