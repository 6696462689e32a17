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
#ifndef bmrParallel_h
#define bmrParallel_h

// Independent tasks on the library's thread budget (private to src/).
#include "BiomechanicalRegistrationExport.h"

#include <functional>
#include <memory>

namespace bmr {

/** \brief The region \a name: task(i, worker) for i = 0, ..., count - 1, each once, on at most \a threads threads;
 * returns when all are done.
 *
 * The tasks must be independent (each writes only its own data), so that what they compute does not depend on
 * which thread runs which, nor on how many there are: a caller keeps its results the same for any thread budget by
 * cutting its work into a number of tasks that depends on the problem alone. \a worker, in [0, min(threads, count)),
 * tells a task which of the caller's per-worker workspaces is its own; no two tasks running at once share one.
 *
 * The threads come from TBB's pool in an arena of \a threads slots, the calling thread one of them, so that calls
 * from several threads of a host (a resample pool, a Python thread) share the pool instead of multiplying threads;
 * nothing process-wide is set. One thread (or one task) runs them here in order, without TBB. A bmr::TaskTrace, while
 * one records, gets the region (\a name) and each task's span. */
void
ParallelFor(const char * name, int count, unsigned threads, const std::function<void(int task, int worker)> & task);

/** The number of worker slots ParallelFor() uses for \a count tasks on \a threads threads. */
unsigned
ParallelWorkers(int count, unsigned threads);

/** \brief Work that runs beside the calling thread until Wait() takes its end (a mesh made while the sweep runs,
 * the resamples' inputs made while the fit runs).
 *
 * With \a alongside (the caller's budget has a thread for it), \a work starts at construction as a task of an arena
 * of its own with two slots, one for a worker of TBB's pool and one for the thread that will wait: it shares the
 * pool with ParallelFor() and with the host, and the library starts no thread of its own. A ParallelFor() inside it
 * takes its own budget. Without (a budget of one thread, or one core), it runs in Wait(), on the waiting thread.
 * Either way the result is the same. A bmr::TaskTrace records the work as background work named \a name, and the
 * wait for it. */
class BiomechanicalRegistration_EXPORT BackgroundTask
{
public:
  BackgroundTask(const char * name, bool alongside, std::function<void()> work);
  /** Waits for work that started (work that did not start is not run); what it threw is dropped (call Wait() to
   * see it). */
  ~BackgroundTask();
  BackgroundTask(const BackgroundTask &) = delete;
  BackgroundTask &
  operator=(const BackgroundTask &) = delete;

  /** Returns when the work is done, having run it here if it had not started; rethrows what it threw. Once. */
  void
  Wait();
  /** Whether the work was started beside the caller. */
  bool
  Alongside() const;

private:
  struct Impl;
  std::unique_ptr<Impl> m_Impl;
};

} // namespace bmr

#endif
