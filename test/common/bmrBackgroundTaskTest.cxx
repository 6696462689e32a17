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
// bmr::BackgroundTask, the library's work beside the caller (the fine mesh during the sweep, the resamples' inputs
// during the fit). What is checked:
// - alongside (where TBB may use two cores): the work starts without the caller, on another thread than the
//   caller's, and Wait() returns once it is done;
// - not alongside: nothing runs until Wait(), which runs the work on the calling thread; a task that is never waited
//   for never runs;
// - what the work throws is rethrown by Wait() (as itk::ExceptionObject), and dropped by the destructor;
// - on a bmr::TaskTrace the work is a "background" span and the caller's wait a "wait" span, both with the name.
#include "bmrError.h"
#include "bmrParallel.h"
#include "bmrTaskTrace.h"
#include "bmrTestUtilities.h"

#include <tbb/info.h>

#include <atomic>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>

namespace {
bool
CheckAlongside()
{
  if (tbb::info::default_concurrency() < 2)
  {
    std::cout << "skipped: TBB may use one core here, nothing runs alongside" << std::endl;
    return true;
  }
  // The work starts without the caller (who only watches for it, up to 20 s), then waits for the caller's signal:
  // run in Wait(), on the caller's thread, it would never have started before.
  std::atomic<bool>   started{ false }, signalled{ false };
  std::thread::id     ranOn;
  bmr::BackgroundTask task("check alongside", true, [&]() {
    ranOn = std::this_thread::get_id();
    started = true;
    while (!signalled)
    {
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
  });
  const auto          limit = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  while (!started && std::chrono::steady_clock::now() < limit)
  {
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  const bool startedAlone = started;
  signalled = true;
  task.Wait();
  return bmr::test::Expect(task.Alongside() && startedAlone && ranOn != std::this_thread::get_id(),
                           "alongside: the work started on another thread before the caller waited");
}

bool
CheckInWait()
{
  int                 runs = 0;
  std::thread::id     ranOn;
  bmr::BackgroundTask task("check in wait", false, [&]() {
    ++runs;
    ranOn = std::this_thread::get_id();
  });
  const bool          notYet = runs == 0 && !task.Alongside();
  task.Wait();
  task.Wait(); // once
  bool neverWaited = true;
  {
    bmr::BackgroundTask dropped("never waited", false, [&]() { neverWaited = false; });
  }
  return bmr::test::Expect(notYet && runs == 1 && ranOn == std::this_thread::get_id() && neverWaited,
                           "not alongside: the work runs once, in Wait(), on the caller's thread; never without it");
}

bool
CheckExceptions()
{
  bool ok = true;
  for (bool alongside : { true, false })
  {
    bmr::BackgroundTask task("throws", alongside, []() { bmr::Fail("BackgroundTaskTest", "the work failed"); });
    ok &= bmr::test::ExpectException(
      alongside ? "exception alongside" : "exception in Wait", [&]() { task.Wait(); }, "the work failed");
  }
  {
    bmr::BackgroundTask dropped("throws, not waited", true, []() { bmr::Fail("BackgroundTaskTest", "dropped"); });
  }
  return ok; // the destructor dropped the last one's exception: reaching here is the check
}

bool
CheckTrace()
{
  std::ostringstream csv;
  {
    bmr::TaskTrace      trace;
    bmr::BackgroundTask task("traced work", true, []() { std::this_thread::sleep_for(std::chrono::milliseconds(20)); });
    task.Wait();
    const std::string path = (std::filesystem::temp_directory_path() / "bmrBackgroundTaskTest.csv").string();
    trace.Write(path);
    csv << std::ifstream(path).rdbuf();
    std::filesystem::remove(path);
  }
  const std::string text = csv.str();
  const bool        alongside = tbb::info::default_concurrency() > 1;
  return bmr::test::Expect(!alongside ||
                             (text.find("background,") != std::string::npos &&
                              text.find("wait,") != std::string::npos && text.find("traced work") != std::string::npos),
                           "the trace holds the work as background and the caller's wait, by name");
}
} // namespace

int
bmrBackgroundTaskTest(int, char *[])
{
  bool ok = CheckAlongside();
  ok &= CheckInWait();
  ok &= CheckExceptions();
  ok &= CheckTrace();
  return ok ? EXIT_SUCCESS : EXIT_FAILURE;
}
