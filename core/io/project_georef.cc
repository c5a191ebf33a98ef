#include "core/io/project_georef.h"

#include <cmath>
#include <set>

#include "core/io/json_fields.h"

namespace scanreg::io {
namespace {

using json = nlohmann::json;


Status Finite(double v, const std::string& what) {
  if (std::isfinite(v)) return Status::Ok();
  return MakeError(ErrorCode::kParseError, what + " is not a finite number");
}

}  // namespace

void GeorefToJson(const Project& project, json* j) {
  if (!project.control.empty()) {
    json control = json::array();
    for (const ControlPoint& c : project.control) {
      json jc{{"name", c.name}, {"e", c.position.x()}, {"n", c.position.y()}, {"h", c.position.z()}};
      if (c.sigma_m) jc["sigma_m"] = *c.sigma_m;
      if (c.check) jc["check"] = true;
      control.push_back(std::move(jc));
    }
    (*j)["control"] = std::move(control);
  }
  if (!project.targets.empty()) {
    json targets = json::array();
    for (const TargetRecord& t : project.targets) {
      json jt{{"scan", t.scan},         {"name", t.name},   {"kind", t.kind},     {"center", Vec(t.center)},
              {"sigma_m", t.sigma_m},   {"rms_m", t.rms_m}, {"points", t.points}, {"residual_m", t.residual_m}};
      if (t.named_by_user) jt["named_by_user"] = true;
      targets.push_back(std::move(jt));
    }
    (*j)["targets"] = std::move(targets);
  }
  if (project.georef) {
    const GeorefRecord& g = *project.georef;
    json rows = json::array();
    for (const ControlResidualRecord& r : g.control) {
      rows.push_back({{"name", r.name},
                      {"role", r.role},
                      {"delta", Vec(r.delta)},
                      {"leave_one_out_m", r.leave_one_out_m},
                      {"observations", r.observations}});
    }
    (*j)["georef"] = json{{"rms_m", g.rms_m},
                          {"used", g.used},
                          {"targets", g.targets},
                          {"tolerance_m", g.tolerance_m},
                          {"control", std::move(rows)}};
  }
}

Status GeorefFromJson(const json& j, const std::string& where, Project* project) {
  if (j.contains("control")) {
    std::set<std::string> names;
    for (const json& c : j.at("control")) {
      ControlPoint p;
      p.name = c.at("name").get<std::string>();
      const std::string what = where + ", control point '" + p.name + "'";
      if (p.name.empty() || !names.insert(p.name).second)
        return MakeError(ErrorCode::kParseError, what + ": control names must be unique and non-empty");
      p.position = Eigen::Vector3d(c.at("e").get<double>(), c.at("n").get<double>(), c.at("h").get<double>());
      if (!p.position.allFinite()) return MakeError(ErrorCode::kParseError, what + ": a coordinate is not finite");
      if (c.contains("sigma_m")) {
        p.sigma_m = c["sigma_m"].get<double>();
        if (!(*p.sigma_m > 0 && *p.sigma_m <= 10))
          return MakeError(ErrorCode::kParseError, what + ": sigma_m must be in (0, 10] m");
      }
      p.check = c.value("check", false);
      project->control.push_back(std::move(p));
    }
  }
  if (j.contains("targets")) {
    int k = 0;
    for (const json& t : j.at("targets")) {
      const std::string what = where + ", target " + std::to_string(k++);
      TargetRecord r;
      r.scan = t.at("scan").get<std::string>();
      if (project->FindScan(r.scan) < 0)
        return MakeError(ErrorCode::kParseError, what + ": '" + r.scan + "' is not a scan of the project");
      r.name = t.value("name", "");
      r.named_by_user = t.value("named_by_user", false);
      r.kind = t.value("kind", "sphere");
      if (r.kind != "sphere" && r.kind != "checker" && r.kind != "picked")
        return MakeError(ErrorCode::kParseError, what + ": kind must be 'sphere' or 'picked'");
      auto c = VecFrom(t.at("center"), what + " center");
      if (!c) return c.error();
      r.center = *c;
      r.sigma_m = t.value("sigma_m", 0.001);
      r.rms_m = t.value("rms_m", 0.0);
      if (Status s = ReadCount(t, "points", 2'000'000'000, what, &r.points); !s) return s;
      r.residual_m = t.value("residual_m", -1.0);
      for (double v : {r.sigma_m, r.rms_m, r.residual_m})
        if (Status s = Finite(v, what + " sigma, rms or residual"); !s) return s;
      if (!(r.sigma_m > 0)) return MakeError(ErrorCode::kParseError, what + ": sigma_m must be > 0");
      project->targets.push_back(std::move(r));
    }
  }
  if (j.contains("georef")) {
    const json& g = j.at("georef");
    GeorefRecord r;
    r.rms_m = g.value("rms_m", 0.0);
    for (const auto& [key, field] : {std::pair{"used", &r.used}, {"targets", &r.targets}})
      if (Status s = ReadCount(g, key, 1'000'000, where + ", georef", field); !s) return s;
    r.tolerance_m = g.value("tolerance_m", 0.0);
    for (const json& c : g.value("control", json::array())) {
      ControlResidualRecord row;
      row.name = c.at("name").get<std::string>();
      row.role = c.value("role", "");
      auto d = VecFrom(c.at("delta"), where + ", georef residual of '" + row.name + "'");
      if (!d) return d.error();
      row.delta = *d;
      row.leave_one_out_m = c.value("leave_one_out_m", -1.0);
      if (Status s = ReadCount(c, "observations", 1'000'000, where + ", georef residual of '" + row.name + "'",
                               &row.observations); !s)
        return s;
      r.control.push_back(std::move(row));
    }
    project->georef = std::move(r);
  }
  return Status::Ok();
}

}  // namespace scanreg::io
