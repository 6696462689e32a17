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

// Neo-Hookean forward model (NeoHookeanForwardModel): homogeneous deformations reproduced exactly with the
// analytic first Piola-Kirchhoff stress (patch tests), Newton's quadratic rate, the small-load limit against
// the linear model, adjoint gradients against the Taylor remainder, invariance under a rigid rotation, a
// compression that no inverted element survives, and the error paths.
#include "bmrLinearElasticModel.h"
#include "bmrMesher.h"
#include "bmrNeoHookeanForwardModel.h"
#include "bmrTestUtilities.h"

#include <cmath>
#include <cstdlib>

namespace {
using Matrix = std::array<std::array<double, 3>, 3>;
const double kMu1 = 10.0 / (2.0 * 1.3), kLambda1 = 10.0 * 0.3 / (1.3 * 0.4); // E = 10 kPa, nu = 0.3

double
Determinant(const Matrix & F)
{
  return F[0][0] * (F[1][1] * F[2][2] - F[1][2] * F[2][1]) - F[0][1] * (F[1][0] * F[2][2] - F[1][2] * F[2][0]) +
         F[0][2] * (F[1][0] * F[2][1] - F[1][1] * F[2][0]);
}

// F^{-T} by cofactors: (F^{-T})_{iJ} = C_{iJ} / J.
Matrix
InverseTranspose(const Matrix & F)
{
  Matrix       C;
  const double J = Determinant(F);
  for (int i = 0; i < 3; ++i)
  {
    for (int j = 0; j < 3; ++j)
    {
      const int i1 = (i + 1) % 3, i2 = (i + 2) % 3, j1 = (j + 1) % 3, j2 = (j + 2) % 3;
      C[i][j] = (F[i1][j1] * F[i2][j2] - F[i1][j2] * F[i2][j1]) / J;
    }
  }
  return C;
}

// The analytic stress of the energy W = mu/2 (I1 - 3) - mu ln J + lambda/2 (ln J)^2.
Matrix
AnalyticStress(const Matrix & F, double mu, double lambda)
{
  const Matrix H = InverseTranspose(F);
  const double lnJ = std::log(Determinant(F));
  Matrix       P;
  for (int i = 0; i < 3; ++i)
  {
    for (int j = 0; j < 3; ++j)
    {
      P[i][j] = mu * (F[i][j] - H[i][j]) + lambda * lnJ * H[i][j];
    }
  }
  return P;
}

std::vector<std::int32_t>
NodesWhere(const bmr::TetrahedralMesh & mesh, const std::function<bool(const double *)> & where)
{
  std::vector<std::int32_t> nodes;
  for (std::size_t n = 0; n < mesh.GetNumberOfPoints(); ++n)
  {
    if (where(&mesh.points[3 * n]))
    {
      nodes.push_back(static_cast<std::int32_t>(n));
    }
  }
  return nodes;
}

double
Norm(const std::vector<double> & v)
{
  double s = 0.0;
  for (double x : v)
  {
    s += x * x;
  }
  return std::sqrt(s);
}

double
Difference(const std::vector<double> & a, const std::vector<double> & b)
{
  double s = 0.0;
  for (std::size_t i = 0; i < a.size(); ++i)
  {
    s += (a[i] - b[i]) * (a[i] - b[i]);
  }
  return std::sqrt(s);
}

// Least-squares slope of log y against log x.
double
LogSlope(const std::vector<double> & x, const std::vector<double> & y)
{
  double mx = 0, my = 0;
  for (std::size_t k = 0; k < x.size(); ++k)
  {
    mx += std::log(x[k]) / x.size();
    my += std::log(y[k]) / y.size();
  }
  double sxy = 0, sxx = 0;
  for (std::size_t k = 0; k < x.size(); ++k)
  {
    sxy += (std::log(x[k]) - mx) * (std::log(y[k]) - my);
    sxx += (std::log(x[k]) - mx) * (std::log(x[k]) - mx);
  }
  return sxy / sxx;
}

// 1. A homogeneous deformation F prescribed on the boundary of a cube is reproduced inside, every element
// carries the analytic stress, and the internal forces on the face x = L add up to P N times its area.
bool
PatchTest(const std::string & name, const Matrix & F)
{
  using bmr::test::Expect;
  using bmr::test::ToString;
  const bmr::TetrahedralMesh mesh = bmr::test::StructuredCube(3, 2.0);
  const double               L = 6.0;
  std::vector<double>        exact(mesh.points.size());
  for (std::size_t n = 0; n < mesh.GetNumberOfPoints(); ++n)
  {
    const double * X = &mesh.points[3 * n];
    for (int i = 0; i < 3; ++i)
    {
      exact[3 * n + i] = F[i][0] * X[0] + F[i][1] * X[1] + F[i][2] * X[2] - X[i];
    }
  }
  const auto boundary = NodesWhere(
    mesh, [L](const double * X) { return X[0] == 0 || X[1] == 0 || X[2] == 0 || X[0] == L || X[1] == L || X[2] == L; });
  bmr::NeoHookeanForwardModel model(mesh, { { 1, { 10.0, 0.3 } } });
  model.SetConstrainedNodes(boundary);
  const std::vector<double> u = model.SolveState({}, exact);
  const double              error = Difference(u, exact) / Norm(exact);
  const auto                stress = model.FirstPiolaKirchhoffStress(u);
  const Matrix              P = AnalyticStress(F, kMu1, kLambda1);
  double                    stressError = 0.0, scale = 0.0;
  for (std::size_t e = 0; e < mesh.GetNumberOfTetrahedra(); ++e)
  {
    for (int k = 0; k < 9; ++k)
    {
      stressError = std::max(stressError, std::abs(stress[9 * e + k] - P[k / 3][k % 3]));
      scale = std::max(scale, std::abs(P[k / 3][k % 3]));
    }
  }
  const std::vector<double> internal = model.InternalForces(u);
  double                    faceForce[3] = { 0, 0, 0 };
  for (std::int32_t n : NodesWhere(mesh, [L](const double * X) { return X[0] == L; }))
  {
    for (int i = 0; i < 3; ++i)
    {
      faceForce[i] += internal[3 * n + i];
    }
  }
  double forceError = 0.0, forceScale = 0.0;
  for (int i = 0; i < 3; ++i)
  {
    forceError = std::max(forceError, std::abs(faceForce[i] - P[i][0] * L * L));
    forceScale = std::max(forceScale, std::abs(P[i][0] * L * L));
  }
  std::cout << name << ": displacement error " << error << ", stress error " << stressError / scale
            << ", face force error " << forceError / forceScale << ", " << model.GetStatistics().iterations
            << " Newton iterations" << std::endl;
  // 1e-9: F is in the element space and Newton stops at a relative residual of 1e-9; rounding is far below.
  bool ok = Expect(error <= 1e-9, name + ": displacements exact to 1e-9 (got " + ToString(error) + ")");
  ok &= Expect(stressError <= 1e-9 * scale,
               name + ": stress = analytic P to 1e-9 (got " + ToString(stressError / scale) + ")");
  ok &= Expect(forceError <= 1e-9 * forceScale,
               name + ": face force = P N area to 1e-9 (got " + ToString(forceError / forceScale) + ")");
  return ok;
}

// The cube of two materials held at z = 0 under a downward and sideways load on its top.
struct LoadedCube
{
  bmr::TetrahedralMesh                            mesh = bmr::test::StructuredCube(4, 2.0, 2);
  std::vector<std::int32_t>                       bottom;
  std::vector<double>                             forces;
  std::map<std::int32_t, bmr::MaterialParameters> materials{ { 1, { 10.0, 0.3 } }, { 2, { 30.0, 0.4 } } };

