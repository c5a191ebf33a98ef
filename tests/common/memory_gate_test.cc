// MemoryGate: work runs side by side only while its bytes fit the budget; one always runs.
#include "core/common/memory_gate.h"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <thread>

namespace scanreg {
namespace {

TEST(MemoryGate, WorkThatDoesNotFitWaitsForTheHolderAndWorkThatFitsDoesNot) {
  MemoryGate gate(100);
  {
    MemoryGate::Hold a(gate, 40), b(gate, 60);  // fit together: no wait
    EXPECT_EQ(gate.held(), 100u);
  }
  EXPECT_EQ(gate.held(), 0u);

  std::atomic<bool> second_in{false};
  auto first = std::make_unique<MemoryGate::Hold>(gate, 70);
  std::thread t([&] {
    MemoryGate::Hold second(gate, 70);  // 140 > 100: waits for the first
    second_in = true;
  });
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  EXPECT_FALSE(second_in) << "admitted beside a holder although both do not fit";
  first.reset();
  t.join();
  EXPECT_TRUE(second_in);
  EXPECT_EQ(gate.held(), 0u);
}

TEST(MemoryGate, WorkLargerThanTheBudgetRunsAlone) {
  MemoryGate gate(10);
  MemoryGate::Hold big(gate, 1000);  // nothing else held: admitted
  EXPECT_EQ(gate.held(), 1000u);
}

}  // namespace
}  // namespace scanreg
