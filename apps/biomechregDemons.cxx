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
// biomechreg demons: the intensity-based baseline (itk::DemonsBaselineRegistrationFilter) from the command line,
// and the settings parser shared with biomechreg compare.
#include "biomechregCommon.h"

namespace bmrcli {

itk::DemonsSettings
ParseDemonsSettings(const Arguments & args)
{
  itk::DemonsSettings s;
  s.variant = args.Get("--demons-variant", s.variant);
  if (s.variant != "diffeomorphic" && s.variant != "symmetric")
  {
    throw UsageError("--demons-variant must be diffeomorphic or symmetric");
  }
  const double levels = args.Number("--demons-levels", s.levels);
  const double iterations = args.Number("--demons-iterations", s.iterations);
  if (!(levels >= 1 && levels <= 6 && levels == std::floor(levels)) ||
      !(iterations >= 1 && iterations <= 10000 && iterations == std::floor(iterations)))
  {
    throw UsageError("--demons-levels must be an integer in [1, 6] and --demons-iterations one in [1, 10000]");
  }
  s.levels = static_cast<unsigned int>(levels);
  s.iterations = static_cast<unsigned int>(iterations);
  s.sigma = args.Number("--demons-sigma", s.sigma);
  if (!(s.sigma > 0.0 && s.sigma <= 20.0))
  {
    throw UsageError("--demons-sigma must lie in (0, 20] voxels");
  }
  const std::string matching = args.Get("--histogram-matching", "on");
  if (matching != "on" && matching != "off")
  {
    throw UsageError("--histogram-matching must be on or off");
  }
  s.histogramMatching = matching == "on";
  return s;
}

int
DemonsCommand(const Arguments & args)
{
  const std::string movingCTPath = args.Require("--moving-ct");
  const std::string fixedCTPath = args.Require("--fixed-ct");
  const std::string out = args.Require("--out");
  const std::string movingLabelsPath = args.Get("--moving-labels");
  const std::string fixedLabelsPath = args.Get("--fixed-labels");
  const auto        flatten = bmr::ParseLabelList(args.Get("--flatten"), nullptr);
  const auto        settings = ParseDemonsSettings(args);
  args.CheckAllUsed();
  if (!flatten.empty() && (movingLabelsPath.empty() || fixedLabelsPath.empty()))
  {
    throw UsageError("--flatten needs --moving-labels and --fixed-labels (each image is flattened with its own)");
  }

  StageTimer timer;
  std::cout << "biomechreg demons -> " << out << std::endl;
  timer.Begin("read inputs");
  auto                    movingCT = ReadImage<CTImageType>(movingCTPath, "moving CT");
  auto                    fixedCT = ReadImage<CTImageType>(fixedCTPath, "fixed CT");
  LabelImageType::Pointer movingLabels, fixedLabels;
  if (!flatten.empty())
  {
    movingLabels = ReadImage<LabelImageType>(movingLabelsPath, "moving label image");
    fixedLabels = ReadImage<LabelImageType>(fixedLabelsPath, "fixed label image");
  }
  timer.End();
  MakeOutputDirectory(out);
  std::ostringstream detail;
  detail << settings.variant << ", " << settings.levels << " levels x " << settings.iterations << " iterations";
  timer.Begin("Demons");
  const auto field = itk::RunDemonsBaseline(fixedCT, movingCT, fixedLabels, movingLabels, flatten, settings, &timer);
  timer.End(detail.str());
  timer.Begin("warp CT (linear)");
  auto warped = itk::WarpImage(movingCT.GetPointer(), field.GetPointer(), false, -1000.0f);
  timer.End();
  timer.Begin("write outputs");
  itk::WriteImageAtomically(field.GetPointer(), out + "/field.nrrd");
  itk::WriteImageAtomically(warped.GetPointer(), out + "/warped_ct.nrrd");
  timer.End();
  PrintTimings(timer.stages);
  return EXIT_SUCCESS;
}

} // namespace bmrcli
