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
// The compression barrier of the nonlinear estimation objective (bmrCompressionBarrier.h):
// - a uniform compression x -> s x gives J = s^3 in every element: Phi_b = w/2 sum_e (V_e^{1/3} ln(s^3/J_0))^2
//   to 1e-12 relative (rounding of a sum of 750 terms), and exactly 0 for s^3 >= J_0;
// - Taylor test of dPhi_b/du from a state whose elements span all three branches (J >= J_0, the logarithm, the
//   tangent continuation below J_0/16 including inverted elements): the remainder shrinks as h^2 (slope in
//   [1.9, 2.1]; Phi_b is C^1 with a piecewise bounded second derivative);
// - bad settings are named.
#include "bmrCompressionBarrier.h"
#include "bmrTestUtilities.h"

#include <cmath>
#include <iostream>
#include <random>

namespace {
using bmr::test::Expect;

std::vector<double>
UniformScaling(const bmr::TetrahedralMesh & mesh, double s)
{
  std::vector<double> u(mesh.points.size());
  for (std::size_t i = 0; i < u.size(); ++i)
  {
    u[i] = (s - 1.0) * mesh.points[i];
  }
  return u;
}

bool
UniformCompressionIsExact(const bmr::TetrahedralMesh & mesh)
{
  const bmr::CompressionBarrier barrier(mesh, 0.25, 2.0);
  const double                  s = std::cbrt(0.2); // J = 0.2: the logarithmic branch
  double                        expected = 0.0;
  for (std::size_t e = 0; e < mesh.GetNumberOfTetrahedra(); ++e)
  {
    const double r = std::cbrt(std::abs(bmr::TetrahedronVolume(mesh, e))) * std::log(0.2 / 0.25);
    expected += 0.5 * 2.0 * r * r;
  }
  const double value = barrier.Evaluate(UniformScaling(mesh, s), nullptr);
  const double relative = std::abs(value - expected) / expected;
  std::cout << "uniform compression J = 0.2: Phi_b " << value << " expected " << expected << " relative error "
            << relative << std::endl;
  bool ok = Expect(relative < 1e-12, "Phi_b of a uniform compression matches the closed form to 1e-12");
  const std::vector<double> mild = UniformScaling(mesh, std::cbrt(0.26));
  ok &= Expect(barrier.Evaluate(mild, nullptr) == 0.0 && barrier.CountCompressed(mild) == 0,
               "no element below J_0 = 0.25 (J = 0.26): Phi_b is exactly 0");
  ok &= Expect(barrier.CountCompressed(UniformScaling(mesh, s)) == mesh.GetNumberOfTetrahedra(),
               "J = 0.2: every element counted as compressed");
  return ok;
}

bool
GradientPassesTaylor(const bmr::TetrahedralMesh & mesh)
{
  const bmr::CompressionBarrier barrier(mesh, 0.25, 1.0);
  // Compress along x by 0.12 (J ~ 0.12 on average) and add noise of 0.4 element sizes: J spreads over
  // [-0.5, 1.5], so every branch of psi is visited.
  std::mt19937                     random(7);
  std::normal_distribution<double> noise(0.0, 0.4);
  std::vector<double>              u(mesh.points.size()), direction(u.size());
  for (std::size_t n = 0; n < mesh.GetNumberOfPoints(); ++n)
  {
    u[3 * n] = -0.88 * mesh.points[3 * n];
    for (int c = 0; c < 3; ++c)
    {
      u[3 * n + c] += noise(random);
      direction[3 * n + c] = noise(random);
    }
  }
  bmr::TetrahedralMesh moved = mesh;
  for (std::size_t i = 0; i < u.size(); ++i)
  {
    moved.points[i] += u[i];
  }
  std::size_t inverted = 0, tangentBranch = 0;
  for (std::size_t e = 0; e < mesh.GetNumberOfTetrahedra(); ++e)
  {
    const double J = bmr::TetrahedronVolume(moved, e) / bmr::TetrahedronVolume(mesh, e);
    inverted += J <= 0.0;
    tangentBranch += J < 0.25 / 16.0;
  }
  std::cout << "Taylor state: " << barrier.CountCompressed(u) << " of " << mesh.GetNumberOfTetrahedra()
            << " elements below J_0, " << tangentBranch << " below J_0/16, " << inverted << " inverted" << std::endl;
  bool ok = Expect(inverted > 0 && tangentBranch > inverted && barrier.CountCompressed(u) > tangentBranch &&
                     barrier.CountCompressed(u) < mesh.GetNumberOfTetrahedra(),
                   "the Taylor state visits every branch of the barrier");
  std::vector<double> gradient(u.size(), 0.0);
  const double        phi0 = barrier.Evaluate(u, &gradient);
  double              slope0 = 0.0;
  for (std::size_t i = 0; i < u.size(); ++i)
  {
    slope0 += gradient[i] * direction[i];
  }
  const auto phiAt = [&](double h) {
    std::vector<double> v(u);
    for (std::size_t i = 0; i < v.size(); ++i)
    {
      v[i] += h * direction[i];
    }
    return barrier.Evaluate(v, nullptr);
  };
  ok &= Expect(bmr::test::CheckTaylor("barrier", phiAt, phi0, slope0, 1e-3),
               "dPhi_b/du passes the Taylor test (slope in [1.9, 2.1])");
  return ok;
}
} // namespace

int
bmrCompressionBarrierTest(int, char *[])
{
  const bmr::TetrahedralMesh mesh = bmr::test::StructuredCube(5, 2.0);
  bool                       ok = UniformCompressionIsExact(mesh);
  ok &= GradientPassesTaylor(mesh);
  ok &= bmr::test::ExpectException(
    "threshold", [&] { bmr::CompressionBarrier(mesh, 1.5); }, "threshold J_0 must lie in (0, 1)");
  ok &= bmr::test::ExpectException(
    "weight", [&] { bmr::CompressionBarrier(mesh, 0.25, -1.0); }, "weight must be finite and non-negative");
  ok &= bmr::test::ExpectException(
    "size", [&] { bmr::CompressionBarrier(mesh).Evaluate(std::vector<double>(3), nullptr); }, "3 values per node");
  return ok ? EXIT_SUCCESS : EXIT_FAILURE;
}
