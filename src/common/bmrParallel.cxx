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

#include "bmrError.h"
#include "bmrTaskTrace.h"

#include <tbb/blocked_range.h>
#include <tbb/info.h>
#include <tbb/parallel_for.h>
#include <tbb/partitioner.h>
#include <tbb/task_group.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <fstream>
#include <mutex>
#include <vector>

namespace bmr {

struct TaskTrace::Impl
{
  struct Event
  {
    char         kind; // r(egion), t(ask), b(ackground), w(ait)
    int          thread;
    std::int64_t id;
    std::int64_t parent;
    unsigned     budget;
    int          worker;
    double       start;
    double       end;
    const char * name;
  };
  std::chrono::steady_clock::time_point origin{ std::chrono::steady_clock::now() };
  mutable std::mutex                    lock;
  std::vector<Event>                    events;
  std::int64_t                          nextId{ 0 };
  std::size_t                           regions{ 0 };
  int                                   recordingThread{ 0 }; // the thread that made the trace

  double
  Now() const
  {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - origin).count();
  }
  std::int64_t
  Add(const Event & event)
  {
    const std::lock_guard<std::mutex> guard(lock);
    Event                             e = event;
    e.id = nextId++;
    regions += e.kind == 'r' ? 1 : 0;
    events.push_back(e);
    return e.id;
  }
};

namespace {

std::atomic<TaskTrace::Impl *> activeTrace{ nullptr };
std::atomic<int>               threadsSeen{ 0 };
/** This thread's number on traces (in the order threads first record). */
thread_local const int threadNumber = threadsSeen++;
/** The traced task this thread runs (-1: none, the recording thread's own timeline). */
thread_local std::int64_t currentTask = -1;

/** task(i, worker) for each i, recording each task on \a trace (when not null) as part of region \a region. */
void
RunRange(int                                               begin,
         int                                               end,
         int                                               worker,
         const std::function<void(int task, int worker)> & task,
         TaskTrace::Impl *                                 trace,
         std::int64_t                                      region)
{
  for (int i = begin; i != end; ++i)
  {
    if (trace == nullptr)
    {
      task(i, worker);
      continue;
    }
    const std::int64_t outer = currentTask;
    const double       start = trace->Now();
    // The task's id is known only once it is recorded; nested regions name it as their parent.
    const std::int64_t id = trace->Add({ 't', threadNumber, 0, region, 0, worker, start, start, "" });
    currentTask = id;
    task(i, worker);
    currentTask = outer;
    const double                      end = trace->Now();
    const std::lock_guard<std::mutex> guard(trace->lock);
    trace->events[static_cast<std::size_t>(id)].end = end;
  }
}

} // namespace

unsigned
ParallelWorkers(int count, unsigned threads)
{
  return count <= 0 ? 1U : std::max(1U, std::min(threads, static_cast<unsigned>(count)));
}

void
ParallelFor(const char * name, int count, unsigned threads, const std::function<void(int task, int worker)> & task)
{
  const unsigned     workers = ParallelWorkers(count, threads);
  TaskTrace::Impl *  trace = activeTrace.load();
  const double       start = trace ? trace->Now() : 0.0;
  const std::int64_t region =
    trace ? trace->Add({ 'r', threadNumber, 0, currentTask, workers, 0, start, start, name }) : -1;
  if (workers == 1)
  {
    RunRange(0, count, 0, task, trace, region);
  }
  else
  {
    // Slot 0 is the calling thread's; the arena's slot indices are the workers' numbers. No more slots than the
    // cores TBB may use (the process's affinity): more would only wait, and TBB warns about them.
    tbb::task_arena arena(std::min(static_cast<int>(workers), tbb::info::default_concurrency()), 1);
    arena.execute([&]() {
      tbb::parallel_for(
        tbb::blocked_range<int>(0, count, 1),
        [&](const tbb::blocked_range<int> & range) {
          RunRange(range.begin(), range.end(), tbb::this_task_arena::current_thread_index(), task, trace, region);
        },
        tbb::simple_partitioner());
    });
  }
  if (trace != nullptr)
  {
    const double                      end = trace->Now();
    const std::lock_guard<std::mutex> guard(trace->lock);
    trace->events[static_cast<std::size_t>(region)].end = end;
  }
}

