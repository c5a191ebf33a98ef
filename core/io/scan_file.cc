#include "core/io/scan_file.h"

#include "core/common/log.h"

#include "core/io/e57_reader.h"
#include "core/io/e57_writer.h"
#include "core/io/las_reader.h"
#include "core/io/pcd.h"
#include "core/io/ply.h"
#include "core/io/ptx.h"
#include "core/io/text_parse.h"

namespace scanreg::io {

const char* SupportedScanExtensions() { return ".ptx, .e57, .ply, .pcd, .las"; }

namespace {

Error UnknownExtension(const std::filesystem::path& path) {
  const std::string ext = path.extension().string();
  return MakeError(ErrorCode::kUnsupported, path.string() + ": unknown scan file type " +
                                                (ext.empty() ? "(no extension)" : "'" + ext + "'") +
                                                "; supported: " + SupportedScanExtensions());
}

Expected<std::vector<Scan>> One(Expected<Scan> scan) {
  if (!scan) return scan.error();
  std::vector<Scan> scans;
  scans.push_back(std::move(*scan));
  return scans;
}

}  // namespace

Expected<std::vector<Scan>> ReadScanFile(const std::filesystem::path& path, ProgressSink& progress,
                                         const CancelToken& cancel) {
  const std::string ext = LowerExtension(path);
  if (ext != ".ptx" && ext != ".e57" && ext != ".ply" && ext != ".pcd" && ext != ".las" && ext != ".laz")
    return UnknownExtension(path);
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) {
    return MakeError(ErrorCode::kNotFound, path.string() + ": no such file; check the path");
  }
  if (ext == ".ptx") return ReadPtx(path, progress, cancel);
  if (ext == ".e57") return ReadE57(path, E57ReadOptions{}, progress, cancel);
  if (ext == ".ply") return One(ReadPly(path, progress, cancel));
  if (ext == ".las" || ext == ".laz") return One(ReadLas(path, progress, cancel));
  return One(ReadPcd(path, progress, cancel));
}

Status WriteScanFile(const std::filesystem::path& path, const std::vector<Scan>& scans, ProgressSink& progress,
                     const CancelToken& cancel) {
  const std::string ext = LowerExtension(path);
  if (ext == ".las") {
    return MakeError(ErrorCode::kUnsupported, path.string() + ": LAS files are written by the export "
                                                              "(scanreg-cli export-clouds PROJECT --out DIR --format las)");
  }
  if (ext != ".ptx" && ext != ".e57" && ext != ".ply" && ext != ".pcd") return UnknownExtension(path);
  if (ext == ".ptx" || ext == ".pcd") {  // no time field
    for (const Scan& scan : scans)
      if (scan.HasTime())
        LogWarning(path.string() + ": scan '" + scan.name + "' has a time per point (" + scan.time_base +
                   "), which " + ext.substr(1) + " does not keep; export ply, las or e57 to keep it");
  }
  for (const Scan& scan : scans)
    if (scan.HasSensor() && ext != ".ply")
      LogWarning(path.string() + ": scan '" + scan.name + "' has a sensor position per point, which " + ext.substr(1) +
                 " has no field for: they are left out; write ply to keep them (scalar_x_origin, _y_, _z_)");
  if (ext == ".ptx") return WritePtx(path, scans, progress, cancel);
  if (ext == ".e57") return WriteE57(path, scans, progress, cancel);
  if (scans.size() != 1) {
    return MakeError(ErrorCode::kInvalidArgument, path.string() + ": a " + ext + " file holds one scan, but " +
                                                      std::to_string(scans.size()) +
                                                      " were given; write a .ptx or .e57 file, or one file per scan");
  }
  if (ext == ".ply") return WritePly(path, scans[0], progress, cancel);
  return WritePcd(path, scans[0], progress, cancel);
}

}  // namespace scanreg::io
