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
// Example: a registration with joint estimation of elasticity, with the library. A concentric-spheres phantom
// pair is made with a known core modulus (80 kPa, the fixed scan from a finer, independent mesh), then the
// pair is registered as a user's scans would be: the estimator sees the two label maps, the moving CT and
// a scene in which the core's modulus is unknown.
#include "itkBiomechanicalPipelines.h"
#include "itkBiomechanicalReports.h"

#include <cstdlib>
#include <iostream>
#include <string>

int
main()
{
  itk::PhantomSettings phantom;
  phantom.anatomy = itk::PhantomSettings::AnatomyEnum::Spheres;
  phantom.grid = bmr::SpherePhantomParameters().grid; // 96^3 voxels of 1 mm: the shapes resolve the modulus
  phantom.prostateE = 80.0;                           // kPa, the core
  phantom.bladderMM = 1.5;                            // the outer surface moves inwards by 1.5 mm
  const itk::PhantomPair pair = itk::MakePhantomPair(phantom);

  const itk::RegistrationResult result =
    itk::RegisterSegmentedPair(pair.movingLabels, pair.fixedLabels, pair.movingCT, pair.scene);

  // The fit's modulus and the stated one: bias-corrected by the parametric bootstrap, with its 68 % and 95 %
  // intervals, or a one-sided bound when the images do not determine an end (ModulusInterval).
  const itk::ModulusInterval & stated = result.modulusInterval.at("inner");
  std::cout << "core modulus: true " << phantom.prostateE << " kPa, fit " << result.youngsModulus.at("inner")
            << " kPa; " << itk::ModulusIntervalText("inner", stated) << "; gauge " << result.gaugeLabel << " "
            << result.gaugeModulus << " kPa" << std::endl;
  for (const auto & kv : result.dice)
  {
    std::cout << "  Dice " << kv.first << " " << kv.second << std::endl;
  }
  // result.state.pullBack is the fixed -> moving field, result.warpedCT the warped moving CT.
  return result.estimation.identifiable ? EXIT_SUCCESS : EXIT_FAILURE;
}
