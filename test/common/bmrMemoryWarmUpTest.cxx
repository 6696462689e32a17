/*=========================================================================
 *
 *  Copyright NumFOCUS
 *
 *  Licensed under the Apache License, Version 2.0 (the "License");
 *  you may not use this file except in compliance with the License.
 *  You may obtain a copy of the License at
 *
 *         http://www.apache.org/licenses/LICENSE-2.0.txt
 *
 *  Unless required by applicable law or agreed to in writing, software
 *  distributed under the License is distributed on an "AS IS" BASIS,
 *  WITHOUT WARRANTIES OR CONDITIONS OF ANY KIND, either express or implied.
 *  See the License for the specific language governing permissions and
 *  limitations under the License.
 *
 *=========================================================================*/
#include "bmrMemoryWarmUp.h"
#include "bmrTestUtilities.h"

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <fstream>
#include <future>
#include <iostream>
#include <thread>

// bmr::MemoryWarmUp's contract: nothing after Close(); the warmed memory really written (resident) while held,
// never more than the cap, and released before Close() returns.
namespace {
constexpr std::size_t MiB = std::size_t{ 1 } << 20;

/** Resident set size of this process [bytes], from /proc (0 where there is none). */
std::size_t
ResidentBytes()
{
  std::ifstream statm("/proc/self/statm");
  std::size_t   pages = 0, resident = 0;
  if (!(statm >> pages >> resident))
  {
    return 0;
  }
  return resident * 4096;
}

/** Waits until the warming holds at least \a bytes (false after 60 s: the test fails rather than hangs). */
bool
WaitForHeld(const bmr::MemoryWarmUp & warmUp, std::size_t bytes)
{
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  while (warmUp.GetHeldBytes() < bytes)
  {
    if (std::chrono::steady_clock::now() > deadline)
    {
      return false;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  return true;
}
} // namespace

int
bmrMemoryWarmUpTest(int, char *[])
{
  bool ok = true;

  // 1. Closed first: no warming at all.
  {
    bmr::MemoryWarmUp warmUp(64 * MiB);
    warmUp.Close();
    ok &=
      bmr::test::Expect(warmUp.IsClosed() && warmUp.WarmWhileOpen() == 0, "WarmWhileOpen after Close writes nothing");
  }

  // 2. The cap: 96 MiB (3 chunks) written, resident while held, released before Close() returns. RSS tolerance
  // 16 MiB: other allocations of this process between the readings are far smaller.
  {
    bmr::MemoryWarmUp        warmUp(96 * MiB);
    const std::size_t        before = ResidentBytes();
    std::future<std::size_t> warmed = std::async(std::launch::async, [&warmUp] { return warmUp.WarmWhileOpen(); });
    ok &= bmr::test::Expect(WaitForHeld(warmUp, 96 * MiB), "the warming reaches its cap of 96 MiB");
    std::this_thread::sleep_for(std::chrono::milliseconds(50)); // it must stop there and hold
    const std::size_t held = warmUp.GetHeldBytes(), whileHeld = ResidentBytes();
    ok &= bmr::test::Expect(held == 96 * MiB, "held " + std::to_string(held / MiB) + " MiB, the cap exactly");
    if (before > 0)
    {
      ok &= bmr::test::Expect(whileHeld + 16 * MiB >= before + 96 * MiB,
                              "resident while held: +" +
                                std::to_string((whileHeld - std::min(whileHeld, before)) / MiB) + " MiB");
    }
    warmUp.Close();
    const std::size_t after = ResidentBytes();
    if (before > 0)
    {
      ok &= bmr::test::Expect(after <= before + 16 * MiB,
                              "released when Close() returns: resident +" +
                                std::to_string((after - std::min(after, before)) / MiB) + " MiB");
    }
    ok &= bmr::test::Expect(warmUp.GetHeldBytes() == 0 && warmed.get() == 96 * MiB,
                            "WarmWhileOpen returns the 96 MiB it wrote");
  }

  // 3. Close() stops the warming early: a cap of 4 GiB, closed once one chunk is held.
  {
    bmr::MemoryWarmUp        warmUp(4096 * MiB);
    std::future<std::size_t> warmed = std::async(std::launch::async, [&warmUp] { return warmUp.WarmWhileOpen(); });
    ok &= bmr::test::Expect(WaitForHeld(warmUp, 32 * MiB), "the warming starts");
    warmUp.Close();
    const std::size_t wrote = warmed.get();
    ok &=
      bmr::test::Expect(wrote >= 32 * MiB && wrote < 4096 * MiB,
                        "Close() stopped it after " + std::to_string(wrote / MiB) + " MiB, before the 4096 MiB cap");
  }

  // 4. A second warmer while one is running returns at once.
  {
    bmr::MemoryWarmUp        warmUp(64 * MiB);
    std::future<std::size_t> first = std::async(std::launch::async, [&warmUp] { return warmUp.WarmWhileOpen(); });
    ok &= bmr::test::Expect(WaitForHeld(warmUp, 32 * MiB), "the first warming starts");
    ok &= bmr::test::Expect(warmUp.WarmWhileOpen() == 0, "a second WarmWhileOpen meanwhile writes nothing");
    warmUp.Close();
    ok &= bmr::test::Expect(first.get() >= 32 * MiB, "the first one returns after Close()");
  }

  // 5. WarmWhile() stops once asked and keeps its memory held; WarmWhileOpen() adds to it up to the cap; Close()
  // releases both (RSS tolerance 16 MiB as in 2).
  {
    bmr::MemoryWarmUp warmUp(128 * MiB);
    const std::size_t before = ResidentBytes();
    int               asked = 0;
    const std::size_t first = warmUp.WarmWhile([&asked] { return asked++ < 2; });
    ok &= bmr::test::Expect(first == 64 * MiB && warmUp.GetHeldBytes() == 64 * MiB,
                            "WarmWhile wrote the 2 chunks it was allowed and holds them (" +
                              std::to_string(first / MiB) + " MiB)");
    std::future<std::size_t> rest = std::async(std::launch::async, [&warmUp] { return warmUp.WarmWhileOpen(); });
    ok &= bmr::test::Expect(WaitForHeld(warmUp, 128 * MiB), "WarmWhileOpen adds to them up to the cap of 128 MiB");
    warmUp.Close();
    const std::size_t after = ResidentBytes();
    ok &= bmr::test::Expect(rest.get() == 128 * MiB && warmUp.GetHeldBytes() == 0,
                            "WarmWhileOpen returns all 128 MiB held");
    if (before > 0)
    {
      ok &= bmr::test::Expect(after <= before + 16 * MiB,
                              "both released when Close() returns: resident +" +
                                std::to_string((after - std::min(after, before)) / MiB) + " MiB");
    }
  }
  return ok ? EXIT_SUCCESS : EXIT_FAILURE;
}
