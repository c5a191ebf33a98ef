#include "core/io/pose_file.h"

#include <array>
#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>

#include "core/common/atomic_file.h"
#include "core/common/log.h"
#include "core/geometry/transform.h"
#include "core/io/text_parse.h"

namespace scanreg::io {

namespace {

Error ParseErr(const std::filesystem::path& path, long line, const std::string& what) {
  return MakeError(ErrorCode::kParseError, AtLine(path, line) + what);
}

// A rigid transform from 16 row-major numbers, or an error when it is not rigid.
Expected<Eigen::Isometry3d> RigidFromRowMajor(const std::array<double, 16>& m, const std::string& where) {
  Eigen::Matrix3d raw, rotation;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) raw(r, c) = m[r * 4 + c];
  const bool last_row_ok =
      std::fabs(m[12]) < 1e-6 && std::fabs(m[13]) < 1e-6 && std::fabs(m[14]) < 1e-6 && std::fabs(m[15] - 1.0) < 1e-6;
  if (!last_row_ok || !ProjectToRotation(raw, &rotation)) {
    return MakeError(ErrorCode::kParseError,
                     where + "the matrix is not a rigid transform (rotation + translation, last row 0 0 0 1)");
  }
  return IsometryFromRowMajor(m);
}

std::string MatrixText(const Eigen::Isometry3d& t, const char* sep, const char* row_end) {
  const std::array<double, 16> m = RowMajorFromIsometry(t);
  std::string s;
  char buf[64];
  for (int i = 0; i < 16; ++i) {
    s.append(buf, AppendNumber(buf, m[i]));
    s += (i % 4 == 3) ? row_end : sep;
  }
  return s;
}

Status WriteText(const std::filesystem::path& path, const std::string& text) {
  AtomicFile file(path);
  if (Status s = file.Open(); !s) return s;
  if (Status s = file.Write(text); !s) return s;
  return file.Commit();
}

}  // namespace

Expected<std::vector<NamedPose>> ReadBunConf(const std::filesystem::path& path) {
  Expected<std::string> text = ReadWholeFile(path);
  if (!text) return text.error();
  LineReader lines(*text);
  std::string_view line;
  std::vector<NamedPose> poses;
  while (lines.Next(&line)) {
    std::string_view rest = line;
    const std::string_view key = NextToken(&rest);
    if (key.empty() || key[0] == '#' || key == "camera") continue;
    const long n = lines.line_number();
    if (key != "bmesh") {  // e.g. the dragon's `mesh <reconstruction>` line: not a scan of the project
      LogWarning(AtLine(path, n) + "skipped the " + QuoteToken(key) +
                 " line; scanreg reads the scan poses of `bmesh <file> tx ty tz qx qy qz qw` lines");
      continue;
    }
    const std::string_view file = NextToken(&rest);
    double v[8];
    const NumberParse p = ParseNumbers(rest, v, 8);
    if (file.empty() || p.status != ParseStatus::kOk || p.count != 7) {
      return ParseErr(path, n,
                      (p.status == ParseStatus::kBadToken    ? QuoteToken(p.token) + " is not a number; "
                       : p.status == ParseStatus::kNonFinite ? std::string("NaN or infinite value; ")
                                                             : std::string()) +
                          "expected `bmesh <file> tx ty tz qx qy qz qw` (7 numbers)");
    }
    Eigen::Quaterniond q(v[6], v[3], v[4], v[5]);  // (w, x, y, z)
    if (q.norm() < 1e-6) return ParseErr(path, n, "the quaternion is zero; it must be a rotation");
    if (std::abs(q.norm() - 1.0) > 1e-3) {  // normalised, but a typo in a digit is likely
      char buf[64];
      std::snprintf(buf, sizeof buf, "%.6g", q.norm());
      LogWarning(AtLine(path, n) + "the quaternion's norm is " + buf + ", not 1; it was normalised — check the line");
    }
    NamedPose pose;
    pose.scan = std::string(file);
    pose.world_from_scan.linear() = q.normalized().toRotationMatrix().transpose();
    pose.world_from_scan.translation() = Eigen::Vector3d(v[0], v[1], v[2]);
    poses.push_back(std::move(pose));
  }
  if (poses.empty()) {
    return MakeError(ErrorCode::kParseError, path.string() + ": no `bmesh` line; is this a Stanford .conf file?");
  }
  return poses;
}

