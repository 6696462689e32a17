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
// The marker parts of dissertation chapter 4: the landmark term (barycentric markers), the organ-surface force
// parameterization and the marker alignments a clinic uses (rigid, thin-plate spline).
// - P1 shape functions reproduce a linear displacement exactly: markers carried by u(x) = A x + b land on
//   X + A X + b to 1e-12 mm (rounding of ~20 mm coordinates);
// - Taylor test of dPhi/dq through the adjoint with landmark term, surface forces and prior: the remainder
//   shrinks as h^2 (slope in [1.9, 2.1]);
// - Levenberg-Marquardt fits three markers moved by 1 mm to < 1e-3 mm (the prior alpha = 1e-6 shrinks the fit
//   by ~alpha |q|^2 / |r|: far below);
// - rigid: a known rotation and translation recovered from 3 markers to 1e-10; 2 markers give the smallest
//   rotation of their line; the spline interpolates exactly and reproduces an affine map with 4 markers to 1e-9;
// - bad input is named.
#include "bmrEstimationObjective.h"
#include "bmrLandmarkTerm.h"
#include "bmrMarkerAlignment.h"
#include "bmrOrganSurfaceForces.h"
#include "bmrSimulation.h"
#include "bmrTestUtilities.h"

#include <cmath>
#include <cstdlib>
#include <iostream>

namespace {
using bmr::test::Expect;
using bmr::test::ToString;

const std::vector<bmr::Point3> InclusionMarkers = { { { 8.0, 1.5, 0.5 } },
                                                    { { 6.5, -1.0, 1.0 } },
                                                    { { 9.0, 0.5, -2.0 } } };

bool
LinearFieldIsExact(const bmr::TetrahedralMesh & mesh)
{
  const double        A[3][3] = { { 0.01, -0.02, 0.005 }, { 0.03, 0.0, -0.01 }, { 0.002, 0.015, 0.02 } };
  const double        b[3] = { 0.7, -0.4, 1.1 };
  std::vector<double> u(mesh.points.size());
  for (std::size_t n = 0; n < mesh.GetNumberOfPoints(); ++n)
  {
    for (int r = 0; r < 3; ++r)
    {
      u[3 * n + r] = b[r];
      for (int c = 0; c < 3; ++c)
      {
        u[3 * n + r] += A[r][c] * mesh.points[3 * n + c];
      }
    }
  }
  std::vector<bmr::LandmarkTarget> targets;
  for (const auto & X : InclusionMarkers)
  {
    targets.push_back({ "", X, X, 1.0 });
  }
  const bmr::LandmarkTerm term(mesh, targets);
  const auto              moved = term.DeformedPositions(u);
  double                  worst = 0.0;
  for (std::size_t k = 0; k < moved.size(); ++k)
  {
    for (int r = 0; r < 3; ++r)
    {
      double expected = InclusionMarkers[k][r] + b[r];
      for (int c = 0; c < 3; ++c)
      {
        expected += A[r][c] * InclusionMarkers[k][c];
      }
      worst = std::max(worst, std::abs(moved[k][r] - expected));
    }
  }
  return Expect(worst < 1e-12, "a linear field carries the markers exactly (max error " + ToString(worst) + " mm)");
}

/** The box model of the inclusion ball: boundary held, forces on the inclusion's surface. */
struct InclusionModel
{
  bmr::TetrahedralMesh                     mesh = bmr::test::CavityInclusionBall(3.0);
  bmr::Scene                               scene = bmr::test::CavityInclusionScene(false);
  bmr::BoundaryConditions                  bc = bmr::SceneBoundaryConditions(scene, mesh);
  std::unique_ptr<bmr::ForwardModel>       model = bmr::MakeForwardModel(scene, mesh, bmr::SceneMaterials(scene));
  std::unique_ptr<bmr::OrganSurfaceForces> loads;