  explicit LoadedCube(double load)
  {
    bottom = NodesWhere(mesh, [](const double * X) { return X[2] == 0.0; });
    forces.assign(mesh.points.size(), 0.0);
    for (std::int32_t n : NodesWhere(mesh, [](const double * X) { return X[2] == 8.0; }))
    {
      forces[3 * n] = 0.5 * load;
      forces[3 * n + 2] = -load;
    }
  }
};

// The thick hollow sphere A <= R <= B inflated by a prescribed inner radial displacement, outer surface free:
// the radial solution r(R) of the compressible neo-Hookean ball, independently of the finite elements. With
// lr = r', lt = r / R, J = lr lt^2, the radial and hoop first Piola-Kirchhoff stresses are
// Pr = mu (lr - 1/lr) + lambda ln J / lr and Pt = mu (lt - 1/lt) + lambda ln J / lt, and equilibrium is
// dPr/dR + 2 (Pr - Pt) / R = 0, i.e. r'' = -[2 (Pr - Pt) / R + dPr/dlt (r' - r/R) / R] / dPr/dlr.
// RK4 in R for (r, r'), shooting on r'(A) (bisection) until Pr(B) = 0.
struct HollowSphere
{
  double A{ 5.0 }, B{ 10.0 }, innerDisplacement{ 2.5 }, mu{ kMu1 }, lambda{ kLambda1 };

