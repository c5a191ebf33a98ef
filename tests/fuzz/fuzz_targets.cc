#include "tests/fuzz/fuzz_targets.h"

#include <cmath>
#include <fstream>
#include <sstream>

#include "core/features/feature_cache.h"
#include "core/io/e57_reader.h"
#include "core/io/e57_writer.h"
#include "core/io/las_reader.h"
#include "core/io/las_writer.h"
#include "core/io/pcd.h"
#include "core/io/ply.h"
#include "core/io/pose_csv.h"
#include "core/io/pose_file.h"
#include "core/io/scan_cache.h"
#include "core/io/project.h"
#include "core/io/ptx.h"

namespace scanreg::fuzz {
namespace {

namespace fs = std::filesystem;

// A small scan of a room corner: a wall, a floor and a gap, with an angular grid and reflectance.
Scan SeedScan(const std::string& name, int rows, int cols, double turn) {
  Scan s(name, rows, cols);
  s.angles.azimuth.resize(cols);
  s.angles.elevation.resize(rows);
  for (int c = 0; c < cols; ++c) s.angles.azimuth[c] = float(-0.6 + 1.2 * c / cols);
  for (int r = 0; r < rows; ++r) s.angles.elevation[r] = float(0.4 - 0.8 * r / rows);
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c < cols; ++c) {
      const std::size_t i = std::size_t(r) * cols + c;
      const double az = s.angles.azimuth[c], el = s.angles.elevation[r];
      const Eigen::Vector3d dir(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el));
      const double range = el < -0.1 ? -1.5 / dir.z() : 4.0 / std::max(0.2, dir.x());
      s.valid[i] = (r + c) % 11 != 3;
      if (!s.valid[i]) continue;
      s.points[i] = (range * dir).cast<float>();
      s.reflectance[i] = float(0.2 + 0.6 * ((r * 7 + c * 3) % 10) / 10.0);
    }
  s.world_from_scan = Eigen::Translation3d(1.0 + turn, -2.0, 0.3) * Eigen::AngleAxisd(turn, Eigen::Vector3d::UnitZ());
  return s;
}

std::string Slurp(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream out;
  out << in.rdbuf();
  return out.str();
}

// The promises every reader makes about its errors: one line, printable (control bytes escaped).
std::string CheckError(const Error& e) {
  if (e.message.empty()) return "an error without a message";
  for (unsigned char ch : e.message)
    if (ch < 0x20 || ch == 0x7f) return "an error message with a raw control byte: " + e.message.substr(0, 200);
  return "";
}

std::string CheckScans(const std::vector<Scan>& scans) {
  if (scans.empty()) return "accepted a file with no scan";
  for (const Scan& s : scans) {
    if (Status v = s.Validate(); !v) return "accepted an invalid scan '" + s.name + "': " + v.error().message;
    if (!s.world_from_scan.matrix().allFinite()) return "accepted a scan with a non-finite pose";
  }
  return "";
}

std::string CheckPose(const Eigen::Isometry3d& pose, const std::string& what) {
  if (!pose.matrix().allFinite()) return "accepted a non-finite pose (" + what + ")";
  const Eigen::Matrix3d r = pose.linear();
  if ((r.transpose() * r - Eigen::Matrix3d::Identity()).norm() > 1e-3 || r.determinant() < 0.5)
    return "accepted a pose that is not a rotation (" + what + ")";
  return "";
}

template <typename T, typename Check>
std::string Judge(const Expected<T>& result, bool* accepted, Check check) {
  *accepted = result.ok();
  return result.ok() ? check(*result) : CheckError(result.error());
}

std::string CheckPoses(const std::vector<io::NamedPose>& poses) {
  for (const io::NamedPose& p : poses)
    if (std::string why = CheckPose(p.world_from_scan, p.scan); !why.empty()) return why;
  return "";
}

}  // namespace

