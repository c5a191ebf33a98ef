#include "core/pipeline/manual_alignment.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

#include "core/pipeline/refine_pair.h"
#include "core/registration/rigid_fit.h"

namespace scanreg::pipeline {
namespace {

// The largest distance of a picked point (parent side) from their centroid.
double Spread(const std::vector<io::PickedPoint>& pairs) {
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  for (const io::PickedPoint& p : pairs) c += p.parent;
  c /= std::max<double>(1.0, pairs.size());
  double r = 0.0;
  for (const io::PickedPoint& p : pairs) r = std::max(r, (p.parent - c).norm());
  return r;
}

std::string Mm(double m) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.0f mm", 1e3 * m);
  return buf;
}

}  // namespace

Expected<PickedFit> FitPickedPoints(const std::vector<io::PickedPoint>& pairs, bool levelled) {
  const std::size_t need = levelled ? 2 : 3;
  if (pairs.size() < need) {
    return MakeError(ErrorCode::kInvalidArgument,
                     "picked-point alignment needs at least " + std::to_string(need) + " point pairs" +
                         (levelled ? " (levelled scans)" : " (or 2 when both scans are levelled)") + "; " +
                         std::to_string(pairs.size()) + " picked");
  }
  std::vector<Eigen::Vector3d> child, parent;
  for (std::size_t i = 0; i < pairs.size(); ++i) {
    if (!pairs[i].parent.allFinite() || !pairs[i].child.allFinite()) {
      return MakeError(ErrorCode::kInvalidArgument,
                       "picked pair " + std::to_string(i + 1) + " has a non-finite coordinate; pick it again");
    }
    child.push_back(pairs[i].child);
    parent.push_back(pairs[i].parent);
  }
  PickedFit fit;
  fit.levelled = levelled;
  if (levelled) {
    std::optional<Eigen::Isometry3d> pose = FitHeading(child, parent);
    if (!pose) {
      return MakeError(ErrorCode::kInvalidArgument,
                       "the picked points lie above one another; pick points apart from each other across the view");
    }
    fit.parent_from_child = *pose;
  } else {
    Expected<Eigen::Isometry3d> pose = FitRigid(child, parent);
    if (!pose) {
      return MakeError(ErrorCode::kInvalidArgument,
                       "the picked points are on one line or coincide; pick at least 3 points that are not in a "
                       "line (or 2 with 'levelled' when both scans are level)");
    }
    fit.parent_from_child = *pose;
  }
  double sum_sq = 0.0;
  for (std::size_t i = 0; i < pairs.size(); ++i) {
    const double r = (parent[i] - fit.parent_from_child * child[i]).norm();
    fit.residual_m.push_back(r);
    sum_sq += r * r;
  }
  fit.rms_m = std::sqrt(sum_sq / double(pairs.size()));
  return fit;
}

double PickedReach(const PickedFit& fit, const std::vector<io::PickedPoint>& pairs) {
  const double worst = fit.residual_m.empty() ? 0.0 : *std::max_element(fit.residual_m.begin(), fit.residual_m.end());
  const double spread = Spread(pairs);
  return std::min(std::max(3.0 * worst, spread / 100.0), spread / 5.0);
}

Expected<io::LinkRecord> AlignFromPickedPoints(const Scan& parent, const Scan& child,
                                               const std::vector<io::PickedPoint>& pairs, bool levelled,
                                               const RegisterOptions& options, const CancelToken& cancel) {
  Expected<PickedFit> fit = FitPickedPoints(pairs, levelled);
  if (!fit) return fit.error();
  const double worst = *std::max_element(fit->residual_m.begin(), fit->residual_m.end());
  const double spread = Spread(pairs);
  if (worst > spread / 10.0) {
    const std::size_t bad = std::max_element(fit->residual_m.begin(), fit->residual_m.end()) - fit->residual_m.begin();
    return MakeError(ErrorCode::kInvalidArgument,
                     "picked pair " + std::to_string(bad + 1) + " is " + Mm(worst) +
                         " off the others' pose (the picks span " + Mm(spread) +
                         "): it is probably not the same point in both scans; pick it again or remove it");
  }
  Expected<io::LinkRecord> link =
      RefinePairFromPose(parent, child, fit->parent_from_child, options, PickedReach(*fit, pairs), cancel);
  if (!link) return link.error();
  const std::string fine = link->method.substr(link->method.find('+') + 1);
  link->method = "picked+" + fine;
  link->picked = pairs;
  return link;
}

}  // namespace scanreg::pipeline
