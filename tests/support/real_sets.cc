#include "tests/support/real_sets.h"

#include <opencv2/imgcodecs.hpp>

#include "core/common/progress.h"
#include "core/io/ply.h"

#include <cstdio>
#include <fstream>
#include <sstream>

namespace scanreg::test {

namespace {

// fr3's intrinsics (TUM: its images are undistorted and the depth registered to the colour).
constexpr double kFx = 535.4, kFy = 539.2, kCx = 320.1, kCy = 247.6;
constexpr double kDepthPerMetre = 5000.0;

Expected<Scan> ReadDepthFrame(const std::filesystem::path& depth_png, const std::filesystem::path& rgb_jpg,
                              const std::string& name) {
  const cv::Mat depth = cv::imread(depth_png.string(), cv::IMREAD_ANYDEPTH);
  const cv::Mat grey = cv::imread(rgb_jpg.string(), cv::IMREAD_GRAYSCALE);
  if (depth.empty() || depth.type() != CV_16UC1)
    return MakeError(ErrorCode::kParseError, depth_png.string() + ": not a 16-bit depth image");
  if (grey.size() != depth.size()) return MakeError(ErrorCode::kParseError, rgb_jpg.string() + ": missing or not the depth image's size");
  Scan s(name, depth.rows, depth.cols);
  for (int r = 0; r < depth.rows; ++r)
    for (int c = 0; c < depth.cols; ++c) {
      const std::uint16_t d = depth.at<std::uint16_t>(r, c);
      if (d == 0) continue;
      const double z = d / kDepthPerMetre;
      s.Set(r, c, Eigen::Vector3f(float((c - kCx) * z / kFx), float((r - kCy) * z / kFy), float(z)),
            grey.at<std::uint8_t>(r, c) / 255.0f);
    }
  return s;
}

// A folder of PLY scans and its poses.txt: `<file> r11 r12 r13 t1 r21 r22 r23 t2 r31 r32 r33 t3` per
// line, p_ref = R p_scan + t.
Expected<RealSet> LoadPlySet(const std::filesystem::path& dir, const std::string& name) {
  std::ifstream in(dir / "poses.txt");
  if (!in) return MakeError(ErrorCode::kIoError, (dir / "poses.txt").string() + ": cannot be read");
  RealSet set;
  set.name = name;
  NullProgress progress;
  CancelToken cancel;
  for (std::string line; std::getline(in, line);) {
    std::istringstream fields(line);
    std::string file;
    Eigen::Matrix<double, 3, 4> m;
    if (!(fields >> file)) continue;
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 4; ++c)
        if (!(fields >> m(r, c))) return MakeError(ErrorCode::kParseError, (dir / "poses.txt").string() + ": bad line for " + file);
    Expected<Scan> s = io::ReadPly(dir / file, progress, cancel);
    if (!s.ok()) return s.error();
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    pose.linear() = m.leftCols<3>();
    pose.translation() = m.col(3);
    s->name = std::filesystem::path(file).stem().string();
    s->reference_world_from_scan = pose;
    set.scans.push_back(std::move(*s));
  }
  if (set.scans.size() < 2) return MakeError(ErrorCode::kParseError, (dir / "poses.txt").string() + ": fewer than two scans");
  return set;
}

}  // namespace

Expected<RealSet> LoadKittiVelodyne(const std::filesystem::path& realdata) {
  Expected<RealSet> set = LoadPlySet(realdata / "kitti00_velodyne", "kitti00_velodyne");
  if (!set.ok()) return set;
  // The reference is 0.13-0.17 m a frame off along the way the car drives, 0.45 m from the first to
  // the last scan, and 0.12-0.41 deg (an independent ICP, SOURCES.md); the HDL-64E's noise ~2 cm.
  set->within_m = 0.17 + 2 * 0.02;
  set->within_m_per_step = 0.15;
  set->within_deg = 0.5;
  set->wrong_m = 1.0;
  set->wrong_deg = 2.0;
  return set;
}

Expected<RealSet> Load3dtkCorridor(const std::filesystem::path& realdata) {
  Expected<RealSet> set = LoadPlySet(realdata / "3dtk_robot_scans", "3dtk_robot_scans");
  if (!set.ok()) return set;
  // The authors' registrations disagree by up to 12 cm / 0.9 deg; the scanner's noise ~1-2 cm.
  set->within_m = 0.12 + 2 * 0.02;
  set->within_deg = 1.5;
  set->wrong_m = 0.3;
  set->wrong_deg = 3.0;
  return set;
}

Expected<RealSet> LoadTumCabinet(const std::filesystem::path& realdata) {
  const std::filesystem::path dir = realdata / "tum_fr3_cabinet";
  // Line k of truth_cam_poses.txt is keyframe k: timestamp tx ty tz qx qy qz qw, camera to world.
  std::ifstream in(dir / "truth_cam_poses.txt");
  if (!in) return MakeError(ErrorCode::kIoError, (dir / "truth_cam_poses.txt").string() + ": cannot be read");
  std::vector<Eigen::Isometry3d> poses;
  for (std::string line; std::getline(in, line);) {
    std::istringstream fields(line);
    double stamp, tx, ty, tz, qx, qy, qz, qw;
    if (!(fields >> stamp >> tx >> ty >> tz >> qx >> qy >> qz >> qw)) continue;
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    pose.linear() = Eigen::Quaterniond(qw, qx, qy, qz).normalized().toRotationMatrix();
    pose.translation() = Eigen::Vector3d(tx, ty, tz);
    poses.push_back(pose);
  }
  RealSet set;
  set.name = "tum_fr3_cabinet";
  for (int k = 30; k <= 41; ++k) {
    char stem[16];
    std::snprintf(stem, sizeof stem, "%04d", k);
    if (k >= static_cast<int>(poses.size())) return MakeError(ErrorCode::kParseError, (dir / "truth_cam_poses.txt").string() + ": too few poses");
    Expected<Scan> s = ReadDepthFrame(dir / "depth" / (std::string(stem) + "_depth_raw.png"),
                                      dir / "rgb" / (std::string(stem) + "_rgb_raw.jpg"), std::string("f") + stem);
    if (!s.ok()) return s.error();
    s->reference_world_from_scan = poses[k];
    set.scans.push_back(std::move(*s));
  }
  // Keyframe poses are good to a few cm / 1-2 deg (SOURCES.md); the Kinect's depth noise ~5 mm at 1.5 m.
  set.within_m = 0.03 + 2 * 0.005;
  set.within_deg = 2.0;
  set.wrong_m = 0.10;
  set.wrong_deg = 4.0;
  return set;
}

}  // namespace scanreg::test
