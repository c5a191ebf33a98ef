#include "tests/bench/bench_table.h"

namespace scanreg::bench {
void RunIoBench(Table&, bool) {}  // filled by the io work
}  // namespace scanreg::bench
