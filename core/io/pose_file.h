// Pose files: Stanford .conf, scanreg poses JSON, CloudCompare 4x4 matrix .txt.
// All poses are world_from_scan (p_world = T p_scan), metres.
#pragma once

#include <Eigen/Geometry>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "core/common/expected.h"

namespace scanreg::io {

struct NamedPose {
  NamedPose() = default;
  NamedPose(std::string scan_name, const Eigen::Isometry3d& pose, std::string pose_status = {})
      : scan(std::move(scan_name)), world_from_scan(pose), status(std::move(pose_status)) {}

  std::string scan;  // scan or file name as written in the pose file
  Eigen::Isometry3d world_from_scan = Eigen::Isometry3d::Identity();
  // Optional (JSON and CSV): where the pose comes from, io::PoseStateName(). "unregistered" entries
  // carry no pose: they are written without numbers and the readers leave them out.
  std::string status;
};
inline constexpr char kUnregisteredStatus[] = "unregistered";

// Stanford `.conf`: `bmesh <file> tx ty tz qx qy qz qw` lines; `camera` lines (viewer settings),
// blank lines and `#` comments are ignored; other lines (the dragon's `mesh` of its
// reconstruction) are skipped with a logged warning naming the line. Verified convention (realdata README):
// p_world = R(q)^T p + t with q = (qx, qy, qz, qw) as written.
Expected<std::vector<NamedPose>> ReadBunConf(const std::filesystem::path& path);

// {"version":1,"poses":[{"scan":"name","status":"registered","world_from_scan":[16 numbers, row-major]}]}
// ("status" optional; an "unregistered" entry has no world_from_scan and is not read back)
Expected<std::vector<NamedPose>> ReadPosesJson(const std::filesystem::path& path);
Status WritePosesJson(const std::filesystem::path& path, const std::vector<NamedPose>& poses);  // atomic

// CloudCompare-style matrix file: 4 lines of 4 numbers, row-major.
Expected<Eigen::Isometry3d> ReadMatrixTxt(const std::filesystem::path& path);
Status WriteMatrixTxt(const std::filesystem::path& path, const Eigen::Isometry3d& world_from_scan);  // atomic

}  // namespace scanreg::io
