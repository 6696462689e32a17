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
// biomechreg train-basis: a basis of wall motion learned from one patient's daily scans (itk::TrainWallBasis).
#include "biomechregCommon.h"
#include "itkWallBasisTraining.h"

#include <iomanip>

namespace bmrcli {

int
TrainBasisCommand(const Arguments & args)
{
  const std::string              movingPath = args.Require("--moving-labels");
  const std::vector<std::string> fixedPaths = args.RequireList("--fixed-labels");
  const std::string              scenePath = args.Require("--scene");
  const std::string              out = args.Require("--out");
  const unsigned int             modes = args.Count("--modes", 1000000, 1, 1000000);
  itk::RegistrationSettings      settings;
  settings.meshScale = args.Number("--mesh-scale", settings.meshScale);
  settings.interpolateSlices = args.Choice("--slice-interpolation", { "off", "on" }) == "on";
  args.CheckAllUsed();
  if (fixedPaths.size() < 2)
  {
    throw UsageError("--fixed-labels needs at least two label images (the examples)");
  }

  StageTimer timer;
  std::cout << "biomechreg train-basis: " << fixedPaths.size() << " examples -> " << out << std::endl;
  timer.Begin("read inputs");
  const bmr::Scene                                      scene = bmr::ReadScene(scenePath);
  const auto                                            moving = ReadImage<LabelImageType>(movingPath, "moving labels");
  std::vector<LabelImageType::Pointer>                  fixed;
  std::vector<const itk::BiomechanicalLabelImageType *> fixedImages;
  for (const std::string & path : fixedPaths)
  {
    fixed.push_back(ReadImage<LabelImageType>(path, "fixed labels"));
    fixedImages.push_back(fixed.back().GetPointer());
  }
  timer.End();
  timer.Begin("mesh, surface matching, PCA");
  std::string training = "moving " + movingPath + "; fixed";
  for (const std::string & path : fixedPaths)
  {
    training += " " + path;
  }
  const bmr::WallMotionBasis basis =
    itk::TrainWallBasis(moving.GetPointer(), fixedImages, scene, settings, modes, training);
  timer.End(std::to_string(basis.GetNumberOfModes()) + " modes on " + std::to_string(basis.points.size()) +
            " wall points");
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
