#include "core/report/report.h"

#include <algorithm>
#include <cmath>
#include <ctime>

#include "core/common/atomic_file.h"
#include "core/common/output_set.h"
#include "core/common/skipped_pair.h"
#include "core/geometry/pose_angles.h"
#include "core/geometry/transform.h"
#include "core/io/project_tree.h"
#include "core/pipeline/register_project.h"
#include "core/report/canvas.h"
#include "core/report/confusion_image.h"
#include "core/report/control_section.h"
#include "core/report/error_chart.h"
#include "core/report/html_table.h"
#include "core/report/network_image.h"

namespace scanreg::report {
namespace {

constexpr double kDeg = 180.0 / M_PI;

constexpr const char* kStyle = R"(<style>
body { font-family: sans-serif; margin: 2em; color: #222; max-width: 1400px; }
h1 { font-size: 1.6em; } h2 { font-size: 1.25em; margin-top: 2em; border-bottom: 1px solid #ccc; }
table { border-collapse: collapse; font-size: 0.85em; margin: 0.5em 0; }
th, td { border: 1px solid #ccc; padding: 3px 7px; text-align: right; }
th { background: #eee; } td:first-child, th:first-child { text-align: left; }
tr.ok td.status { color: #287a28; } tr.weak td.status, tr.weak { background: #fff4e0; }
tr.failed { background: #fde8e8; } tr.check { color: #555; font-style: italic; }
.notice { background: #fde8e8; border: 1px solid #d99; padding: 0.6em 1em; }
.side { display: flex; flex-wrap: wrap; gap: 2em; align-items: flex-start; }
img { max-width: 100%; border: 1px solid #ddd; } pre { margin: 0; font-size: 0.9em; text-align: left; }
</style>
)";

std::string Utc() {
  const std::time_t now = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&now, &tm);
  char buf[64];
  std::strftime(buf, sizeof buf, "%Y-%m-%d %H:%M UTC", &tm);
  return buf;
}

std::string Image(const char* file, const std::string& alt) {
  return std::string("<img src=\"") + file + "\" alt=\"" + Escape(alt) + "\">\n";
}

std::string Matrix(const Eigen::Isometry3d& t) {
  const auto m = RowMajorFromIsometry(t);
  std::string s = "<pre>";
  for (int r = 0; r < 4; ++r) {
    char buf[128];
    std::snprintf(buf, sizeof buf, "%10.6f %10.6f %10.6f %12.4f%s", m[4 * r], m[4 * r + 1], m[4 * r + 2], m[4 * r + 3],
                  r < 3 ? "\n" : "");
    s += buf;
  }
  return s + "</pre>";
}

std::string SummarySection(const io::Project& p) {
  int registered = 0, imported = 0, tree_ok = 0, tree_weak = 0, failed = 0, checks = 0;
  for (const io::ProjectScan& s : p.scans) registered += s.registered, imported += s.registered && s.imported_pose;
  for (const io::LinkRecord& l : p.links) {
    if (l.loop_check) {
      ++checks;
    } else if (!io::IsTreeLink(l)) {
      ++failed;
    } else {
      ++(l.status == io::LinkStatus::kOk ? tree_ok : tree_weak);
    }
  }
  std::string html = "<h2 id=\"summary\">Project summary</h2>\n";
  if (registered == 0) {
    html +=
        "<p class=\"notice\" id=\"not-registered\">This project has not been registered: no scan has a "
        "registered pose. Run <code>scanreg-cli register " +
        Escape(p.file.filename().string()) +
        "</code> (or Registration &rarr; Register all scans) and export the report again.</p>\n";
  }
  HtmlTable t("summary-table", {"item", "value"});
  t.AddRow({"project file", Escape(p.file.string())});
  t.AddRow({"scans", std::to_string(p.scans.size())});
  t.AddRow({"registered", std::to_string(registered)});
  if (imported > 0) t.AddRow({"of which imported poses (from files)", std::to_string(imported)});
  t.AddRow({"not registered", std::to_string(p.scans.size() - registered)});
  t.AddRow({"root (scan-order start)", Escape(p.root.value_or("(not set)"))});
  t.AddRow({"tree links ok / weak", std::to_string(tree_ok) + " / " + std::to_string(tree_weak)});
  t.AddRow({"failed or rejected links", std::to_string(failed)});
  t.AddRow({"loop checks", std::to_string(checks)});
  t.AddRow({"scanreg version", SCANREG_VERSION});
  t.AddRow({"report written", Utc()});
  html += t.Html();
  html += "<h3>Settings used</h3>\n";
  if (p.settings.empty()) {
    html += "<p id=\"settings-none\">No settings recorded: the defaults of this scanreg version apply.</p>\n";
  } else {
    HtmlTable s("settings-table", {"setting", "value"});
    for (const auto& [key, value] : p.settings) s.AddRow({Escape(key), Escape(value)});
    html += s.Html();
  }
  return html;
}

std::string ConfusionSection(const io::Project& p, const std::filesystem::path& dir, Status* status) {
  std::string html = "<h2 id=\"confusion\">Confusion matrix</h2>\n";
  const Eigen::MatrixXi* confusion = p.CurrentConfusion();
  if (!confusion) {
    return html +
           "<p>Not available: the project has not been registered since its scans last changed (the matrix is "
           "stored by <code>scanreg-cli register</code>).</p>\n";
  }
  const std::vector<int> order = io::OrderedScanIndices(p);
  const int n = static_cast<int>(order.size());
  Eigen::MatrixXi ordered(n, n);
  std::vector<std::string> names;
  for (int i = 0; i < n; ++i) {
    names.push_back(p.scans[order[i]].name);
    for (int j = 0; j < n; ++j) ordered(i, j) = (*confusion)(order[i], order[j]);
  }
  *status = WritePng(DrawConfusionHeatMap(ordered, names), dir / kConfusionPng);
  std::string listed;
  for (const std::string& name : names) listed += (listed.empty() ? "" : ", ") + Escape(name);
  int skipped = 0;
  for (int i = 0; i < n; ++i)
    for (int j = i + 1; j < n; ++j) skipped += ordered(i, j) == kSkippedPair && ordered(j, i) == kSkippedPair;
  const std::string skipped_text =
      skipped == 0 ? std::string()
                   : " <span id=\"skipped-pairs\">" + std::to_string(skipped) + " of " + std::to_string(n * (n - 1) / 2) +
                         " pairs were not matched</span> (shown as -): neither scan ranked the other among its most "
                         "similar scans by global descriptors, nor were they neighbours in capture order or linked by "
                         "the user (setting register.candidates; 0 matches every pair).";
  return html +
         "<p>C(i, j): matches of scan i's SIFT features in scan j (ratio test, W §2 step 3); diagonal: "
         "features of scan i. Rows and columns in scan order (the root, then each scan as the registration "
         "placed it): <span id=\"scan-order\">" +
         listed + "</span>." + skipped_text + "</p>\n" + Image(kConfusionPng, "confusion matrix heat map");
}

std::string NetworkSection(const io::Project& p, const std::filesystem::path& dir, Status* status) {
  *status = WritePng(DrawScanNetwork(p), dir / kNetworkPng);
  return "<h2 id=\"network\">Scan network</h2>\n<p>Top view at the registered positions; thick lines are the "
         "scan-order tree along which the poses are chained.</p>\n" +
         Image(kNetworkPng, "scan network, top view");
}

std::string LinksSection(const io::Project& p) {
  std::string html = "<h2 id=\"links\">Links</h2>\n";
  HtmlTable t("links-table",
              {"parent", "child", "kind", "method", "SIFT matches", "FPFH matches", "reliable", "RANSAC inliers",
               "of which FPFH", "consistent", "RMS (mm)",
               "overlap %", "conflict %", "moving objects %", "iterations", "time (s)", "status", "reason"});
  for (const io::LinkRecord& l : p.links) {
    const std::string kind = l.loop_check ? "loop check" : io::IsTreeLink(l) ? "tree" : "attempt";
    std::string status = io::LinkStatusName(l.status);
    if (l.user_accepted) status += " (accepted by user)";
    if (l.user_rejected) status += " (rejected by user)";
    t.AddRow(
        {Escape(l.parent), Escape(l.child), kind, Escape(l.method), std::to_string(l.matches),
         std::to_string(l.geometric_matches), std::to_string(l.reliable), std::to_string(l.ransac_inliers),
         std::to_string(l.geometric_inliers), std::to_string(l.consistent),
         Fixed(l.rms_m * 1000, 1), Fixed(l.overlap * 100, 1), Fixed(l.conflict * 100, 1), Fixed(l.moving * 100, 1), std::to_string(l.iterations),
         Fixed(l.seconds, 2), "<span class=\"status\">" + Escape(status) + "</span>", Escape(l.reason)},
        l.loop_check ? "check" : io::LinkStatusName(l.status));
  }
  if (p.links.empty()) html += "<p>No links: the project has not been registered.</p>\n";
  return html + t.Html();
}

std::string PosesSection(const io::Project& p) {
  std::string html =
      "<h2 id=\"poses\">Scan poses</h2>\n<p>world_from_scan: position of the scanner origin (m); "
      "heading, pitch, roll with R = Rz(heading) Ry(pitch) Rx(roll); tilt = angle between the "
      "scanner's and the world's z axes (degrees).</p>\n";
  if (p.consistency) {  // refinement from current poses: checked without ground truth
    const io::ConsistencyRecord& c = *p.consistency;
    html += "<p id=\"consistency\">Consistency without ground truth: the robust RMS of the point-to-plane residuals "
            "over the " + std::to_string(c.pairs) + " overlapping pairs (a sample meets the other surface within " +
            Fixed(1e3 * c.cutoff_m, 2) + " mm) was <b>" + Fixed(1e3 * c.start_rms_m, 3) + " mm</b> at the start poses and <b>" +
            Fixed(1e3 * c.result_rms_m, 3) + " mm</b> after" + (c.multiview ? " the multi-view fine step" : "") +
            (c.refused ? "; the result was less consistent than the start and was refused: the start poses are kept" : "") +
            ". Each scan's overlap residual below is the median RMS of its overlapping pairs; a scan is registered only "
            "when it agrees with the others, overlaps a registered scan and its overlaps constrain every direction of "
            "its pose (conditioning: 1 every direction alike, near 0 one is free).</p>\n";
  }
  HtmlTable t("poses-table", {"scan", "status", "x (m)", "y (m)", "z (m)", "heading (°)", "pitch (°)", "roll (°)",
                              "tilt (°)", "world_from_scan", "overlap residual (mm): start → result", "conditioning"});
  const std::vector<bool> on_hand = io::RestsOnHandPlacement(p);
  for (std::size_t i = 0; i < p.scans.size(); ++i) {
    const io::ProjectScan& s = p.scans[i];
    const Eigen::Vector3d x = s.world_from_scan.translation();
    const HeadingPitchRoll a = HeadingPitchRollFromRotation(s.world_from_scan.linear());
    std::string status = s.registered ? (p.root && *p.root == s.name ? "root" : "registered") : "not registered";
    if (!s.registered && !s.cluster.empty()) status += " (in the cluster of " + s.cluster + ")";
    if (!s.registered && !s.unregistered_reason.empty()) status += ": " + s.unregistered_reason;
    if (!s.registered && s.unverified) {  // placed, but the pose waits for the user's accept
      const std::string prefix = "not verified: ";
      const std::string& why = s.unregistered_reason;
      status = "not verified, kept at its start pose" +
               (why.empty() ? "" : ": " + (why.rfind(prefix, 0) == 0 ? why.substr(prefix.size()) : why));
    }
    if (s.registered && s.manual_pose) status = "placed by hand (no link evidence)";
    if (s.registered && !s.manual_pose && on_hand[i])
      status = "registered through a scan placed by hand: its pose carries that placement's error";
    if (s.registered && !s.manual_pose && s.imported_pose) {
      status = "imported from a file (no link evidence)";
      if (!s.unregistered_reason.empty()) status += "; the registration could not verify it: " + s.unregistered_reason;
    }
    t.AddRow({Escape(s.name), Escape(status), Fixed(x.x(), 4), Fixed(x.y(), 4), Fixed(x.z(), 4),
              Fixed(a.heading * kDeg, 4), Fixed(a.pitch * kDeg, 4), Fixed(a.roll * kDeg, 4),
              Fixed(TiltAngle(s.world_from_scan.linear()) * kDeg, 4), Matrix(s.world_from_scan),
              (s.start_consistency_m ? Fixed(1e3 * *s.start_consistency_m, 3) : std::string("-")) + " → " +
                  (s.consistency_m ? Fixed(1e3 * *s.consistency_m, 3) : std::string("-")),
              s.conditioning ? Fixed(*s.conditioning, 3) : std::string("-")},
             !s.registered && !s.unverified     ? "failed"
             : !s.registered || s.manual_pose || s.imported_pose || on_hand[i] ? "weak"
                                                : "ok");
  }
  return html + t.Html();
}

std::string Range(const std::vector<double>& v, double factor, int decimals) {
  if (v.empty()) return "-";
  const auto [lo, hi] = std::minmax_element(v.begin(), v.end());
  return Fixed(*lo * factor, decimals) + " – " + Fixed(*hi * factor, decimals);
}

std::string ErrorsSection(const io::Project& p, const std::filesystem::path& dir, Status* status) {
  bool any_reference = false;
  for (const io::ProjectScan& s : p.scans) any_reference |= s.reference_world_from_scan.has_value();
  if (!any_reference) return "";
  std::string html = "<h2 id=\"errors\">Errors against the reference poses</h2>\n";
  const std::vector<pipeline::ReferenceError> errors = pipeline::ReferenceErrors(p);
  bool any = false;
  for (const auto& e : errors) any |= e.available;
  if (!any) {
    return html +
           "<p>Reference poses are present, but no registered scan can be compared yet (the root needs a "
           "reference pose and a registered scan).</p>\n";
  }
  std::vector<std::string> names;
  for (const io::ProjectScan& s : p.scans) names.push_back(s.name);
  *status = WritePng(DrawReferenceErrorChart(names, errors), dir / kErrorsPng);
  HtmlTable t("errors-table",
              {"scan", "coarse position (mm)", "fine position (mm)", "coarse angle (°)", "fine angle (°)"});
  std::vector<double> cp, fp, ca, fa;
  for (std::size_t i = 0; i < errors.size(); ++i) {
    const auto& e = errors[i];
    if (!e.available) {
      t.AddRow({Escape(names[i]), "-", "-", "-", "-"}, "failed");
      continue;
    }
    const bool c = e.has_coarse;
    t.AddRow({Escape(names[i]), c ? Fixed(e.coarse_position_m * 1000, 1) : "-", Fixed(e.position_m * 1000, 1),
              c ? Fixed(e.coarse_angle_rad * kDeg, 4) : "-", Fixed(e.angle_rad * kDeg, 4)});
    if (c) cp.push_back(e.coarse_position_m), ca.push_back(e.coarse_angle_rad);
    fp.push_back(e.position_m);
    fa.push_back(e.angle_rad);
  }
  html +=
      "<p>Both poses taken relative to the root, so the datum of the registration does not matter (as in W "
      "fig. 6). Range: position " +
      Range(cp, 1000, 1) + " mm after coarse, " + Range(fp, 1000, 1) + " mm after fine; angle " + Range(ca, kDeg, 4) +
      "° after coarse, " + Range(fa, kDeg, 4) + "° after fine.</p>\n";
  return html + "<div class=\"side\">\n<div>" + Image(kErrorsPng, "position and angle errors per scan") +
         "</div>\n<div>" + t.Html() + "</div>\n</div>\n";
}

}  // namespace

Expected<std::filesystem::path> WriteReport(const io::Project& project, const std::filesystem::path& dir,
                                            ProgressSink& progress, const CancelToken& cancel) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (fs::exists(dir, ec) && !fs::is_directory(dir, ec)) {
    return MakeError(ErrorCode::kInvalidArgument,
                     "report: '" + dir.string() + "' is a file, not a folder; give a folder for the report");
  }
  fs::create_directories(dir, ec);
  if (ec) {
    return MakeError(ErrorCode::kIoError, "report: cannot create the folder '" + dir.string() + "': " + ec.message() +
                                              "; choose a folder you can write to");
  }
  // The page and its pictures are one set: a failure halfway removes the new files.
  OutputSet written;
  for (const char* name : {kConfusionPng, kNetworkPng, kErrorsPng, "index.html"}) written.Track(dir / name);
  const std::string title = "Registration report — " + project.file.stem().stem().string();
  std::string html = "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<title>" + Escape(title) +
                     "</title>\n" + kStyle + "</head>\n<body>\n<h1>" + Escape(title) + "</h1>\n";
  html += SummarySection(project);
  // Sections with pictures write their PNG beside the page; a failed write names the file.
  constexpr int kSteps = 4;
  for (int step = 0; step < kSteps; ++step) {
    if (cancel.IsCancelled()) return written.Failed(MakeError(ErrorCode::kCancelled, "report cancelled"));
    progress.Report(double(step) / kSteps, "report");
    Status status;
    switch (step) {
      case 0:
        html += ConfusionSection(project, dir, &status);
        break;
      case 1:
        html += NetworkSection(project, dir, &status);
        break;
      case 2:
        html += LinksSection(project) + PosesSection(project) + ControlSection(project);
        break;
      default:
        html += ErrorsSection(project, dir, &status);
        break;
    }
    if (!status) return written.Failed(MakeError(status.error().code, "report: " + status.error().message));
  }
  html += "</body>\n</html>\n";
  const fs::path index = dir / "index.html";
  AtomicFile file(index);
  Status s = file.Open();
  if (s) s = file.Write(html);
  if (s) s = file.Commit();
  if (!s) return written.Failed(MakeError(s.error().code, "report: " + s.error().message));
  written.Complete();
  progress.Report(1.0, "report");
  return index;
}

}  // namespace scanreg::report
