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
// bmr::ElasticityEstimator with two unknown moduli, through the library's pipelines: a block of tissue
// (10 kPa, the gauge; its outer boundary fixed) holding a cavity that grows by 2 mm between two stiff
// inclusions of different moduli. The fixed labels are the analytic anatomy deformed by a forward simulation
// on a finer, independently seeded mesh (itk::SimulateLabelImage), voxelised once; itk::RegisterSegmentedPair must recover both moduli
// together, say that both are identifiable, and give each a finite uncertainty.
#include "itkBiomechanicalPipelines.h"
#include "itkGridGeometryConversion.h"

#include <cmath>
#include <cstdlib>
#include <iostream>

namespace {
constexpr double TrueSoftE = 40.0;  // kPa, inclusion "soft" (x < 0)
constexpr double TrueStiffE = 120.0; // kPa, inclusion "stiff" (x > 0)

/** The anatomy at a physical point [mm]: tissue (1), cavity (4, radius 7 mm at the centre), inclusions 2 and
 * 3 (radius 7 mm at x = -17 and x = +17 mm): 3 mm of tissue between the cavity and each inclusion, 4 mm
 * between each inclusion and the fixed boundary. */
std::int32_t
BlockLabelAt(const std::array<double, 3> & x)
{
  const double r2 = x[1] * x[1] + x[2] * x[2];
  if (x[0] * x[0] + r2 < 36.0)
  {
    return 4;
  }
  if ((x[0] + 17.0) * (x[0] + 17.0) + r2 < 36.0)
  {
    return 2;
  }
  return (x[0] - 17.0) * (x[0] - 17.0) + r2 < 36.0 ? 3 : 1;
}

/** 1 mm voxels over 56 x 40 x 40 mm; with a field, the labels at each voxel's pull-back point x + d(x): the
 * deformed anatomy voxelised once, as a scan would (warping the voxelised labels would quantise twice). */
itk::BiomechanicalLabelImageType::Pointer
BlockLabels(const itk::BiomechanicalFieldType * field = nullptr)
{
  bmr::GridGeometry g;
  g.size = { { 60, 40, 40 } };
  g.spacing = { { 1.0, 1.0, 1.0 } };
  g.origin = { { -29.5, -19.5, -19.5 } };
  std::vector<std::int32_t> labels(g.GetNumberOfVoxels(), 1);
  for (std::size_t v = 0; v < labels.size(); ++v)
  {
    auto x = g.IndexToPoint(
      { { double(v % g.size[0]), double((v / g.size[0]) % g.size[1]), double(v / (g.size[0] * g.size[1])) } });
    for (unsigned int c = 0; field && c < 3; ++c)
    {
      x[c] += field->GetBufferPointer()[v][c];
    }
    labels[v] = BlockLabelAt(x);
  }
  return itk::MakeImageOnGrid<itk::BiomechanicalLabelImageType>(g, labels);
}

/** The scene: both inclusions unknown in [10, 400] kPa (truth: known, and the cavity growing by 3 mm). */
bmr::Scene
BlockScene(bool truth)
{
  using R = bmr::LabelRole;
  bmr::Scene      s;
  bmr::SceneLabel soft{ "soft", 2, truth ? R::Material : R::UnknownMaterial, truth ? TrueSoftE : 50.0, 0.4 };
  bmr::SceneLabel stiff{ "stiff", 3, truth ? R::Material : R::UnknownMaterial, truth ? TrueStiffE : 50.0, 0.4 };
  for (bmr::SceneLabel * l : { &soft, &stiff })
  {
    l->lowerBound = truth ? 0.0 : 10.0;
    l->upperBound = truth ? 0.0 : 400.0;
  }
  s.name = truth ? "two inclusions (truth)" : "two inclusions";
  s.labels = { { "tissue", 1, R::Material, 10.0, 0.35 }, soft, stiff, { "cavity", 4, R::Hollow } };
  s.gauge = "tissue";
  s.forceSurfaces = { "cavity" };
  s.objective = { { "soft", 1.0 }, { "stiff", 1.0 }, { "cavity", 1.0 } };
  s.roiBoundaryFixed = true;
  s.mesh.cellSize = 2.0;
  s.mesh.facetSize = 2.0;
  s.mesh.facetDistance = 0.5;
  s.mesh.cellSizePerLabel = { { 2, 1.5 }, { 3, 1.5 } };
  if (truth)
  {
    s.loads = { { "cavity", bmr::SceneLoad::Type::RadialDisplacement, { { 0, 0, 0 } }, 3.0 } };
    s = itk::ScaledMeshSizes(s, 1.0);
    s.mesh.randomSeed = 4242;
  }
  return s;
}
} // namespace

int
bmrElasticityEstimatorTest(int, char *[])
{
  const auto moving = BlockLabels();
  const auto truth = itk::SimulateLabelImage(moving, BlockScene(true), moving, nullptr, false);
  const auto fixed = BlockLabels(truth.pullBack);

  itk::RegistrationSettings settings;
  settings.estimator.numberOfSweepSamples = 6;
  const auto   result = itk::RegisterSegmentedPair(moving, fixed, nullptr, BlockScene(false), settings);
  const double soft = result.youngsModulus.at("soft"), stiff = result.youngsModulus.at("stiff");
  for (const auto & r : result.estimation.sweep)
  {
    std::cout << "sweep " << r.iteration << ": E " << r.youngsModuli[0] << ", " << r.youngsModuli[1] << " kPa, Phi* "
              << r.value << " mm^2, dPhi*/dlogE " << r.logModulusGradient[0] << ", " << r.logModulusGradient[1] << "\n";
  }
  const auto sigmaOf = [&result](const char * name) {
    const auto it = result.modulusUncertainty.find(name);
    return it == result.modulusUncertainty.end() ? std::nan("") : it->second;
  };
  std::cout << "truth mesh " << truth.mesh.GetNumberOfTetrahedra() << " tetrahedra, estimation mesh "
            << result.state.mesh.GetNumberOfTetrahedra() << "; sweep " << result.estimation.sweep.size()
            << " samples, fine " << result.estimation.history.size() << " solves\n"
            << "soft: true " << TrueSoftE << " kPa, recovered " << soft << " kPa (sigma log E "
            << sigmaOf("soft") << ")\nstiff: true " << TrueStiffE << " kPa, recovered " << stiff
            << " kPa (sigma log E " << sigmaOf("stiff") << ")\n"
            << result.estimation.identifiabilityMessage << std::endl;
  int failures = 0;
  const auto check = [&failures](bool ok, const std::string & what) {
    if (!ok)
    {
      std::cerr << "FAIL: " << what << std::endl;
      ++failures;
    }
  };
  check(result.estimation.sweep.size() == 12, "a coordinate sweep of 6 samples per unknown (12 in all)");
  check(std::abs(soft / TrueSoftE - 1.0) < 0.15, "soft inclusion within 15 % of the truth");
  check(std::abs(stiff / TrueStiffE - 1.0) < 0.15, "stiff inclusion within 15 % of the truth");
  check(stiff > 2.0 * soft, "the stiff inclusion recovered stiffer than the soft one by the true ratio's order");
  check(result.estimation.identifiable, "both moduli identifiable");
  for (const char * name : { "soft", "stiff" })
  {
    const double sigma = sigmaOf(name);
    check(std::isfinite(sigma) && sigma > 0.0 && sigma < 0.3, std::string("finite uncertainty of ") + name);
  }
  check(result.estimation.curvature.size() == 4, "a 2 x 2 curvature of Phi*");
  return failures == 0 ? EXIT_SUCCESS : EXIT_FAILURE;
}
