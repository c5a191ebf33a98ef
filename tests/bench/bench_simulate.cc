#include "tests/bench/bench_table.h"

namespace scanreg::bench {
void RunSimulateBench(Table&, bool) {}  // filled by the simulator work
}  // namespace scanreg::bench
