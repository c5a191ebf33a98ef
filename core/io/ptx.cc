#include "core/io/ptx.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "core/common/atomic_file.h"
#include "core/geometry/transform.h"
#include "core/io/text_parse.h"

namespace scanreg::io {

namespace {

constexpr double kMaxSide = 1e6;    // rows or columns
constexpr double kMaxCells = 5e8;   // rows * columns
constexpr int kProgressSteps = 40;  // progress reports per scan

Error ParseErr(const std::filesystem::path& path, long line, const std::string& what) {
  return MakeError(ErrorCode::kParseError, AtLine(path, line) + what);
}

Error Cancelled(const std::filesystem::path& path) {
  return MakeError(ErrorCode::kCancelled, path.string() + ": cancelled");
}

constexpr int kMaxHeaderNumbers = 4;  // a PTX header line holds 1 (grid size), 3 (position, axes) or 4 (matrix row)

// Reads one header line of exactly n numbers.
Status ReadHeaderLine(LineReader& lines, const std::filesystem::path& path, int n, const char* what, double* out) {
  std::string_view line;
  if (!lines.Next(&line)) {
    return ParseErr(path, lines.line_number() + 1,
                    std::string("the file ends inside a scan header (expected the ") + what +
                        "); the file is truncated, export it again");
  }
  // One number more than expected is parsed to tell "too many" apart: into a buffer with room for
  // it (out holds exactly n; ASan found the extra number written past it).
  double parsed[kMaxHeaderNumbers + 1];
  if (n < 1 || n > kMaxHeaderNumbers) return ParseErr(path, lines.line_number(), "internal: bad header width");
  const NumberParse r = ParseNumbers(line, parsed, n + 1);
  if (r.status == ParseStatus::kBadToken) {
    return ParseErr(path, lines.line_number(),
                    QuoteToken(r.token) + " is not a number (expected the " + what +
                        "); is this a PTX file? Check the header of each scan");
  }
  if (r.status == ParseStatus::kNonFinite) {
    return ParseErr(path, lines.line_number(), std::string("NaN or infinite value in the ") + what);
  }
  if (r.count != n) {
    return ParseErr(path, lines.line_number(),
                    "expected " + std::to_string(n) + " number" + (n > 1 ? "s" : "") + " (the " + what + "), found " +
                        std::to_string(r.count) + "; the scan header is malformed");
  }
  std::copy(parsed, parsed + n, out);
  return Status::Ok();
}

Error Truncated(const std::filesystem::path& path, long missing_line, std::size_t have, std::size_t want,
                int scan_index) {
  return ParseErr(path, missing_line,
                  "the file ends after " + std::to_string(have) + " of " + std::to_string(want) +
                      " point lines of scan " + std::to_string(scan_index + 1) +
                      "; the file is truncated (copy or export it again)");
}

// Parses one scan starting at a header; lines is left after its last point line.
Expected<Scan> ReadOneScan(LineReader& lines, std::string_view text, const std::filesystem::path& path, int scan_index,
                           ProgressSink& progress, const CancelToken& cancel) {
  if (cancel.IsCancelled()) return Cancelled(path);
  double cols_d = 0, rows_d = 0;
  const long header_line = lines.line_number() + 1;
  if (Status s = ReadHeaderLine(lines, path, 1, "number of columns", &cols_d); !s) return s.error();
  if (Status s = ReadHeaderLine(lines, path, 1, "number of rows", &rows_d); !s) return s.error();
  if (cols_d != std::floor(cols_d) || rows_d != std::floor(rows_d) || cols_d < 1 || rows_d < 1 || cols_d > kMaxSide ||
      rows_d > kMaxSide || cols_d * rows_d > kMaxCells) {
    return ParseErr(path, header_line,
                    "impossible scan size " + std::to_string(cols_d) + " columns x " + std::to_string(rows_d) +
                        " rows (each must be a whole number 1..1000000, at most 5e8 cells); "
                        "the header is corrupt or this is not a PTX file");
  }
  const int cols = static_cast<int>(cols_d), rows = static_cast<int>(rows_d);
  double position[3], axes[3][3], matrix[4][4];
  if (Status s = ReadHeaderLine(lines, path, 3, "scanner position", position); !s) return s.error();
  const long axes_line = lines.line_number() + 1;
  for (auto& a : axes)
    if (Status s = ReadHeaderLine(lines, path, 3, "scanner axis", a); !s) return s.error();
  const long matrix_line = lines.line_number() + 1;
  for (auto& m : matrix)
    if (Status s = ReadHeaderLine(lines, path, 4, "transform row", m); !s) return s.error();

  Eigen::Matrix3d axis_matrix, rotation;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) axis_matrix(i, j) = axes[i][j];
  if (!ProjectToRotation(axis_matrix, &rotation)) {
    return ParseErr(path, axes_line,
                    "the 3 scanner axes (lines " + std::to_string(axes_line) + "-" + std::to_string(axes_line + 2) +
                        ") are not a rotation (orthonormal, right-handed); the header is corrupt");
  }
  Eigen::Matrix3d transform_rotation;
  for (int c = 0; c < 3; ++c)
    for (int r = 0; r < 3; ++r) transform_rotation(r, c) = matrix[c][r];  // file rows are rotation columns
  const double tol = 1e-4;
  const bool affine_ok = std::fabs(matrix[0][3]) < tol && std::fabs(matrix[1][3]) < tol &&
                         std::fabs(matrix[2][3]) < tol && std::fabs(matrix[3][3] - 1.0) < tol;
  if (!affine_ok || !ProjectToRotation(transform_rotation, &rotation)) {
    return ParseErr(path, matrix_line,
                    "the 4x4 transform (lines " + std::to_string(matrix_line) + "-" + std::to_string(matrix_line + 3) +
                        ") is not rigid: rows 1-3 must hold a rotation with a trailing 0 and row 4 \"tx ty tz 1\"");
  }

