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
// biomechreg dose: per-organ DVHs, D95/D2/Dmean, V-doses and gEUD of a dose image (or of a synthetic conformal
// plan) on a label map, optionally after warping the dose through a displacement field (itkDoseEvaluation.h).
#include "biomechregCommon.h"
#include "itkDicomRT.h"
#include "itkDoseEvaluation.h"
#include "itkImageRegionConstIteratorWithIndex.h"

#include <cstdlib>
#include <filesystem>
#include <fstream>

namespace bmrcli {

namespace {

using DoseImageType = itk::BiomechanicalDoseImageType;

/** The dose [Gy] at \a path: a DICOM RTDOSE (its dose grid scaling applied) or any image ITK reads, in Gy
 * (itk::ReadDoseImage()); refuses a negative dose, naming the file and the voxel. */
DoseImageType::Pointer
ReadDose(const std::string & path)
{
  DoseImageType::Pointer dose = itk::ReadDoseImage(path);
  for (itk::ImageRegionConstIteratorWithIndex<DoseImageType> it(dose, dose->GetLargestPossibleRegion()); !it.IsAtEnd();
       ++it)
  {
    if (it.Get() < 0.0f)
    {
      std::ostringstream os;
      os << "dose image \"" << path << "\": voxel " << it.GetIndex() << " holds " << it.Get()
         << " Gy (a dose must be >= 0)";
      throw std::runtime_error(os.str());
    }
  }
  return dose;
}

/** Comma-separated numbers of option \a key ("" gives none). */
std::vector<double>
ParseNumberList(const std::string & key, const std::string & text)
{
  std::vector<double> values;
  std::stringstream   in(text);
  std::string         item;
  while (std::getline(in, item, ','))
  {
    char *       end = nullptr;
    const double v = std::strtod(item.c_str(), &end);
    if (item.empty() || *end != '\0' || !std::isfinite(v) || v < 0.0)
    {
      throw UsageError(key + " expects comma-separated doses >= 0 [Gy], got \"" + text + "\"");
    }
    values.push_back(v);
  }
  return values;
}

std::string
ShellQuoted(const std::string & text)
{
  std::string quoted = "'";
  for (const char c : text)
  {
    quoted += c == '\'' ? std::string("'\\''") : std::string(1, c);
  }
  return quoted + "'";
}

/** scripts/plot_dvh.py: $BMR_SCRIPTS, else <prefix>/share/biomechreg/scripts next to the executable (installed),
 * else the source tree this binary was built from; empty when none holds it. */
std::string
FindPlotScript()
{
  namespace fs = std::filesystem;
  std::vector<fs::path> candidates;
  if (const char * root = std::getenv("BMR_SCRIPTS"))
  {
    candidates.push_back(fs::path(root) / "plot_dvh.py");
  }
  std::error_code error;
  const fs::path  executable = fs::read_symlink("/proc/self/exe", error);
  if (!error)
  {
    candidates.push_back(executable.parent_path().parent_path() / "share" / "biomechreg" / "scripts" / "plot_dvh.py");
  }
  candidates.push_back(fs::path(BMR_SOURCE_DIR) / "scripts" / "plot_dvh.py");
  for (const auto & c : candidates)
  {
    if (fs::is_regular_file(c, error))
    {
      return c.string();
    }
  }
  return std::string();
}

/** Runs plot_dvh.py on \a out (it writes dvh.png through a temporary file). A missing script, Python or
 * matplotlib is a warning, not an error: the tables are the results, the figure a view of them. */
void
PlotDoseVolumeHistograms(const std::string & out)
{
  const std::string script = FindPlotScript();
  if (script.empty())
  {
    PrintWarning("no dvh.png: scripts/plot_dvh.py not found (set BMR_SCRIPTS to the folder that holds it)");
    return;
  }
  const char *      python = std::getenv("BMR_PYTHON");
  const std::string interpreter = python ? python : "/usr/bin/python3";
  const std::string log = out + "/.plot_dvh.log";
  const std::string command =
    ShellQuoted(interpreter) + " " + ShellQuoted(script) + " " + ShellQuoted(out) + " > " + ShellQuoted(log) + " 2>&1";
  const int   status = std::system(command.c_str());
  std::string lastLine, line;
  for (std::ifstream in(log); std::getline(in, line);)
  {
    lastLine = line.empty() ? lastLine : line;
  }
  std::error_code error;
  std::filesystem::remove(log, error);
  if (status != 0)
  {
    PrintWarning("no dvh.png: " + interpreter + " " + script + " failed: " + lastLine);
  }
}

void
PrintDoseTable(const itk::DoseEvaluation & evaluation)
{
  std::cout << "  " << std::left << std::setw(22) << "structure" << std::right << std::setw(9) << "a" << std::setw(10)
            << "gEUD Gy" << std::setw(10) << "Dmean Gy" << std::setw(10) << "D95 Gy" << std::setw(10) << "D2 Gy"
            << std::setw(11) << "volume cc"
            << "\n";
  for (const auto & s : evaluation.structures)
  {
    const bmr::DoseMetrics & m = s.metrics;
    std::cout << "  " << std::left << std::setw(22) << s.name << std::right << std::fixed << std::setprecision(1)
              << std::setw(9) << m.eudA << std::setprecision(2) << std::setw(10) << m.gEUD << std::setw(10) << m.mean
              << std::setw(10) << m.D95 << std::setw(10) << m.D2 << std::setw(11) << m.volumeCC << "\n";
    if (s.fractionOutsideDoseGrid > 0.0)
    {
      std::ostringstream os;
      os << std::setprecision(1) << std::fixed << 100.0 * s.fractionOutsideDoseGrid << " % of \"" << s.name
         << "\" lies outside the dose grid (counted as 0 Gy)";
      PrintWarning(os.str());
    }
  }
  std::cout.unsetf(std::ios::floatfield);
}

/** The synthetic plan's settings from the options; refuses them out of range, or without --plan-margin (\a plan). */
itk::ConformalPlanSettings
ParsePlanSettings(const Arguments & args, bool plan)
{
  itk::ConformalPlanSettings planSettings;
  planSettings.marginMm = args.Number("--plan-margin", planSettings.marginMm);
  planSettings.prescriptionGy = args.Number("--prescription-Gy", planSettings.prescriptionGy);
  planSettings.penumbraMm = args.Number("--penumbra-mm", planSettings.penumbraMm);
  planSettings.bathFraction = args.Number("--bath-fraction", planSettings.bathFraction);
  if (!(planSettings.marginMm >= 0.0 && planSettings.marginMm <= 50.0) || !(planSettings.prescriptionGy > 0.0) ||
      !(planSettings.penumbraMm > 0.0 && planSettings.penumbraMm <= 50.0) ||
      !(planSettings.bathFraction >= 0.0 && planSettings.bathFraction < 1.0))
  {
    throw UsageError("--plan-margin must lie in [0, 50] mm, --prescription-Gy be > 0, --penumbra-mm in (0, 50] and "
                     "--bath-fraction in [0, 1)");
  }
  if (!plan && (args.Has("--prescription-Gy") || args.Has("--penumbra-mm") || args.Has("--bath-fraction")))
  {
    throw UsageError("--prescription-Gy, --penumbra-mm and --bath-fraction describe the plan of --plan-margin");
  }
  return planSettings;
}

/** The evaluation's settings from the options: bins, V-doses, gEUD parameters and the wall's organs. */
itk::DoseEvaluationSettings
ParseDoseEvaluationSettings(const Arguments & args)
{
  itk::DoseEvaluationSettings settings;
  settings.binWidthGy = args.Number("--bin-width-Gy", settings.binWidthGy);
  if (!(settings.binWidthGy >= 0.001 && settings.binWidthGy <= 10.0))
  {
    throw UsageError("--bin-width-Gy must lie in [0.001, 10]");
  }
  if (args.Has("--v-doses"))
  {
    settings.volumeDosesGy = ParseNumberList("--v-doses", args.Get("--v-doses"));
  }
  settings.eudParameters = args.NamedNumbers("--eud-a");
  settings.wall.prostateName = args.Get("--prostate", settings.wall.prostateName);
  settings.wall.rectumName = args.Get("--rectum", settings.wall.rectumName);
  return settings;
}

/** Refuses a --eud-a name that is neither a structure of the scene at \a scenePath nor the wall. */
void
CheckEudStructures(const itk::DoseEvaluationSettings &         settings,
                   const std::map<std::string, std::int32_t> & structures,
                   const std::string &                         scenePath)
{
  for (const auto & kv : settings.eudParameters)
  {
    if (structures.count(kv.first) == 0 && kv.first != settings.wall.name)
    {
      throw std::runtime_error("--eud-a names \"" + kv.first + "\", which is not a structure of the scene \"" +
                               scenePath + "\" (nor " + settings.wall.name + ")");
    }
  }
}

/** The synthetic conformal plan around the prostate of \a structures (the scene at \a scenePath). */
DoseImageType::Pointer
MakePlanDose(const LabelImageType *                      labels,
             const std::map<std::string, std::int32_t> & structures,
             const itk::DoseEvaluationSettings &         settings,
             const itk::ConformalPlanSettings &          planSettings,
             const std::string &                         scenePath,
             StageTimer &                                timer)
{
  const auto prostate = structures.find(settings.wall.prostateName);
  if (prostate == structures.end())
  {
    throw std::runtime_error("the scene \"" + scenePath + "\" has no structure \"" + settings.wall.prostateName +
                             "\" for the plan's target (see --prostate)");
  }
  std::ostringstream detail;
  detail << "PTV = " << settings.wall.prostateName << " + " << planSettings.marginMm << " mm, Rx "
         << planSettings.prescriptionGy << " Gy, penumbra " << planSettings.penumbraMm << " mm";
  timer.Begin("conformal plan");
  DoseImageType::Pointer dose = itk::MakeConformalDosePlan(labels, prostate->second, planSettings);
  timer.End(detail.str());
  return dose;
}

/** Writes the tables, the dose on the label grid and (with \a plot) dvh.png into \a out. */
void
WriteDoseOutputs(const std::string &         out,
                 const itk::DoseEvaluation & evaluation,
                 const DoseImageType *       dose,
                 const LabelImageType *      labels,
                 bool                        plot,
                 StageTimer &                timer)
{
  timer.Begin("write outputs");
  MakeOutputDirectory(out);
  itk::WriteDoseEvaluation(out, evaluation);
  itk::WriteImageAtomically(itk::ResampleDoseOntoGrid(dose, labels).GetPointer(), out + "/dose.nrrd");
  timer.End();
  if (plot)
  {
    timer.Begin("plot (dvh.png)");
    PlotDoseVolumeHistograms(out);
    timer.End();
  }
}

} // namespace

int
DoseCommand(const Arguments & args)
{
  const std::string labelsPath = args.Require("--labels");
  const std::string scenePath = args.Require("--scene");
  const std::string out = args.Require("--out");
  const std::string dosePath = args.Get("--dose");
  const std::string fieldPath = args.Get("--field");
  const bool        plan = args.Has("--plan-margin");
  if (plan == !dosePath.empty())
  {
    throw UsageError("give either --dose FILE or --plan-margin MM (a synthetic conformal plan)");
  }
  const itk::ConformalPlanSettings  planSettings = ParsePlanSettings(args, plan);
  const itk::DoseEvaluationSettings settings = ParseDoseEvaluationSettings(args);
  const bool                        plot = args.Choice("--plot", { "on", "off" }) == "on";
  args.CheckAllUsed();

  // Every input is read and checked before anything is written: a bad input leaves no output directory.
  StageTimer timer;
  std::cout << "biomechreg dose -> " << out << std::endl;
  timer.Begin("read inputs");
  const bmr::Scene scene = bmr::ReadScene(scenePath);
  auto             labels = ReadImage<LabelImageType>(labelsPath, "label image");
  const auto       structures = itk::DoseStructuresFromScene(scene);
  CheckEudStructures(settings, structures, scenePath);
  DoseImageType::Pointer dose = plan ? nullptr : ReadDose(dosePath);
  FieldType::Pointer     field = fieldPath.empty() ? nullptr : ReadImage<FieldType>(fieldPath, "displacement field");
  timer.End();

  if (plan)
  {
    dose = MakePlanDose(labels, structures, settings, planSettings, scenePath, timer);
  }
  if (field)
  {
    timer.Begin("warp dose (linear)");
    dose = itk::WarpDose(dose, field);
    timer.End();
  }
  timer.Begin("DVH and metrics");
  const itk::DoseEvaluation evaluation = itk::EvaluateDose(labels, dose, structures, settings);
  timer.End(evaluation.doseResampled ? "dose resampled linearly onto the label grid" : "");

  WriteDoseOutputs(out, evaluation, dose, labels, plot, timer);
  std::cout << "\n";
  PrintDoseTable(evaluation);
  PrintTimings(timer.stages);
  std::cout << "Wrote " << out << "/{dvh.csv, dose_metrics.csv, dose.nrrd" << (plot ? ", dvh.png" : "") << "}"
            << std::endl;
  return EXIT_SUCCESS;
}

} // namespace bmrcli