struct BackgroundTask::Impl
{
  const char *                     name;
  std::function<void()>            work;
  std::unique_ptr<tbb::task_arena> arena; // null: run in Wait()
  tbb::task_group                  group;
  bool                             waited{ false };
};

BackgroundTask::BackgroundTask(const char * name, bool alongside, std::function<void()> work)
  : m_Impl(std::make_unique<Impl>())
{
  Impl & d = *m_Impl;
  d.name = name;
  d.work = std::move(work);
  // Two slots, the waiting thread's reserved; none for a worker where TBB may use one core only.
  if (alongside && tbb::info::default_concurrency() > 1)
  {
    d.arena = std::make_unique<tbb::task_arena>(2, 1);
    d.arena->execute([&d]() {
      d.group.run([&d]() {
        const TracedSpan span(TracedSpan::Kind::Background, d.name);
        d.work();
      });
    });
  }
}

BackgroundTask::~BackgroundTask()
{
  if (m_Impl->arena == nullptr || m_Impl->waited)
  {
    return; // nothing started, or already taken
  }
  try
  {
    Wait();
  }
  catch (...)
  {
    // Dropped: the caller that wanted it called Wait().
  }
}

void
BackgroundTask::Wait()
{
  Impl & d = *m_Impl;
  if (d.waited)
  {
    return;
  }
  d.waited = true;
  if (d.arena == nullptr)
  {
    d.work();
    return;
  }
  const TracedSpan wait(TracedSpan::Kind::Wait, d.name);
  d.arena->execute([&d]() { d.group.wait(); });
}

bool
BackgroundTask::Alongside() const
{
  return m_Impl->arena != nullptr;
}

TaskTrace::TaskTrace()
  : m_Impl(std::make_unique<Impl>())
{
  Impl * expected = nullptr;
  if (!activeTrace.compare_exchange_strong(expected, m_Impl.get()))
  {
    Fail("TaskTrace", "another task trace is recording in this process");
  }
  m_Impl->recordingThread = threadNumber;
}

TaskTrace::~TaskTrace()
{
  Impl * expected = m_Impl.get();
  activeTrace.compare_exchange_strong(expected, nullptr);
}

std::size_t
TaskTrace::GetNumberOfRegions() const
{
  const std::lock_guard<std::mutex> guard(m_Impl->lock);
  return m_Impl->regions;
}

void
TaskTrace::Write(const std::string & path) const
{
  std::ofstream out(path);
  out << "kind,thread,id,parent,budget,worker,start_s,end_s,name\n";
  out.precision(9);
  {
    const std::lock_guard<std::mutex> guard(m_Impl->lock);
    for (const Impl::Event & e : m_Impl->events)
    {
      const char * kind = e.kind == 'r' ? "region" : e.kind == 't' ? "task" : e.kind == 'b' ? "background" : "wait";
      out << kind << ',' << e.thread << ',' << e.id << ',' << e.parent << ',' << e.budget << ',' << e.worker << ','
          << e.start << ',' << e.end << ',' << e.name << '\n';
    }
    // The recording thread's whole timeline: from the trace's start to this write.
    out << "end," << m_Impl->recordingThread << ",-1,-1,0,0,0," << m_Impl->Now() << ",\n";
  }
  if (!out.good())
  {
    Fail("TaskTrace::Write", "cannot write the task trace " + path);
  }
}

TracedSpan::TracedSpan(Kind kind, const char * name)
  : m_Kind(kind)
  , m_Name(name)
  , m_Start(0.0)
  , m_Recording(activeTrace.load() != nullptr)
{
  if (m_Recording)
  {
    m_Start = activeTrace.load()->Now();
  }
}

TracedSpan::~TracedSpan()
{
  TaskTrace::Impl * trace = activeTrace.load();
  if (m_Recording && trace != nullptr)
  {
    trace->Add(
      { m_Kind == Kind::Background ? 'b' : 'w', threadNumber, 0, currentTask, 1, 0, m_Start, trace->Now(), m_Name });
  }
}

} // namespace bmr
