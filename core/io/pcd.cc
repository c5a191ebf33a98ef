#include "core/io/pcd.h"

#include <pcl/PCLPointCloud2.h>
#include <pcl/console/print.h>
#include <pcl/conversions.h>
#include <pcl/exceptions.h>
#include <pcl/io/pcd_io.h>
#include <pcl/point_types.h>

#include <cmath>
#include <limits>

#include "core/common/atomic_file.h"
#include "core/io/organize_default.h"
#include "core/io/pcd_header.h"

namespace scanreg::io {

namespace {

bool HasField(const pcl::PCLPointCloud2& cloud, const std::string& name) {
  for (const auto& f : cloud.fields)
    if (f.name == name) return true;
  return false;
}

}  // namespace

Expected<Scan> ReadPcd(const std::filesystem::path& path, ProgressSink& progress, const CancelToken& cancel) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) {
    return MakeError(ErrorCode::kNotFound, path.string() + ": no such file; check the path");
  }
  // PCL trusts the header: check it against itself and the file's size first.
  if (Expected<PcdHeader> header = ReadPcdHeader(path); !header) return header.error();
  const std::string stage = "reading " + path.filename().string();
  progress.Report(0.0, stage);
  pcl::PCLPointCloud2 blob;
  Eigen::Vector4f origin = Eigen::Vector4f::Zero();
  Eigen::Quaternionf orientation = Eigen::Quaternionf::Identity();
  int version = 0;
  pcl::PCDReader reader;
  pcl::console::setVerbosityLevel(pcl::console::L_ALWAYS);  // our one-line errors instead of PCL's prints
  int read = -1;
  std::string pcl_message;
  try {
    read = reader.read(path.string(), blob, origin, orientation, version);
  } catch (const std::exception& e) {  // pcl::PCLException, std::bad_alloc
    pcl_message = std::string(" (") + e.what() + ")";
  }
  if (read < 0) {
    return MakeError(ErrorCode::kParseError,
                     path.string() + ": PCL cannot read the data of this PCD file" + pcl_message +
                         "; the header is consistent, so the data section is damaged (a value that is not a "
                         "number, a short line, corrupt compression)");
  }
  if (!HasField(blob, "x") || !HasField(blob, "y") || !HasField(blob, "z")) {
    return MakeError(ErrorCode::kUnsupported, path.string() + ": the PCD file has no x, y, z fields");
  }
  if (cancel.IsCancelled()) return MakeError(ErrorCode::kCancelled, path.string() + ": cancelled");
  progress.Report(0.6, stage);
  pcl::PointCloud<pcl::PointXYZI> cloud;
  const bool has_intensity = HasField(blob, "intensity");
  if (has_intensity) {
    pcl::fromPCLPointCloud2(blob, cloud);
  } else {
    pcl::PointCloud<pcl::PointXYZ> xyz;
    pcl::fromPCLPointCloud2(blob, xyz);
    cloud.resize(xyz.size());
    cloud.width = xyz.width;
    cloud.height = xyz.height;
    for (std::size_t i = 0; i < xyz.size(); ++i) {
      cloud[i].x = xyz[i].x, cloud[i].y = xyz[i].y, cloud[i].z = xyz[i].z;
      cloud[i].intensity = 0.5f;
    }
  }
  std::vector<Rgb> colour;  // from an rgb or rgba field (PCL packs 8-bit channels)
  if (HasField(blob, "rgb") || HasField(blob, "rgba")) {
    pcl::PointCloud<pcl::PointXYZRGB> rgb;
    pcl::fromPCLPointCloud2(blob, rgb);
    colour.reserve(rgb.size());
    for (const pcl::PointXYZRGB& p : rgb) colour.push_back(Rgb{p.r, p.g, p.b});
  }
  blob = pcl::PCLPointCloud2();  // free memory early
  const std::string name = path.stem().string();
  Scan scan;
  if (cloud.height > 1) {
    scan = Scan(name, static_cast<int>(cloud.height), static_cast<int>(cloud.width));
    if (!colour.empty()) scan.AddColour();
    for (int r = 0; r < scan.rows; ++r) {
      for (int c = 0; c < scan.cols; ++c) {
        const pcl::PointXYZI& p = cloud.at(c, r);
        const Eigen::Vector3f q(p.x, p.y, p.z);
        if (!q.allFinite() || q.isZero()) continue;
        scan.Set(r, c, q, std::isfinite(p.intensity) ? p.intensity : 0.5f);
        if (!colour.empty()) scan.colour[scan.Index(r, c)] = colour[static_cast<std::size_t>(r) * scan.cols + c];
      }
    }
  } else {
    std::vector<Eigen::Vector3f> points;
    std::vector<float> reflectance;
    points.reserve(cloud.size());
    reflectance.reserve(cloud.size());
    for (const auto& p : cloud) {
      points.emplace_back(p.x, p.y, p.z);
      reflectance.push_back(std::isfinite(p.intensity) ? p.intensity : 0.5f);
    }
    Expected<Scan> organized = OrganizeCloudByDensity(points, reflectance, name, path.string(), colour);
    if (!organized) return organized.error();
    scan = std::move(*organized);
  }
  scan.world_from_scan = Eigen::Isometry3d::Identity();
  scan.world_from_scan.linear() = orientation.cast<double>().normalized().toRotationMatrix();
  scan.world_from_scan.translation() = origin.head<3>().cast<double>();
  if (!scan.world_from_scan.matrix().allFinite()) {
    return MakeError(ErrorCode::kParseError, path.string() + ": the VIEWPOINT line does not give a pose PCL can read; "
                                                             "write it as 7 finite numbers, e.g. VIEWPOINT 0 0 0 1 0 0 0");
  }
  progress.Report(1.0, stage);
  return scan;
}