  explicit InclusionModel(double spacing)
  {
    // Only the outer boundary is held here: the scene's cavity wall is loaded in the estimation tests.
    loads = std::make_unique<bmr::OrganSurfaceForces>(
      mesh, bc.dirichletNodes, bc.dirichletValues, bmr::NodesOnLabelSurface(mesh, 2), spacing);
    loads->SetForceScale(50.0);
  }
  std::vector<bmr::LandmarkTarget>
  Targets(double shift) const
  {
    std::vector<bmr::LandmarkTarget> t;
    for (const auto & X : InclusionMarkers)
    {
      t.push_back({ "m" + std::to_string(t.size()), X, { { X[0] + shift, X[1] - 0.5 * shift, X[2] } }, 1.0 });
    }
    return t;
  }
};

bool
GradientPassesTaylorTest()
{
  InclusionModel m(3.0);
  m.loads->SetRegularization(0.05);
  const bmr::LandmarkTerm  term(m.mesh, m.Targets(1.0));
  bmr::EstimationObjective objective(*m.model, *m.loads, { &term }, {});
  const std::size_t        np = objective.GetNumberOfParameters();
  std::vector<double>      p(np), v(np), g;
  for (std::size_t i = 0; i < np; ++i)
  {
    p[i] = 0.2 * std::sin(1.0 + 0.7 * i);
    v[i] = std::cos(0.3 + 1.3 * i);
  }
  const double phi0 = objective.Evaluate(p, &g, nullptr);
  double       slope0 = 0.0;
  for (std::size_t i = 0; i < np; ++i)
  {
    slope0 += g[i] * v[i];
  }
  const auto phiAt = [&](double h) {
    std::vector<double> q(p);
    for (std::size_t i = 0; i < np; ++i)
    {
      q[i] += h * v[i];
    }
    return objective.Evaluate(q, nullptr, nullptr);
  };
  std::cout << np << " load parameters on " << m.loads->GetSurfaceNodes().size() << " surface nodes" << std::endl;
  return Expect(np > 9, "more load parameters than marker equations (" + ToString(np) + ")") &
         bmr::test::CheckTaylor("surface forces + landmarks", phiAt, phi0, slope0, 0.5);
}

bool
MarkersAreFitted()
{
  InclusionModel m(4.0);
  m.loads->SetRegularization(1e-6);
  const bmr::LandmarkTerm  term(m.mesh, m.Targets(1.0));
  bmr::EstimationObjective objective(*m.model, *m.loads, { &term }, {});
  const auto               solution =
    objective.SolveLoadsLevenbergMarquardt(std::vector<double>(objective.GetNumberOfParameters(), 0.0), 30, 1e-10);
  const auto stats = term.ComputeStatistics(objective.ComputeDisplacement(solution.parameters));
  std::cout << "fit: " << solution.iterations << " iterations, marker RMS " << stats[0].rms << " mm" << std::endl;
  return Expect(stats[0].rms < 1e-3,
                "LM fits three markers moved by 1.1 mm to < 1e-3 mm (RMS " + ToString(stats[0].rms) + ")");
}

bool
RigidAndSplineReproduceKnownMotions()
{
  const double        angle = 0.2;
  bmr::RigidTransform truth;
  truth.rotation = { { std::cos(angle), -std::sin(angle), 0, std::sin(angle), std::cos(angle), 0, 0, 0, 1 } };
  truth.translation = { { 3.0, -2.0, 1.5 } };
  const std::vector<bmr::Point3> from = { { { 10, 0, 0 } }, { { 0, 12, 1 } }, { { -3, -4, 8 } }, { { 5, 5, -6 } } };
  std::vector<bmr::Point3>       to;
  for (const auto & x : from)
  {
    to.push_back(truth.Apply(x));
  }
  const std::vector<bmr::Point3> three(from.begin(), from.begin() + 3), threeTo(to.begin(), to.begin() + 3);
  const bmr::RigidTransform      fitted = bmr::FitRigidTransform(three, threeTo);
  double                         worst = 0.0;
  for (int i = 0; i < 9; ++i)
  {
    worst = std::max(worst, std::abs(fitted.rotation[i] - truth.rotation[i]));
  }
  for (int i = 0; i < 3; ++i)
  {
    worst = std::max(worst, std::abs(fitted.translation[i] - truth.translation[i]));
  }
  bool              ok = Expect(worst < 1e-10, "rigid motion from 3 markers (max error " + ToString(worst) + ")");
  const bmr::Point3 back = fitted.ApplyInverse(fitted.Apply(from[3]));
  ok &= Expect(std::abs(back[0] - from[3][0]) + std::abs(back[1] - from[3][1]) + std::abs(back[2] - from[3][2]) < 1e-10,
               "ApplyInverse undoes Apply");
  // Two markers along x moved along y: the smallest rotation turns x into y (a quarter turn about z).
  const bmr::RigidTransform two =
    bmr::FitRigidTransform({ { { -1, 0, 0 } }, { { 1, 0, 0 } } }, { { { 0, -1, 0 } }, { { 0, 1, 0 } } });
  const bmr::Point3 z = two.Apply({ { 0, 0, 1 } });
  ok &= Expect(std::abs(z[2] - 1.0) < 1e-12 && std::abs(two.rotation[3] - 1.0) < 1e-12,
               "two markers: the smallest rotation, about the normal of both lines");
  // The spline: exact at the markers; with 4 non-coplanar markers an affine motion is reproduced everywhere.
  const double             A[3][3] = { { 1.05, 0.02, 0.0 }, { -0.03, 0.97, 0.01 }, { 0.0, 0.04, 1.02 } };
  std::vector<bmr::Point3> affine;
  for (const auto & x : from)
  {
    affine.push_back({ { A[0][0] * x[0] + A[0][1] * x[1] + A[0][2] * x[2] + 1.0,
                         A[1][0] * x[0] + A[1][1] * x[1] + A[1][2] * x[2] - 2.0,
                         A[2][0] * x[0] + A[2][1] * x[1] + A[2][2] * x[2] + 0.5 } });
  }
  const bmr::ThinPlateSpline spline(from, affine);
  const bmr::Point3          probe{ { 2.0, -3.0, 4.0 } };
  const bmr::Point3          y = spline.Apply(probe);
  double                     affineError = 0.0;
  const double               expected[3] = { A[0][0] * 2 - A[0][1] * 3 + A[0][2] * 4 + 1.0,
                                             A[1][0] * 2 - A[1][1] * 3 + A[1][2] * 4 - 2.0,
                                             A[2][0] * 2 - A[2][1] * 3 + A[2][2] * 4 + 0.5 };
  for (int c = 0; c < 3; ++c)
  {
    affineError = std::max(affineError, std::abs(y[c] - expected[c]));
  }
  ok &= Expect(affineError < 1e-9, "the spline reproduces an affine map (error " + ToString(affineError) + " mm)");
  const bmr::ThinPlateSpline threeSpline(three, threeTo);
  double                     atMarkers = 0.0;
  for (std::size_t k = 0; k < 3; ++k)
  {
    const bmr::Point3 yk = threeSpline.Apply(three[k]);
    atMarkers = std::max(atMarkers, std::hypot(yk[0] - threeTo[k][0], yk[1] - threeTo[k][1], yk[2] - threeTo[k][2]));
  }
  ok &= Expect(atMarkers < 1e-9, "the 3-marker spline interpolates (error " + ToString(atMarkers) + " mm)");
  return ok;
}

bool
BadInputIsNamed(const bmr::TetrahedralMesh & mesh)
{
  using bmr::test::ExpectException;
  bool ok = ExpectException(
    "marker outside",
    [&] {
      bmr::LandmarkTerm(mesh, { { "gold2", { { 40, 0, 0 } }, { { 40, 0, 0 } }, 1.0 } });
    },
    "gold2");
  ok &= ExpectException(
    "all weights zero",
    [&] {
      bmr::LandmarkTerm(mesh, { { "a", { { 8, 0, 0 } }, { { 8, 0, 0 } }, 0.0 } });
    },
    "weight 0");
  ok &= ExpectException(
    "NaN target",
    [&] {
      bmr::LandmarkTerm(mesh, { { "a", { { 8, 0, 0 } }, { { NAN, 0, 0 } }, 1.0 } });
    },
    "not finite");
  ok &= ExpectException(
    "rigid sizes",
    [] {
      bmr::FitRigidTransform({ { { 0, 0, 0 } } }, {});
    },
    "non-empty");
  ok &= ExpectException(
    "coinciding spline markers",
    [] {
      bmr::ThinPlateSpline({ { { 0, 0, 0 } }, { { 0, 0, 0 } } }, { { { 1, 0, 0 } }, { { 1, 0, 0 } } });
    },
    "coincide");
  return ok;
}
} // namespace

int
bmrLandmarkTermTest(int, char *[])
{
  const bmr::TetrahedralMesh mesh = bmr::test::CavityInclusionBall(3.0);
  bool                       ok = LinearFieldIsExact(mesh);
  ok &= GradientPassesTaylorTest();
  ok &= MarkersAreFitted();
  ok &= RigidAndSplineReproduceKnownMotions();
  ok &= BadInputIsNamed(mesh);
  std::cout << (ok ? "bmrLandmarkTermTest passed" : "bmrLandmarkTermTest FAILED") << std::endl;
  return ok ? EXIT_SUCCESS : EXIT_FAILURE;
}
