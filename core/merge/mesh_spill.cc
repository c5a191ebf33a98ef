#include "core/merge/mesh_spill.h"

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cstring>
#include <limits>
#include <string>

namespace scanreg::merge {

namespace {

// A vertex in the spill: its position and what the measurements say of it.
struct SpilledVertex {
  Eigen::Vector3f position;
  VertexInfo info;
};

constexpr std::uint32_t kDropped = std::numeric_limits<std::uint32_t>::max();
constexpr std::size_t kChunkItems = 1 << 18;  // read back 256 k vertices or triangles at a time

std::filesystem::path TempName(const std::filesystem::path& dir, const char* what) {
  static std::atomic<int> serial{0};
  return dir / (".scanreg-mesh-" + std::to_string(::getpid()) + "-" + std::to_string(serial++) + "." + what);
}

// Reads `file` from its start in chunks of T, calling f(chunk, count) for each.
template <typename T, typename F>
Status ReadBack(std::FILE* file, const std::filesystem::path& path, std::size_t total, F&& f) {
  if (std::fflush(file) != 0 || std::fseek(file, 0, SEEK_SET) != 0)
    return MakeError(ErrorCode::kIoError, "cannot read back the merge's temporary file " + path.string());
  std::vector<T> chunk(std::min(total, kChunkItems));
  for (std::size_t done = 0; done < total;) {
    const std::size_t n = std::min(chunk.size(), total - done);
    if (std::fread(chunk.data(), sizeof(T), n, file) != n)
      return MakeError(ErrorCode::kIoError, "the merge's temporary file " + path.string() + " is shorter than written");
    if (Status s = f(chunk.data(), n); !s) return s;
    done += n;
  }
  if (std::fseek(file, 0, SEEK_END) != 0)
    return MakeError(ErrorCode::kIoError, "cannot seek the merge's temporary file " + path.string());
  return Status::Ok();
}

}  // namespace

Expected<std::unique_ptr<MeshSpill>> MeshSpill::Create(const std::filesystem::path& dir) {
  std::unique_ptr<MeshSpill> spill(new MeshSpill());
  spill->vertex_path_ = TempName(dir.empty() ? "." : dir, "vertices");
  spill->triangle_path_ = TempName(dir.empty() ? "." : dir, "triangles");
  spill->vertex_file_ = std::fopen(spill->vertex_path_.c_str(), "w+b");
  if (spill->vertex_file_) spill->triangle_file_ = std::fopen(spill->triangle_path_.c_str(), "w+b");
  if (!spill->vertex_file_ || !spill->triangle_file_) {
    return MakeError(ErrorCode::kIoError, "cannot create the merge's temporary files in " + dir.string() + ": " +
                                              std::strerror(errno) + " (the mesh is written there: check the folder)");
  }
  return spill;
}

MeshSpill::~MeshSpill() {
  for (auto [file, path] : {std::make_pair(vertex_file_, vertex_path_), std::make_pair(triangle_file_, triangle_path_)}) {
    if (!file) continue;
    std::fclose(file);
    std::error_code ignored;
    std::filesystem::remove(path, ignored);
  }
}

Status MeshSpill::Flush(std::FILE* file, const std::filesystem::path& path, const void* data, std::size_t bytes) {
  if (bytes == 0 || std::fwrite(data, 1, bytes, file) == bytes) return Status::Ok();
  return MakeError(ErrorCode::kIoError, "cannot write the merge's temporary file " + path.string() + ": " +
                                            std::strerror(errno) + " (is the disk full?)");
}

std::uint32_t MeshSpill::Find(std::uint32_t v) {
  while (parent_[v] != v) v = parent_[v] = parent_[parent_[v]];
  return v;
}

Status MeshSpill::Append(Mesh& piece) {
  if (renumbered_) return MakeError(ErrorCode::kFailed, "merge: a piece appended after the small pieces were removed");
  origin_ = piece.origin;
  const std::size_t first = vertices_;
  if (first + piece.vertices.size() >= 0x7FFFFFFFu)  // ids are int, and the pieces' marks need the top bit
    return MakeError(ErrorCode::kInvalidArgument, "merge: the mesh has more than 2 billion vertices; use a larger voxel");
  undescribed_ = undescribed_ || piece.info.size() != piece.vertices.size();
  coloured_ = coloured_ || piece.coloured;
  std::vector<SpilledVertex> records(piece.vertices.size());
  for (std::size_t i = 0; i < records.size(); ++i) {
    records[i].position = piece.vertices[i];
    if (i < piece.info.size()) records[i].info = piece.info[i];
  }
  if (Status s = Flush(vertex_file_, vertex_path_, records.data(), records.size() * sizeof(SpilledVertex)); !s)
    return s;
  if (Status s = Flush(triangle_file_, triangle_path_, piece.triangles.data(),
                       piece.triangles.size() * sizeof(Eigen::Vector3i));
      !s)
    return s;
  vertices_ += piece.vertices.size();
  triangles_ += piece.triangles.size();
  parent_.resize(vertices_);
  for (std::size_t v = first; v < vertices_; ++v) parent_[v] = std::uint32_t(v);
  for (const Eigen::Vector3i& t : piece.triangles) {
    const std::uint32_t a = Find(std::uint32_t(t[0]));
    parent_[Find(std::uint32_t(t[1]))] = a;
    parent_[Find(std::uint32_t(t[2]))] = a;
  }
  kept_vertices_ = vertices_, kept_triangles_ = triangles_;
  piece.vertices = {};
  piece.triangles = {};
  piece.info = {};
  return Status::Ok();
}

Expected<std::size_t> MeshSpill::RemoveSmallPieces(double min_fraction) {
  if (renumbered_) return std::size_t(0);
  // In the union-find array alone (4 bytes a vertex, no second array). Vertex ids are below
  // kKeepMark (Append): a root's entry is kRoot | its triangle count, then kRoot | keep; every other
  // vertex's entry its root, then kKeepMark or kDropped, then its new id.
  constexpr std::uint32_t kRoot = 0x80000000u, kCount = 0x7FFFFFFFu, kKeepMark = 0x7FFFFFFFu;
  for (std::size_t v = 0; v < vertices_; ++v) parent_[v] = Find(std::uint32_t(v));
  for (std::size_t v = 0; v < vertices_; ++v)
    if (parent_[v] == v) parent_[v] = kRoot;
  auto root_of = [&](std::uint32_t v) { return (parent_[v] & kRoot) ? v : parent_[v]; };
  if (Status s = ReadBack<Eigen::Vector3i>(triangle_file_, triangle_path_, triangles_,
                                           [&](const Eigen::Vector3i* t, std::size_t n) {
                                             for (std::size_t i = 0; i < n; ++i) {
                                               std::uint32_t& entry = parent_[root_of(std::uint32_t(t[i][0]))];
                                               if ((entry & kCount) < kCount) ++entry;  // saturates
                                             }
                                             return Status::Ok();
                                           });
      !s)
    return s.error();
  std::uint32_t largest = 0;
  for (std::size_t v = 0; v < vertices_; ++v)
    if (parent_[v] & kRoot) largest = std::max(largest, parent_[v] & kCount);
  const double keep_from = min_fraction * double(largest);
  std::size_t kept_triangles = 0;
  for (std::size_t v = 0; v < vertices_; ++v) {
    if (!(parent_[v] & kRoot)) continue;
    const std::uint32_t count = parent_[v] & kCount;
    const bool keep = double(count) >= keep_from;
    if (keep) kept_triangles += count;
    parent_[v] = kRoot | (keep ? 1u : 0u);
  }
  for (std::size_t v = 0; v < vertices_; ++v) {  // roots untouched here: every read is of a root
    if (parent_[v] & kRoot) continue;
    parent_[v] = (parent_[parent_[v]] & 1u) ? kKeepMark : kDropped;
  }
  // New ids in vertex order (every vertex belongs to a triangle).
  std::uint32_t next = 0;
  for (std::size_t v = 0; v < vertices_; ++v) {
    const bool keep = parent_[v] == kKeepMark || parent_[v] == (kRoot | 1u);
    parent_[v] = keep ? next++ : kDropped;
  }
  renumbered_ = true;
  kept_vertices_ = next;
  kept_triangles_ = kept_triangles;
  return triangles_ - kept_triangles;
}

Status MeshSpill::ForEachVertex(const VertexVisitor& f) const {
  std::size_t v = 0;
  return ReadBack<SpilledVertex>(vertex_file_, vertex_path_, vertices_, [&](const SpilledVertex* p, std::size_t n) {
    for (std::size_t i = 0; i < n; ++i, ++v) {
      if (renumbered_ && parent_[v] == kDropped) continue;
      if (Status s = f(p[i].position, p[i].info); !s) return s;
    }
    return Status::Ok();
  });
}

Status MeshSpill::ForEachTriangle(const std::function<Status(const Eigen::Vector3i&)>& f) const {
  return ReadBack<Eigen::Vector3i>(triangle_file_, triangle_path_, triangles_,
                                   [&](const Eigen::Vector3i* t, std::size_t n) {
                                     for (std::size_t i = 0; i < n; ++i) {
                                       Eigen::Vector3i out = t[i];
                                       if (renumbered_) {
                                         if (parent_[out[0]] == kDropped) continue;
                                         for (int k = 0; k < 3; ++k) out[k] = int(parent_[out[k]]);
                                       }
                                       if (Status s = f(out); !s) return s;
                                     }
                                     return Status::Ok();
                                   });
}

}  // namespace scanreg::merge
