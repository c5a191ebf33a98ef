#include "core/io/pose_csv.h"

#include <cmath>

#include "core/common/atomic_file.h"
#include "core/geometry/pose_angles.h"
#include "core/io/text_parse.h"

namespace scanreg::io {
namespace {

constexpr char kHeader[] = "scan,x_m,y_m,z_m,heading_deg,pitch_deg,roll_deg,status";
constexpr char kHeaderWithoutStatus[] = "scan,x_m,y_m,z_m,heading_deg,pitch_deg,roll_deg";  // scanreg 0.1
constexpr double kDeg = 180.0 / M_PI;

std::string CsvField(const std::string& s) {
  if (s.find_first_of(",\"\n") == std::string::npos) return s;
  std::string q = "\"";
  for (char c : s) q += c == '"' ? std::string("\"\"") : std::string(1, c);
  return q + "\"";
}

// Splits off the first field of a CSV row (quoted or not); false when the quoting is broken.
bool NextField(std::string_view* row, std::string* field) {
  field->clear();
  std::size_t i = 0;
  if (!row->empty() && (*row)[0] == '"') {
    for (i = 1; i < row->size(); ++i) {
      if ((*row)[i] != '"') {
        *field += (*row)[i];
      } else if (i + 1 < row->size() && (*row)[i + 1] == '"') {
        *field += '"';
        ++i;
      } else {
        break;
      }
    }
    if (i >= row->size()) return false;
    ++i;  // closing quote
    if (i < row->size() && (*row)[i] != ',') return false;
  } else {
    i = std::min(row->find(','), row->size());
    *field = std::string(row->substr(0, i));
  }
  row->remove_prefix(std::min(i + 1, row->size()));
  return true;
}

}  // namespace

Status WritePosesCsv(const std::filesystem::path& path, const std::vector<NamedPose>& poses) {
  std::string text = std::string(kHeader) + "\n";
  char buf[32];
  for (const NamedPose& p : poses) {
    const HeadingPitchRoll a = HeadingPitchRollFromRotation(p.world_from_scan.linear());
    text += CsvField(p.scan);
    const Eigen::Vector3d t = p.world_from_scan.translation();
    for (double v : {t.x(), t.y(), t.z(), a.heading * kDeg, a.pitch * kDeg, a.roll * kDeg}) {
      text += ',';
      if (p.status != kUnregisteredStatus) text.append(buf, AppendNumber(buf, v + 0.0));  // + 0.0: no "-0"
    }
    text += ',' + CsvField(p.status) + '\n';
  }
  AtomicFile file(path);
  if (Status s = file.Open(); !s) return s;
  if (Status s = file.Write(text); !s) return s;
  return file.Commit();
}

Expected<std::vector<NamedPose>> ReadPosesCsv(const std::filesystem::path& path) {
  Expected<std::string> text = ReadWholeFile(path);
  if (!text) return text.error();
  LineReader lines(*text);
  std::string_view line;
  if (!lines.Next(&line) || (line != kHeader && line != kHeaderWithoutStatus)) {
    return MakeError(ErrorCode::kParseError,
                     AtLine(path, 1) + "expected the header '" + kHeader + "'; is this a scanreg pose CSV?");
  }
  const bool has_status = line == kHeader;
  std::vector<NamedPose> poses;
  while (lines.Next(&line)) {
    if (IsBlank(line)) continue;
    const std::string at = AtLine(path, lines.line_number());
    NamedPose pose;
    std::string field;
    if (!NextField(&line, &pose.scan) || pose.scan.empty()) {
      return MakeError(ErrorCode::kParseError, at + "the scan name is missing or badly quoted");
    }
    double v[6];
    std::string numbers[6];
    for (std::string& x : numbers) {
      if (!NextField(&line, &x)) return MakeError(ErrorCode::kParseError, at + "a field is badly quoted");
    }
    if (has_status && !NextField(&line, &pose.status)) {
      return MakeError(ErrorCode::kParseError, at + "the status field is missing or badly quoted");
    }
    if (!line.empty()) return MakeError(ErrorCode::kParseError, at + "more fields than the header names");
    if (pose.status == kUnregisteredStatus) continue;  // no pose to read
    for (int k = 0; k < 6; ++k) {
      if (ParseNumbers(numbers[k], &v[k], 1).count != 1) {
        return MakeError(ErrorCode::kParseError, at + "expected 6 numbers after the scan name (x, y, z in metres, "
                                                      "heading, pitch, roll in degrees)");
      }
    }
    pose.world_from_scan.linear() = RotationFromHeadingPitchRoll({v[3] / kDeg, v[4] / kDeg, v[5] / kDeg});
    pose.world_from_scan.translation() = Eigen::Vector3d(v[0], v[1], v[2]);
    poses.push_back(std::move(pose));
  }
  return poses;
}

}  // namespace scanreg::io
