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
// The two-layer sphere of dissertation section 3.2.2 under external pressure, solved on a CGAL mesh and
// compared with the closed form (bmr::TwoLayerSphereSolution): shared by bmrTwoLayerSphereTest and the
// extreme-case benchmark.
#ifndef bmrTwoLayerSphereCase_h
#define bmrTwoLayerSphereCase_h

#include "bmrDisplacementFieldRasterizer.h"
#include "bmrMesher.h"
#include "bmrSimulation.h"
#include "bmrTwoLayerSphere.h"

#include <algorithm>
#include <cmath>

namespace bmr {
namespace test {
constexpr double InnerRadius = 5.0;  // mm; a shell of half the radius keeps several elements through its thickness
constexpr double OuterRadius = 10.0; // mm
constexpr double Pressure = 1.0;     // kPa

/** The two-layer sphere meshed with cell size \a h [mm]; \a optimize false skips CGAL's sliver
 * perturbation and exudation (a mesh with slivers). */
inline bmr::TetrahedralMesh
SphereMesh(double h, bool optimize = true)
{
  bmr::MeshingParameters p;
  p.cellSize = h;
  p.facetSize = h;
  // The sagitta of a chord of length h on the inner sphere: surface error of the order of the element error.
  p.facetDistance = h * h / (8.0 * InnerRadius);
  p.facetAngle = 25.0;
  p.exude = optimize; // sliver exudation: perturbation alone can leave a flat element on the curved interface
  p.optimize = optimize;
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
  double residual; // || K u - f || / || f || over the free degrees of freedom (the solver's own accuracy)
};

/** Pressure on the outer surface; rigid-body modes removed by prescribing the exact
 * displacement at three interior nodes (so the constraint adds no error of its own). */
inline Errors
Solve(const bmr::TetrahedralMesh & mesh, double E1, double nu1, double E2, double nu2, bool averagedPressure = false)
{
  const bmr::TwoLayerSphereSolution exact(InnerRadius, OuterRadius, E1, nu1, E2, nu2, Pressure);
  bmr::Scene                        scene;
  scene.labels = { { "outside", 0, bmr::LabelRoleEnum::Outside },
                   { "shell", 1, bmr::LabelRoleEnum::Material, E2, nu2 },
                   { "core", 2, bmr::LabelRoleEnum::Material, E1, nu1 } };
  scene.loads = { { "outside", bmr::SceneLoad::TypeEnum::Pressure, { { 0, 0, 0 } }, Pressure } };
  scene.formulation =
    averagedPressure ? bmr::ElementFormulationEnum::NodalAveragedPressure : bmr::ElementFormulationEnum::Standard;
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
  const std::vector<double> Ku = model.ComputeInternalForces(u);
  const std::vector<char> & constrained = model.GetConstrainedDegreesOfFreedom();
  double                    r2 = 0.0, f2 = 0.0;
  for (std::size_t i = 0; i < Ku.size(); ++i)
  {
    if (!constrained[i])
    {
      const double f = bc.forces.empty() ? 0.0 : bc.forces[i];
      r2 += (Ku[i] - f) * (Ku[i] - f);
      f2 += f * f;
    }
  }
  return { std::sqrt(num / den), std::sqrt(l2), std::sqrt(l2 / l2u), std::sqrt(r2 / std::max(f2, 1e-300)) };
}
} // namespace test
} // namespace bmr

#endif
