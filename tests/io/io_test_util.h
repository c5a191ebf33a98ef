// Synthetic scans with known content for the io tests.
#pragma once

#include <Eigen/Geometry>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "core/geometry/scan.h"

namespace scanreg::test {

// A panoramic scan of a box room (half sizes 6 x 4 x 2.5 m, scanner 1 m off-centre): row 0 is the
// top (elevation +50 deg), a checker reflectance, and every 7th cell empty (no return).
inline Scan MakeRoomScan(int rows, int cols, const std::string& name = "room") {
  Scan scan(name, rows, cols);
  const Eigen::Vector3d half(6.0, 4.0, 2.5), centre(1.0, -0.5, 0.8);
  for (int r = 0; r < rows; ++r) {
    const double el = (50.0 - 90.0 * r / std::max(1, rows - 1)) * M_PI / 180.0;
    for (int c = 0; c < cols; ++c) {
      if ((r * cols + c) % 7 == 3) continue;
      const double az = -M_PI + (c + 0.5) * 2 * M_PI / cols;
      const Eigen::Vector3d d(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el));
      double t = 1e9;
      for (int k = 0; k < 3; ++k) {
        if (std::abs(d[k]) < 1e-12) continue;
        const double wall = (d[k] > 0 ? half[k] : -half[k]) + centre[k];
        t = std::min(t, wall / d[k]);
      }
      const Eigen::Vector3d p = t * d;
      const float refl =
          0.2f +
          0.6f * float(((int(std::floor(p.x() * 2)) + int(std::floor(p.y() * 2)) + int(std::floor(p.z() * 2))) & 1)) +
          0.001f * float(c % 50);
      scan.Set(r, c, p.cast<float>(), refl);
    }
  }
  EstimateAngularGrid(scan);
  return scan;
}

inline Eigen::Isometry3d MakePose(double angle, const Eigen::Vector3d& axis, const Eigen::Vector3d& t) {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = Eigen::AngleAxisd(angle, axis.normalized()).toRotationMatrix();
  pose.translation() = t;
  return pose;
}

inline std::string ReadBytes(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

inline void WriteBytes(const std::filesystem::path& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary);
  out << bytes;
}

}  // namespace scanreg::test
