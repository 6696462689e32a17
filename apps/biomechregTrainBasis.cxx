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
// biomechreg train-basis: a basis of wall motion learned from daily scans (itk::TrainWallBasis).
#include "biomechregCommon.h"
#include "itkWallBasisTraining.h"

#include <fstream>
#include <iomanip>

namespace bmrcli {
namespace {
/** The training scans: --moving-labels FILE --fixed-labels FILE,... (one patient), or --patients CSV whose lines
 * are "moving labels,fixed labels" (a header line "moving_labels,fixed_labels" allowed), one example each, grouped
 * into patients by their moving labels in the order they first appear. */
std::vector<std::pair<std::string, std::vector<std::string>>>
TrainingScans(const Arguments & args)
{
  if (!args.Has("--patients"))
  {
    return { { args.Require("--moving-labels"), args.RequireList("--fixed-labels") } };
  }
  if (args.Has("--moving-labels") || args.Has("--fixed-labels"))
  {
    throw UsageError("--patients replaces --moving-labels and --fixed-labels");
  }
  const std::string path = args.Require("--patients");
  std::ifstream     in(path);
  if (!in)
  {
    throw UsageError("cannot read --patients " + path);
  }
  std::vector<std::pair<std::string, std::vector<std::string>>> patients;
  for (std::string line; std::getline(in, line);)
  {
    const auto comma = line.find(',');
    if (line.empty() || line == "moving_labels,fixed_labels")
    {
      continue;
    }
    if (comma == std::string::npos || comma == 0 || comma + 1 == line.size())
    {
      throw UsageError("--patients " + path + ": expected \"moving labels,fixed labels\" per line, got \"" + line +
                       "\"");
    }
    const std::string moving = line.substr(0, comma), fixed = line.substr(comma + 1);
    const auto        found =
      std::find_if(patients.begin(), patients.end(), [&](const auto & p) { return p.first == moving; });
    (found == patients.end() ? patients.emplace_back(moving, std::vector<std::string>()) : *found)
      .second.push_back(fixed);
  }
  return patients;
}
} // namespace

int
TrainBasisCommand(const Arguments & args)
{
  const auto                scans = TrainingScans(args);
  const std::string         scenePath = args.Require("--scene");
  const std::string         out = args.Require("--out");
  const unsigned int        modes = args.Count("--modes", 1000000, 1, 1000000);
  itk::RegistrationSettings settings;
  settings.meshScale = args.Number("--mesh-scale", settings.meshScale);
  settings.interpolateSlices = args.Choice("--slice-interpolation", { "off", "on" }) == "on";
  args.CheckAllUsed();

  StageTimer timer;
  std::cout << "biomechreg train-basis: " << scans.size() << " patient(s) -> " << out << std::endl;
  timer.Begin("read inputs");
  const bmr::Scene                           scene = bmr::ReadScene(scenePath);
  std::vector<LabelImageType::Pointer>       images; // held while the patients point into them
  std::vector<itk::WallBasisTrainingPatient> patients;
  std::string                                training;
  for (const auto & [moving, fixed] : scans)
  {
    images.push_back(ReadImage<LabelImageType>(moving, "moving labels"));
    patients.push_back({ images.back().GetPointer(), {} });
    training += (training.empty() ? "" : "; ") + std::string("moving ") + moving + ", fixed";
    for (const std::string & path : fixed)
    {
      images.push_back(ReadImage<LabelImageType>(path, "fixed labels"));
      patients.back().fixedLabels.push_back(images.back().GetPointer());
      training += " " + path;
    }
  }
  timer.End();
  timer.Begin("mesh, surface matching, PCA");
  const bmr::WallMotionBasis basis = itk::TrainWallBasis(patients, scene, settings, modes, training);
  timer.End(std::to_string(basis.examples) + " examples, " + std::to_string(basis.GetNumberOfModes()) + " modes on " +
            std::to_string(basis.points.size()) + " wall points");
  timer.Begin("write basis");
  bmr::WriteWallMotionBasis(basis, out);
  timer.End();
  std::cout << "  mode  variance [mm^2]  explained" << std::endl;
  for (std::size_t k = 0; k < basis.GetNumberOfModes(); ++k)
  {
    std::cout << "  " << std::setw(4) << k + 1 << "  " << std::setw(15) << std::setprecision(4) << basis.variances[k]
              << "  " << std::setw(9) << std::setprecision(3) << basis.explainedVariance[k] << std::endl;
  }
  PrintTimings(timer.stages);
  return EXIT_SUCCESS;
}

} // namespace bmrcli
