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
// bmr::ElasticityEstimator with two unknown moduli, through itk::FEMElasticityOptimizer: two concentric-sphere
// phantoms (dissertation 3.2.2) side by side, each a core (radius 14 mm) in a 10 kPa shell (to 20 mm; the
// gauge), the cores of different moduli ("soft" at x = -24 mm, "stiff" at x = +24 mm). A thin hollow layer
// around each ball carries its load: the ball's outer surface is pressed 2 mm towards its center. The truth is
// simulated on a finer, independent mesh of the same analytic geometry; the compressed balls stay spheres, so
// the fixed surfaces are exact signed distance maps of spheres with the truth's deformed radii (no voxel
// staircase: with voxelized labels the staircase, not the estimator, sets the error of such small organs).
// Both moduli must be recovered together within 10 %, identifiable, each with a finite uncertainty, after a
// coordinate sweep of 6 samples per unknown.
#include "bmrSimulation.h"
#include "itkFEMElasticityOptimizer.h"
#include "bmrTestUtilities.h"

#include <cmath>
#include <cstdlib>
#include <iostream>

namespace {
using MapType = itk::FEMElasticityOptimizer::DistanceMapType;
constexpr double       TrueSoftE = 25.0;                                                        // kPa
constexpr double       TrueStiffE = 60.0;                                                       // kPa
constexpr double       BallX = 24.0, CoreRadius = 14.0, ShellRadius = 20.0, LayerRadius = 23.0; // mm
constexpr std::int32_t Shell = 1, Soft = 2, Stiff = 3, AroundSoft = 4, AroundStiff = 5;

std::int32_t
LabelAt(double x, double y, double z)
{
  const bool   left = x < 0.0;
  const double dx = x - (left ? -BallX : BallX);
  const double r = std::sqrt(dx * dx + y * y + z * z);
  return r <= CoreRadius    ? (left ? Soft : Stiff)
         : r <= ShellRadius ? Shell
         : r <= LayerRadius ? (left ? AroundSoft : AroundStiff)
                            : 0;
}

/** The two balls meshed from the analytic geometry (cell size \a h mm), the hollow layers removed. */
bmr::TetrahedralMesh
TwoBalls(double h, int seed)
{
  bmr::MeshingParameters p;
  p.cellSize = h;
  p.facetSize = h;
  p.facetDistance = 0.3;
  p.randomSeed = seed;
  return bmr::ExtractSubmesh(bmr::MeshImplicitLabels(LabelAt, { { 0, 0, 0 } }, 48.0, p), { AroundSoft, AroundStiff });
}

bmr::Scene
TwoBallScene(bool truth)
{
  using R = bmr::LabelRoleEnum;
  bmr::Scene      s;
  bmr::SceneLabel soft{ "soft", Soft, truth ? R::Material : R::UnknownMaterial, truth ? TrueSoftE : 50.0, 0.4 };
  bmr::SceneLabel stiff{ "stiff", Stiff, truth ? R::Material : R::UnknownMaterial, truth ? TrueStiffE : 50.0, 0.4 };
  if (!truth)
  {
    soft.lowerBound = stiff.lowerBound = 10.0;
    soft.upperBound = stiff.upperBound = 400.0;
  }
  s.labels = { { "outside", 0, R::Outside },
               { "shell", Shell, R::Material, 10.0, 0.35 },
               soft,
               stiff,
               { "around_soft", AroundSoft, R::Hollow },
               { "around_stiff", AroundStiff, R::Hollow } };
  s.gauge = "shell";
  s.forceSurfaces = { "around_soft", "around_stiff" };
  s.objective = { { "soft", 1.0 }, { "stiff", 1.0 }, { "around_soft", 1.0 }, { "around_stiff", 1.0 } };
  if (truth)
  {
    using L = bmr::SceneLoad;
    s.loads = { { "around_soft", L::TypeEnum::RadialDisplacement, { { -BallX, 0, 0 } }, -2.0 },
                { "around_stiff", L::TypeEnum::RadialDisplacement, { { BallX, 0, 0 } }, -2.0 } };
  }
  return s;
}

/** Mean deformed distance [mm] of \a nodes from the center (x0, 0, 0). */
double
DeformedRadius(const bmr::TetrahedralMesh &      mesh,
               const std::vector<double> &       u,
               const std::vector<std::int32_t> & nodes,
               double                            x0)
{
  double sum = 0.0;
  for (std::int32_t n : nodes)
  {
    const double * p = &mesh.points[3 * n];
    const double * d = &u[3 * n];
    sum += std::sqrt((p[0] + d[0] - x0) * (p[0] + d[0] - x0) + (p[1] + d[1]) * (p[1] + d[1]) +
                     (p[2] + d[2]) * (p[2] + d[2]));
  }
  return sum / double(nodes.size());
}

/** Signed distance [mm] to the sphere (x0, 0, 0; r) on a 1 mm grid over both balls, negative inside (\a sign 1)
 * or outside (\a sign -1: the hollow layer's own inside). */
MapType::Pointer
SphereMap(double x0, double r, double sign)
{
  return bmr::test::SphereDistanceMap({ { x0, 0.0, 0.0 } }, r, sign, { { -50.0, -26.0, -26.0 } }, { { 101, 53, 53 } });
}
} // namespace

