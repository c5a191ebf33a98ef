#include "core/registration/geometric_features.h"

#include <pcl/features/fpfh_omp.h>
#include <pcl/features/normal_3d_omp.h>
#include <pcl/kdtree/kdtree_flann.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>

#include "core/registration/cell_search.h"
#include "core/registration/data_scale.h"
#include "core/registration/voxel_filter.h"

namespace scanreg {

struct GeometricFeatures::DescriptorIndex {
  pcl::KdTreeFLANN<pcl::FPFHSignature33> tree;
};

namespace {

// Every levelled scan is levelled by the up its own walls and ground give, not by its z axis, so a
// tripod set up without a compensator (a few degrees off) is levelled as well as one with: a busy
// street with stations tilted up to 5° went from 2, 2, 2 scans of 6 registered to 4, 6, 5 when its
// scans got plan views and the levelled solver (issue 37). Beyond 10°, the 15° bands that sort the
// normals into ground and walls, first taken about z, no longer hold.
constexpr double kMaxLevelTiltRad = 10.0 * M_PI / 180.0;

// Up from the normals: the direction most perpendicular to the walls (normals within 15° of
// horizontal) and most parallel to the ground (within 15° of vertical), refined from z.
void EstimateUp(const std::vector<Eigen::Vector3d>& normals, GeometricFeatures* f) {
  const double c15 = std::cos(15.0 * M_PI / 180.0), s15 = std::sin(15.0 * M_PI / 180.0);
  Eigen::Vector3d up = Eigen::Vector3d::UnitZ();
  long ground = 0, walls = 0;
  for (int round = 0; round < 4; ++round) {
    Eigen::Matrix3d m = Eigen::Matrix3d::Zero();
    ground = walls = 0;
    for (const Eigen::Vector3d& n : normals) {
      const double d = std::abs(n.dot(up));
      if (d > c15) {
        m -= n * n.transpose();
        ++ground;
      } else if (d < s15) {
        m += n * n.transpose();
        ++walls;
      }
    }
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(m);
    Eigen::Vector3d u = eig.eigenvectors().col(0);  // smallest eigenvalue
    if (u.z() < 0) u = -u;
    up = u.normalized();
  }
  f->up = up;
  f->tilt_rad = std::acos(std::clamp(up.z(), -1.0, 1.0));
  const double total = std::max<double>(1.0, normals.size());
  f->levelled = f->tilt_rad < kMaxLevelTiltRad && ground >= 0.05 * total && walls >= 0.05 * total &&
                (ground + walls) >= 0.3 * total;
}

}  // namespace

Eigen::Isometry3d GeometricFeatures::Levelling() const {
  Eigen::Isometry3d out = Eigen::Isometry3d::Identity();
  if (levelled) out.linear() = Eigen::Quaterniond::FromTwoVectors(up, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  return out;
}

Status GeometricOptions::Validate() const {
  auto bad = [](const std::string& m) { return Status(MakeError(ErrorCode::kInvalidArgument, "geometric features: " + m)); };
  if (!(voxel_m >= 0.0) || !std::isfinite(voxel_m)) return bad("the voxel must be >= 0 metres (0: from the data)");
  if (max_samples < 100) return bad("max_samples must be >= 100");
  if (max_keypoints < 10) return bad("max_keypoints must be >= 10");
  if (!(distinctive_fraction > 0.0 && distinctive_fraction <= 1.0)) return bad("distinctive_fraction must be in (0, 1]");
  if (!(normal_radius_voxels >= 1.0) || !(feature_radius_voxels > normal_radius_voxels))
    return bad("need 1 <= normal_radius_voxels < feature_radius_voxels");
  if (!(coarse_scale == 0.0 || (coarse_scale > 1.0 && coarse_scale <= 20.0)))
    return bad("coarse_scale must be 0 (one scale) or in (1, 20] voxels");
  return Status::Ok();
}

double SuggestVoxel(const DataScale& d) { return d.ok() ? std::max(3.0 * d.spacing_m, d.extent_m / 60.0) : 0.0; }

double SuggestVoxel(const Scan& scan) { return SuggestVoxel(MeasureDataScale(scan)); }

double GeometricFeatures::VoxelOf(int point) const {
  for (const Scale& s : scales)
    if (point >= s.begin && point < s.end) return s.voxel_m;
  return voxel_m;
}

namespace {

// Keypoints of one scale: the most curved fraction of its samples, in sample order, thinned evenly
// to at most max_keypoints.
void AddKeypoints(const GeometricFeatures::Scale& scale, const std::vector<float>& curvature,
                  double distinctive_fraction, int max_keypoints, std::vector<int>* keypoints) {
  if (curvature.empty()) return;
  std::vector<float> sorted = curvature;
  const std::size_t cut = static_cast<std::size_t>((1.0 - distinctive_fraction) * (sorted.size() - 1));
  std::nth_element(sorted.begin(), sorted.begin() + cut, sorted.end());
  std::vector<int> distinctive;
  for (std::size_t i = 0; i < curvature.size(); ++i)
    if (distinctive_fraction >= 1.0 || curvature[i] >= sorted[cut]) distinctive.push_back(scale.begin + static_cast<int>(i));
  const int m = static_cast<int>(distinctive.size());
  const int k = std::min(m, max_keypoints);
  for (int i = 0; i < k; ++i) keypoints->push_back(distinctive[static_cast<std::size_t>(i * double(m) / k)]);
}

// Normals, FPFH descriptors and keypoints (the distinctive_fraction most curved samples) of the
// scan's samples at one voxel, appended to *f as a new scale. False when cancelled.
bool DescribeScale(const std::vector<Eigen::Vector3d>& valid, double voxel_m, double distinctive_fraction,
                   const GeometricOptions& options, const CancelToken& cancel, GeometricFeatures* f) {
  GeometricFeatures::Scale scale;
  scale.voxel_m = voxel_m;
  scale.begin = scale.end = static_cast<int>(f->points.size());
  const std::vector<Eigen::Vector3d> samples = ThinEvenly(VoxelDownsample(valid, voxel_m), options.max_samples);
  if (samples.size() < 20) {  // nothing to describe at this scale: no matches from it
    f->scales.push_back(scale);
    return true;
  }
  // Float coordinates relative to the centroid (clouds far from the origin keep their precision).
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  for (const auto& p : samples) origin += p;
  origin /= double(samples.size());
  auto cloud = pcl::make_shared<pcl::PointCloud<pcl::PointXYZ>>();
  cloud->resize(samples.size());
  for (std::size_t i = 0; i < samples.size(); ++i) {
    const Eigen::Vector3f q = (samples[i] - origin).cast<float>();
    (*cloud)[i] = pcl::PointXYZ(q.x(), q.y(), q.z());
  }
  // Neighbours from cells one search radius wide: the k-d tree's neighbours, found faster.
  const double normal_radius = options.normal_radius_voxels * voxel_m, feature_radius = options.feature_radius_voxels * voxel_m;
  // (Cells a hair wider than the radius: a neighbour is never more than one cell away.)
  const auto normal_search = pcl::make_shared<CellSearch>(normal_radius * (1 + 1e-4));
  const auto feature_search = pcl::make_shared<CellSearch>(feature_radius * (1 + 1e-4));
  auto normals = pcl::make_shared<pcl::PointCloud<pcl::Normal>>();
  pcl::NormalEstimationOMP<pcl::PointXYZ, pcl::Normal> ne;
  ne.setInputCloud(cloud);
  ne.setSearchMethod(normal_search);
  ne.setRadiusSearch(normal_radius);
  // Normals face the scanner (the scan frame's origin), as PCL's viewpoint convention.
  const Eigen::Vector3f viewpoint = (-origin).cast<float>();
  ne.setViewPoint(viewpoint.x(), viewpoint.y(), viewpoint.z());
  ne.compute(*normals);
  if (cancel.IsCancelled()) return false;

  pcl::FPFHEstimationOMP<pcl::PointXYZ, pcl::Normal, pcl::FPFHSignature33> fe;
  fe.setInputCloud(cloud);
  fe.setInputNormals(normals);
  fe.setSearchMethod(feature_search);
  fe.setRadiusSearch(feature_radius);
  pcl::PointCloud<pcl::FPFHSignature33> fpfh;
  fe.compute(fpfh);
  if (cancel.IsCancelled()) return false;

  auto kept = pcl::make_shared<pcl::PointCloud<pcl::FPFHSignature33>>();
  std::vector<float> curvature;
  for (std::size_t i = 0; i < samples.size(); ++i) {
    const pcl::Normal& n = (*normals)[i];
    const float* h = fpfh[i].histogram;
    if (!std::isfinite(n.normal_x) || !std::all_of(h, h + 33, [](float v) { return std::isfinite(v); })) continue;
    float sum = 0.f;
    for (int k = 0; k < 33; ++k) sum += h[k];
    if (!(sum > 0.f)) continue;  // too few neighbours
    f->points.push_back(samples[i]);
    Fpfh d;
    std::copy(h, h + 33, d.begin());
    f->descriptors.push_back(d);
    kept->push_back(fpfh[i]);
    f->normals.emplace_back(n.normal_x, n.normal_y, n.normal_z);
    curvature.push_back(n.curvature);
  }
  if (kept->size() < 20) {  // too few described samples: drop them, no matches from this scale
    f->points.resize(scale.begin);
    f->normals.resize(scale.begin);
    f->descriptors.resize(scale.begin);
    f->scales.push_back(scale);
    return true;
  }
  scale.end = static_cast<int>(f->points.size());
  auto index = std::make_shared<GeometricFeatures::DescriptorIndex>();
  index->tree.setInputCloud(kept);
  scale.index = index;
  f->scales.push_back(scale);
  AddKeypoints(scale, curvature, distinctive_fraction, options.max_keypoints, &f->keypoints);
  return true;
}

}  // namespace

Expected<GeometricFeatures> DetectGeometricFeatures(const Scan& scan, const GeometricOptions& options,
                                                    const CancelToken& cancel) {
  if (Status s = options.Validate(); !s) return s.error();
  if (!(options.voxel_m > 0.0)) return MakeError(ErrorCode::kInvalidArgument, "geometric features: no voxel size");
  GeometricFeatures f;
  f.voxel_m = options.voxel_m;
  const std::vector<Eigen::Vector3d> valid = ValidPoints(scan);
  const auto cancelled = [] { return MakeError(ErrorCode::kCancelled, "geometric features cancelled"); };
  if (cancel.IsCancelled() ||
      !DescribeScale(valid, options.voxel_m, options.distinctive_fraction, options, cancel, &f))
    return cancelled();
  if (f.FinestEnd() == 0) {  // nothing to describe: no geometric matches, no levelling
    f.scales.clear();
    return f;
  }
  // The coarse scale's samples are all candidates: at half a metre the curvature no longer tells a
  // corner from a façade (measured: the most curved half gives a 12 m tilted street 3 of 6 scans,
  // every sample 6 of 6).
  if (options.coarse_scale > 0.0 && !DescribeScale(valid, options.coarse_scale * options.voxel_m, 1.0, options, cancel, &f))
    return cancelled();
  EstimateUp(std::vector<Eigen::Vector3d>(f.normals.begin(), f.normals.begin() + f.FinestEnd()), &f);
  return f;
}

std::vector<GeometricMatch> MatchGeometric(const GeometricFeatures& parent, const GeometricFeatures& child,
                                           double ratio) {
  std::vector<GeometricMatch> out;
  const std::size_t scales = std::min(parent.scales.size(), child.scales.size());
  pcl::Indices idx(2), back(1);
  std::vector<float> d2(2), back_d2(1);
  for (std::size_t s = 0; s < scales; ++s) {
    const GeometricFeatures::Scale& ps = parent.scales[s];
    const GeometricFeatures::Scale& cs = child.scales[s];
    if (!ps.index || !cs.index) continue;
    const double near2 = 4.0 * cs.voxel_m * cs.voxel_m;
    for (int k : child.keypoints) {
      if (k < cs.begin || k >= cs.end) continue;
      pcl::FPFHSignature33 q;
      std::copy(child.descriptors[k].begin(), child.descriptors[k].end(), q.histogram);
      if (ps.index->tree.nearestKSearch(q, 2, idx, d2) < 2) continue;
      if (!(d2[0] <= ratio * ratio * d2[1])) continue;
      const int p = ps.begin + static_cast<int>(idx[0]);
      pcl::FPFHSignature33 pd;
      std::copy(parent.descriptors[p].begin(), parent.descriptors[p].end(), pd.histogram);
      if (cs.index->tree.nearestKSearch(pd, 1, back, back_d2) < 1) continue;
      if ((child.points[cs.begin + back[0]] - child.points[k]).squaredNorm() > near2) continue;
      out.push_back({p, k});
    }
  }
  return out;
}

}  // namespace scanreg
