// Checked reading of the project file's whole-number fields: nlohmann's get<int>() wraps a value
// like 2^40 to 0 silently, which made a project naming scan 1099511627776 of a file read scan 0.
#pragma once

#include <Eigen/Core>
#include <nlohmann/json.hpp>
#include <string>

#include "core/common/expected.h"

namespace scanreg::io {

// A 3-vector as a JSON array of 3 numbers, and back (an error naming `what` when it is not one).
inline nlohmann::json Vec(const Eigen::Vector3d& v) { return nlohmann::json::array({v.x(), v.y(), v.z()}); }

inline Expected<Eigen::Vector3d> VecFrom(const nlohmann::json& j, const std::string& what) {
  if (!j.is_array() || j.size() != 3) return MakeError(ErrorCode::kParseError, what + ": expected 3 numbers");
  Eigen::Vector3d v;
  for (int k = 0; k < 3; ++k) {
    if (!j[k].is_number()) return MakeError(ErrorCode::kParseError, what + ": expected 3 numbers");
    v[k] = j[k].get<double>();
  }
  if (!v.allFinite()) return MakeError(ErrorCode::kParseError, what + ": a number is not finite");
  return v;
}

// j[key], when present, into *out: a whole number from 0 to max; else an error naming `what` and key.
inline Status ReadCount(const nlohmann::json& j, const char* key, long long max, const std::string& what, int* out) {
  if (!j.is_object() || !j.contains(key)) return Status::Ok();
  const nlohmann::json& v = j[key];
  const bool ok = v.is_number_integer() && !(v.is_number_unsigned() && v.get<unsigned long long>() > 1ull << 62) &&
                  v.get<long long>() >= 0 && v.get<long long>() <= max;
  if (!ok) {
    return MakeError(ErrorCode::kParseError,
                     what + ": '" + key + "' must be a whole number from 0 to " + std::to_string(max));
  }
  *out = static_cast<int>(v.get<long long>());
  return Status::Ok();
}

}  // namespace scanreg::io
