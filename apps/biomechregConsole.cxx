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
// Console manners of biomechreg: the global options (--threads, --quiet, --verbose, --help, --version), ITK's
// warnings as one "warning: ..." line, the progress line on a terminal and the peak memory.
#include "biomechregCommon.h"

#include "bmrNumerics.h"
#include "itkMultiThreaderBase.h"
#include "itkOutputWindow.h"

#include <cstdlib>
#include <mutex>
#include <sys/resource.h>
#include <unistd.h>

namespace bmrcli {
namespace {

Verbosity g_Verbosity = Verbosity::Normal;
bool      g_SlicerProgress = false;
// The stage line that StageBegin() left open (no newline yet), so that a warning does not land mid-line.
std::string g_OpenStage;
bool        g_StageOpen = false;
bool        g_StageInterrupted = false; // a line was printed while it was open
// Warnings may come from worker threads (ITK's, the resamples'): one line at a time.
std::mutex g_Console;

/** Discards what is written to it (std::cout under --quiet). */
class NullBuffer : public std::streambuf
{
protected:
  int
  overflow(int c) override
  {
    return c;
  }
};

/** ITK's warnings ("WARNING: In /path/file.hxx, line N\nClass (0x...): text\n\n") as "warning: text". */
class ConsoleOutputWindow : public itk::OutputWindow
{
public:
  ITK_DISALLOW_COPY_AND_MOVE(ConsoleOutputWindow);
  using Self = ConsoleOutputWindow;
  using Superclass = itk::OutputWindow;
  using Pointer = itk::SmartPointer<Self>;
  itkNewMacro(Self);

