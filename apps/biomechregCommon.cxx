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
#include "itkDicomRT.h"

#include <algorithm>
#include <cmath>

namespace bmrcli {

void
StageTimer::StageBegin(const std::string & name)
{
  // Formatted apart, so that std::cout's own flags (and what later lines print) stay as they were.
  std::ostringstream line;
  line << "  " << std::left << std::setw(34) << (name + " ...");
  m_StageStart = Clock::now();
  m_Solves = 0;
  OpenStageLine(line.str());
  if (SlicerProgress())
  {
    PrintLine("<filter-start><filter-name>" + name + "</filter-name><filter-comment> \"" + name +
              "\" </filter-comment></filter-start>");
  }
}

void
StageTimer::StageEnd(const std::string & name, double seconds, const std::string & detail)
{
  std::ostringstream time;
  time << std::fixed << std::setprecision(2) << std::setw(7) << seconds << " s";
  CloseStageLine(time.str() + (detail.empty() ? "" : "  ") + detail);
  if (SlicerProgress())
  {
    PrintLine("<filter-end><filter-name>" + name + "</filter-name><filter-time>" + std::to_string(seconds) +
              "</filter-time></filter-end>");
  }
}

void
StageTimer::Warning(const std::string & message)
{
  PrintWarning(message);
}

void
StageTimer::Progress(double fraction, const std::string & detail)
{
  ShowProgress(fraction, std::chrono::duration<double>(Clock::now() - m_StageStart).count(), detail);
  if (SlicerProgress() && fraction >= 0.0)
  {
    PrintLine("<filter-progress>" + std::to_string(std::min(1.0, fraction)) + "</filter-progress>");
  }
}

void
StageTimer::Iteration(const bmr::IterationRecord & r)
{
  if (!m_Iterations)
  {
    // How many solves and where the estimation is: a progress line without a known end.
    Progress(-1.0, std::to_string(++m_Solves) + " solves, " + r.stage);
    return;
  }
  if (r.stage == "sweep" && r.iteration == 0)
  {
    PrintLine("  inner solves (sweep of E on the coarse mesh, then the outer search over log E on the fine mesh):");
  }
  PrintLine(itk::FormatIterationRecord(r));
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
  std::ostringstream memory;
  memory << std::fixed << std::setprecision(0) << PeakMemoryMB();
  std::cout << "\n" << itk::StageTable(stages) << "peak memory (resident): " << memory.str() << " MB" << std::endl;
}

Arguments::Arguments(const std::vector<std::string> & args)
{
  for (std::size_t i = 0; i < args.size(); ++i)
  {
    const std::string & key = args[i];
    if (key.rfind("--", 0) != 0)
    {
      throw UsageError("unexpected argument \"" + key + "\"");
    }
    if (i + 1 >= args.size())
    {
      throw UsageError("option " + key + " needs a value");
    }
    m_Values[key] = args[++i];
  }
  ExpandUncertaintyOptions();
}

void
Arguments::ExpandUncertaintyOptions()
{
  const auto group = m_Values.find("--uncertainty-options");
  if (group == m_Values.end())
  {
    return;
  }
  std::stringstream items(group->second);
  for (std::string item; std::getline(items, item, ',');)
  {
    const auto        equals = item.find('=');
    const std::string name = item.substr(0, equals);
    if (equals == std::string::npos || equals + 1 == item.size() ||
        std::find(std::begin(AdvancedUncertaintyOptions), std::end(AdvancedUncertaintyOptions), name) ==
          std::end(AdvancedUncertaintyOptions))
    {
      std::string known;
      for (const char * option : AdvancedUncertaintyOptions)
      {
        known += std::string(known.empty() ? "" : ", ") + option;
      }
      throw UsageError("--uncertainty-options takes NAME=VALUE pairs separated by commas, NAME one of " + known +
                       "; got \"" + item + "\"");
    }
    if (!m_Values.emplace("--uncertainty-" + name, item.substr(equals + 1)).second)
    {
      throw UsageError("--uncertainty-" + name + " is given twice (also in --uncertainty-options)");
    }
  }
  m_Used.insert(group->first);
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

std::vector<std::string>
Arguments::RequireList(const std::string & key) const
{
  std::vector<std::string> list;
  std::stringstream        items(Require(key));
  for (std::string item; std::getline(items, item, ',');)
  {
    if (item.empty())
    {
      throw UsageError("option " + key + " expects ITEM,ITEM,... without empty items");
    }
    list.push_back(item);
  }
  return list;
}

std::map<std::string, double>
Arguments::NamedNumbers(const std::string & key) const
{
  std::map<std::string, double> values;
  const std::string             text = Get(key);
  std::stringstream             items(text);
  for (std::string item; !text.empty() && std::getline(items, item, ',');)
  {
    const auto        equals = item.find('=');
    const std::string value = equals == std::string::npos ? std::string() : item.substr(equals + 1);
    char *            end = nullptr;
    const double      v = std::strtod(value.c_str(), &end);
    if (equals == 0 || equals == std::string::npos || value.empty() || *end != '\0' || !std::isfinite(v))
    {
      throw UsageError("option " + key + " expects NAME=NUMBER,... with finite numbers, got \"" + item + "\"");
    }
    values[item.substr(0, equals)] = v;
  }
  return values;
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

LabelImageType::Pointer
ReadLabelsOrRTStruct(const std::string &       path,
                     const std::string &       what,
                     const itk::ImageBase<3> * ctGrid,
                     const bmr::Scene &        scene,
                     bool                      ignoreUnmappedROIs)
{
  if (itk::ReadDicomModality(path) != "RTSTRUCT")
  {
    return ReadImage<LabelImageType>(path, what);
  }
  std::map<std::string, std::int32_t> roiNameToLabel;
  for (const auto & [value, name] : itk::SceneROINames(scene))
  {
    roiNameToLabel[name] = value;
  }
  itk::RTStructRasterizationOptions options;
  options.ignoreUnmappedROIs = ignoreUnmappedROIs;
  const auto outside = std::find_if(scene.labels.begin(), scene.labels.end(), [](const bmr::SceneLabel & label) {
    return label.role == bmr::LabelRoleEnum::Outside;
  });
  if (outside != scene.labels.end())
  {
    options.backgroundLabel = outside->value; // the first outside label, as before
  }
  try
  {
    return itk::ReadRTStructAsLabelImage(path, ctGrid, roiNameToLabel, options);
  }
  catch (const itk::ExceptionObject & e)
  {
    bmr::Fail("ReadLabelsOrRTStruct", what + ": " + e.GetDescription());
  }
}

bool
IgnoreUnmappedROIs(const Arguments & args)
{
  const std::string choice = args.Get("--unmapped-rois", "refuse");
  if (choice != "ignore" && choice != "refuse")
  {
    throw UsageError("--unmapped-rois must be ignore or refuse");
  }
  return choice == "ignore";
}

bmr::GridGeometry
GridFromArguments(const Arguments & args, const bmr::GridGeometry & defaults)
{
  const std::array<double, 3> size =
    args.Triple("--size", { { double(defaults.size[0]), double(defaults.size[1]), double(defaults.size[2]) } });
  std::array<std::size_t, 3> voxels;
  for (int i = 0; i < 3; ++i)
  {
    if (!(size[i] >= 1.0 && size[i] <= 4096.0 && size[i] == std::floor(size[i])))
    {
      throw UsageError("--size must be three integers in [1, 4096]");
    }
    voxels[i] = static_cast<std::size_t>(size[i]);
  }
  // Centred on the physical origin unless an origin is given; a rotation about z makes an oblique volume.
  bmr::GridGeometry g = bmr::CenteredGrid(voxels,
                                          args.Triple("--spacing", defaults.spacing),
                                          args.Number("--rotate-z-deg", 0.0) * 3.14159265358979323846 / 180.0);
  g.origin = args.Triple("--origin", g.origin);
  g.Validate("phantom grid (--size/--spacing/--origin)");
  return g;
}

} // namespace bmrcli
