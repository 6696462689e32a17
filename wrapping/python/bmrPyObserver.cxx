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
#include "bmrPyObserver.h"

#include "itkMacro.h"

#include <pybind11/stl.h>

namespace bmrpy {

PythonObserver::PythonObserver(py::object callback)
  : m_Callback(std::move(callback))
{}

PythonObserver::~PythonObserver()
{
  // The kept exception holds Python objects: release them with the GIL held (the destructor runs in the binding,
  // which holds it).
  m_Reason = nullptr;
}

template<typename TFill>
void
PythonObserver::Deliver(TFill && fill)
{
  ThrowIfStopped();
  {
    const std::lock_guard<std::mutex> one(m_Mutex);
    py::gil_scoped_acquire            gil;
    try
    {
      if (!m_Callback.is_none())
      {
        py::dict event;
        fill(event);
        m_Callback(event);
      }
      if (PyErr_CheckSignals() != 0) // a signal handler raised (KeyboardInterrupt); only on the main thread
      {
        throw py::error_already_set();
      }
    }
    catch (const py::error_already_set &)
    {
      if (!m_Stopped)
      {
        m_Reason = std::current_exception();
        m_Stopped = true;
      }
    }
  }
  ThrowIfStopped();
}

void
PythonObserver::ThrowIfStopped() const
{
  if (m_Stopped)
  {
    throw itk::ProcessAborted(__FILE__, __LINE__); // "AbortGenerateData call detected": unwinds the run
  }
}

void
PythonObserver::RaiseIfStopped()
{
  if (m_Stopped && m_Reason)
  {
    std::exception_ptr reason = m_Reason;
    m_Reason = nullptr;
    std::rethrow_exception(reason);
  }
}

void
PythonObserver::StageBegin(const std::string & stage)
{
  Deliver([&](py::dict & e) {
    e["event"] = "stage_begin";
    e["stage"] = stage;
  });
}

void
PythonObserver::StageEnd(const std::string & stage, double seconds, const std::string & detail)
{
  Deliver([&](py::dict & e) {
    e["event"] = "stage_end";
    e["stage"] = stage;
    e["seconds"] = seconds;
    e["detail"] = detail;
  });
}

void
PythonObserver::Warning(const std::string & message)
{
  Deliver([&](py::dict & e) {
    e["event"] = "warning";
    e["message"] = message;
  });
}

void
PythonObserver::Iteration(const bmr::IterationRecord & record)
{
  Deliver([&](py::dict & e) {
    e["event"] = "iteration";
    e["stage"] = record.stage;
    e["iteration"] = record.iteration;
    e["inner_iterations"] = record.innerIterations;
    e["value"] = record.value;
    e["youngs_moduli"] = record.youngsModuli;
  });
}

void
PythonObserver::Progress(double fraction, const std::string & detail)
{
  Deliver([&](py::dict & e) {
    e["event"] = "progress";
    e["fraction"] = fraction;
    e["detail"] = detail;
  });
}

} // namespace bmrpy
