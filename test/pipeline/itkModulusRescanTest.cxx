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
// The rescan interval of an estimated modulus (itk::UncertaintyMethodEnum::Rescan, the default of
// itk::RegisterSegmentedPair) on the concentric-spheres phantom (96^3 voxels of 1 mm, the core 80 kPa, unknown
// within [30, 300] kPa). What is checked, and why these limits:
// - the rescans revoxelize the fixed anatomy itself, with no model in the loop: without mesh jitter their median
//   must not differ significantly from the fit (|b| < 3 standard errors of a median, 3 x 1.2533 s / sqrt(n),
//   the rule by which the interval would correct it). The resimulating bootstrap is off by 0.1-0.5 in log E on
//   the pelvis (docs/estimation.md);
// - the spread comes from the data: it is larger on 2 mm voxels than on 1 mm ones;
// - deterministic: the same seed gives bit-identical rescans, also on one thread (no meshes made ahead) and with
//   the moving anatomy meshed beforehand (MeshMovingAnatomy), whose meshes are checked against the settings;
// - resampling scales the rescans cannot honour are refused with an itk::ExceptionObject naming the setting.
#include "itkBiomechanicalPipelines.h"
#include "itkBiomechanicalReports.h"
#include "itkIntervalTestSupport.h"
#include "bmrTestUtilities.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <iostream>

namespace {

itk::RegistrationSettings
RescanSettings(double meshJitter, double stepTolerance, unsigned int threads)
{
  itk::RegistrationSettings settings;
  settings.uncertainty.threads = threads;
  settings.uncertainty.method = itk::UncertaintyMethodEnum::Rescan;
  settings.uncertainty.resamples = 4;
  settings.uncertainty.meshJitter = meshJitter;
  settings.uncertainty.stepTolerance = stepTolerance;
  settings.uncertainty.statedVoxelLimitMM = 2.5; // the 2 mm case below studies the rescans' spread there
  return settings;
}

itk::ModulusInterval
Rescan(const itk::PhantomPair &                 pair,
       const itk::BiomechanicalLabelImageType * fixed,
       double                                   meshJitter,
       double                                   stepTolerance = itk::UncertaintySettings().stepTolerance,
       unsigned int                             threads = 0,
       const itk::MovingAnatomyMeshes *         meshes = nullptr)
{
  itk::RegistrationSettings settings = RescanSettings(meshJitter, stepTolerance, threads);
  settings.meshes = meshes;
  const itk::RegistrationResult r = itk::RegisterSegmentedPair(pair.movingLabels, fixed, nullptr, pair.scene, settings);
  const itk::ModulusInterval    i = r.modulusInterval.at("inner");
  std::cout << "  " << itk::ModulusIntervalText("inner", i) << "; b " << i.logBias << ", s " << i.logSigma
            << ", rescans";
  for (double E : i.resampleModuli)
  {
    std::cout << " " << E;
  }
  std::cout << std::endl;
  return i;
}
} // namespace

