#include "core/pipeline/register_settings.h"

#include <cmath>
#include <cstdlib>

#include "core/io/text_parse.h"

namespace scanreg::pipeline {
namespace {

std::string Number(double v) {
  char buf[32];
  return std::string(buf, io::AppendNumber(buf, v));
}

bool ParseDouble(const std::string& text, double* out) {
  if (text.empty()) return false;
  char* end = nullptr;
  *out = std::strtod(text.c_str(), &end);
  return end == text.c_str() + text.size() && std::isfinite(*out);
}

std::string Join(const std::vector<std::string>& v) {
  std::string s;
  for (std::size_t i = 0; i < v.size(); ++i) s += (i ? (i + 1 == v.size() ? " or " : ", ") : "") + v[i];
  return s;
}

// The names of every value of an enumerated setting, in the order the GUI lists them.
template <typename T>
std::vector<std::string> Names(const std::vector<T>& all, const char* (*name)(T)) {
  std::vector<std::string> names;
  for (T v : all) names.push_back(name(v));
  return names;
}

Status Bad(const RegisterSetting& s, const std::string& value, const std::string& want) {
  return MakeError(ErrorCode::kInvalidArgument, std::string(s.label) + ": '" + value + "' is not valid; " + want);
}

// Sets *out to the value named `value`, or says which names are valid.
template <typename T>
Status SetChoice(const RegisterSetting& s, const std::string& value, const std::vector<T>& all,
                 const char* (*name)(T), T* out) {
  for (T v : all) {
    if (value == name(v)) {
      *out = v;
      return Status::Ok();
    }
  }
  return Bad(s, value, "choose " + Join(s.choices));
}

Status SetNumber(const RegisterSetting& s, const std::string& value, double lo, double hi, double* out) {
  double v = 0;
  if (!ParseDouble(value, &v) || v < lo || v > hi) {
    return Bad(s, value, "give a number from " + Number(lo) + " to " + Number(hi));
  }
  *out = v;
  return Status::Ok();
}

// A count of scans from 0 to 1000; `zero` says what 0 means.
Status SetScanCount(const RegisterSetting& s, const std::string& value, const std::string& zero, int* out) {
  double k = 0;
  if (Status st = SetNumber(s, value, 0.0, 1000.0, &k); !st) return st;
  if (k != std::floor(k)) return Bad(s, value, "give a whole number of scans (0: " + zero + ")");
  *out = static_cast<int>(k);
  return Status::Ok();
}

}  // namespace

const std::vector<RegisterSetting>& RegisterSettings() {
  static const std::vector<RegisterSetting> all = {
      {"register.coarse", "coarse", "coarse method", {"3d", "epnp", "none"}},
      {"register.features", "features", "correspondences", Names(AllFeatureSources(), FeatureSourcesName)},
      {"register.fine", "fine", "fine method", Names(AllFineMethods(), FineMethodName)},
      {"register.ratio", "ratio", "descriptor ratio t_des", {}},
      {"register.sift_half_size_step_deg", "sift-half-size-step", "SIFT on a half-size panorama when its cells are at most this far apart (°; 0: always full size)", {}},
      {"register.coarse_scale", "coarse-scale", "coarse FPFH scale (x the voxel; 0: fine scale only)", {}},
      {"register.noise_m", "noise", "range noise (m; 0: from the data)", {}},
      {"register.overlap_distance_m", "overlap-distance", "overlap distance (m; 0: from the data)", {}},
      {"register.global", "global", "global registration", {}, true},
      {"register.multiview", "multiview", "multi-view fine step (refinement from current poses)", {}, true},
      {"register.keep_imported", "keep-imported", "keep imported poses fixed", {}, true},
      {"register.sphere_radius_m", "sphere-radius", "sphere target radius (m)", {}},
      {"register.checker_size_m", "checker-size", "checkerboard target size (m; 0: none)", {}},
      {"register.control_tolerance_m", "control-tolerance", "control residual tolerance (m)", {}},
      {"register.levelled_deg", "levelled", "levelled scans: accuracy (°; 0: not levelled)", {}},
      {"register.candidates", "candidates", "partners matched per scan (0: every pair)", {}},
      {"register.global_partners", "global-partners", "overlap partners per scan in the global step (0: every overlapping pair)", {}},
  };
  return all;
}

std::string RegisterSettingValue(const RegisterOptions& o, const RegisterSetting& s) {
  const std::string key = s.key;
  if (key == "register.coarse") return o.from_current_poses ? "none" : CoarseMethodName(o.coarse.method);
  if (key == "register.fine") return FineMethodName(o.fine);
  if (key == "register.features") return FeatureSourcesName(o.features);
  if (key == "register.ratio") return Number(o.match.ratio);
  if (key == "register.sift_half_size_step_deg") return Number(o.sift.half_size_max_step_deg);
  if (key == "register.coarse_scale") return Number(o.geometric.coarse_scale);
  if (key == "register.noise_m") return Number(o.range_sigma_m);
  if (key == "register.overlap_distance_m") return Number(o.overlap_distance_m);
  if (key == "register.global") return o.global ? "true" : "false";
  if (key == "register.multiview") return o.multiview ? "true" : "false";
  if (key == "register.keep_imported") return o.keep_imported ? "true" : "false";
  if (key == "register.sphere_radius_m") return Number(o.spheres.radius_m);
  if (key == "register.checker_size_m") return Number(o.checkers.size_m);
  if (key == "register.control_tolerance_m") return Number(o.georef.tolerance_m);
  if (key == "register.levelled_deg") return Number(o.georef.levelled_sigma_rad * 180.0 / M_PI);
  if (key == "register.candidates") return std::to_string(o.candidates);
  if (key == "register.global_partners") return std::to_string(o.global_partners);
  return "";
}

Status ApplyRegisterSetting(const RegisterSetting& s, const std::string& value, RegisterOptions* o) {
  const std::string key = s.key;
  if (s.boolean) {
    if (value != "true" && value != "false") return Bad(s, value, "give true or false");
    (key == "register.global" ? o->global : key == "register.multiview" ? o->multiview : o->keep_imported) = value == "true";
    return Status::Ok();
  }
  if (key == "register.coarse") {
    if (value == "none") {
      o->from_current_poses = true;
      return Status::Ok();
    }
    for (CoarseMethod m : AllCoarseMethods()) {
      if (value == CoarseMethodName(m)) {
        o->coarse.method = m;
        o->from_current_poses = false;
        return Status::Ok();
      }
    }
    return Bad(s, value, "choose " + Join(s.choices));
  }
  if (key == "register.fine") return SetChoice(s, value, AllFineMethods(), FineMethodName, &o->fine);
  if (key == "register.features") return SetChoice(s, value, AllFeatureSources(), FeatureSourcesName, &o->features);
  if (key == "register.ratio") return SetNumber(s, value, 0.05, 1.0, &o->match.ratio);
  if (key == "register.sift_half_size_step_deg") return SetNumber(s, value, 0.0, 10.0, &o->sift.half_size_max_step_deg);
  if (key == "register.coarse_scale") {
    if (Status st = SetNumber(s, value, 0.0, 20.0, &o->geometric.coarse_scale); !st) return st;
    if (o->geometric.coarse_scale != 0 && o->geometric.coarse_scale <= 1.0)
      return Bad(s, value, "give 0 (the fine scale only) or more than 1 voxel (3: for stations far apart)");
    return Status::Ok();
  }
  if (key == "register.noise_m") return SetNumber(s, value, 0.0, 0.5, &o->range_sigma_m);
  if (key == "register.overlap_distance_m") return SetNumber(s, value, 0.0, 100.0, &o->overlap_distance_m);
  if (key == "register.sphere_radius_m") return SetNumber(s, value, 0.005, 2.0, &o->spheres.radius_m);
  if (key == "register.checker_size_m") {
    if (Status st = SetNumber(s, value, 0.0, 2.0, &o->checkers.size_m); !st) return st;
    if (o->checkers.size_m != 0 && o->checkers.size_m < 0.02) return Bad(s, value, "give 0 (none) or 0.02 to 2 m");
    return Status::Ok();
  }
  if (key == "register.control_tolerance_m") return SetNumber(s, value, 0.0001, 10.0, &o->georef.tolerance_m);
  if (key == "register.levelled_deg") {
    double deg = 0;
    if (Status st = SetNumber(s, value, 0.0, 5.0, &deg); !st) return st;
    o->georef.levelled_sigma_rad = deg * M_PI / 180.0;
    return Status::Ok();
  }
  if (key == "register.candidates") return SetScanCount(s, value, "every pair", &o->candidates);
  if (key == "register.global_partners") return SetScanCount(s, value, "every overlapping pair", &o->global_partners);
  return MakeError(ErrorCode::kInvalidArgument, std::string("unknown registration setting '") + s.key + "'");
}

Expected<RegisterOptions> RegisterOptionsFromSettings(const std::map<std::string, std::string>& settings,
                                                      RegisterOptions base) {
  for (const auto& [key, value] : settings) {
    if (key.rfind("register.", 0) != 0) continue;
    const RegisterSetting* setting = nullptr;
    for (const RegisterSetting& s : RegisterSettings())
      if (key == s.key) setting = &s;
    if (!setting) {
      return MakeError(ErrorCode::kInvalidArgument,
                       "the project's setting '" + key + "' is not a registration setting of this scanreg");
    }
    if (Status st = ApplyRegisterSetting(*setting, value, &base); !st) {
      return MakeError(st.error().code, "the project's saved " + st.error().message);
    }
  }
  return base;
}

Expected<RegisterOptions> ProjectRegisterOptions(const io::Project& project) {
  RegisterOptions defaults;
  bool all_imported = !project.scans.empty();
  for (const io::ProjectScan& s : project.scans) all_imported &= s.registered && s.imported_pose;
  defaults.from_current_poses = all_imported;
  return RegisterOptionsFromSettings(project.settings, defaults);
}

void StoreRegisterSettings(const RegisterOptions& options, std::map<std::string, std::string>* settings) {
  for (const RegisterSetting& s : RegisterSettings()) (*settings)[s.key] = RegisterSettingValue(options, s);
}

}  // namespace scanreg::pipeline
