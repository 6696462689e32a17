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
// Two-layer elastic sphere under external pressure against the closed form
// (bmr::TwoLayerSphereSolution): accuracy at the default mesh over nu <= 0.45 and
// stiffness ratios 1e-3 ... 1e3, near incompressibility (nu 0.49, 0.499) with the nodal-averaged
// pressure formulation, and the L2 convergence order under refinement.
#include "bmrDisplacementFieldRasterizer.h"
#include "bmrMesher.h"
#include "bmrSimulation.h"
#include "bmrTwoLayerSphere.h"

#include <cmath>
#include <cstdlib>
#include <iostream>

namespace {
constexpr double InnerRadius = 5.0;  // mm; a shell of half the radius keeps several elements through its thickness
constexpr double OuterRadius = 10.0; // mm
constexpr double Pressure = 1.0;     // kPa

bmr::TetrahedralMesh
SphereMesh(double h)
{
  bmr::MeshingParameters p;
  p.cellSize = h;
  p.facetSize = h;
  // The sagitta of a chord of length h on the inner sphere: surface error of the order of the element error.
  p.facetDistance = h * h / (8.0 * InnerRadius);
  p.facetAngle = 25.0;
  p.exude = true; // sliver exudation: perturbation alone can leave a flat element on the curved interface
  auto label = [](double x, double y, double z) -> std::int32_t {
    const double r2 = x * x + y * y + z * z;
    return r2 < InnerRadius * InnerRadius ? 2 : (r2 < OuterRadius * OuterRadius ? 1 : 0);
  };
  return bmr::ExtractSubmesh(bmr::MeshImplicitLabels(label, { { 0, 0, 0 } }, 1.2 * OuterRadius, p), {});
}

struct Errors
{
  double nodalRadialRelative; // sqrt(sum (ur_h - ur)^2 / sum ur^2) over nodes
  double l2;                  // || u_h - u ||_L2 over the domain [mm * mm^1.5]
  double l2Relative;
};

/** Pressure on the outer surface; rigid-body modes removed by prescribing the exact
 * displacement at three interior nodes (so the constraint adds no error of its own). */
Errors
Solve(const bmr::TetrahedralMesh & mesh, double E1, double nu1, double E2, double nu2, bool averagedPressure = false)
{
  const bmr::TwoLayerSphereSolution exact(InnerRadius, OuterRadius, E1, nu1, E2, nu2, Pressure);
  bmr::Scene                        scene;
  scene.labels = { { "outside", 0, bmr::LabelRole::Outside },
                   { "shell", 1, bmr::LabelRole::Material, E2, nu2 },
                   { "core", 2, bmr::LabelRole::Material, E1, nu1 } };
  scene.loads = { { "outside", bmr::SceneLoad::Type::Pressure, { { 0, 0, 0 } }, Pressure } };
  scene.nodalAveragedPressure = averagedPressure;
  bmr::BoundaryConditions bc = bmr::SceneBoundaryConditions(scene, mesh);

  const std::array<std::array<double, 3>, 3> targets{ { { { 0, 0, 0 } }, { { 4, 0, 0 } }, { { 0, 4, 0 } } } };
  for (const auto & t : targets)
  {
    std::size_t best = 0;
    double      bestD = 1e300;
    for (std::size_t n = 0; n < mesh.GetNumberOfPoints(); ++n)
    {
      const double d =
        std::hypot(mesh.points[3 * n] - t[0], mesh.points[3 * n + 1] - t[1], mesh.points[3 * n + 2] - t[2]);
      if (d < bestD)
      {
        bestD = d;
        best = n;
      }
    }
    bc.dirichletNodes.push_back(static_cast<std::int32_t>(best));
    const auto u =
      exact.Displacement({ { mesh.points[3 * best], mesh.points[3 * best + 1], mesh.points[3 * best + 2] } }, true);
    bc.dirichletValues.insert(bc.dirichletValues.end(), u.begin(), u.end());
  }
  bmr::LinearElasticModel model(mesh, bmr::SceneMaterials(scene));
  model.SetDirichletConditions(bc.dirichletNodes, bc.dirichletValues);
  const std::vector<double> u = model.Solve(bc.forces);

  // Nodal radial error (nodes on the interface use the core formula: both agree there).
  double num = 0.0, den = 0.0;
  for (std::size_t n = 0; n < mesh.GetNumberOfPoints(); ++n)
  {
    const double * x = &mesh.points[3 * n];
    const double   r = std::sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]);
    if (r < 1e-9)
    {
      continue;
    }
    const double ur = (u[3 * n] * x[0] + u[3 * n + 1] * x[1] + u[3 * n + 2] * x[2]) / r;
    const double ue = exact.RadialDisplacement(r, r <= InnerRadius);
    num += (ur - ue) * (ur - ue);
    den += ue * ue;
  }
  // L2 error with the 4-point (degree 2) tetrahedron rule; the exact solution is
  // evaluated with the formula of the element's own material.
  const double alpha = 0.5854101966249685, beta = 0.1381966011250105;
  double       l2 = 0.0, l2u = 0.0;
  for (std::size_t e = 0; e < mesh.GetNumberOfTetrahedra(); ++e)
  {
    const double V = bmr::TetrahedronVolume(mesh, e);
    for (int q = 0; q < 4; ++q)
    {
      std::array<double, 3> x{ { 0, 0, 0 } }, uh{ { 0, 0, 0 } };
      for (int a = 0; a < 4; ++a)
      {
        const double w = a == q ? alpha : beta;
        const auto   node = mesh.tetrahedra[4 * e + a];
        for (int c = 0; c < 3; ++c)
        {
          x[c] += w * mesh.points[3 * node + c];
          uh[c] += w * u[3 * node + c];
        }
      }
      const auto ue = exact.Displacement(x, mesh.labels[e] == 2);
      for (int c = 0; c < 3; ++c)
      {
        l2 += 0.25 * V * (uh[c] - ue[c]) * (uh[c] - ue[c]);
        l2u += 0.25 * V * ue[c] * ue[c];
      }
    }
  }
  return { std::sqrt(num / den), std::sqrt(l2), std::sqrt(l2 / l2u) };
}
} // namespace

