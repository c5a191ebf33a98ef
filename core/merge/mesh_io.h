// Mesh and merged point-cloud export, each written atomically (a failed or interrupted write
// leaves no partial file). Every format holds world coordinates (mesh.origin + vertex), so any
// other program places the mesh on the registered clouds: PLY as doubles, OBJ as text with 1 µm
// digits, STL as the 32-bit floats the format allows (a warning is logged when that rounds a
// coordinate by more than kFloatWarningM: beyond ~1.7 km from the origin).
#pragma once

#include <Eigen/Geometry>
#include <filesystem>
#include <vector>

#include "core/common/expected.h"
#include "core/merge/mesh.h"

namespace scanreg::merge {

constexpr double kFloatWarningM = 1e-4;  // 0.1 mm
// Largest rounding error of a coordinate of this magnitude stored as a 32-bit float (metres).
double FloatRoundingError(double magnitude);

Status WriteMeshPly(const std::filesystem::path& path, const Mesh& mesh);  // binary little-endian
Status WriteMeshObj(const std::filesystem::path& path, const Mesh& mesh);
Status WriteMeshStl(const std::filesystem::path& path, const Mesh& mesh);  // binary
// By extension: .ply, .obj or .stl (case-insensitive); other extensions are an error.
Status WriteMeshFile(const std::filesystem::path& path, const Mesh& mesh);
// Points (world = origin + point) as a binary PLY vertex list of doubles.
Status WritePointCloudPly(const std::filesystem::path& path, const Eigen::Vector3d& origin,
                          const std::vector<Eigen::Vector3f>& points);

}  // namespace scanreg::merge
