// What the report's pictures and tables read from a saved project beyond its fields: which links
// form the scan-order tree and the order in which the registration placed the scans.
#pragma once

#include <vector>

#include "core/io/project.h"

namespace scanreg::report {

// A link the poses are chained along: not a loop check, not failed, not rejected by the user.
bool IsTreeLink(const io::LinkRecord& link);

// Scan indices in scan order (W §2 step 4): the root, then each child of a tree link in the order
// the links were placed, then the scans the tree does not reach, in project order.
std::vector<int> ScanOrder(const io::Project& project);

}  // namespace scanreg::report