int
bmrElasticityEstimatorTest(int, char *[])
{
  const bmr::TetrahedralMesh   truthMesh = TwoBalls(1.5, 4242);
  const bmr::ForwardSimulation truth = bmr::SimulateScene(TwoBallScene(true), truthMesh);
  const double                 core[2] = {
                    DeformedRadius(truthMesh, truth.displacement, bmr::NodesOnLabelSurface(truthMesh, Soft), -BallX),
                    DeformedRadius(truthMesh, truth.displacement, bmr::NodesOnLabelSurface(truthMesh, Stiff), BallX)
  };
  const double ball[2] = {
    DeformedRadius(truthMesh, truth.displacement, bmr::NodesOnBoundary(truthMesh, AroundSoft), -BallX),
    DeformedRadius(truthMesh, truth.displacement, bmr::NodesOnBoundary(truthMesh, AroundStiff), BallX)
  };
  std::cout << "truth (" << truthMesh.GetNumberOfTetrahedra() << " tetrahedra): deformed core radii " << core[0] << ", "
            << core[1] << " mm, balls " << ball[0] << ", " << ball[1] << " mm" << std::endl;

  auto mesh = itk::TetrahedralMeshObject::New();
  mesh->Set(TwoBalls(3.0, 0));
  auto optimizer = itk::FEMElasticityOptimizer::New();
  optimizer->SetMesh(mesh);
  optimizer->SetScene(TwoBallScene(false));
  optimizer->SetDistanceMap("soft", SphereMap(-BallX, core[0], 1.0));
  optimizer->SetDistanceMap("stiff", SphereMap(BallX, core[1], 1.0));
  optimizer->SetDistanceMap("around_soft", SphereMap(-BallX, ball[0], -1.0));
  optimizer->SetDistanceMap("around_stiff", SphereMap(BallX, ball[1], -1.0));
  optimizer->SetNumberOfSweepSamples(6);
  optimizer->Update();

  const double soft = optimizer->GetEstimatedYoungsModuli().at("soft");
  const double stiff = optimizer->GetEstimatedYoungsModuli().at("stiff");
  const auto   sigmaOf = [&optimizer](const char * name) {
    const auto it = optimizer->GetModulusUncertainty().find(name);
    return it == optimizer->GetModulusUncertainty().end() ? std::nan("") : it->second;
  };
  for (const auto & r : optimizer->GetHistory())
  {
    std::cout << r.stage << " " << r.iteration << ": E " << r.youngsModuli[0] << ", " << r.youngsModuli[1]
              << " kPa, Phi* " << r.value << " mm^2\n";
  }
  std::cout << "estimation mesh " << mesh->Get().GetNumberOfTetrahedra() << " tetrahedra\nsoft: true " << TrueSoftE
            << " kPa, recovered " << soft << " kPa (sigma log E " << sigmaOf("soft") << ")\nstiff: true " << TrueStiffE
            << " kPa, recovered " << stiff << " kPa (sigma log E " << sigmaOf("stiff") << ")\n"
            << optimizer->GetIdentifiabilityMessage() << std::endl;
  bool ok = true;
  ok &=
    bmr::test::Expect(optimizer->GetSweep().size() == 12, "a coordinate sweep of 6 samples per unknown (12 in all)");
  ok &= bmr::test::Expect(std::abs(soft / TrueSoftE - 1.0) < 0.10, "soft core within 10 % of the truth");
  ok &= bmr::test::Expect(std::abs(stiff / TrueStiffE - 1.0) < 0.10, "stiff core within 10 % of the truth");
  ok &= bmr::test::Expect(optimizer->GetIdentifiable(), "both moduli identifiable");
  for (const char * name : { "soft", "stiff" })
  {
    const double sigma = sigmaOf(name);
    ok &= bmr::test::Expect(std::isfinite(sigma) && sigma > 0.0, std::string("finite uncertainty of ") + name);
  }
  ok &= bmr::test::Expect(optimizer->GetResult().curvature.size() == 4, "a 2 x 2 curvature of Phi*");
  return ok ? EXIT_SUCCESS : EXIT_FAILURE;
}
