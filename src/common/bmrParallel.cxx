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
#include "bmrParallel.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/partitioner.h>
#include <tbb/task_arena.h>

#include <algorithm>

namespace bmr {

unsigned
ParallelWorkers(int count, unsigned threads)
{
  return count <= 0 ? 1U : std::max(1U, std::min(threads, static_cast<unsigned>(count)));
}

void
ParallelFor(int count, unsigned threads, const std::function<void(int task, int worker)> & task)
{
  const unsigned workers = ParallelWorkers(count, threads);
  if (workers == 1)
  {
    for (int i = 0; i < count; ++i)
    {
      task(i, 0);
    }
    return;
  }
  // Slot 0 is the calling thread's; the arena's slot indices are the workers' numbers.
  tbb::task_arena arena(static_cast<int>(workers), 1);
  arena.execute([&]() {
    tbb::parallel_for(
      tbb::blocked_range<int>(0, count, 1),
      [&](const tbb::blocked_range<int> & range) {
        const int worker = tbb::this_task_arena::current_thread_index();
        for (int i = range.begin(); i != range.end(); ++i)
        {
          task(i, worker);
        }
      },
      tbb::simple_partitioner());
  });
}

} // namespace bmr
