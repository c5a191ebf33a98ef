#include "tests/bench/pcl_baseline.h"

// GCC 12 reports a false -Warray-bounds inside Eigen's umeyama (SSE load of a Vector3f), inlined
// from PCL's SVD transformation estimation into this file's functions (so the whole file): the
// headers are not ours.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Warray-bounds"
#include <pcl/features/fpfh_omp.h>
#include <pcl/features/normal_3d_omp.h>
#include <pcl/filters/voxel_grid.h>
#include <pcl/io/pcd_io.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/registration/ia_kfpcs.h>
#include <pcl/registration/icp.h>
#include <pcl/registration/sample_consensus_prerejective.h>
#include <pcl/search/kdtree.h>

#include <poll.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <sstream>
#include <string>

#include "tests/bench/bench_table.h"
#include "tests/bench/pcl_clouds.h"

namespace scanreg::bench {
namespace {
struct PclScan {
  pcl::PointCloud<pcl::PointXYZ>::Ptr fine{new pcl::PointCloud<pcl::PointXYZ>};
  pcl::PointCloud<pcl::PointXYZ>::Ptr cloud{new pcl::PointCloud<pcl::PointXYZ>};  // coarse, with features
  pcl::PointCloud<pcl::FPFHSignature33>::Ptr features{new pcl::PointCloud<pcl::FPFHSignature33>};
};

// Voxel grids (scanner frame): the fine cloud for ICP, the coarse one with normals and FPFH; points
// whose normal could not be estimated are dropped (their histograms would be NaN).
PclScan PclPrepare(const Scan& scan, const PclOptions& o) {
  const pcl::PointCloud<pcl::PointXYZ>::Ptr raw = PclPoints(scan, o.max_range_m);
  PclScan out;
  out.fine = Downsample(raw, o.fine_voxel_m);
  pcl::PointCloud<pcl::PointXYZ>::Ptr down = Downsample(out.fine, o.coarse_voxel_m);

  pcl::PointCloud<pcl::Normal>::Ptr normals(new pcl::PointCloud<pcl::Normal>);
  pcl::NormalEstimationOMP<pcl::PointXYZ, pcl::Normal> ne;
  ne.setInputCloud(down);
  ne.setSearchMethod(pcl::search::KdTree<pcl::PointXYZ>::Ptr(new pcl::search::KdTree<pcl::PointXYZ>));
  ne.setRadiusSearch(o.normal_radius_m);
  ne.setViewPoint(0, 0, 0);  // the scanner
  ne.compute(*normals);

  pcl::PointCloud<pcl::Normal>::Ptr good_normals(new pcl::PointCloud<pcl::Normal>);
  for (std::size_t i = 0; i < down->size(); ++i) {
    const pcl::Normal& n = (*normals)[i];
    if (!std::isfinite(n.normal_x) || !std::isfinite(n.normal_y) || !std::isfinite(n.normal_z)) continue;
    out.cloud->push_back((*down)[i]);
    good_normals->push_back(n);
  }
  pcl::FPFHEstimationOMP<pcl::PointXYZ, pcl::Normal, pcl::FPFHSignature33> fpfh;
  fpfh.setInputCloud(out.cloud);
  fpfh.setInputNormals(good_normals);
  fpfh.setSearchMethod(pcl::search::KdTree<pcl::PointXYZ>::Ptr(new pcl::search::KdTree<pcl::PointXYZ>));
  fpfh.setRadiusSearch(o.fpfh_radius_m);
  fpfh.compute(*out.features);
  return out;
}



// ICP on the fine clouds from the global stage's guess; PCL's float matrix, re-orthonormalised in
// double: a float rotation's trace is only good to ~1e-7, which hides (or clamps to 0) angle errors
// below ~0.05 deg in ComparePoses.
void Icp(const PclScan& p, const PclScan& c, const Eigen::Matrix4f& guess, const PclOptions& o, PclPairResult* r) {
  r->seconds_icp = Seconds([&] {
    pcl::PointCloud<pcl::PointXYZ> aligned;
    pcl::IterativeClosestPoint<pcl::PointXYZ, pcl::PointXYZ> icp;
    icp.setInputSource(c.fine);
    icp.setInputTarget(p.fine);
    icp.setMaxCorrespondenceDistance(o.icp_max_distance_m);
    icp.setMaximumIterations(o.icp_iterations);
    icp.align(aligned, guess);
    const Eigen::Matrix4d m = icp.getFinalTransformation().cast<double>();
    r->parent_from_child.linear() =
        Eigen::Quaterniond(Eigen::Matrix3d(m.topLeftCorner<3, 3>())).normalized().toRotationMatrix();
    r->parent_from_child.translation() = m.topRightCorner<3, 1>();
  });
}

void Prepare(const Scan& parent, const Scan& child, const PclOptions& o, PclScan* p, PclScan* c, PclPairResult* r) {
  r->seconds_features = Seconds([&] {
    *p = PclPrepare(parent, o);
    *c = PclPrepare(child, o);
  });
  r->parent_points = p->fine->size();
  r->child_points = c->fine->size();
  r->parent_coarse_points = p->cloud->size();
  r->child_coarse_points = c->cloud->size();
}

}  // namespace

PclPairResult PclRegisterPair(const Scan& parent, const Scan& child, const PclOptions& o) {
  PclPairResult r;
  PclScan p, c;
  Prepare(parent, child, o, &p, &c, &r);
  Eigen::Matrix4f guess = Eigen::Matrix4f::Identity();
  r.seconds_sac = Seconds([&] {
    pcl::PointCloud<pcl::PointXYZ> aligned;
    pcl::SampleConsensusPrerejective<pcl::PointXYZ, pcl::PointXYZ, pcl::FPFHSignature33> sac;
    sac.setInputSource(c.cloud);
    sac.setSourceFeatures(c.features);
    sac.setInputTarget(p.cloud);
    sac.setTargetFeatures(p.features);
    sac.setMaximumIterations(o.max_iterations);
    sac.setNumberOfSamples(o.samples);
    sac.setCorrespondenceRandomness(o.randomness);
    sac.setSimilarityThreshold(o.similarity);
    sac.setMaxCorrespondenceDistance(o.sac_max_distance_m);
    sac.setInlierFraction(o.inlier_fraction);
    sac.align(aligned);
    r.converged = sac.hasConverged();
    guess = sac.getFinalTransformation();
  });
  Icp(p, c, guess, o, &r);
  return r;
}

namespace {

}  // namespace

int RunKfpcsChild(const char* target_pcd, const char* source_pcd, double delta_m, int max_seconds) {
  pcl::PointCloud<pcl::PointXYZ>::Ptr target(new pcl::PointCloud<pcl::PointXYZ>);
  pcl::PointCloud<pcl::PointXYZ>::Ptr source(new pcl::PointCloud<pcl::PointXYZ>);
  if (pcl::io::loadPCDFile(target_pcd, *target) != 0 || pcl::io::loadPCDFile(source_pcd, *source) != 0) return 1;
  pcl::registration::KFPCSInitialAlignment<pcl::PointXYZ, pcl::PointXYZ> kfpcs;
  kfpcs.setInputSource(source);
  kfpcs.setInputTarget(target);
  kfpcs.setNumberOfThreads(2);
  kfpcs.setDelta(static_cast<float>(delta_m), false);
  kfpcs.setScoreThreshold(0.01f);
  kfpcs.setApproxOverlap(0.5f);
  kfpcs.setMaxComputationTime(max_seconds);
  pcl::PointCloud<pcl::PointXYZ> aligned;
  kfpcs.align(aligned);
  const Eigen::Matrix4f m = kfpcs.getFinalTransformation();
  std::printf("%d", kfpcs.hasConverged() ? 1 : 0);
  for (int k = 0; k < 16; ++k) std::printf(" %.9g", double(m(k / 4, k % 4)));
  std::printf("\n");
  return 0;
}

PclPairResult PclKfpcsPair(const Scan& parent, const Scan& child, const PclOptions& o, double timeout_s,
                           bool* timed_out) {
  *timed_out = false;
  PclPairResult r;
  PclScan p, c;
  Prepare(parent, child, o, &p, &c, &r);
  // K-4PCS works on keypoints (Theiler et al.: a few thousand); on the full coarse cloud its base
  // matching ran for more than 5 minutes per pair whatever the time limit. Keypoints here: the
  // coarse cloud thinned to a 2 m grid. It runs in a fresh process (this program re-executed with
  // --kfpcs-child): PCL ignores its own time limit, and a fork of a process that has used OpenMP
  // deadlocks in libgomp (measured), so the child is exec'd, then killed after timeout_s.
  const pcl::PointCloud<pcl::PointXYZ>::Ptr ck = Downsample(c.cloud, o.kfpcs_voxel_m);
  const pcl::PointCloud<pcl::PointXYZ>::Ptr pk = Downsample(p.cloud, o.kfpcs_voxel_m);
  char dir_template[] = "/tmp/scanreg-kfpcs-XXXXXX";
  if (!::mkdtemp(dir_template)) return r;
  const std::string dir = dir_template, target = dir + "/target.pcd", source = dir + "/source.pcd";
  pcl::io::savePCDFileBinary(target, *pk);
  pcl::io::savePCDFileBinary(source, *ck);
  Eigen::Matrix4f guess = Eigen::Matrix4f::Identity();
  r.seconds_sac = Seconds([&] {
    int fds[2];
    if (::pipe(fds) != 0) return;
    const pid_t pid = ::fork();
    if (pid == 0) {
      ::dup2(fds[1], 1);
      ::close(fds[0]);
      ::close(fds[1]);
      const std::string delta = std::to_string(0.5 * o.kfpcs_voxel_m);
      const std::string seconds = std::to_string(static_cast<int>(timeout_s));
      ::execl("/proc/self/exe", "scanreg-bench", "--kfpcs-child", target.c_str(), source.c_str(), delta.c_str(),
              seconds.c_str(), static_cast<char*>(nullptr));
      ::_exit(127);
    }
    ::close(fds[1]);
    if (pid < 0) {
      ::close(fds[0]);
      return;
    }
    std::string text;
    const auto t0 = std::chrono::steady_clock::now();
    for (;;) {
      const double left = timeout_s - std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      pollfd pfd{fds[0], POLLIN, 0};
      if (left <= 0 || ::poll(&pfd, 1, static_cast<int>(1000 * left)) != 1) {
        *timed_out = true;
        break;
      }
      char buf[512];
      const ssize_t got = ::read(fds[0], buf, sizeof buf);
      if (got <= 0) break;
      text.append(buf, static_cast<std::size_t>(got));
    }
    if (*timed_out) ::kill(pid, SIGKILL);
    ::close(fds[0]);
    int status = 0;
    ::waitpid(pid, &status, 0);
    std::istringstream in(text);
    int converged = 0;
    Eigen::Matrix4f m;
    if (!*timed_out && in >> converged) {
      for (int k = 0; k < 16; ++k) in >> m(k / 4, k % 4);
      if (in) {
        r.converged = converged == 1;
        guess = m;
      }
    }
  });
  std::filesystem::remove_all(dir);
  Icp(p, c, guess, o, &r);
  return r;
}

}  // namespace scanreg::bench

#pragma GCC diagnostic pop
