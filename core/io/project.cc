#include "core/io/project.h"

#include "core/io/text_parse.h"

#include <cstdint>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "core/common/atomic_file.h"
#include "core/common/skipped_pair.h"
#include "core/geometry/transform.h"
#include "core/io/json_fields.h"
#include "core/io/project_georef.h"

namespace scanreg::io {
namespace {

using nlohmann::json;

LinkStatus LinkStatusFromName(const std::string& s) {
  if (s == "ok") return LinkStatus::kOk;
  if (s == "weak") return LinkStatus::kWeak;
  return LinkStatus::kFailed;
}

// {"scans": [names], "matches": [[counts]]}: one row of non-negative integers per named scan.
Status ConfusionFromJson(const json& j, const std::string& where, Project* project) {
  const Error bad =
      MakeError(ErrorCode::kParseError, where +
                                            ": 'confusion' must hold 'scans' (names) and 'matches' (one row of "
                                            "non-negative integers or null per scan); delete it and register again");
  if (!j.is_object() || !j.contains("scans") || !j.contains("matches")) return bad;
  const json& names = j["scans"];
  const json& rows = j["matches"];
  if (!names.is_array() || !rows.is_array() || rows.size() != names.size()) return bad;
  const std::size_t n = names.size();
  Eigen::MatrixXi c(n, n);
  for (std::size_t i = 0; i < n; ++i) {
    if (!names[i].is_string() || !rows[i].is_array() || rows[i].size() != n) return bad;
    project->confusion_scans.push_back(names[i].get<std::string>());
    for (std::size_t k = 0; k < n; ++k) {
      if (rows[i][k].is_null()) {  // a pair left out of the candidate pairs
        c(i, k) = kSkippedPair;
        continue;
      }
      if (!rows[i][k].is_number_integer() || rows[i][k].get<long long>() < 0 ||
          rows[i][k].get<long long>() > (1LL << 31) - 1)
        return bad;
      c(i, k) = rows[i][k].get<int>();
    }
  }
  project->confusion = std::move(c);
  return Status::Ok();
}

}  // namespace

json PoseToJson(const Eigen::Isometry3d& t) {
  const auto m = RowMajorFromIsometry(t);
  return json(std::vector<double>(m.begin(), m.end()));
}

Expected<Eigen::Isometry3d> PoseFromJson(const json& j, const std::string& what) {
  if (!j.is_array() || j.size() != 16) {
    return MakeError(ErrorCode::kParseError, what + " must be a list of 16 numbers (row-major 4x4)");
  }
  std::array<double, 16> m{};
  for (int i = 0; i < 16; ++i) {
    if (!j[i].is_number()) return MakeError(ErrorCode::kParseError, what + " holds a value that is not a number");
    m[i] = j[i].get<double>();
    if (!std::isfinite(m[i])) return MakeError(ErrorCode::kParseError, what + " holds a non-finite number");
  }
  Eigen::Matrix3d r, clean;
  for (int i = 0; i < 3; ++i)
    for (int k = 0; k < 3; ++k) r(i, k) = m[4 * i + k];
  if (!ProjectToRotation(r, &clean, 1e-4) || m[12] != 0 || m[13] != 0 || m[14] != 0 || m[15] != 1) {
    return MakeError(ErrorCode::kParseError, what + " is not a rigid transform");
  }
  return IsometryFromRowMajor(m);
}

json LinkToJson(const LinkRecord& l) {
  json j{{"parent", l.parent},
              {"child", l.child},
              {"method", l.method},
              {"status", LinkStatusName(l.status)},
              {"reason", l.reason},
              {"matches", l.matches},
              {"geometric_matches", l.geometric_matches},
              {"reliable", l.reliable},
              {"ransac_inliers", l.ransac_inliers},
              {"geometric_inliers", l.geometric_inliers},
              {"consistent", l.consistent},
              {"rms_m", l.rms_m},
              {"overlap", l.overlap},
              {"conflict", l.conflict},
              {"moving", l.moving},
              {"iterations", l.iterations},
              {"seconds", l.seconds},
              {"parent_from_child", PoseToJson(l.parent_from_child)},
              {"loop_check", l.loop_check},
              {"user_accepted", l.user_accepted},
              {"user_rejected", l.user_rejected}};
  if (!l.picked.empty()) {
    json picked = json::array();
    for (const PickedPoint& p : l.picked)
      picked.push_back({p.parent.x(), p.parent.y(), p.parent.z(), p.child.x(), p.child.y(), p.child.z()});
    j["picked"] = picked;
  }
  return j;
}

Expected<LinkRecord> LinkFromJson(const json& j, const std::string& where) {
  LinkRecord l;
  try {
    l.parent = j.at("parent").get<std::string>();
    l.child = j.at("child").get<std::string>();
    l.method = j.value("method", "");
    l.status = LinkStatusFromName(j.value("status", "failed"));
    l.reason = j.value("reason", "");
    for (const auto& [key, field] : {std::pair{"matches", &l.matches}, {"reliable", &l.reliable},
                                     {"ransac_inliers", &l.ransac_inliers}, {"geometric_matches", &l.geometric_matches},
                                     {"geometric_inliers", &l.geometric_inliers}, {"consistent", &l.consistent},
                                     {"iterations", &l.iterations}})
      if (Status s = ReadCount(j, key, 2'000'000'000, where, field); !s) return s.error();
    l.rms_m = j.value("rms_m", 0.0);
    l.overlap = j.value("overlap", 0.0);
    l.conflict = j.value("conflict", 0.0);
    l.moving = j.value("moving", 0.0);
    l.seconds = j.value("seconds", 0.0);
    l.loop_check = j.value("loop_check", false);
    l.user_accepted = j.value("user_accepted", false);
    l.user_rejected = j.value("user_rejected", false);
  } catch (const json::exception& e) {
    return MakeError(ErrorCode::kParseError, where + ": " + e.what());
  }
  if (j.contains("parent_from_child")) {
    auto t = PoseFromJson(j["parent_from_child"], where + " parent_from_child");
    if (!t) return t.error();
    l.parent_from_child = *t;
  }
  if (j.contains("picked")) {  // [[parent x y z, child x y z], ...] in metres, each scan's own frame
    const json& picked = j["picked"];
    const Error bad = MakeError(ErrorCode::kParseError, where + ": 'picked' must be a list of 6 finite numbers per "
                                                                "picked point (parent x y z, child x y z)");
    if (!picked.is_array()) return bad;
    for (const json& row : picked) {
      if (!row.is_array() || row.size() != 6) return bad;
      double v[6];
      for (int k = 0; k < 6; ++k) {
        if (!row[k].is_number()) return bad;
        v[k] = row[k].get<double>();
        if (!std::isfinite(v[k])) return bad;
      }
      l.picked.push_back({Eigen::Vector3d(v[0], v[1], v[2]), Eigen::Vector3d(v[3], v[4], v[5])});
    }
  }
  return l;
}

const char* LinkStatusName(LinkStatus status) {
  switch (status) {
    case LinkStatus::kOk:
      return "ok";
    case LinkStatus::kWeak:
      return "weak";
    case LinkStatus::kFailed:
      return "failed";
  }
  return "failed";
}

PoseState ScanPoseState(const ProjectScan& scan) {
  if (!scan.registered) return scan.unverified ? PoseState::kNotVerified : PoseState::kUnregistered;
  if (scan.manual_pose) return PoseState::kManual;
  if (scan.imported_pose) return PoseState::kImported;
  return PoseState::kRegistered;
}

const char* PoseStateName(PoseState state) {
  switch (state) {
    case PoseState::kUnregistered:
      return "unregistered";
    case PoseState::kNotVerified:
      return "not verified";
    case PoseState::kRegistered:
      return "registered";
    case PoseState::kImported:
      return "imported";
    case PoseState::kManual:
      return "manual pose";
  }
  return "unregistered";
}

int Project::FindScan(const std::string& name) const {
  for (std::size_t i = 0; i < scans.size(); ++i)
    if (scans[i].name == name) return static_cast<int>(i);
  return -1;
}

const Eigen::MatrixXi* Project::CurrentConfusion() const {
  const auto n = static_cast<Eigen::Index>(scans.size());
  if (confusion.rows() != n || confusion.cols() != n || confusion_scans.size() != scans.size() || n == 0)
    return nullptr;
  for (std::size_t i = 0; i < scans.size(); ++i)
    if (confusion_scans[i] != scans[i].name) return nullptr;
  return &confusion;
}

Expected<Project> LoadProject(const std::filesystem::path& path) {
  namespace fs = std::filesystem;
  const std::string where = "project '" + path.string() + "'";
  std::error_code ec;
  if (!fs::exists(path, ec)) return MakeError(ErrorCode::kNotFound, where + " does not exist; check the path");
  // Only a regular file of a sane size: a directory, a FIFO or a device would crash, block or never end.
  if (!fs::is_regular_file(path, ec)) {
    return MakeError(ErrorCode::kIoError, where +
                                              " is not a regular file (a directory or a device?); give the "
                                              "*.scanreg.json file");
  }
  constexpr std::uintmax_t kMaxBytes = 256u << 20;
  if (fs::file_size(path, ec) > kMaxBytes) {
    return MakeError(ErrorCode::kParseError, where + " is larger than 256 MiB; it is not a scanreg project");
  }
  Expected<std::string> text = ReadWholeFile(path);
  if (!text) return text.error();
  json j;
  try {
    j = json::parse(*text);
  } catch (const json::exception& e) {  // malformed, or a number out of range (1e309)
    return MakeError(ErrorCode::kParseError,
                     where + " is not valid JSON (" + e.what() + "); restore it from a backup or create a new project");
  }
  if (!j.is_object() || !j.contains("schema_version") || !j["schema_version"].is_number_integer()) {
    return MakeError(ErrorCode::kParseError, where + " has no schema_version; is it a scanreg project?");
  }
  const int version = j["schema_version"].get<int>();
  if (version != Project::kSchemaVersion) {
    return MakeError(ErrorCode::kUnsupported,
                     where + " has schema version " + std::to_string(version) + "; this scanreg reads version " +
                         std::to_string(Project::kSchemaVersion) + " — use a matching scanreg");
  }
  Project project;
  project.file = fs::absolute(path);
  project.disk_digest = Digest(*text);
  const fs::path base = project.file.parent_path();
  std::set<std::string> names;
  try {
    for (const json& s : j.at("scans")) {
      ProjectScan scan;
      scan.name = s.at("name").get<std::string>();
      const std::string label = where + ", scan '" + scan.name + "'";
      if (scan.name.empty() || !names.insert(scan.name).second) {
        return MakeError(ErrorCode::kParseError, label + ": scan names must be unique and non-empty");
      }
      scan.path = fs::path(s.at("path").get<std::string>());
      if (scan.path.is_relative()) scan.path = (base / scan.path).lexically_normal();
      // A missing scan file is not an error here: the project can still be read, and relinked
      // (pipeline::MissingScanFiles); loading the scans' points names it.
      if (Status st = ReadCount(s, "index_in_file", 1'000'000, label, &scan.index_in_file); !st) return st.error();
      scan.registered = s.value("registered", false);
      if (s.contains("world_from_scan")) {
        auto t = PoseFromJson(s["world_from_scan"], label + " world_from_scan");
        if (!t) return t.error();
        scan.world_from_scan = *t;
      }
      if (s.contains("reference_world_from_scan")) {
        auto t = PoseFromJson(s["reference_world_from_scan"], label + " reference_world_from_scan");
        if (!t) return t.error();
        scan.reference_world_from_scan = *t;
      }
      if (s.contains("parent_override")) scan.parent_override = s["parent_override"].get<std::string>();
      if (s.contains("coarse_world_from_scan")) {
        auto t = PoseFromJson(s["coarse_world_from_scan"], label + " coarse_world_from_scan");
        if (!t) return t.error();
        scan.coarse_world_from_scan = *t;
      }
      scan.unregistered_reason = s.value("unregistered_reason", "");
      scan.manual_pose = s.value("manual_pose", false);
      scan.cluster = s.value("cluster", "");
      scan.unverified = s.value("unverified", false);
      scan.imported_pose = s.value("imported_pose", false);
      for (const auto& [key, field] : {std::make_pair("start_consistency_m", &scan.start_consistency_m),
                                       std::make_pair("consistency_m", &scan.consistency_m),
                                       std::make_pair("conditioning", &scan.conditioning)}) {
        if (!s.contains(key)) continue;
        if (!s[key].is_number() || !(s[key].get<double>() >= 0))
          return MakeError(ErrorCode::kParseError, label + " " + key + ": not a number of 0 or more");
        *field = s[key].get<double>();
      }
      if (s.contains("file_up")) {
        auto up = VecFrom(s["file_up"], label + " file_up");
        if (!up) return up.error();
        if (!(up->norm() > 0.5)) return MakeError(ErrorCode::kParseError, label + " file_up: not a direction");
        scan.file_up = up->normalized();
      }
      project.scans.push_back(std::move(scan));
    }
    for (const ProjectScan& scan : project.scans) {
      if (scan.parent_override && project.FindScan(*scan.parent_override) < 0) {
        return MakeError(ErrorCode::kParseError, where + ", scan '" + scan.name + "': parent override '" +
                                                     *scan.parent_override + "' is not a scan of the project");
      }
    }
    if (j.contains("root") && !j["root"].is_null()) {
      project.root = j["root"].get<std::string>();
      if (project.FindScan(*project.root) < 0) {
        return MakeError(ErrorCode::kParseError, where + ": the root '" + *project.root +
                                                     "' is not a scan of the project; name one of its scans or "
                                                     "remove 'root'");
      }
    }
    if (j.contains("links")) {
      int k = 0;
      for (const json& l : j["links"]) {
        auto link = LinkFromJson(l, where + ", link " + std::to_string(k++));
        if (!link) return link.error();
        for (const std::string& end : {link->parent, link->child}) {
          if (project.FindScan(end) < 0) {
            return MakeError(ErrorCode::kParseError, where + ", link " + std::to_string(k) + ": '" + end +
                                                         "' is not a scan of the project; remove the link or "
                                                         "register again");
          }
        }
        project.links.push_back(std::move(*link));
      }
    }
    if (j.contains("confusion")) {
      if (Status s = ConfusionFromJson(j["confusion"], where, &project); !s) return s.error();
    }
    if (j.contains("consistency")) {
      const json& c = j["consistency"];
      ConsistencyRecord r;
      try {
        r.start_rms_m = c.at("start_rms_m").get<double>();
        r.result_rms_m = c.at("result_rms_m").get<double>();
        r.cutoff_m = c.at("cutoff_m").get<double>();
        r.pairs = c.at("pairs").get<int>();
        r.multiview = c.value("multiview", false);
        r.refused = c.value("refused", false);
      } catch (const json::exception& e) {
        return MakeError(ErrorCode::kParseError, where + ": 'consistency' needs start_rms_m, result_rms_m, cutoff_m "
                                                         "and pairs (" + e.what() + "); register again");
      }
      project.consistency = r;
    }
    if (j.contains("settings")) {
      for (auto it = j["settings"].begin(); it != j["settings"].end(); ++it)
        project.settings[it.key()] = it->is_string() ? it->get<std::string>() : it->dump();
    }
    if (Status s = GeorefFromJson(j, where, &project); !s) return s.error();
  } catch (const json::exception& e) {
    return MakeError(ErrorCode::kParseError, where + " is malformed: " + e.what());
  }
  return project;
}

std::uint64_t Digest(const std::string& bytes) {
  std::uint64_t h = 1469598103934665603ull;
  for (unsigned char c : bytes) h = (h ^ c) * 1099511628211ull;
  return h;
}

Status SaveProject(const Project& project, const std::filesystem::path& path, std::uint64_t* saved_digest) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (project.disk_digest != 0 && !project.file.empty() && fs::exists(path, ec) &&
      fs::equivalent(path, project.file, ec)) {
    Expected<std::string> now = ReadWholeFile(path);
    if (now && Digest(*now) != project.disk_digest) {
      return MakeError(ErrorCode::kConflict, "project '" + path.string() +
                                               "' changed on disk since it was read (another run or an editor wrote "
                                               "it); nothing was saved — open it again, or save under another name");
    }
  }
  const fs::path base = fs::absolute(path).parent_path();
  json scans = json::array();
  for (const ProjectScan& s : project.scans) {
    fs::path rel = s.path.is_absolute() ? s.path.lexically_relative(base) : s.path;
    if (rel.empty()) rel = s.path;
    json js{{"name", s.name},
            {"path", rel.generic_string()},
            {"index_in_file", s.index_in_file},
            {"registered", s.registered},
            {"world_from_scan", PoseToJson(s.world_from_scan)}};
    if (s.reference_world_from_scan) js["reference_world_from_scan"] = PoseToJson(*s.reference_world_from_scan);
    if (s.parent_override) js["parent_override"] = *s.parent_override;
    if (s.coarse_world_from_scan) js["coarse_world_from_scan"] = PoseToJson(*s.coarse_world_from_scan);
    if (!s.unregistered_reason.empty()) js["unregistered_reason"] = s.unregistered_reason;
    if (s.manual_pose) js["manual_pose"] = true;
    if (!s.cluster.empty()) js["cluster"] = s.cluster;
    if (s.unverified && !s.registered) js["unverified"] = true;
    if (s.imported_pose) js["imported_pose"] = true;
    if (s.file_up) js["file_up"] = Vec(*s.file_up);
    if (s.start_consistency_m) js["start_consistency_m"] = *s.start_consistency_m;
    if (s.consistency_m) js["consistency_m"] = *s.consistency_m;
    if (s.conditioning) js["conditioning"] = *s.conditioning;
    scans.push_back(std::move(js));
  }
  json links = json::array();
  for (const LinkRecord& l : project.links) links.push_back(LinkToJson(l));
  json j{{"schema_version", Project::kSchemaVersion},
         {"generator", "scanreg"},
         {"scans", std::move(scans)},
         {"links", std::move(links)},
         {"settings", project.settings}};
  j["root"] = project.root ? json(*project.root) : json(nullptr);
  GeorefToJson(project, &j);
  if (const ConsistencyRecord* c = project.consistency ? &*project.consistency : nullptr) {
    j["consistency"] = json{{"start_rms_m", c->start_rms_m}, {"result_rms_m", c->result_rms_m},
                            {"cutoff_m", c->cutoff_m},       {"pairs", c->pairs},
                            {"multiview", c->multiview},     {"refused", c->refused}};
  }
  if (const Eigen::MatrixXi* confusion = project.CurrentConfusion()) {
    json rows = json::array();
    for (int i = 0; i < confusion->rows(); ++i) {
      json row = json::array();
      for (int k = 0; k < confusion->cols(); ++k) {
        if ((*confusion)(i, k) == kSkippedPair) row.push_back(nullptr);
        else row.push_back((*confusion)(i, k));
      }
      rows.push_back(std::move(row));
    }
    j["confusion"] = json{{"scans", project.confusion_scans}, {"matches", std::move(rows)}};
  }
  const std::string text = j.dump(2) + "\n";
  AtomicFile file(path);
  if (Status s = file.Open(); !s) return s;
  if (Status s = file.Write(text); !s) return s;
  if (Status s = file.Commit(); !s) return s;
  if (saved_digest) *saved_digest = Digest(text);
  return Status::Ok();
}

}  // namespace scanreg::io