  const std::size_t cells = static_cast<std::size_t>(rows) * cols;
  // Each point line takes at least 8 bytes ("0 0 0 0\n"): refuse to allocate for a truncated file.
  if (text.size() - lines.offset() < cells * 8) {
    const std::size_t have = lines.CountRemainingLines();
    if (have < cells) return Truncated(path, lines.line_number() + long(have) + 1, have, cells, scan_index);
  }

  Scan scan(path.stem().string(), rows, cols);
  // Keep the file's own numbers when they are a rotation to rounding: round trips stay exact.
  scan.world_from_scan.linear() =
      (transform_rotation - rotation).cwiseAbs().maxCoeff() < 1e-12 ? transform_rotation : rotation;
  scan.world_from_scan.translation() = Eigen::Vector3d(matrix[3][0], matrix[3][1], matrix[3][2]);

  const std::size_t report_every = std::max<std::size_t>(1, cells / kProgressSteps);
  std::size_t next_report = report_every;
  std::size_t done = 0;
  float v[7];
  std::string_view line;
  for (int c = 0; c < cols; ++c) {
    for (int r = 0; r < rows; ++r, ++done) {
      if (done == next_report) {
        next_report += report_every;
        if (cancel.IsCancelled()) return Cancelled(path);
        progress.Report(double(lines.offset()) / double(text.size()), "reading " + path.filename().string());
      }
      if (!lines.Next(&line)) return Truncated(path, lines.line_number() + 1, done, cells, scan_index);
      const NumberParse p = ParseNumbers(line, v, 7);
      if (p.status == ParseStatus::kBadToken) {
        return ParseErr(path, lines.line_number(),
                        QuoteToken(p.token) + " is not a number; point lines must be `x y z intensity [r g b]`");
      }
      if (p.status == ParseStatus::kNonFinite) {
        return ParseErr(path, lines.line_number(),
                        "NaN or infinite value " + QuoteToken(p.token) +
                            "; empty cells must be written as `0 0 0 ...`, fix the exporter's settings");
      }
      if (p.count < 4) {
        return ParseErr(path, lines.line_number(),
                        "expected 4 or more numbers `x y z intensity [r g b]`, found " + std::to_string(p.count) +
                            " (point " + std::to_string(done + 1) + " of " + std::to_string(cells) + " of scan " +
                            std::to_string(scan_index + 1) + "); the file is damaged or the header's size is wrong");
      }
      if (done == 0 && p.count >= 7) scan.AddColour();             // `x y z intensity r g b`: the scan has colour
      if (v[0] == 0.0f && v[1] == 0.0f && v[2] == 0.0f) continue;  // empty cell
      const std::size_t i = scan.Index(r, c);
      scan.points[i] = Eigen::Vector3f(v[0], v[1], v[2]);
      scan.reflectance[i] = v[3];
      scan.valid[i] = 1;
      if (scan.HasColour() && p.count >= 7) {
        for (int k = 0; k < 3; ++k)
          scan.colour[i][k] = static_cast<std::uint8_t>(std::clamp(v[4 + k], 0.0f, 255.0f) + 0.5f);
      }
    }
  }
  EstimateAngularGrid(scan);
  return scan;
}

}  // namespace

