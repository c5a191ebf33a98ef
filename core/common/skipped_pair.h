// The confusion matrix's mark of a pair whose features were not matched (not among the candidate
// pairs, issue 13 item 3): C(i, j) = kSkippedPair. Saved in the project file as null.
#pragma once

namespace scanreg {

constexpr int kSkippedPair = -1;

}  // namespace scanreg