Status WritePcd(const std::filesystem::path& path, const Scan& scan, ProgressSink& progress,
                const CancelToken& cancel) {
  if (Status s = scan.Validate(); !s) return s;
  if (cancel.IsCancelled()) return MakeError(ErrorCode::kCancelled, path.string() + ": writing cancelled");
  const std::string stage = "writing " + path.filename().string();
  progress.Report(0.0, stage);
  pcl::PointCloud<pcl::PointXYZI> cloud;
  if (!scan.list_points.empty()) {  // points off the grid: an unorganized cloud of every point
    scan.ForEachPoint([&](const Eigen::Vector3f& q, float refl) {
      pcl::PointXYZI p;
      p.x = q.x(), p.y = q.y(), p.z = q.z();
      p.intensity = refl;
      cloud.push_back(p);
    });
  } else {
    cloud =
        pcl::PointCloud<pcl::PointXYZI>(static_cast<std::uint32_t>(scan.cols), static_cast<std::uint32_t>(scan.rows));
  }
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (int r = 0; r < scan.rows && scan.list_points.empty(); ++r) {
    for (int c = 0; c < scan.cols; ++c) {
      pcl::PointXYZI& p = cloud.at(c, r);
      const std::size_t i = scan.Index(r, c);
      if (scan.valid[i]) {
        p.x = scan.points[i].x(), p.y = scan.points[i].y(), p.z = scan.points[i].z();
        p.intensity = scan.reflectance[i];
      } else {
        p.x = p.y = p.z = nan;
        p.intensity = 0.0f;
      }
    }
  }
  cloud.is_dense = false;
  const Eigen::Vector3d t = scan.world_from_scan.translation();
  cloud.sensor_origin_ = Eigen::Vector4f(float(t.x()), float(t.y()), float(t.z()), 0.0f);
  cloud.sensor_orientation_ = Eigen::Quaternionf(Eigen::Quaterniond(scan.world_from_scan.linear()).cast<float>());
  progress.Report(0.3, stage);

  AtomicFile file(path);
  if (Status s = file.Open(); !s) return s;
  if (Status s = file.CloseForExternalWriter(); !s) return s;
  pcl::PCDWriter writer;
  int written = -1;
  try {
    written = writer.writeBinary(file.temp_path().string(), cloud);
  } catch (const std::exception&) {  // pcl::IOException on a full disk
    written = -1;
  }
  if (written < 0) {
    return MakeError(ErrorCode::kIoError, path.string() +
                                              ": PCL could not write the PCD file; check the folder "
                                              "is writable and has free space");
  }
  if (Status s = file.Commit(); !s) return s;
  progress.Report(1.0, stage);
  return Status::Ok();
}

}  // namespace scanreg::io