int
bmrTwoLayerSphereTest(int, char *[])
{
  bool ok = true;
  // 1. Accuracy at the default mesh (cell size 0.5 mm: ~10 elements through the 5 mm shell): radial error <= 1 %.
  //    The soft-core cases are the hardest: the shell then carries the whole load and bends inwards.
  const bmr::TetrahedralMesh mesh = SphereMesh(0.5);
  std::cout << "default mesh: " << mesh.GetNumberOfTetrahedra() << " tetrahedra" << std::endl;
  for (double nu : { 0.3, 0.45 }) // the ends of the range nu <= 0.45 (0.4 lies between them)
  {
    for (double ratio : { 1e-3, 1e-2, 1e-1, 1.0, 1e1, 1e2, 1e3 })
    {
      const Errors err = Solve(mesh, 10.0 * ratio, nu, 10.0, 0.35);
      std::cout << "nu_core " << nu << " E_core/E_shell " << ratio << ": radial error " << 100 * err.nodalRadialRelative
                << " %, relative L2 " << 100 * err.l2Relative << " %" << std::endl;
      // 1 %: the accuracy requirement for the default mesh.
      if (!(err.nodalRadialRelative <= 0.01))
      {
        std::cerr << "FAIL: radial error above 1 %" << std::endl;
        ok = false;
      }
    }
  }
  // 2. Near incompressibility, both layers at nu = 0.49 and 0.499 (lambda/mu = 49, 499), a core 10x stiffer
  //    and 10x softer than the shell: the shell's B/r^2 term is isochoric, which locked P1 tetrahedra cannot
  //    represent. With the nodal-averaged pressure formulation the radial error stays <= 2 % (the issue's
  //    requirement at the default mesh); the standard formulation's error is printed for comparison and
  //    must be the larger one at nu = 0.499 (locking is real, and the remedy removes it).
  for (double nu : { 0.49, 0.499 })
  {
    for (double ratio : { 0.1, 10.0 })
    {
      const Errors averaged = Solve(mesh, 10.0 * ratio, nu, 10.0, nu, true);
      const Errors standard = Solve(mesh, 10.0 * ratio, nu, 10.0, nu, false);
      std::cout << "nu " << nu << " E_core/E_shell " << ratio << ": radial error, nodal-averaged pressure "
                << 100 * averaged.nodalRadialRelative << " %, standard P1 " << 100 * standard.nodalRadialRelative
                << " %" << std::endl;
      if (!(averaged.nodalRadialRelative <= 0.02))
      {
        std::cerr << "FAIL: radial error above 2 % with the nodal-averaged pressure formulation" << std::endl;
        ok = false;
      }
      if (nu == 0.499 && !(standard.nodalRadialRelative > averaged.nodalRadialRelative))
      {
        std::cerr << "FAIL: the standard formulation is not less accurate at nu = 0.499" << std::endl;
        ok = false;
      }
    }
  }
  // 3. L2 convergence order over three refinements (P1 elements: order 2 expected).
  const double        sizes[] = { 2.0, 1.6, 1.25, 1.0 };
  std::vector<double> logh, loge;
  for (double h : sizes)
  {
    const bmr::TetrahedralMesh m = SphereMesh(h);
    const double               hMean = bmr::ComputeMeshQuality(m).meanEdgeLength;
    const Errors               err = Solve(m, 50.0, 0.4, 10.0, 0.35);
    std::cout << "h " << h << " (mean edge " << hMean << " mm, " << m.GetNumberOfTetrahedra() << " tets): L2 error "
              << err.l2 << std::endl;
    logh.push_back(std::log(hMean));
    loge.push_back(std::log(err.l2));
  }
  double mh = 0, me = 0;
  for (std::size_t i = 0; i < logh.size(); ++i)
  {
    mh += logh[i] / logh.size();
    me += loge[i] / loge.size();
  }
  double sxy = 0, sxx = 0;
  for (std::size_t i = 0; i < logh.size(); ++i)
  {
    sxy += (logh[i] - mh) * (loge[i] - me);
    sxx += (logh[i] - mh) * (logh[i] - mh);
  }
  const double order = sxy / sxx;
  std::cout << "observed L2 convergence order " << order << std::endl;
  // >= 1.8: P1 elements converge with order 2 in L2; 0.2 allows for unstructured, non-nested meshes.
  if (!(order >= 1.8))
  {
    std::cerr << "FAIL: convergence order below 1.8" << std::endl;
    ok = false;
  }
  return ok ? EXIT_SUCCESS : EXIT_FAILURE;
}