  double
  RadialStress(double r, double dr, double R) const
  {
    const double lt = r / R, J = dr * lt * lt;
    return mu * (dr - 1.0 / dr) + lambda * std::log(J) / dr;
  }
  void
  Derivative(double R, const double y[2], double dy[2]) const
  {
    const double r = y[0], lr = y[1], lt = r / R, lnJ = std::log(lr * lt * lt);
    const double Pr = mu * (lr - 1.0 / lr) + lambda * lnJ / lr, Pt = mu * (lt - 1.0 / lt) + lambda * lnJ / lt;
    const double dPrdlr = mu + (mu + lambda * (1.0 - lnJ)) / (lr * lr), dPrdlt = 2.0 * lambda / (lr * lt);
    dy[0] = lr;
    dy[1] = -(2.0 * (Pr - Pt) / R + dPrdlt * (lr - lt) / R) / dPrdlr;
  }
  // r at n + 1 equally spaced radii from A to B for the slope s = r'(A); false when the stretch turns <= 0.
  bool
  Integrate(double s, int n, std::vector<double> & r, double & slopeAtB) const
  {
    double       y[2] = { A + innerDisplacement, s };
    const double h = (B - A) / n;
    r.assign(1, y[0]);
    for (int k = 0; k < n; ++k)
    {
      const double R = A + k * h;
      double       k1[2], k2[2], k3[2], k4[2], t[2];
      Derivative(R, y, k1);
      for (int i = 0; i < 2; ++i)
        t[i] = y[i] + 0.5 * h * k1[i];
      Derivative(R + 0.5 * h, t, k2);
      for (int i = 0; i < 2; ++i)
        t[i] = y[i] + 0.5 * h * k2[i];
      Derivative(R + 0.5 * h, t, k3);
      for (int i = 0; i < 2; ++i)
        t[i] = y[i] + h * k3[i];
      Derivative(R + h, t, k4);
      for (int i = 0; i < 2; ++i)
        y[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
      if (!(y[0] > 0.0 && y[1] > 0.0))
      {
        return false;
      }
      r.push_back(y[0]);
    }
    slopeAtB = y[1];
    return true;
  }
  // The radii r(R_k) of the solution with Pr(B) = 0 on n steps.
  std::vector<double>
  Solve(int n) const
  {
    double              lo = 0.05, hi = 3.0; // Pr(B) < 0 at lo (the wall barely stretches), > 0 at hi
    std::vector<double> r;
    double              slope = 0.0;
    for (int it = 0; it < 200 && hi - lo > 1e-15; ++it)
    {
      const double mid = 0.5 * (lo + hi);
      const bool   ok = Integrate(mid, n, r, slope);
      (ok && RadialStress(r.back(), slope, B) > 0.0 ? hi : lo) = mid;
    }
    Integrate(hi, n, r, slope);
    return r;
  }
};
} // namespace

int
bmrNeoHookeanModelTest(int, char *[])
{
  using bmr::test::Expect;
  using bmr::test::ExpectException;
  using bmr::test::ToString;
  bool ok = true;

  // 1. Patch tests: uniaxial stretch (lateral contraction free of the analytic value: any F is reproduced),
  // simple shear and equibiaxial stretch, each far from the linear range.
  ok &= PatchTest("uniaxial stretch 1.3", { { { 1.3, 0, 0 }, { 0, 0.9, 0 }, { 0, 0, 0.9 } } });
  ok &= PatchTest("simple shear 0.5", { { { 1, 0.5, 0 }, { 0, 1, 0 }, { 0, 0, 1 } } });
  ok &= PatchTest("equibiaxial 1.2", { { { 1.2, 0, 0 }, { 0, 1.2, 0 }, { 0, 0, 0.75 } } });

  // 2. Newton's rate: near the solution the relative residual squares, r_{k+1} <= C r_k^2.
  const LoadedCube cube(0.8);
  {
    bmr::NewtonSettings settings;
    settings.residualTolerance = 1e-13;
    bmr::NeoHookeanForwardModel model(cube.mesh, cube.materials, settings);
    model.SetConstrainedNodes(cube.bottom);
    const std::vector<double> u = model.SolveState(cube.forces, std::vector<double>(cube.forces.size(), 0.0));
    const auto &              r = model.GetStatistics().lastResiduals;
    std::cout << "Newton residuals of the last increment (" << model.GetStatistics().acceptedIncrements
              << " increments, max |u| " << *std::max_element(u.begin(), u.end()) << " mm):";
    for (double x : r)
    {
      std::cout << ' ' << x;
    }
    std::cout << std::endl;
    // The asymptotic pairs: r_k below 1e-2 and r_{k+1} above the rounding floor 1e-13.
    double worstRatio = 0.0;
    int    pairs = 0;
    for (std::size_t k = 0; k + 1 < r.size(); ++k)
    {
      if (r[k] < 1e-2 && r[k + 1] > 1e-13)
      {
        worstRatio = std::max(worstRatio, r[k + 1] / (r[k] * r[k]));
        ++pairs;
      }
    }
    // C <= 100: a linear rate would give r_{k+1} / r_k^2 = c / r_k >= 1e2 c at r_k < 1e-2 and grow without bound.
    ok &= Expect(pairs >= 1 && worstRatio <= 100.0,
                 "quadratic Newton rate: r_{k+1} / r_k^2 <= 100 over " + ToString(pairs) + " asymptotic pairs (got " +
                   ToString(worstRatio) + ")");
    // The cumulative work counts this solve and, after a second one, both (the estimator's per-solve reports).
    const bmr::NewtonStatistics first = model.GetStatistics();
    model.SolveAdjoint(u);
    const unsigned int        withAdjoint = model.GetStatistics().factorizations;
    const std::vector<double> half(cube.forces.size(), 0.0);
    model.SolveState(half, half);
    const bmr::SolverWork work = model.GetSolverWork();
    std::cout << "solver work: " << work.stateSolves << " solves, " << work.newtonIterations << " Newton iterations, "
              << work.factorizations << " factorizations, " << work.conjugateGradientIterations << " CG iterations"
              << std::endl;
    ok &=
      Expect(work.stateSolves == 2 && work.newtonIterations == first.iterations + model.GetStatistics().iterations &&
               work.factorizations == withAdjoint + model.GetStatistics().factorizations && first.iterations > 0,
             "GetSolverWork() sums the Newton iterations and factorizations of both solves and the adjoint's");
  }

  // 3. Small loads: the neo-Hookean state differs from the linear one by O(load^2).
  {
    std::vector<double> loads, differences;
    for (double load : { 0.04, 0.02, 0.01, 0.005 })
    {
      const LoadedCube            c(load);
      bmr::NeoHookeanForwardModel nonlinear(c.mesh, c.materials);
      nonlinear.SetConstrainedNodes(c.bottom);
      const std::vector<double> zero(c.forces.size(), 0.0);
      const std::vector<double> u = nonlinear.SolveState(c.forces, zero);
      bmr::LinearElasticModel   linear(c.mesh, c.materials);
      linear.SetDirichletConditions(c.bottom, {});
      loads.push_back(load);
      differences.push_back(Difference(u, linear.Solve(c.forces)));
    }
    const double slope = LogSlope(loads, differences);
    std::cout << "small-load limit: |u_nh - u_lin| slope " << slope << " (at load 0.005: " << differences.back()
              << " mm)" << std::endl;
    // [1.9, 2.1]: the difference is quadratic in the load; Newton's 1e-9 stop is far below it.
    ok &= Expect(slope >= 1.9 && slope <= 2.1,
                 "|u_nh - u_lin| = O(load^2): slope in [1.9, 2.1] (got " + ToString(slope) + ")");
  }

  // 4. Adjoint gradients of Phi(u) = 1/2 |u - u_target|^2 with respect to log E_2 and to a force direction,
  // against the Taylor remainder |Phi(p + h d) - Phi(p) - h dPhi/dp . d| = O(h^2).
  {
    bmr::NewtonSettings settings;
    settings.residualTolerance = 1e-12;
    bmr::NeoHookeanForwardModel model(cube.mesh, cube.materials, settings);
    model.SetConstrainedNodes(cube.bottom);
    const std::vector<double> zero(cube.forces.size(), 0.0);
    std::vector<double>       target = model.SolveState(cube.forces, zero);
    for (std::size_t i = 0; i < target.size(); ++i)
    {
      target[i] *= 1.0 + 0.2 * std::sin(double(i)); // a target the model does not reach
    }
    auto phi = [&](double logE, double forceStep, std::vector<double> * gradient) {
      model.SetYoungsModulus(2, 30.0 * std::exp(logE));
      std::vector<double> f(cube.forces);
      for (std::size_t i = 0; i < f.size(); ++i)
      {
        f[i] *= 1.0 + forceStep;
      }
      const std::vector<double> u = model.SolveState(f, zero);
      std::vector<double>       g(u.size());
      double                    value = 0.0;
      for (std::size_t i = 0; i < u.size(); ++i)
      {
        g[i] = u[i] - target[i];
        value += 0.5 * g[i] * g[i];
      }
      if (gradient)
      {
        const std::vector<double> lambda = model.SolveAdjoint(g);
        const std::vector<double> dfdE = model.ModulusDerivative(2, u);
        double                    dlogE = 0.0, dforce = 0.0;
        for (std::size_t i = 0; i < u.size(); ++i)
        {
          dlogE -= lambda[i] * dfdE[i] * model.GetYoungsModulus(2); // dE/dlogE = E
          dforce += lambda[i] * cube.forces[i];
        }
        *gradient = { dlogE, dforce };
      }
      return value;
    };
    std::vector<double> gradient;
    const double        phi0 = phi(0.0, 0.0, &gradient);
    for (int direction = 0; direction < 2; ++direction)
    {
      std::vector<double> steps, remainders;
      for (double h : { 0.08, 0.04, 0.02, 0.01 })
      {
        const double value = direction == 0 ? phi(h, 0.0, nullptr) : phi(0.0, h, nullptr);
        steps.push_back(h);
        remainders.push_back(std::abs(value - phi0 - h * gradient[direction]));
      }
      const double      slope = LogSlope(steps, remainders);
      const std::string what = direction == 0 ? "log E" : "force scale";
      std::cout << "Taylor test, " << what << ": gradient " << gradient[direction] << ", remainder slope " << slope
                << std::endl;
      // [1.9, 2.1]: the remainder of a correct gradient is O(h^2); a wrong one leaves O(h).
      ok &= Expect(slope >= 1.9 && slope <= 2.1,
                   "Taylor remainder slope for " + what + " in [1.9, 2.1] (got " + ToString(slope) + ")");
    }
  }

  // 5. A rigid rotation of a loaded state: the stored energy and P^T P unchanged, the forces rotated.
  {
    bmr::NeoHookeanForwardModel model(cube.mesh, cube.materials);
    model.SetConstrainedNodes(cube.bottom);
    const std::vector<double> u = model.SolveState(cube.forces, std::vector<double>(cube.forces.size(), 0.0));
    const double              c = std::cos(0.7), s = std::sin(0.7), c2 = std::cos(-0.4), s2 = std::sin(-0.4);
    const Matrix Rz{ { { c, -s, 0 }, { s, c, 0 }, { 0, 0, 1 } } }, Rx{ { { 1, 0, 0 }, { 0, c2, -s2 }, { 0, s2, c2 } } };
    Matrix       R{};
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j)
        for (int k = 0; k < 3; ++k)
          R[i][j] += Rz[i][k] * Rx[k][j];
    std::vector<double> rotated(u.size());
    for (std::size_t n = 0; n < cube.mesh.GetNumberOfPoints(); ++n)
    {
      const double * X = &cube.mesh.points[3 * n];
      const double   x[3] = { X[0] + u[3 * n], X[1] + u[3 * n + 1], X[2] + u[3 * n + 2] };
      for (int i = 0; i < 3; ++i)
      {
        rotated[3 * n + i] = R[i][0] * x[0] + R[i][1] * x[1] + R[i][2] * x[2] - X[i];
      }
    }
    const double energy = model.StoredEnergy(u), energyRotated = model.StoredEnergy(rotated);
    const auto   P = model.FirstPiolaKirchhoffStress(u), Pr = model.FirstPiolaKirchhoffStress(rotated);
    double       invariantError = 0.0, invariantScale = 0.0;
    for (std::size_t e = 0; e < cube.mesh.GetNumberOfTetrahedra(); ++e)
    {
      for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b)
        {
          double ptp = 0.0, ptpRotated = 0.0;
          for (int i = 0; i < 3; ++i)
          {
            ptp += P[9 * e + 3 * i + a] * P[9 * e + 3 * i + b];
            ptpRotated += Pr[9 * e + 3 * i + a] * Pr[9 * e + 3 * i + b];
          }
          invariantError = std::max(invariantError, std::abs(ptp - ptpRotated));
          invariantScale = std::max(invariantScale, std::abs(ptp));
        }
    }
    const auto f = model.InternalForces(u), fr = model.InternalForces(rotated);
    double     forceError = 0.0;
    for (std::size_t n = 0; n < cube.mesh.GetNumberOfPoints(); ++n)
    {
      for (int i = 0; i < 3; ++i)
      {
        const double expected = R[i][0] * f[3 * n] + R[i][1] * f[3 * n + 1] + R[i][2] * f[3 * n + 2];
        forceError = std::max(forceError, std::abs(fr[3 * n + i] - expected));
      }
    }
    const double energyError = std::abs(energyRotated - energy) / energy;
    std::cout << "rigid rotation: energy " << energy << " kPa mm^3, relative change " << energyError
              << ", P^T P change " << invariantError / invariantScale << ", force error " << forceError / Norm(f)
              << std::endl;
    // 1e-12: frame indifference is exact; only rounding of the rotated coordinates remains.
    ok &= Expect(energyError <= 1e-12,
                 "stored energy invariant under rotation to 1e-12 (got " + ToString(energyError) + ")");
    ok &= Expect(invariantError <= 1e-12 * invariantScale,
                 "P^T P invariant to 1e-12 (got " + ToString(invariantError / invariantScale) + ")");
    ok &= Expect(forceError <= 1e-12 * Norm(f),
                 "internal forces rotate with the state to 1e-12 (got " + ToString(forceError / Norm(f)) + ")");
  }

  // 6. A compression to 40 % of the height (prescribed on the top face): the path is followed in increments
  // and no element of the result is inverted.
  {
    bmr::NeoHookeanForwardModel model(cube.mesh, cube.materials);
    std::vector<std::int32_t>   held = cube.bottom;
    const auto                  top = NodesWhere(cube.mesh, [](const double * X) { return X[2] == 8.0; });
    held.insert(held.end(), top.begin(), top.end());
    std::sort(held.begin(), held.end());
    model.SetConstrainedNodes(held);
    std::vector<double> prescribed(cube.forces.size(), 0.0);
    for (std::int32_t n : top)
    {
      prescribed[3 * n + 2] = -4.8;
    }
    const std::vector<double> u = model.SolveState({}, prescribed);
    const std::size_t         inverted = bmr::CountInvertedElements(cube.mesh, u);
    std::cout << "compression to 40 %: " << model.GetStatistics().acceptedIncrements << " increments accepted, "
              << model.GetStatistics().rejectedIncrements << " halved, " << model.GetStatistics().iterations
              << " Newton iterations, " << inverted << " inverted elements" << std::endl;
    ok &= Expect(inverted == 0, "no inverted element after a compression to 40 % (got " + ToString(inverted) + ")");
    ok &= Expect(std::isfinite(model.StoredEnergy(u)), "finite stored energy after the compression");
  }

  // 7. Errors.
  {
    const bmr::TetrahedralMesh mesh = bmr::test::StructuredCube(2, 1.0);
    ok &= ExpectException(
      "nodal-averaged pressure",
      [&] {
        bmr::MaterialParameters     m{ 10.0, 0.45, bmr::ElementFormulationEnum::NodalAveragedPressure };
        bmr::NeoHookeanForwardModel model(mesh, { { 1, m } });
      },
      "only the standard P1 formulation");
    ok &= ExpectException(
      "label without material",
      [&] {
        bmr::NeoHookeanForwardModel model(mesh, { { 2, { 10.0, 0.3 } } });
      },
      "has no material");
    ok &= ExpectException(
      "unheld mesh",
      [&] {
        bmr::NeoHookeanForwardModel model(mesh, { { 1, { 10.0, 0.3 } } });
        model.SetConstrainedNodes({ 0 });
      },
      "rigid-body motion");
    ok &= ExpectException(
      "adjoint before a state",
      [&] {
        bmr::NeoHookeanForwardModel model(mesh, { { 1, { 10.0, 0.3 } } });
        model.SolveAdjoint(std::vector<double>(mesh.points.size(), 0.0));
      },
      "needs an equilibrium");
    // Loads no state can carry: the boundary of the 2 x 2 x 2 cube mirrored through the plane x = 1, which
    // would turn every element around the one free node (the center) inside out; the path stops before x = 1.
    ok &= ExpectException(
      "unreachable load",
      [&] {
        bmr::NewtonSettings settings;
        settings.minimumIncrement = 1.0 / 64.0;
        bmr::NeoHookeanForwardModel model(mesh, { { 1, { 10.0, 0.3 } } }, settings);
        const auto                  boundary =
          NodesWhere(mesh, [](const double * X) { return X[0] != 1.0 || X[1] != 1.0 || X[2] != 1.0; });
        model.SetConstrainedNodes(boundary);
        std::vector<double> prescribed(mesh.points.size(), 0.0);
        for (std::int32_t n : boundary)
        {
          prescribed[3 * n] = 2.0 - 2.0 * mesh.points[3 * n];
        }
        model.SolveState({}, prescribed);
      },
      "could not be applied");
    // The same unreachable load after a reachable one (5 % of it): the warm path fails, and only with
    // restartFromRest is the load tried again from u = 0 (what an estimator's infeasible trial points cost).
    for (bool restart : { true, false })
    {
      bmr::NewtonSettings settings;
      settings.minimumIncrement = 1.0 / 64.0;
      settings.restartFromRest = restart;
      bmr::NeoHookeanForwardModel model(mesh, { { 1, { 10.0, 0.3 } } }, settings);
      const auto                  boundary =
        NodesWhere(mesh, [](const double * X) { return X[0] != 1.0 || X[1] != 1.0 || X[2] != 1.0; });
      model.SetConstrainedNodes(boundary);
      std::vector<double> mirrored(mesh.points.size(), 0.0), small(mesh.points.size(), 0.0), u;
      for (std::int32_t n : boundary)
      {
        mirrored[3 * n] = 2.0 - 2.0 * mesh.points[3 * n];
        small[3 * n] = 0.05 * mirrored[3 * n];
      }
      const bool            reachable = model.TrySolveState({}, small, u);
      const bool            unreachable = model.TrySolveState({}, mirrored, u);
      const bmr::SolverWork work = model.GetSolverWork();
      std::cout << "restartFromRest " << restart << ": " << work.stateSolves << " solves, " << work.coldStarts
                << " cold starts, " << work.rejectedIncrements << " halved increments" << std::endl;
      ok &= Expect(reachable && !unreachable && work.stateSolves == 2 && work.coldStarts == (restart ? 1u : 0u) &&
                     work.rejectedIncrements >= 6,
                   std::string("a failed warm path ") + (restart ? "is" : "is not") +
                     " retried from rest, and the halvings (>= 6 down to 1/64) are counted");
    }
  }
  // 8. The thick hollow sphere (5 to 10 mm) inflated by 2.5 mm at its inner wall, outer surface free, against
  // the radial solution of the 1-D equilibrium ODE (solved here to 1e-8 mm: RK4 on 4000 and 8000 steps agree).
  {
    const HollowSphere        sphere;
    const std::vector<double> fine = sphere.Solve(8000), coarse = sphere.Solve(4000);
    double                    odeError = 0.0;
    for (std::size_t k = 0; k < coarse.size(); ++k)
    {
      odeError = std::max(odeError, std::abs(coarse[k] - fine[2 * k]));
    }
    ok &= Expect(odeError <= 1e-8, "the radial ODE converged to 1e-8 mm (got " + ToString(odeError) + ")");
    const auto exactDisplacement = [&](double R) { // linear interpolation on the 8000-step solution
      const double t = (R - sphere.A) / (sphere.B - sphere.A) * 8000.0;
      const int    k = std::min(7999, std::max(0, static_cast<int>(t)));
      return fine[k] + (t - k) * (fine[k + 1] - fine[k]) - R;
    };
    std::vector<double> errors, linearErrors;
    for (double h : { 2.0, 1.0 })
    {
      bmr::MeshingParameters p;
      p.cellSize = p.facetSize = h;
      p.facetDistance = 0.1 * h;
      auto labelAt = [&](double x, double y, double z) -> std::int32_t {
        const double R = std::sqrt(x * x + y * y + z * z);
        return R < sphere.A ? 3 : (R <= sphere.B ? 1 : 0);
      };
      const bmr::TetrahedralMesh mesh =
        bmr::ExtractSubmesh(bmr::MeshImplicitLabels(labelAt, { { 0, 0, 0 } }, 11.0, p), { 3 });
      const auto          inner = bmr::NodesOnBoundary(mesh, 3);
      std::vector<double> prescribed(mesh.points.size(), 0.0);
      for (std::int32_t n : inner)
      {
        const double * X = &mesh.points[3 * n];
        const double   R = std::sqrt(X[0] * X[0] + X[1] * X[1] + X[2] * X[2]);
        for (int i = 0; i < 3; ++i)
        {
          prescribed[3 * n + i] = (sphere.A + sphere.innerDisplacement) * X[i] / R - X[i]; // onto the radius 7.5
        }
      }
      bmr::NeoHookeanForwardModel model(mesh, { { 1, { 10.0, 0.3 } } });
      model.SetConstrainedNodes(inner);
      const std::vector<double> u = model.SolveState({}, prescribed);
      bmr::LinearElasticModel   linear(mesh, { { 1, { 10.0, 0.3 } } });
      linear.SetDirichletConditions(inner, {});
      const std::vector<double> uLinear = linear.Solve({}, prescribed);
      double                    sum = 0.0, sumLinear = 0.0;
      for (std::size_t n = 0; n < mesh.GetNumberOfPoints(); ++n)
      {
        const double * X = &mesh.points[3 * n];
        const double   R = std::sqrt(X[0] * X[0] + X[1] * X[1] + X[2] * X[2]);
        const double   exact = exactDisplacement(std::min(sphere.B, std::max(sphere.A, R)));
        for (int i = 0; i < 3; ++i)
        {
          sum += std::pow(u[3 * n + i] - exact * X[i] / R, 2);
          sumLinear += std::pow(uLinear[3 * n + i] - exact * X[i] / R, 2);
        }
      }
      const double rms = std::sqrt(sum / mesh.GetNumberOfPoints());
      linearErrors.push_back(std::sqrt(sumLinear / mesh.GetNumberOfPoints()) / sphere.innerDisplacement);
      errors.push_back(rms / sphere.innerDisplacement);
      std::cout << "hollow sphere, h " << h << " mm (" << mesh.GetNumberOfTetrahedra() << " tetrahedra, "
                << model.GetStatistics().iterations << " Newton iterations, " << model.GetStatistics().factorizations
                << " factorizations): outer radius " << sphere.B + exactDisplacement(sphere.B)
                << " mm exact, RMS nodal error " << rms << " mm (linear model "
                << linearErrors.back() * sphere.innerDisplacement << " mm)" << std::endl;
    }
    const double order = std::log2(errors[0] / errors[1]);
    // 1 %: P1 nodal errors fall as h^2 (and CGAL's surfaces approach the spheres as h^2); measured 0.57 % at
    // h = 1 mm and order 2.2. The linear model on the same meshes stays 9 % off: the test tells the models apart.
    ok &= Expect(errors[1] <= 0.01,
                 "hollow sphere: RMS nodal error <= 1 % of the inflation at h = 1 mm (got " +
                   ToString(100.0 * errors[1]) + " %)");
    ok &= Expect(order >= 1.5,
                 "hollow sphere: the error falls at least as h^1.5 from h = 2 to 1 mm (order " + ToString(order) + ")");
    ok &=
      Expect(linearErrors[1] >= 5.0 * errors[1],
             "hollow sphere: the linear model misses the neo-Hookean solution by >= 5x the neo-Hookean error (got " +
               ToString(linearErrors[1] / errors[1]) + "x)");
  }
  return ok ? EXIT_SUCCESS : EXIT_FAILURE;
}
