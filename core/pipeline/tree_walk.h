// The scan order of the registration driver (registration_driver.h), walked until it holds (W §2
// step 4 with failure handling, beyond W): a failed link is excluded and the tree recomputed so the
// next-best edge takes its place; each link is loop-checked against another placed scan; scans no
// link reaches get partners by position.
#pragma once

#include <Eigen/Geometry>
#include <vector>

#include "core/common/expected.h"
#include "core/pipeline/pair_book.h"
#include "core/pipeline/registration_driver.h"
#include "core/registration/scan_order.h"

namespace scanreg::pipeline {

struct TreeWalk {
  ScanOrder order;
  std::vector<Eigen::Isometry3d> world;  // chained from the root at the identity
  std::vector<int> checked_with;         // per scan: the scan its link was loop-checked with, or -1
  // Per scan: its tree link is weak for want of support (PairResult::weak_support) and no loop
  // through another scan closed on it (a lone pair, or every check failed on its own), so its pose
  // is not verified (issue 33: "registered" means verified). Only when loops are checked; never
  // for a link the user kept.
  std::vector<bool> unconfirmed_weak;
  Eigen::MatrixXi weights;               // the source's weights and the partners by position
};

Expected<TreeWalk> WalkTree(const std::vector<Scan>& scans, const ScanOrderChoices& choices, const LinkSource& source,
                            const RegisterOptions& options, const CancelToken& cancel, PairBook& book);

}  // namespace scanreg::pipeline
