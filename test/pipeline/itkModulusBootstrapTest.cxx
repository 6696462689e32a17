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
// The resimulating interval of an estimated modulus (UncertaintyMethodEnum::Bootstrap of
// itk::RegisterSegmentedPair; the default, the rescan, is itkModulusRescanTest) on the
// concentric-spheres phantom (96^3 voxels of 1 mm, the core's modulus unknown within [30, 300] kPa), and the
// phantom's truth mesh. What is checked, and why these limits:
// - core 80 kPa: the fit is about 30 % too soft (the label staircase of the fixed scan; docs/estimation.md), the
//   bootstrap reproduces that bias. The stated estimate must lie closer to the truth than the fit, and both of
//   its intervals must be determined at both ends and the 95 % one must contain the truth;
// - deterministic: the same seed gives bit-identical resamples, on 1 and on 2 resampling threads alike (each
//   resample draws from its own random stream and runs as a task of its own), another seed other resamples;
// - the interval widens when the fixed voxels coarsen from 1 to 2 mm (the data carry less; an end left undetermined
//   counts as wider);
// - core 1000 kPa, beyond the upper bound: stated as "E >=" a lower bound, never as a number;
// - the truth's mesh shares no node set with the estimation mesh at the truth's own scale (the closest
//   register --mesh-scale can come): no inverse crime.
#include "itkBiomechanicalPipelines.h"
#include "itkBiomechanicalReports.h"
#include "itkIntervalTestSupport.h"
#include "bmrTestUtilities.h"
#include "itkLabelImageToTetrahedralMeshFilter.h"

#include <cmath>
#include <cstdlib>
#include <iomanip>
#include <iostream>
#include <set>

namespace {

itk::PhantomPair
Spheres(double coreE)
{
  itk::PhantomSettings s = itk::PhantomSettings::Defaults(itk::PhantomSettings::AnatomyEnum::Spheres);
  s.prostateE = coreE;
  return itk::MakePhantomPair(s);
}

itk::ModulusInterval
Interval(const itk::PhantomPair &                 pair,
         const itk::BiomechanicalLabelImageType * fixed,
         unsigned int                             threads,
         std::uint64_t                            seed)
{
  itk::RegistrationSettings settings;
  settings.uncertainty.method = itk::UncertaintyMethodEnum::Bootstrap;
  settings.uncertainty.correctBias = true; // what is checked at 80 kPa
  settings.uncertainty.resamples = 4;
  settings.uncertainty.threads = threads;
  settings.uncertainty.seed = seed;
  settings.uncertainty.statedVoxelLimitMM = 2.5; // the 2 mm case below studies the interval's width there
  const itk::RegistrationResult r = itk::RegisterSegmentedPair(pair.movingLabels, fixed, nullptr, pair.scene, settings);
  const itk::ModulusInterval    i = r.modulusInterval.at("inner");
  std::cout << "  " << itk::ModulusIntervalText("inner", i) << " [" << threads << " threads, seed " << seed << "]"
            << "; 95 %: " << i.interval95[0] << " to " << i.interval95[1] << " kPa, fit " << i.fit << ", resamples";
  for (double E : i.resampleModuli)
  {
    std::cout << " " << std::setprecision(17) << E;
  }
  std::cout << std::setprecision(6);
  std::cout << std::endl;
  return i;
}

std::set<std::array<double, 3>>
NodeSet(const itk::BiomechanicalLabelImageType * labels, const bmr::Scene & scene)
{
  auto mesher = itk::LabelImageToTetrahedralMeshFilter<itk::BiomechanicalLabelImageType>::New();
  mesher->SetInput(labels);
  mesher->SetScene(scene);
  mesher->Update();
  const auto &                    p = mesher->GetOutput()->Get().points;
  std::set<std::array<double, 3>> nodes;
  for (std::size_t n = 0; 3 * n < p.size(); ++n)
  {
    nodes.insert({ { p[3 * n], p[3 * n + 1], p[3 * n + 2] } });
  }
  return nodes;
}
} // namespace

int
itkModulusBootstrapTest(int, char *[])
{
  bool                   ok = true;
  const itk::PhantomPair pair = Spheres(80.0);
  const double           truth = 80.0;

  const itk::ModulusInterval two = Interval(pair, pair.fixedLabels, 2, 1);
  ok &= bmr::test::Expect(two.lowerDetermined && two.upperDetermined, "80 kPa: both ends of the interval determined");
  ok &= bmr::test::Expect(two.interval95[0] <= truth && truth <= two.interval95[1],
                          "80 kPa: the 95 % interval contains the truth");
  ok &= bmr::test::Expect(std::abs(std::log(two.estimate / truth)) < std::abs(std::log(two.fit / truth)),
                          "80 kPa: the bias-corrected estimate lies closer to the truth than the fit");

  // The same seed gives the same bits, whatever the number of resampling threads.
  const itk::ModulusInterval one = Interval(pair, pair.fixedLabels, 1, 1);
  const itk::ModulusInterval again = Interval(pair, pair.fixedLabels, 1, 1);
  ok &= bmr::test::Expect(one.resampleModuli == again.resampleModuli && one.estimate == again.estimate,
                          "the same seed gives bit-identical resamples (1 thread)");
  ok &= bmr::test::Expect(one.resampleModuli == two.resampleModuli && one.estimate == two.estimate,
                          "1 and 2 resampling threads give bit-identical resamples");
  const itk::ModulusInterval other = Interval(pair, pair.fixedLabels, 2, 2);
  ok &= bmr::test::Expect(other.resampleModuli != two.resampleModuli, "another seed gives other resamples");

  const itk::ModulusInterval coarse = Interval(pair, itk::test::Coarsened(pair.fixedLabels), 2, 1);
  // An end the images do not determine is reported at the prior's bound: the interval is then unbounded on that
  // side, wider than the 1 mm one (determined at both ends, checked above) whatever the ratio of its clipped ends.
  // (Measured: 30 to 72.2 kPa with the lower end undetermined, against 44.5 to 109.4 kPa at 1 mm.)
  ok &= bmr::test::Expect(!coarse.lowerDetermined || !coarse.upperDetermined ||
                            coarse.interval95[1] / coarse.interval95[0] > two.interval95[1] / two.interval95[0],
                          "the 95 % interval widens when the fixed voxels coarsen from 1 to 2 mm");

  const itk::PhantomPair     stiffPair = Spheres(1000.0);
  const itk::ModulusInterval stiff = Interval(stiffPair, stiffPair.fixedLabels, 2, 1);
  ok &= bmr::test::Expect(!stiff.upperDetermined && itk::ModulusIntervalText("inner", stiff).find("inner E >= ") == 0,
                          "1000 kPa (bound 300 kPa): stated as a lower bound");

  const auto truthNodes = NodeSet(pair.movingLabels, pair.truthScene);
  const auto closest =
    NodeSet(pair.movingLabels, itk::ScaledMeshSizes(pair.scene, itk::PhantomSettings().truthRefinement));
  std::size_t shared = 0;
  for (const auto & x : closest)
  {
    shared += truthNodes.count(x);
  }
  std::cout << "  truth mesh " << truthNodes.size() << " nodes, estimation mesh at the truth's scale " << closest.size()
            << " nodes, " << shared << " shared" << std::endl;
  ok &= bmr::test::Expect(
    truthNodes != closest && shared < closest.size() / 2,
    "the truth's mesh is not the estimation mesh at the truth's scale (fewer than half the nodes shared)");
  return ok ? EXIT_SUCCESS : EXIT_FAILURE;
}
