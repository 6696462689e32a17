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
#ifndef bmrTaskTrace_h
#define bmrTaskTrace_h

#include "BiomechanicalRegistrationExport.h"

#include <memory>
#include <string>

namespace bmr {

/** \brief Records the library's parallel work while it lives, so that its scaling can be predicted by replaying it
 * on more workers than the machine has (benchmarks/replay_task_trace.py).
 *
 * Recorded are the regions of independent tasks the library runs on its thread budget (factorization bins and
 * tiles, triangular-solve bins, the interval's resamples), with each task's start and end and the regions nested
 * in it, and the spans of work other threads do alongside the calling thread (a mesh made during the sweep) with
 * the calling thread's waits for them. What is in neither is serial. Recording costs two clock reads and a lock
 * per task; nothing is recorded while no trace lives. A program's opt-in (biomechreg --task-trace FILE); one at a
 * time per process (a second throws itk::ExceptionObject); destroy it only after the work it records has ended.
 */
class BiomechanicalRegistration_EXPORT TaskTrace
{
public:
  TaskTrace();
  ~TaskTrace();
  TaskTrace(const TaskTrace &) = delete;
  TaskTrace &
  operator=(const TaskTrace &) = delete;

  /** Writes what was recorded so far as CSV, one row per event: kind (region, task, background, wait), thread
   * (numbered as threads first record), id, parent (the task a region runs in, or the region a task belongs to;
   * -1: its thread's own timeline), budget (a region's threads), worker, start_s and end_s (seconds since the
   * trace began), name; and a last row "end" on the thread that made the trace, from 0 to the write. Throws
   * itk::ExceptionObject when the file cannot be written. */
  void
  Write(const std::string & path) const;

  /** The number of regions recorded so far. */
  std::size_t
  GetNumberOfRegions() const;

  struct Impl;

private:
  std::unique_ptr<Impl> m_Impl;
};

/** \brief Marks, on the trace that records (if any), work done alongside the recording thread (\a background) or
 * the recording thread's wait for such work, from construction to destruction. */
class BiomechanicalRegistration_EXPORT TracedSpan
{
public:
  enum class Kind
  {
    Background,
    Wait
  };
  TracedSpan(Kind kind, const char * name);
  ~TracedSpan();
  TracedSpan(const TracedSpan &) = delete;
  TracedSpan &
  operator=(const TracedSpan &) = delete;

private:
  Kind         m_Kind;
  const char * m_Name;
  double       m_Start;
  bool         m_Recording;
};

} // namespace bmr

#endif
