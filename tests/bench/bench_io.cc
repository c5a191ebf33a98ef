// IO section: PTX and E57 write/read throughput of a W-sized (3000 x 750) scan, with PCL's ASCII PCD and
// PLY readers on the same points as the baseline, and our PLY reader on PCL's ASCII PLY.
#include <pcl/console/print.h>
#include <pcl/io/pcd_io.h>
#include <pcl/io/ply_io.h>
#include <pcl/point_types.h>

#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <string>

#include "core/io/e57_reader.h"
#include "core/io/e57_writer.h"
#include "core/io/ply.h"
#include "core/io/ptx.h"
#include "core/io/scan_cache.h"
#include "tests/bench/bench_table.h"
#include "tests/io/io_test_util.h"

namespace scanreg::bench {

namespace {

double MiB(const std::filesystem::path& p) { return double(std::filesystem::file_size(p)) / (1 << 20); }

std::string Millions(double n, const char* what = "points") {
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%.2f M %s", n / 1e6, what);
  return buf;
}

}  // namespace

void RunIoBench(Table& table, bool quick) {
  const int cols = quick ? 750 : 3000, rows = quick ? 188 : 750;
  const Scan scan = test::MakeRoomScan(rows, cols, "bench");
  const double cells = double(scan.size()), valid = double(scan.CountValid());
  const std::string size = std::to_string(cols) + " x " + std::to_string(rows);
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("scanreg-bench-io-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  NullProgress progress;
  CancelToken cancel;
  pcl::console::setVerbosityLevel(pcl::console::L_ERROR);  // PCL's PLY reader warns per camera property

  // Ours: PTX (every cell is a line, empty ones `0 0 0 0.5`).
  const auto ptx = dir / "bench.ptx";
  Status written = Status::Ok();
  const double write_s = Seconds([&] { written = io::WritePtx(ptx, {scan}, progress, cancel); });
  if (!written) {
    table.Add({"io", "PTX write " + size, 0.0, "", "failed: " + written.error().ToString()});
    std::filesystem::remove_all(dir);
    return;
  }
  const double ptx_mib = MiB(ptx);
  Expected<std::vector<Scan>> back = MakeError(ErrorCode::kFailed, "not run");
  const double read_s = Seconds([&] { back = io::ReadPtx(ptx, progress, cancel); });
  const std::string note = Millions(cells, "cells") + ", " + Millions(valid, "valid") + ", " +
                           std::to_string(int(ptx_mib)) + " MiB, incl. fsync";
  table.Add({"io", "PTX write " + size + " (scanreg)", cells / write_s / 1e6, "M points/s", note});
  table.Add({"io", "PTX write " + size + " (scanreg)", ptx_mib / write_s, "MiB/s", note});
  if (!back || back->size() != 1 || (*back)[0].CountValid() != scan.CountValid()) {
    table.Add({"io", "PTX read " + size, 0.0, "", "failed: " + (back ? "wrong content" : back.error().ToString())});
  } else {
    table.Add({"io", "PTX read " + size + " (scanreg)", cells / read_s / 1e6, "M points/s",
               Millions(cells, "lines") + ", " + std::to_string(int(read_s * 1e3)) + " ms incl. angles"});
    table.Add({"io", "PTX read " + size + " (scanreg)", ptx_mib / read_s, "MiB/s", ""});
  }
  back = MakeError(ErrorCode::kFailed, "freed");

  // Reopening (issue 13, item 2): the same PTX through the binary scan cache, first read (parse and
  // store) and second (from the cache: the key hashes the file, then the arrays are read).
  const auto cache = dir / "cache";
  bool hit = false;
  const double first_s = Seconds([&] { back = io::ReadScanFileCached(ptx, cache, progress, cancel, &hit); });
  const double cached_s = Seconds([&] { back = io::ReadScanFileCached(ptx, cache, progress, cancel, &hit); });
  const bool same = back && back->size() == 1 && (*back)[0].CountValid() == scan.CountValid();
  table.Add({"io", "PTX reopen " + size + ": parse + store in the scan cache", first_s, "s", ""});
  table.Add({"io", "PTX reopen " + size + ": from the scan cache", cached_s, "s",
             same && hit ? "x" + std::to_string(int(read_s / cached_s)) + " faster than parsing"
                         : std::string("failed: not from the cache or wrong content")});
  back = MakeError(ErrorCode::kFailed, "freed");

  // Ours: E57 (valid cells only; Float single xyz + intensity, bit-packed row/column indices).
  const auto e57 = dir / "bench.e57";
  written = Status::Ok();
  const double e57_write_s = Seconds([&] { written = io::WriteE57(e57, {scan}, progress, cancel); });
  const double e57_read_s = Seconds([&] { back = io::ReadE57(e57, {}, progress, cancel); });
  const bool e57_ok = written && back && back->size() == 1 && (*back)[0].CountValid() == scan.CountValid();
  const double e57_mib = written ? MiB(e57) : 0.0;
  char e57_note[96];
  std::snprintf(e57_note, sizeof(e57_note), "%.1f MiB = %.0f%% of the PTX, incl. fsync", e57_mib,
                100.0 * e57_mib / ptx_mib);
  table.Add({"io", "E57 write " + size + " (scanreg)", written ? cells / e57_write_s / 1e6 : 0.0, "M points/s",
             written ? e57_note : "failed: " + written.error().ToString()});
  table.Add({"io", "E57 read " + size + " (scanreg)", e57_ok ? cells / e57_read_s / 1e6 : 0.0, "M points/s",
             e57_ok ? std::to_string(int(e57_read_s * 1e3)) + " ms incl. CRC-32C and angles"
                    : "failed: " + (back ? std::string("wrong content") : back.error().ToString())});
  table.Add({"io", "E57 read " + size + " (scanreg)", e57_ok ? e57_mib / e57_read_s : 0.0, "MiB/s", ""});
  back = MakeError(ErrorCode::kFailed, "freed");

  // Baseline: the valid points as ASCII PCD and ASCII PLY, read by PCL.
  pcl::PointCloud<pcl::PointXYZI> cloud;
  cloud.reserve(scan.CountValid());
  for (std::size_t i = 0; i < scan.size(); ++i) {
    if (!scan.valid[i]) continue;
    pcl::PointXYZI p;
    p.x = scan.points[i].x(), p.y = scan.points[i].y(), p.z = scan.points[i].z();
    p.intensity = scan.reflectance[i];
    cloud.push_back(p);
  }
  const auto pcd = dir / "bench.pcd";
  const auto ply = dir / "bench.ply";
  const double pcd_write_s = Seconds([&] { pcl::io::savePCDFileASCII(pcd.string(), cloud); });
  const double ply_write_s = Seconds([&] { pcl::io::savePLYFileASCII(ply.string(), cloud); });
  table.Add({"io", "ASCII PCD write (PCL savePCDFileASCII)", valid / pcd_write_s / 1e6, "M points/s",
             "baseline, " + Millions(valid) + ", " + std::to_string(int(MiB(pcd))) + " MiB"});
  table.Add({"io", "ASCII PLY write (PCL savePLYFileASCII)", valid / ply_write_s / 1e6, "M points/s",
             "baseline, " + Millions(valid) + ", " + std::to_string(int(MiB(ply))) + " MiB"});
  cloud = pcl::PointCloud<pcl::PointXYZI>();

  pcl::PointCloud<pcl::PointXYZI> loaded;
  int rc = 0;
  const double pcd_read_s = Seconds([&] { rc = pcl::io::loadPCDFile(pcd.string(), loaded); });
  table.Add({"io", "ASCII PCD read (PCL loadPCDFile)", rc == 0 ? valid / pcd_read_s / 1e6 : 0.0, "M points/s",
             "baseline, " + Millions(double(loaded.size())) + (rc == 0 ? "" : " FAILED")});
  table.Add({"io", "ASCII PCD read (PCL loadPCDFile)", rc == 0 ? MiB(pcd) / pcd_read_s : 0.0, "MiB/s", ""});
  loaded = pcl::PointCloud<pcl::PointXYZI>();
  const double ply_read_s = Seconds([&] { rc = pcl::io::loadPLYFile(ply.string(), loaded); });
  table.Add({"io", "ASCII PLY read (PCL loadPLYFile)", rc == 0 ? valid / ply_read_s / 1e6 : 0.0, "M points/s",
             "baseline, " + Millions(double(loaded.size())) + (rc == 0 ? "" : " FAILED")});
  table.Add({"io", "ASCII PLY read (PCL loadPLYFile)", rc == 0 ? MiB(ply) / ply_read_s : 0.0, "MiB/s", ""});
  loaded = pcl::PointCloud<pcl::PointXYZI>();

  Expected<Scan> ours = MakeError(ErrorCode::kFailed, "not run");
  const double our_ply_s = Seconds([&] { ours = io::ReadPly(ply, progress, cancel); });
  table.Add({"io", "ASCII PLY read (scanreg ReadPly)", ours ? valid / our_ply_s / 1e6 : 0.0, "M points/s",
             ours ? "same file; " + Millions(valid) + " incl. spherical organizing, " +
                        Millions(double(ours->CountValid()), "kept")
                  : "failed: " + ours.error().ToString()});
  table.Add({"io", "ASCII PLY read (scanreg ReadPly)", ours ? MiB(ply) / our_ply_s : 0.0, "MiB/s", ""});

  // Ours, binary organized PLY (the format `convert` writes).
  const auto bply = dir / "bench_binary.ply";
  written = Status::Ok();
  const double bply_write_s = Seconds([&] { written = io::WritePly(bply, scan, progress, cancel); });
  const double bply_read_s = Seconds([&] { ours = io::ReadPly(bply, progress, cancel); });
  table.Add({"io", "binary PLY write " + size + " (scanreg)", written ? cells / bply_write_s / 1e6 : 0.0, "M points/s",
             "organized, range_grid, " + std::to_string(int(MiB(bply))) + " MiB"});
  table.Add({"io", "binary PLY read " + size + " (scanreg)", ours ? cells / bply_read_s / 1e6 : 0.0, "M points/s",
             ours ? "organized" : "failed: " + ours.error().ToString()});
  std::filesystem::remove_all(dir);
}

}  // namespace scanreg::bench
