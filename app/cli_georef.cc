#include "app/cli_georef.h"

#include <cmath>
#include <cstdio>

#include "core/io/control_file.h"
#include "core/pipeline/georeference_project.h"
#include "core/pipeline/project_edits.h"

namespace scanreg::cli {
namespace {

constexpr double kDeg = 180.0 / M_PI;

// Largest error of the registered scans against their reference poses in the control frame
// (absolute: the datum is the control's, not the root's); false when no scan has a reference.
bool AbsoluteErrors(const io::Project& project, double* metres, double* degrees, int* scans) {
  *metres = *degrees = 0;
  *scans = 0;
  for (const io::ProjectScan& s : project.scans) {
    if (!s.registered || !s.reference_world_from_scan) continue;
    const Eigen::Isometry3d e = s.reference_world_from_scan->inverse() * s.world_from_scan;
    *metres = std::max(*metres, (s.world_from_scan.translation() - s.reference_world_from_scan->translation()).norm());
    *degrees = std::max(*degrees, Eigen::AngleAxisd(e.linear()).angle() * kDeg);
    ++*scans;
  }
  return *scans > 0;
}

}  // namespace

std::vector<OptionSpec> ControlOptions() {
  return {{"control", true, false,
           "FILE     control points (CSV: name, E, N, H [, sigma_m]); the project is georeferenced on them "
           "through the sphere targets found in the scans"},
          {"check", true, true, "NAME     make control point NAME a check point: compared, not used (repeatable)"}};
}

Status ImportControl(const Args& args, io::Project* project) {
  const std::vector<std::string> checks = args.GetAll("check");
  if (auto file = args.Get("control")) return pipeline::ImportControl(*file, checks, *project);
  if (checks.empty()) return Status::Ok();
  project->georef.reset();  // the roles change: the residuals were graded with the old ones
  return io::MarkCheckPoints(checks, &project->control);
}

void PrintGeoref(const io::Project& project, const pipeline::ProjectRegistration& result) {
  if (project.control.empty()) return;
  if (!result.georeferenced || !project.georef) {
    std::printf("\ngeoreferencing FAILED: %s\nthe registration is saved in the root scan's frame\n",
                result.georef_error.c_str());
    return;
  }
  const io::GeorefRecord& g = *project.georef;
  std::printf("\ngeoreferencing: %d control points place the project; %d targets in the scans; RMS %.1f mm "
              "(tolerance %.1f mm)\n",
              g.used, g.targets, g.rms_m * 1000, g.tolerance_m * 1000);
  std::printf("%-10s %-10s %4s %8s %8s %8s %8s %12s  %s\n", "point", "role", "obs", "dE mm", "dN mm", "dH mm", "3D mm",
              "left out mm", "grade");
  int red = 0;
  for (const io::ControlResidualRecord& r : g.control) {
    const std::string grade = pipeline::ControlGrade(r, g.tolerance_m);
    if (r.role == "not found") {
      std::printf("%-10s %-10s %4d %8s %8s %8s %8s %12s  %s\n", r.name.c_str(), r.role.c_str(), 0, "-", "-", "-", "-",
                  "-", "-");
      continue;
    }
    red += grade == "red" && r.role != "blunder";
    char loo[32] = "-";
    if (r.leave_one_out_m >= 0) std::snprintf(loo, sizeof loo, "%.1f", r.leave_one_out_m * 1000);
    std::printf("%-10s %-10s %4d %8.1f %8.1f %8.1f %8.1f %12s  %s\n", r.name.c_str(), r.role.c_str(), r.observations,
                r.delta.x() * 1000, r.delta.y() * 1000, r.delta.z() * 1000, r.delta.norm() * 1000, loo, grade.c_str());
  }
  double metres = 0, degrees = 0;
  int scans = 0;
  if (AbsoluteErrors(project, &metres, &degrees, &scans)) {
    std::printf("against the reference poses in the control frame: %d scans, worst %.1f mm / %.4f°\n", scans,
                metres * 1000, degrees);
  }
  if (red > 0) std::fprintf(stderr, "scanreg-cli: %d control point(s) outside the tolerance (table above)\n", red);
}

nlohmann::json GeorefJson(const io::Project& project, const pipeline::ProjectRegistration& result) {
  using nlohmann::json;
  if (project.control.empty()) return nullptr;
  if (!result.georeferenced || !project.georef) return json{{"georeferenced", false}, {"error", result.georef_error}};
  const io::GeorefRecord& g = *project.georef;
  json rows = json::array();
  for (const io::ControlResidualRecord& r : g.control) {
    rows.push_back({{"name", r.name},
                    {"role", r.role},
                    {"observations", r.observations},
                    {"delta_m", {r.delta.x(), r.delta.y(), r.delta.z()}},
                    {"residual_m", r.delta.norm()},
                    {"leave_one_out_m", r.leave_one_out_m},
                    {"grade", pipeline::ControlGrade(r, g.tolerance_m)}});
  }
  json out{{"georeferenced", true}, {"rms_m", g.rms_m},           {"used", g.used},
           {"targets", g.targets},  {"tolerance_m", g.tolerance_m}, {"control", rows}};
  double metres = 0, degrees = 0;
  int scans = 0;
  if (AbsoluteErrors(project, &metres, &degrees, &scans)) {
    out["reference_worst_position_m"] = metres;
    out["reference_worst_angle_deg"] = degrees;
  }
  return out;
}

}  // namespace scanreg::cli
