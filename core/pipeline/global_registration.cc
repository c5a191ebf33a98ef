#include "core/pipeline/global_registration.h"

#include <map>
#include <string>

#include "core/common/log.h"
#include "core/registration/pose_graph.h"

namespace scanreg::pipeline {

Status RunGlobalRegistration(const std::vector<Scan>& scans, const CancelToken& cancel, ProjectRegistration* result) {
#ifdef SCANREG_HAVE_POSE_GRAPH
  // Graph nodes: the registered scans only (an unregistered scan has no link to the root).
  std::map<std::string, int> node;
  std::vector<int> scan_of;
  std::vector<Eigen::Isometry3d> initial;
  for (std::size_t i = 0; i < result->scans.size(); ++i) {
    if (!result->scans[i].registered) continue;
    node[scans[i].name] = static_cast<int>(scan_of.size());
    scan_of.push_back(static_cast<int>(i));
    initial.push_back(result->scans[i].world_from_scan);
  }
  std::vector<PoseGraphLink> graph;
  for (const io::LinkRecord& l : result->links) {
    if (l.status == io::LinkStatus::kFailed || !node.count(l.parent) || !node.count(l.child)) continue;
    graph.push_back({node.at(l.parent), node.at(l.child), l.parent_from_child});
  }
  if (graph.empty() || result->root < 0 || !node.count(scans[result->root].name)) return Status::Ok();
  PoseGraphOptions options;
  options.root = node.at(scans[result->root].name);
  NullProgress quiet;
  Expected<PoseGraphResult> solved = OptimizePoseGraph(initial, graph, options, quiet, cancel);
  if (!solved) return solved.error();
  for (std::size_t k = 0; k < scan_of.size(); ++k)
    result->scans[scan_of[k]].world_from_scan = solved->world_from_scan[k];
  result->global_links.clear();
  for (const PoseGraphLinkReport& r : solved->links) {
    const std::string& parent = scans[scan_of[r.parent]].name;
    const std::string& child = scans[scan_of[r.child]].name;
    result->global_links.push_back({parent, child, r.translation_before_m, r.rotation_before_rad, r.translation_after_m,
                                    r.rotation_after_rad, r.weight, r.down_weighted});
    if (r.down_weighted) LogWarning("global registration down-weighted link " + child + " -> " + parent);
  }
  return Status::Ok();
#else
  (void)scans;
  (void)cancel;
  (void)result;
  return MakeError(ErrorCode::kUnsupported, "global registration needs Ceres: this scanreg was built without it");
#endif
}

}  // namespace scanreg::pipeline
