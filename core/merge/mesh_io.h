// Mesh and merged point-cloud export, each written atomically (a failed or interrupted write
// leaves no partial file). PLY and STL hold float coordinates relative to mesh.origin (the PLY
// header carries `comment scanreg_origin X Y Z`); OBJ holds absolute coordinates in text.
#pragma once

#include <Eigen/Geometry>
#include <filesystem>
#include <vector>

#include "core/common/expected.h"
#include "core/merge/mesh.h"

namespace scanreg::merge {

Status WriteMeshPly(const std::filesystem::path& path, const Mesh& mesh);  // binary little-endian
Status WriteMeshObj(const std::filesystem::path& path, const Mesh& mesh);
Status WriteMeshStl(const std::filesystem::path& path, const Mesh& mesh);  // binary
// By extension: .ply, .obj or .stl (case-insensitive); other extensions are an error.
Status WriteMeshFile(const std::filesystem::path& path, const Mesh& mesh);
// Points (world minus origin) as a binary PLY vertex list with the origin comment.
Status WritePointCloudPly(const std::filesystem::path& path, const Eigen::Vector3d& origin,
                          const std::vector<Eigen::Vector3f>& points);

}  // namespace scanreg::merge
