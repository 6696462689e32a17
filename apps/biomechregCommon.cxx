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
#include "biomechregCommon.h"
#include "itkBiomechanicalReports.h"

#include <cmath>

namespace bmrcli {

void
StageTimer::StageBegin(const std::string & name)
{
  std::cout << "  " << std::left << std::setw(34) << (name + " ...") << std::right << std::flush;
}

void
StageTimer::StageEnd(const std::string &, double seconds, const std::string & detail)
{
  // Formatted apart, so that std::cout's own flags (and what later lines print) stay as they were.
  std::ostringstream time;
  time << std::fixed << std::setprecision(2) << std::setw(7) << seconds << " s";
  std::cout << time.str() << (detail.empty() ? "" : "  ") << detail << std::endl;
}

void
StageTimer::Warning(const std::string & message)
{
  std::cout << "warning: " << message << std::endl;
}

void
StageTimer::Iteration(const bmr::IterationRecord & r)
{
  if (!m_Iterations)
  {
    return;
  }
  if (r.stage == "sweep" && r.iteration == 0)
  {
    std::cout << "\n  estimation (sweep of E on the coarse mesh, then L-BFGS-B over log E on the fine mesh):\n";
  }
  std::cout << itk::FormatIterationRecord(r) << std::endl;
}

void
StageTimer::Begin(const std::string & name)
{
  m_Current = name;
  StageBegin(name);
  m_Start = Clock::now();
}

void
StageTimer::End(const std::string & detail)
{
  const double s = std::chrono::duration<double>(Clock::now() - m_Start).count();
  stages.push_back({ m_Current, s });
  StageEnd(m_Current, s, detail);
}

void
PrintTimings(const Stages & stages)
{
  std::cout << "\n" << itk::StageTable(stages) << std::flush;
}

Arguments::Arguments(int argc, char * argv[], int first)
{
  for (int i = first; i < argc; ++i)
  {
    std::string key = argv[i];
    if (key.rfind("--", 0) != 0)
    {
      throw UsageError("unexpected argument \"" + key + "\"");
    }
    if (i + 1 >= argc)
    {
      throw UsageError("option " + key + " needs a value");
    }
    m_Values[key] = argv[++i];
  }
}

std::string
Arguments::Get(const std::string & key, const std::string & fallback) const
{
  m_Used.insert(key);
  auto it = m_Values.find(key);
  return it == m_Values.end() ? fallback : it->second;
}

std::string
Arguments::Require(const std::string & key) const
{
  if (!Has(key))
  {
    throw UsageError("missing required option " + key);
  }
  return Get(key);
}

double
Arguments::Number(const std::string & key, double fallback) const
{
  if (!Has(key))
  {
    m_Used.insert(key);
    return fallback;
  }
  const std::string text = Get(key);
  char *            end = nullptr;
  const double      v = std::strtod(text.c_str(), &end);
  if (end == text.c_str() || *end != '\0' || !std::isfinite(v))
  {
    throw UsageError("option " + key + " expects a number, got \"" + text + "\"");
  }
  return v;
}

unsigned int
Arguments::Count(const std::string & key, unsigned int fallback, unsigned int lo, unsigned int hi) const
{
  const double v = Number(key, fallback);
  if (!(v >= lo && v <= hi && v == std::floor(v)))
  {
    throw UsageError(key + " must be an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
  }
  return static_cast<unsigned int>(v);
}

std::array<double, 3>
Arguments::Triple(const std::string & key, const std::array<double, 3> & fallback) const
{
  if (!Has(key))
  {
    m_Used.insert(key);
    return fallback;
  }
  std::array<double, 3> v;
  const std::string     text = Get(key);
  std::istringstream    in(text);
  char                  comma1 = 0, comma2 = 0;
  if (!(in >> v[0] >> comma1 >> v[1] >> comma2 >> v[2]) || comma1 != ',' || comma2 != ',' || !in.eof())
  {
    throw UsageError("option " + key + " expects three comma-separated numbers, got \"" + text + "\"");
  }
  return v;
}

std::string
Arguments::Choice(const std::string & key, const std::vector<std::string> & choices) const
{
  const std::string value = Get(key, choices.front());
  if (std::find(choices.begin(), choices.end(), value) == choices.end())
  {
    std::string list;
    for (std::size_t i = 0; i < choices.size(); ++i)
    {
      list += (i ? (i + 1 == choices.size() ? " or " : ", ") : "") + choices[i];
    }
    throw UsageError(key + " must be " + list);
  }
  return value;
}

void
Arguments::CheckAllUsed() const
{
  for (const auto & kv : m_Values)
  {
    if (m_Used.count(kv.first) == 0)
    {
      throw UsageError("unknown option " + kv.first);
    }
  }
}

} // namespace bmrcli