Expected<std::vector<NamedPose>> ReadPosesJson(const std::filesystem::path& path) {
  Expected<std::string> text = ReadWholeFile(path);
  if (!text) return text.error();
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(*text);
  } catch (const nlohmann::json::exception& e) {
    return MakeError(ErrorCode::kParseError, path.string() + ": not valid JSON (" + e.what() + ")");
  }
  if (!j.is_object() || !j.contains("version") || !j["version"].is_number_integer()) {
    return MakeError(ErrorCode::kParseError, path.string() + ": not a scanreg poses file (no \"version\")");
  }
  if (j["version"].get<int>() != 1) {
    return MakeError(ErrorCode::kUnsupported, path.string() + ": poses file version " +
                                                  std::to_string(j["version"].get<int>()) +
                                                  " is not supported (this scanreg reads version 1); update scanreg");
  }
  if (!j.contains("poses") || !j["poses"].is_array()) {
    return MakeError(ErrorCode::kParseError, path.string() + ": \"poses\" must be an array");
  }
  std::vector<NamedPose> poses;
  for (std::size_t i = 0; i < j["poses"].size(); ++i) {
    const nlohmann::json& e = j["poses"][i];
    const std::string where = path.string() + ": poses[" + std::to_string(i) + "]: ";
    if (e.is_object() && e.contains("status") && e["status"] == kUnregisteredStatus) continue;
    if (!e.is_object() || !e.contains("scan") || !e["scan"].is_string() || !e.contains("world_from_scan") ||
        !e["world_from_scan"].is_array() || e["world_from_scan"].size() != 16) {
      return MakeError(ErrorCode::kParseError,
                       where + "needs \"scan\" (a name) and \"world_from_scan\" (16 numbers, row-major)");
    }
    std::array<double, 16> m{};
    for (int k = 0; k < 16; ++k) {
      const nlohmann::json& x = e["world_from_scan"][k];
      if (!x.is_number()) return MakeError(ErrorCode::kParseError, where + "world_from_scan holds a non-number");
      m[k] = x.get<double>();
    }
    Expected<Eigen::Isometry3d> t = RigidFromRowMajor(m, where);
    if (!t) return t.error();
    poses.push_back({e["scan"].get<std::string>(), *t,
                     e.contains("status") && e["status"].is_string() ? e["status"].get<std::string>() : std::string()});
  }
  return poses;
}

Status WritePosesJson(const std::filesystem::path& path, const std::vector<NamedPose>& poses) {
  // Written by hand (not json::dump) so that each matrix keeps shortest round-trip numbers
  // and sits on its own line.
  std::string s = "{\n  \"version\": 1,\n  \"poses\": [";
  for (std::size_t i = 0; i < poses.size(); ++i) {
    s += i ? ",\n    " : "\n    ";
    s += "{\"scan\": " + nlohmann::json(poses[i].scan).dump();
    if (!poses[i].status.empty()) s += ", \"status\": " + nlohmann::json(poses[i].status).dump();
    if (poses[i].status != kUnregisteredStatus) {
      s += ", \"world_from_scan\": [" + MatrixText(poses[i].world_from_scan, ", ", ", ");
      s.resize(s.size() - 2);
      s += "]";
    }
    s += "}";
  }
  s += poses.empty() ? "]\n}\n" : "\n  ]\n}\n";
  return WriteText(path, s);
}

Expected<Eigen::Isometry3d> ReadMatrixTxt(const std::filesystem::path& path) {
  Expected<std::string> text = ReadWholeFile(path);
  if (!text) return text.error();
  LineReader lines(*text);
  std::string_view line;
  std::array<double, 16> m{};
  int row = 0;
  while (lines.Next(&line)) {
    if (IsBlank(line)) continue;
    if (row == 4) {
      return ParseErr(path, lines.line_number(), "more than 4 rows; a matrix file holds 4 lines of 4 numbers");
    }
    double v[5];
    const NumberParse p = ParseNumbers(line, v, 5);
    if (p.status != ParseStatus::kOk || p.count != 4) {
      return ParseErr(
          path, lines.line_number(),
          (p.status == ParseStatus::kOk ? std::string() : QuoteToken(p.token) + " is not a finite number; ") +
              "expected 4 numbers (one row of the 4x4 matrix)");
    }
    for (int k = 0; k < 4; ++k) m[row * 4 + k] = v[k];
    ++row;
  }
  if (row < 4) {
    return ParseErr(path, lines.line_number() + 1,
                    "the file ends after " + std::to_string(row) + " rows; a matrix file holds 4 lines of 4 numbers");
  }
  return RigidFromRowMajor(m, path.string() + ": ");
}

Status WriteMatrixTxt(const std::filesystem::path& path, const Eigen::Isometry3d& world_from_scan) {
  return WriteText(path, MatrixText(world_from_scan, " ", "\n"));
}

}  // namespace scanreg::io