Expected<std::vector<Scan>> ReadPtx(const std::filesystem::path& path, ProgressSink& progress,
                                    const CancelToken& cancel) {
  Expected<std::string> text = ReadWholeFile(path);
  if (!text) return text.error();
  LineReader lines(*text);
  if (!lines.SkipBlankLines()) {
    return MakeError(ErrorCode::kParseError,
                     AtLine(path, 1) +
                         "the file is empty; a PTX file starts with the column and row counts of its "
                         "first scan. Export the scan again");
  }
  std::vector<Scan> scans;
  do {
    Expected<Scan> scan = ReadOneScan(lines, *text, path, static_cast<int>(scans.size()), progress, cancel);
    if (!scan) return scan.error();
    scans.push_back(std::move(*scan));
  } while (lines.SkipBlankLines());
  if (scans.size() > 1) {
    for (std::size_t i = 0; i < scans.size(); ++i) scans[i].name += "_" + std::to_string(i + 1);
  }
  progress.Report(1.0, "reading " + path.filename().string());
  return scans;
}

namespace {

char* AppendLine3(char* p, double a, double b, double c) {
  p = AppendNumber(p, a);
  *p++ = ' ';
  p = AppendNumber(p, b);
  *p++ = ' ';
  p = AppendNumber(p, c);
  return p;
}

}  // namespace

Status WritePtx(const std::filesystem::path& path, const std::vector<Scan>& scans, ProgressSink& progress,
                const CancelToken& cancel) {
  if (scans.empty()) {
    return MakeError(ErrorCode::kInvalidArgument, path.string() + ": no scan to write");
  }
  for (const Scan& scan : scans) {
    if (Status s = scan.Validate(); !s) return s;
    if (scan.rows < 1 || scan.cols < 1) {
      return MakeError(ErrorCode::kInvalidArgument,
                       path.string() + ": scan '" + scan.name + "' has an empty grid; PTX needs rows and columns");
    }
    if (!scan.list_points.empty()) {
      return MakeError(
          ErrorCode::kUnsupported,
          path.string() + ": scan '" + scan.name + "' has " + std::to_string(scan.list_points.size()) +
              " points without a cell of its grid (a cloud seen from more than one place), and PTX holds a "
              "grid only; export it as e57, ply or las, which keep every point");
    }
  }
  AtomicFile file(path);
  if (Status s = file.Open(); !s) return s;
  std::size_t total = 0, done = 0;
  for (const Scan& scan : scans) total += scan.size();
  const std::size_t report_every = std::max<std::size_t>(1, total / kProgressSteps);
  std::string chunk;
  chunk.reserve(1 << 20);
  char buf[512];  // header: 4 lines of 3 doubles (<= 25 chars each)
  for (const Scan& scan : scans) {
    const Eigen::Matrix3d r = scan.world_from_scan.linear();
    const Eigen::Vector3d t = scan.world_from_scan.translation();
    chunk += std::to_string(scan.cols) + "\n" + std::to_string(scan.rows) + "\n";
    char* p = AppendLine3(buf, t.x(), t.y(), t.z());
    *p++ = '\n';
    for (int j = 0; j < 3; ++j) {  // scanner axes: the rotation's columns
      p = AppendLine3(p, r(0, j), r(1, j), r(2, j));
      *p++ = '\n';
    }
    chunk.append(buf, p);
    for (int j = 0; j < 3; ++j) {
      p = AppendLine3(buf, r(0, j), r(1, j), r(2, j));
      chunk.append(buf, p);
      chunk += " 0\n";
    }
    p = AppendLine3(buf, t.x(), t.y(), t.z());
    chunk.append(buf, p);
    chunk += " 1\n";
    for (int c = 0; c < scan.cols; ++c) {
      for (int row = 0; row < scan.rows; ++row, ++done) {
        if (done % report_every == 0) {
          if (cancel.IsCancelled()) return MakeError(ErrorCode::kCancelled, path.string() + ": writing cancelled");
          progress.Report(double(done) / double(total), "writing " + path.filename().string());
        }
        const std::size_t i = scan.Index(row, c);
        if (!scan.valid[i]) {
          chunk += scan.HasColour() ? "0 0 0 0.5 0 0 0\n" : "0 0 0 0.5\n";
          continue;
        }
        const Eigen::Vector3f& q = scan.points[i];
        p = AppendNumber(buf, q.x());
        *p++ = ' ';
        p = AppendNumber(p, q.y());
        *p++ = ' ';
        p = AppendNumber(p, q.z());
        *p++ = ' ';
        p = AppendNumber(p, scan.reflectance[i]);
        for (int k = 0; scan.HasColour() && k < 3; ++k) {
          *p++ = ' ';
          p = AppendNumber(p, static_cast<double>(scan.colour[i][k]));
        }
        *p++ = '\n';
        chunk.append(buf, p);
      }
      if (chunk.size() > (1 << 20) - 4096) {
        if (Status s = file.Write(chunk); !s) return s;
        chunk.clear();
      }
    }
  }
  if (Status s = file.Write(chunk); !s) return s;
  if (Status s = file.Commit(); !s) return s;
  progress.Report(1.0, "writing " + path.filename().string());
  return Status::Ok();
}

}  // namespace scanreg::io