  /** Where ITK's warnings, errors and generic output all end up (OutputWindow's other Display methods call it). */
  void
  DisplayText(const char * text) override
  {
    PrintWarning(StripITKPrefix(text));
  }
  void
  DisplayDebugText(const char * text) override
  {
    if (g_Verbosity == Verbosity::Verbose)
    {
      PrintWarning(StripITKPrefix(text));
    }
  }

protected:
  ConsoleOutputWindow() = default;
  ~ConsoleOutputWindow() override = default;
};

} // namespace

std::string
StripITKPrefix(const std::string & text)
{
  std::string message = text;
  // "WARNING: In FILE, line N" (or "ERROR: In ..."): the first line says where in the source, not what.
  if (message.find(": In ") != std::string::npos && message.find('\n') != std::string::npos &&
      message.find(": In ") < message.find('\n'))
  {
    message.erase(0, message.find('\n') + 1);
  }
  // "ClassName (0x55...): ": the object's class and address.
  const auto open = message.find(" (0x");
  const auto close = message.find("): ");
  if (open != std::string::npos && close != std::string::npos && open < close && message.find_first_of(" \n") == open)
  {
    message.erase(0, close + 3);
  }
  for (char & c : message)
  {
    c = (c == '\n' || c == '\r' || c == '\t') ? ' ' : c;
  }
  const auto last = message.find_last_not_of(' ');
  return last == std::string::npos ? std::string() : message.substr(0, last + 1);
}

void
UseSlicerProgress()
{
  g_SlicerProgress = true;
}

bool
SlicerProgress()
{
  return g_SlicerProgress;
}

Verbosity
GetVerbosity()
{
  return g_Verbosity;
}

void
PrintLine(const std::string & text, bool warning)
{
  const std::lock_guard<std::mutex> lock(g_Console);
  std::ostream &                    os = warning && g_Verbosity == Verbosity::Quiet ? std::cerr : std::cout;
  // An open stage line is ended first; its time comes later on a line that names the stage again (on a
  // terminal the stage line is redrawn below the text at once, for the progress bar).
  if (g_StageOpen && IsTerminal())
  {
    std::cout << "\r\033[K";
  }
  else if (g_StageOpen && !g_StageInterrupted)
  {
    std::cout << "\n";
  }
  g_StageInterrupted = g_StageOpen;
  os << text << std::endl;
  if (g_StageOpen && IsTerminal())
  {
    std::cout << g_OpenStage << std::flush;
  }
}

void
PrintWarning(const std::string & message)
{
  if (!message.empty())
  {
    PrintLine("warning: " + message, true);
  }
}

void
OpenStageLine(const std::string & text)
{
  const std::lock_guard<std::mutex> lock(g_Console);
  g_OpenStage = text;
  g_StageOpen = true;
  g_StageInterrupted = false;
  std::cout << text << std::flush;
}

void
CloseStageLine(const std::string & rest)
{
  const std::lock_guard<std::mutex> lock(g_Console);
  if (IsTerminal() && g_StageOpen)
  {
    std::cout << "\r\033[K" << g_OpenStage; // wipe a progress bar
  }
  else if (g_StageInterrupted)
  {
    std::cout << g_OpenStage;
  }
  g_StageOpen = g_StageInterrupted = false;
  std::cout << rest << std::endl;
}

void
EndStageLineOnError()
{
  bool open = false;
  {
    const std::lock_guard<std::mutex> lock(g_Console);
    open = g_StageOpen;
  }
  if (open)
  {
    CloseStageLine("failed"); // so that the error message that follows starts its own line
  }
}

void
ShowProgress(double fraction, double elapsed, const std::string & detail)
{
  const std::lock_guard<std::mutex> lock(g_Console);
  if (!g_StageOpen || !IsTerminal() || g_Verbosity == Verbosity::Quiet)
  {
    return; // plain output (a file or a pipe) gets the stage's line at its end only
  }
  std::ostringstream line;
  line << "\r\033[K" << g_OpenStage << std::fixed << std::setprecision(0);
  if (fraction >= 0.0)
  {
    const int width = 20;
    const int filled = static_cast<int>(std::min(1.0, fraction) * width);
    line << "[" << std::string(filled, '#') << std::string(width - filled, '.') << "] " << 100.0 * fraction << " %  "
         << elapsed << " s";
    if (fraction > 0.0 && fraction < 1.0)
    {
      line << ", ~" << elapsed * (1.0 - fraction) / fraction << " s left";
    }
  }
  else
  {
    line << elapsed << " s";
  }
  line << (detail.empty() ? "" : "  ") << detail;
  std::cout << line.str() << std::flush;
}

bool
IsTerminal()
{
  static const bool terminal = isatty(STDOUT_FILENO) == 1;
  return terminal;
}

double
PeakMemoryMB()
{
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return usage.ru_maxrss / 1024.0; // kB on Linux
}

GlobalOptions
TakeGlobalOptions(std::vector<std::string> & args)
{
  GlobalOptions            o;
  std::vector<std::string> rest;
  for (std::size_t i = 0; i < args.size(); ++i)
  {
    const std::string & a = args[i];
    if (a == "--help" || a == "-h")
    {
      o.help = true;
    }
    else if (a == "--version")
    {
      o.version = true;
    }
    else if (a == "--quiet" || a == "-q")
    {
      o.quiet = true;
    }
    else if (a == "--verbose" || a == "-v")
    {
      o.verbose = true;
    }
    else if (a == "--threads")
    {
      if (i + 1 == args.size())
      {
        throw UsageError("option --threads needs a value");
      }
      const std::string value = args[++i];
      char *            end = nullptr;
      const long        n = std::strtol(value.c_str(), &end, 10);
      if (end == value.c_str() || *end != '\0' || n < 1 || n > 256)
      {
        throw UsageError("--threads must be an integer in [1, 256], got \"" + value + "\"");
      }
      o.threads = static_cast<unsigned int>(n);
    }
    else if (a == "--task-trace")
    {
      if (i + 1 == args.size())
      {
        throw UsageError("option --task-trace needs a file");
      }
      o.taskTrace = args[++i];
    }
    else
    {
      rest.push_back(a);
    }
  }
  if (o.quiet && o.verbose)
  {
    throw UsageError("--quiet and --verbose exclude each other");
  }
  args = rest;
  return o;
}

void
ApplyGlobalOptions(const GlobalOptions & o)
{
  static NullBuffer discard;
  g_Verbosity = o.quiet ? Verbosity::Quiet : o.verbose ? Verbosity::Verbose : Verbosity::Normal;
  if (o.quiet)
  {
    std::cout.rdbuf(&discard);
  }
  itk::OutputWindow::SetInstance(ConsoleOutputWindow::New());
  bmr::ConfigureNumerics(); // the program owns its process: the BLAS on one thread, the same bits on any machine
  if (o.threads > 0)
  {
    itk::MultiThreaderBase::SetGlobalDefaultNumberOfThreads(o.threads);
  }
}

} // namespace bmrcli