std::vector<FuzzTarget> MakeTargets(const fs::path& work_dir) {
  fs::create_directories(work_dir / "seeds");
  const fs::path seeds = work_dir / "seeds";
  NullProgress progress;
  CancelToken cancel;
  const std::vector<Scan> scans = {SeedScan("a", 6, 10, 0.0), SeedScan("b", 5, 8, 0.7)};
  auto written = [&](const std::string& file, const std::function<Status(const fs::path&)>& write) {
    const fs::path path = seeds / file;
    if (Status s = write(path); !s) throw std::runtime_error("seed " + file + ": " + s.error().message);
    return Slurp(path);
  };
  std::vector<FuzzTarget> targets;

  FuzzTarget ptx{"ptx", ".ptx", {}, nullptr};
  ptx.seeds.push_back(written("two.ptx", [&](const fs::path& p) { return io::WritePtx(p, scans, progress, cancel); }));
  ptx.read = [](const fs::path& f, bool* ok) {
    NullProgress progress;
    return Judge(io::ReadPtx(f, progress, CancelToken()), ok, CheckScans);
  };
  targets.push_back(ptx);

  FuzzTarget e57{"e57", ".e57", {}, nullptr};
  e57.seeds.push_back(written("two.e57", [&](const fs::path& p) { return io::WriteE57(p, scans, progress, cancel); }));
  {  // GPS times: a timeStamp per point from the scan's acquisitionStart
    Scan timed = scans[0];
    timed.AddTime();
    for (std::size_t i = 0; i < timed.size(); ++i) timed.time[i] = 3.2e8 + 0.001 * double(i);
    timed.time_base = io::kAdjustedGpsTime;
    e57.seeds.push_back(written("timed.e57", [&](const fs::path& p) { return io::WriteE57(p, {timed}, progress, cancel); }));
  }
  e57.read = [](const fs::path& f, bool* ok) {
    NullProgress progress;
    return Judge(io::ReadE57(f, io::E57ReadOptions(), progress, CancelToken()), ok, CheckScans);
  };
  targets.push_back(e57);

  FuzzTarget ply{"ply", ".ply", {}, nullptr};
  ply.seeds.push_back(written("a.ply", [&](const fs::path& p) { return io::WritePly(p, scans[0], progress, cancel); }));
  ply.seeds.push_back(  // ASCII, as many other programs write it
      "ply\nformat ascii 1.0\ncomment by hand\nelement vertex 4\nproperty float x\nproperty float y\n"
      "property float z\nproperty uchar intensity\nelement face 1\nproperty list uchar int vertex_indices\n"
      "end_header\n0 0 0 10\n1 0 0 20\n0 1 0 30\n1 1 0.5 40\n3 0 1 2\n");
  ply.read = [](const fs::path& f, bool* ok) {
    NullProgress progress;
    return Judge(io::ReadPly(f, progress, CancelToken()), ok, [](const Scan& s) { return CheckScans({s}); });
  };
  targets.push_back(ply);

  FuzzTarget pcd{"pcd", ".pcd", {}, nullptr};
  pcd.seeds.push_back(written("a.pcd", [&](const fs::path& p) { return io::WritePcd(p, scans[1], progress, cancel); }));
  pcd.seeds.push_back(
      "# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\nFIELDS x y z intensity\nSIZE 4 4 4 4\n"
      "TYPE F F F F\nCOUNT 1 1 1 1\nWIDTH 3\nHEIGHT 2\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 6\nDATA ascii\n"
      "1 0 0 0.5\n1 0.1 0 0.4\n1 0.2 0 0.3\n1 0 0.1 0.2\n1 0.1 0.1 0.1\nnan nan nan 0\n");
  pcd.read = [](const fs::path& f, bool* ok) {
    NullProgress progress;
    return Judge(io::ReadPcd(f, progress, CancelToken()), ok, [](const Scan& s) { return CheckScans({s}); });
  };
  targets.push_back(pcd);

  FuzzTarget las{"las", ".las", {}, nullptr};  // LAS 1.4 format 6, as our export writes it
  las.seeds.push_back(written("a.las", [&](const fs::path& p) {
    io::LasCloud cloud;
    for (std::size_t i = 0; i < scans[0].size(); ++i) {
      if (!scans[0].valid[i]) continue;
      cloud.points.push_back(scans[0].world_from_scan * scans[0].points[i].cast<double>());
      cloud.reflectance.push_back(scans[0].reflectance[i]);
    }
    return io::WriteLas(p, cloud);
  }));
  las.read = [](const fs::path& f, bool* ok) {
    NullProgress progress;
    return Judge(io::ReadLas(f, progress, CancelToken()), ok, [](const Scan& s) { return CheckScans({s}); });
  };
  targets.push_back(las);

  FuzzTarget project{"project", ".scanreg.json", {}, nullptr};
  {
    io::Project p;
    for (const Scan& s : scans) {
      io::ProjectScan ps;
      ps.name = s.name;
      ps.path = seeds / "two.ptx";
      ps.world_from_scan = s.world_from_scan;
      ps.registered = true;
      p.scans.push_back(ps);
    }
    io::LinkRecord link;
    link.parent = "a", link.child = "b", link.method = "epnp+keypoints";
    p.links.push_back(link);
    p.root = "a";
    p.settings["noise"] = "0.01";
    p.confusion = Eigen::MatrixXi::Ones(2, 2);
    p.confusion_scans = {"a", "b"};
    // Saved beside the fuzz input (scan paths are relative to the project file).
    const fs::path file = work_dir / "seed.scanreg.json";
    if (Status st = io::SaveProject(p, file); !st) throw std::runtime_error("seed project: " + st.error().message);
    project.seeds.push_back(Slurp(file));
  }
  project.read = [](const fs::path& f, bool* ok) {
    return Judge(io::LoadProject(f), ok, [](const io::Project& p) {
      for (const io::ProjectScan& s : p.scans)
        if (std::string why = CheckPose(s.world_from_scan, s.name); !why.empty()) return why;
      return std::string();
    });
  };
  targets.push_back(project);

  std::vector<io::NamedPose> poses;
  for (const Scan& s : scans) poses.emplace_back(s.name, s.world_from_scan);
  FuzzTarget json{"poses-json", ".json", {}, nullptr};
  json.seeds.push_back(written("poses.json", [&](const fs::path& p) { return io::WritePosesJson(p, poses); }));
  json.read = [](const fs::path& f, bool* ok) { return Judge(io::ReadPosesJson(f), ok, CheckPoses); };
  targets.push_back(json);

  FuzzTarget csv{"poses-csv", ".csv", {}, nullptr};
  csv.seeds.push_back(written("poses.csv", [&](const fs::path& p) { return io::WritePosesCsv(p, poses); }));
  csv.read = [](const fs::path& f, bool* ok) { return Judge(io::ReadPosesCsv(f), ok, CheckPoses); };
  targets.push_back(csv);

  FuzzTarget conf{"bun-conf", ".conf", {}, nullptr};
  conf.seeds.push_back(  // the Stanford repository's format: camera, then bmesh lines (translation, quaternion)
      "camera -0.0172 -0.0936 -0.734 -0.0461723 0.970603 -0.235889 0.0124573\n"
      "bmesh bun000.ply 0 0 0 0 0 0 1\nbmesh bun045.ply -0.0520211 -0.000383981 -0.0109223 0.00548449 "
      "-0.294635 -0.0038555 0.955586\n");
  conf.read = [](const fs::path& f, bool* ok) { return Judge(io::ReadBunConf(f), ok, CheckPoses); };
  targets.push_back(conf);

  FuzzTarget matrix{"matrix", ".txt", {}, nullptr};
  matrix.seeds.push_back(written("m.txt", [&](const fs::path& p) { return io::WriteMatrixTxt(p, scans[1].world_from_scan); }));
  matrix.read = [](const fs::path& f, bool* ok) {
    return Judge(io::ReadMatrixTxt(f), ok, [](const Eigen::Isometry3d& m) { return CheckPose(m, "matrix"); });
  };
  targets.push_back(matrix);

  // A feature cache entry of a textured scan, parsed for that scan under its key.
  FuzzTarget cache{"feature-cache", ".feat", {}, nullptr};
  {
    // Blobs of several sizes on a 120 x 360 grid: SIFT finds keypoints (an entry without any would
    // leave most of the parser unexercised).
    Scan textured = SeedScan("t", 120, 360, 0.2);
    for (int r = 0; r < textured.rows; ++r)
      for (int c = 0; c < textured.cols; ++c) {
        const double blobs = std::sin(c * 0.21) * std::cos(r * 0.17) + 0.5 * std::sin(c * 0.05 + r * 0.09);
        textured.reflectance[std::size_t(r) * textured.cols + c] = float(0.5 + 0.3 * blobs);
      }
    const SiftOptions options;
    const fs::path dir = seeds / "cache";
    Expected<ScanFeatures> detected = LoadOrDetectFeatures(textured, options, dir);
    if (!detected.ok() || detected->keypoints.size() < 10)
      throw std::runtime_error("seed feature cache: too few keypoints to exercise the parser");
    cache.seeds.push_back(Slurp(FeatureCachePath(textured, options, dir)));
    const std::uint64_t key = FeatureCacheKey(textured, options);
    cache.read = [textured, key](const fs::path& f, bool* ok) {
      return Judge(ParseFeatureCacheEntry(Slurp(f), key, textured), ok, [](const ScanFeatures& sf) {
        return sf.descriptors.size() == sf.keypoints.size() * 128 ? std::string() : "descriptor count mismatch";
      });
    };
  }
  targets.push_back(cache);

  // A binary scan cache entry (issue 13) of two scans, parsed under its key.
  FuzzTarget scan_cache{"scan-cache", ".scan", {}, nullptr};
  {
    const std::uint64_t key = 0x5CA7C4C4E0000001ULL;
    const std::vector<Scan> two = {SeedScan("a", 20, 40, 0.1), SeedScan("b", 10, 30, 0.3)};
    scan_cache.seeds.push_back(io::SerializeScanCache(two, key));
    scan_cache.read = [key](const fs::path& f, bool* ok) {
      return Judge(io::ParseScanCache(Slurp(f), key), ok, [](const std::vector<Scan>& scans) {
        for (const Scan& s : scans)
          if (Status v = s.Validate(); !v) return v.error().message;
        return std::string();
      });
    };
  }
  targets.push_back(scan_cache);
  return targets;
}

}  // namespace scanreg::fuzz
