// Applies a pair registration the user chose (the GUI pair panel's "use this result") to a
// project: the link becomes the child's tree link and the child, with every scan registered
// through it, moves by the change of the child's pose (their relative poses are kept).
#pragma once

#include "core/common/expected.h"
#include "core/io/project.h"

namespace scanreg::pipeline {

// Errors (kInvalidArgument, naming the scans and what to do): unknown scan, a failed link, an
// unregistered parent, a parent registered through the child (the tree would have a cycle).
// When the child's tree parent changes, the parent becomes its parent override, so that a later
// re-registration keeps the user's choice. A weak link is marked accepted.
Status ApplyPairResult(const io::LinkRecord& link, io::Project& project);

}  // namespace scanreg::pipeline
