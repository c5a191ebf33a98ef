#include "core/report/control_section.h"

#include "core/pipeline/georeference_project.h"
#include "core/report/html_table.h"

namespace scanreg::report {
namespace {

// Row colours of the report's style: green = ok, orange = weak, red = failed.
std::string RowClass(const std::string& grade) {
  if (grade == "green") return "ok";
  if (grade == "orange") return "weak";
  if (grade == "red") return "failed";
  return "";
}

std::string Mm(double metres) { return Fixed(metres * 1000, 1); }

}  // namespace

std::string ControlSection(const io::Project& p) {
  if (p.control.empty()) return "";
  std::string html = "<h2 id=\"control\">Georeferencing</h2>\n";
  if (!p.georef) {
    return html + "<p class=\"notice\">Not georeferenced: the project has " + std::to_string(p.control.size()) +
           " control points but its poses are in the root scan's frame (the last registration could not place "
           "it on them, or it was edited since). Register again to see why.</p>\n";
  }
  const io::GeorefRecord& g = *p.georef;
  html += "<p>" + std::to_string(g.used) + " of " + std::to_string(p.control.size()) +
          " control points place the project (datum from control; every scan pose, target and link adjusted "
          "together); " + std::to_string(g.targets) + " targets found in the scans. 3D RMS of the used points: <b>" +
          Mm(g.rms_m) + " mm</b>; tolerance " + Mm(g.tolerance_m) +
          " mm (green below half of it, orange up to it, red beyond). Residual = control minus adjusted target; a "
          "check point or a point left out as a blunder shows its check residual.</p>\n";
  HtmlTable t("control-table",
              {"point", "role", "scans", "ΔE (mm)", "ΔN (mm)", "ΔH (mm)", "3D (mm)", "left out (mm)", "grade"});
  for (const io::ControlResidualRecord& r : g.control) {
    const std::string grade = pipeline::ControlGrade(r, g.tolerance_m);
    if (r.role == "not found") {
      t.AddRow({Escape(r.name), "not found", "0", "-", "-", "-", "-", "-", "-"}, "check");
      continue;
    }
    t.AddRow({Escape(r.name), Escape(r.role), std::to_string(r.observations), Mm(r.delta.x()), Mm(r.delta.y()),
              Mm(r.delta.z()), Mm(r.delta.norm()), r.leave_one_out_m >= 0 ? Mm(r.leave_one_out_m) : "-",
              "<span class=\"status\">" + grade + "</span>"},
             RowClass(grade));
  }
  html += t.Html();
  HtmlTable targets("targets-table", {"scan", "target", "kind", "points", "fit RMS (mm)", "σ centre (mm)", "residual (mm)"});
  for (const io::TargetRecord& r : p.targets) {
    targets.AddRow({Escape(r.scan), Escape(r.name), Escape(r.kind), std::to_string(r.points), Mm(r.rms_m), Mm(r.sigma_m),
                    r.residual_m >= 0 ? Mm(r.residual_m) : "-"});
  }
  html += "<p>Targets per scan (residual: the scan's observation against the adjusted target).</p>\n" + targets.Html();
  return html;
}

}  // namespace scanreg::report
