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
// The settings structs' own checks (itk::RegistrationSettings::Validate, itk::UncertaintySettings::Validate, and the
// estimator's and walls' they call): the defaults pass; each setting just inside its range passes and just outside
// it (or NaN) is refused by an itk::InvalidArgumentError whose description names the setting, the name the CLI
// maps to its option. RegisterSegmentedPair() and MeshMovingAnatomy() refuse the same settings before they mesh.
#include "itkRegistrationPipeline.h"
#include "bmrTestUtilities.h"

#include <functional>
#include <limits>

namespace {
using Edit = std::function<void(itk::RegistrationSettings &)>;

/** Whether settings edited by \a inside validate and those edited by \a outside are refused naming \a setting. */
bool
CheckRange(const std::string & setting, const Edit & inside, const Edit & outside)
{
  itk::RegistrationSettings good, bad;
  inside(good);
  outside(bad);
  bool accepted = true;
  try
  {
    good.Validate();
  }
  catch (const itk::ExceptionObject & e)
  {
    accepted = false;
    std::cerr << "FAIL " << setting << " inside its range refused: " << e.GetDescription() << std::endl;
  }
  const bool refused = bmr::test::ExpectException(
    setting + " outside its range", [&] { bad.Validate(); }, setting);
  bool typed = false;
  try
  {
    bad.Validate();
  }
  catch (const itk::InvalidArgumentError &)
  {
    typed = true; // bad input, not a failed computation (Python: ValueError)
  }
  catch (const itk::ExceptionObject &)
  {}
  return accepted && refused && bmr::test::Expect(typed, setting + ": refused as itk::InvalidArgumentError");
}
} // namespace

int
itkRegistrationSettingsTest(int, char *[])
{
  const double nan = std::numeric_limits<double>::quiet_NaN();
  bool         ok = CheckRange(
    "meshScale", [](auto & s) { s.meshScale = 0.25; }, [](auto & s) { s.meshScale = 0.2499; });
  ok &= CheckRange(
    "meshScale", [](auto & s) { s.meshScale = 4.0; }, [nan](auto & s) { s.meshScale = nan; });
  ok &= CheckRange(
    "coarseFactor", [](auto & s) { s.coarseFactor = 10.0; }, [](auto & s) { s.coarseFactor = 0.0; });
  ok &= CheckRange(
    "meshJitter", [](auto & s) { s.uncertainty.meshJitter = 0.899; }, [](auto & s) { s.uncertainty.meshJitter = 0.9; });
  ok &= CheckRange(
    "shiftVoxels",
    [](auto & s) { s.uncertainty.shiftVoxels = 0.0; },
    [](auto & s) { s.uncertainty.shiftVoxels = -0.1; });
  ok &= CheckRange(
    "simulationMeshScale",
    [](auto & s) { s.uncertainty.simulationMeshScale = 2.0; },
    [](auto & s) { s.uncertainty.simulationMeshScale = 2.01; });
  ok &= CheckRange(
    "statedVoxelLimitMM",
    [](auto & s) { s.uncertainty.statedVoxelLimitMM = 3.0; },
    [](auto & s) { s.uncertainty.statedVoxelLimitMM = 0.0; });
  ok &= CheckRange(
    "resamples", [](auto & s) { s.uncertainty.resamples = 3; }, [](auto & s) { s.uncertainty.resamples = 2; });
  ok &= CheckRange(
    "outerGradientTolerance",
    [](auto & s) { s.estimator.outerGradientTolerance = 0.5; },
    [](auto & s) { s.estimator.outerGradientTolerance = 1.0; });
  ok &= CheckRange(
    "controlSpacing", [](auto & s) { s.walls.controlSpacing = 0.0; }, [](auto & s) { s.walls.controlSpacing = -1.0; });
  ok &= CheckRange(
    "limitElementInversion",
    [](auto & s) {
      s.walls.controlSpacing = 0.0;
      s.estimator.limitElementInversion = true;
    },
    [](auto & s) {
      s.walls.controlSpacing = 6.0;
      s.estimator.limitElementInversion = true;
    });
  // Two resamples are fine when nothing is resampled.
  ok &= CheckRange(
    "resamples",
    [](auto & s) {
      s.uncertainty.method = itk::UncertaintyMethodEnum::Curvature;
      s.uncertainty.resamples = 2;
    },
    [](auto & s) { s.uncertainty.resamples = 1; });
  // MeshMovingAnatomy() refuses them too, before it meshes anything.
  itk::RegistrationSettings jittered;
  jittered.uncertainty.meshJitter = 0.95;
  ok &= bmr::test::ExpectException(
    "MeshMovingAnatomy with a mesh jitter of 0.95",
    [&] { itk::MeshMovingAnatomy(nullptr, bmr::Scene(), jittered); },
    "meshJitter must lie in [0, 0.9)");
  return ok ? EXIT_SUCCESS : EXIT_FAILURE;
}