int
itkModulusRescanTest(int, char *[])
{
  bool                 ok = true;
  itk::PhantomSettings s = itk::PhantomSettings::Defaults(itk::PhantomSettings::AnatomyEnum::Spheres);
  s.prostateE = 80.0;
  const itk::PhantomPair pair = itk::MakePhantomPair(s);

  // The spread's dependence on the voxels, with the strict outer search (1e-3 in log E): the resamples' default
  // step tolerance (0.01) adds up to 1 % per rescan, half the spread (about 2 %) of this staircase-free phantom.
  const double               strictStep = 1e-3;
  const itk::ModulusInterval fine = Rescan(pair, pair.fixedLabels, 0.0, strictStep);
  const double               n = double(fine.resampleModuli.size());
  ok &= bmr::test::Expect(std::abs(fine.logBias) < 3.0 * 1.2533 * fine.logSigma / std::sqrt(n),
                          "no mesh jitter: the rescans' median does not differ significantly from the fit");
  ok &= bmr::test::Expect(fine.lowerDetermined && fine.upperDetermined, "both ends of the interval determined");

  const itk::ModulusInterval coarse = Rescan(pair, itk::test::Coarsened(pair.fixedLabels), 0.0, strictStep);
  ok &= bmr::test::Expect(coarse.logSigma > fine.logSigma,
                          "the rescans spread more on 2 mm fixed voxels than on 1 mm ones");
  // At the default limit (1.5 mm) no modulus is stated from 2 mm voxels, and no rescan is computed for it.
  itk::RegistrationSettings gated = RescanSettings(0.0, strictStep, 0);
  gated.uncertainty.statedVoxelLimitMM = itk::UncertaintySettings().statedVoxelLimitMM;
  const itk::RegistrationResult gatedResult =
    itk::RegisterSegmentedPair(pair.movingLabels, itk::test::Coarsened(pair.fixedLabels), nullptr, pair.scene, gated);
  const itk::ModulusInterval & notStated = gatedResult.modulusInterval.at("inner");
  ok &= bmr::test::Expect(!notStated.notDeterminedReason.empty() && !notStated.lowerDetermined &&
                            !notStated.upperDetermined && notStated.resampleModuli.empty() &&
                            gatedResult.modulusUncertainty.empty(),
                          "2 mm voxels at the default limit: not determined, with a reason, and no rescan computed");

  const double               jitter = itk::UncertaintySettings().meshJitter;
  const itk::ModulusInterval one = Rescan(pair, pair.fixedLabels, jitter);
  const itk::ModulusInterval again = Rescan(pair, pair.fixedLabels, jitter);
  ok &= bmr::test::Expect(again.resampleModuli == one.resampleModuli && again.interval95 == one.interval95,
                          "the same seed gives bit-identical rescans");
  // One resampling thread: no mesh is made ahead while the fit runs (ResampleMeshPrefetch), each rescan meshes its
  // own, and the rescans are the same.
  const itk::ModulusInterval single =
    Rescan(pair, pair.fixedLabels, jitter, itk::UncertaintySettings().stepTolerance, 1);
  ok &= bmr::test::Expect(single.resampleModuli == one.resampleModuli,
                          "one resampling thread without the meshes made ahead gives bit-identical rescans");
  // The moving anatomy meshed beforehand (MeshMovingAnatomy, as for a planning scan): the same meshes, so the same
  // fit and rescans bit for bit; meshes made for another resampling seed are refused.
  const itk::RegistrationSettings defaults = RescanSettings(jitter, itk::UncertaintySettings().stepTolerance, 0);
  const itk::MovingAnatomyMeshes  premeshed = itk::MeshMovingAnatomy(pair.movingLabels, pair.scene, defaults);
  ok &= bmr::test::Expect(premeshed.resamples.size() == 4 && !premeshed.coarse.points.empty(),
                          "MeshMovingAnatomy made the fit's, the sweep's and 4 resample meshes");
  const itk::ModulusInterval reused =
    Rescan(pair, pair.fixedLabels, jitter, itk::UncertaintySettings().stepTolerance, 0, &premeshed);
  ok &= bmr::test::Expect(reused.estimate == one.estimate && reused.resampleModuli == one.resampleModuli &&
                            reused.interval95 == one.interval95,
                          "the meshes made beforehand give the bit-identical fit and rescans");

  // The resamples' looser outer search: it stops once the next secant step in log E would be shorter than the
  // tolerance, and the secant's steps shrink superlinearly, so each rescan lies within that tolerance (plus the
  // strict search's own 1e-3) of where the strict search ends.
  const itk::ModulusInterval strict = Rescan(pair, pair.fixedLabels, jitter, strictStep);
  double                     largest = 0.0;
  for (std::size_t k = 0; k < one.resampleModuli.size(); ++k)
  {
    largest = std::max(largest, std::abs(std::log(one.resampleModuli[k] / strict.resampleModuli[k])));
  }
  std::cout << "  largest |log E| difference between step tolerances 0.01 and 0.001: " << largest << std::endl;
  ok &= bmr::test::Expect(largest <= itk::UncertaintySettings().stepTolerance + 1e-3,
                          "each rescan with the default step tolerance lies within it of the strict search's");

  const auto refusal = [&](const itk::RegistrationSettings & bad) {
    std::string message;
    try
    {
      itk::RegisterSegmentedPair(pair.movingLabels, pair.fixedLabels, nullptr, pair.scene, bad);
    }
    catch (const itk::ExceptionObject & e)
    {
      message = e.GetDescription();
    }
    return message;
  };
  itk::RegistrationSettings bad;
  bad.uncertainty.meshJitter = 1.5; // mesh sizes x U(-0.5, 2.5)
  ok &= bmr::test::Expect(refusal(bad).find("meshJitter") != std::string::npos,
                          "a mesh jitter of 1.5 is refused, naming the setting");
  bad = itk::RegistrationSettings();
  bad.uncertainty.stepTolerance = -0.01;
  ok &= bmr::test::Expect(refusal(bad).find("stepTolerance") != std::string::npos,
                          "a negative step tolerance is refused, naming the setting");
  bad = defaults;
  bad.uncertainty.seed += 1; // other resample meshes
  bad.meshes = &premeshed;
  ok &= bmr::test::Expect(refusal(bad).find("MeshMovingAnatomy") != std::string::npos,
                          "meshes made for another resampling seed are refused, naming MeshMovingAnatomy");
  return ok ? EXIT_SUCCESS : EXIT_FAILURE;
}
