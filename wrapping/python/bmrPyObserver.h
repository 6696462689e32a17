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
#ifndef bmrPyObserver_h
#define bmrPyObserver_h

// What a pipeline does, told to a Python callback; a keyboard interrupt or the callback's own exception stops the
// run at its next event.
#include "itkBiomechanicalPipelines.h"

#include <pybind11/pybind11.h>

#include <atomic>
#include <exception>
#include <mutex>

namespace bmrpy {
namespace py = pybind11;

/** \brief A PipelineObserver that calls \a callback(event) with a dict per event and stops the run when Python
 * asks.
 *
 * Events: {"event": "stage_begin", "stage"}, {"event": "stage_end", "stage", "seconds", "detail"},
 * {"event": "progress", "fraction", "detail"}, {"event": "warning", "message"}, {"event": "iteration",
 * "stage", "iteration", "inner_iterations", "value", "youngs_moduli"}. Every event takes the GIL; on the interpreter's
 * main thread it also runs Python's signal handlers, so Ctrl-C raises KeyboardInterrupt there. When the callback raises
 * or a signal handler does, the exception is kept, and this and every later event throws itk::ProcessAborted, which
 * unwinds the pipeline (its threads joined, nothing written); Run() then raises the kept exception. Events may
 * come from worker threads, one at a time. */
class PythonObserver final : public itk::PipelineObserver
{
public:
  /** \a callback may be None: the events then only check for interruption. */
  explicit PythonObserver(py::object callback);
  ~PythonObserver() override;

  void
  StageBegin(const std::string & stage) override;
  void
  StageEnd(const std::string & stage, double seconds, const std::string & detail) override;
  void
  Warning(const std::string & message) override;
  void
  Iteration(const bmr::IterationRecord & record) override;
  void
  Progress(double fraction, const std::string & detail) override;

  /** Runs \a job with the GIL released; raises the callback's or the interrupt's exception when the run stopped for
   * it (whatever the job then threw), else lets the job's own exception through. */
  template<typename TJob>
  auto
  Run(TJob && job)
  {
    try
    {
      py::gil_scoped_release released;
      auto                   result = job();
      ThrowIfStopped();
      return result;
    }
    catch (...)
    {
      RaiseIfStopped();
      throw;
    }
  }

private:
  /** Calls the callback with the event \a fill makes (holding the GIL), then checks for signals. */
  template<typename TFill>
  void
  Deliver(TFill && fill);
  void
  ThrowIfStopped() const;
  void
  RaiseIfStopped();

  py::object         m_Callback;
  std::mutex         m_Mutex; // one event at a time
  std::atomic<bool>  m_Stopped{ false };
  std::exception_ptr m_Reason;
};

} // namespace bmrpy

#endif
