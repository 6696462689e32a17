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
// NeoHookeanForwardModel's solves: the tangent's factorization and solves, Newton along the load path.
#include "bmrNeoHookeanForwardModelInternal.h"

#include "bmrError.h"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace bmr {
using neohookean::kWho;

namespace {
double
Norm(const std::vector<double> & v)
{
  return std::sqrt(std::inner_product(v.begin(), v.end(), v.begin(), 0.0));
}
} // namespace

void
NeoHookeanForwardModel::Impl::CopyTangentToFreeBlock()
{
  if (Kff.nonZeros() == 0)
  {
    return; // no constrained set yet
  }
  double * values = Kff.valuePtr();
  for (std::size_t k = 0; k < freePositions.size(); ++k)
  {
    if (freePositions[k] >= 0)
    {
      values[freePositions[k]] = tangent[k];
    }
  }
}

// Factorizes the free block of the current tangent; a block that is not positive definite is shifted by
// tau * mean diagonal (tau = 1e-8, 1e-6, ... 1e4) when allowShift (false when even that fails), else it throws.
// The free block itself keeps the unshifted tangent (the preconditioned solves multiply with it).
bool
NeoHookeanForwardModel::Impl::Factorize(bool allowShift)
{
  const fem::SingleThreadedCholmod serial;
  if (!analyzed)
  {
    fem::OrderByNestedDissection(solver.cholmod());
    const auto serialized = fem::LockOrdering();
    solver.analyzePattern(Kff);
    analyzed = true;
  }
  ++statistics.factorizations;
  refactorNext = false;
  solver.factorize(Kff);
  if (solver.info() == Eigen::Success)
  {
    haveFactorization = factorizationExact = true;
    return true;
  }
  double * values = Kff.valuePtr();
  double   meanDiagonal = 0.0;
  for (std::int64_t p : freeDiagonal)
  {
    meanDiagonal += std::abs(values[p]) / static_cast<double>(freeDiagonal.size());
  }
  std::vector<double> diagonal(freeDiagonal.size());
  for (std::size_t k = 0; k < freeDiagonal.size(); ++k)
  {
    diagonal[k] = values[freeDiagonal[k]];
  }
  bool factorized = false;
  for (double tau = 1e-8; allowShift && tau <= 1e4 && !factorized; tau *= 100.0)
  {
    for (std::size_t k = 0; k < freeDiagonal.size(); ++k)
    {
      values[freeDiagonal[k]] = diagonal[k] + tau * meanDiagonal;
    }
    solver.factorize(Kff);
    factorized = solver.info() == Eigen::Success;
  }
  for (std::size_t k = 0; k < freeDiagonal.size(); ++k)
  {
    values[freeDiagonal[k]] = diagonal[k];
  }
  haveFactorization = factorized;
  factorizationExact = false;
  if (factorized)
  {
    ++statistics.shiftedTangents;
    return true;
  }
  if (allowShift)
  {
    return false;
  }
  Fail(kWho,
       "the tangent stiffness at the equilibrium is not positive definite (an unstable equilibrium): no "
       "adjoint solve");
}

// Conjugate gradients on the current tangent's free block, preconditioned by the factorization of an earlier
// tangent (the state moves little between Newton iterations and between the estimator's evaluations, so a
// few iterations replace a factorization). False when it stalls or meets a direction of non-positive
// curvature (an indefinite tangent); converged at a residual of 1e-12 of |b|.
bool
NeoHookeanForwardModel::Impl::PreconditionedCG(const Eigen::VectorXd & b,
                                               Eigen::VectorXd &       x,
                                               unsigned int &          iterations,
                                               double                  tolerance) const
{
  const auto      A = Kff.selfadjointView<Eigen::Lower>();
  const double    target = tolerance * b.norm();
  Eigen::VectorXd r = b - A * (x = solver.solve(b));
  Eigen::VectorXd z = solver.solve(r), p = z, Ap(b.size());
  double          rz = r.dot(z);
  for (iterations = 0; iterations < 30; ++iterations)
  {
    if (r.norm() <= target)
    {
      return true;
    }
    Ap = A * p;
    const double curvature = p.dot(Ap);
    if (!(curvature > 0.0))
    {
      return false;
    }
    const double alpha = rz / curvature;
    x += alpha * p;
    r -= alpha * Ap;
    z = solver.solve(r);
    const double rzNext = r.dot(z);
    p = z + (rzNext / rz) * p;
    rz = rzNext;
  }
  return r.norm() <= target;
}

// K_T out = rhs on the free dofs (out = 0 on the constrained ones): directly on a factorization of the current
// tangent, else by conjugate gradients preconditioned with the last factorization, refactorizing when they
// fail (or, after a slow solve, before the next one). \a exact: the unshifted tangent (adjoints); otherwise a
// shifted one is acceptable (Newton steps, which only need a descent direction). \a tolerance: CG's relative
// residual (a Newton step needs no more than its forcing term).
bool
NeoHookeanForwardModel::Impl::SolveTangent(const std::vector<double> & rhs,
                                           std::vector<double> &       out,
                                           bool                        exact,
                                           double                      tolerance)
{
  const fem::SingleThreadedCholmod serial;
  Eigen::VectorXd                  b(static_cast<Eigen::Index>(nfree)), x;
  for (std::size_t i = 0; i < ndof; ++i)
  {
    if (freeIndex[i] >= 0)
    {
      b[freeIndex[i]] = rhs[i];
    }
  }
  // Several solves with one tangent (the Levenberg-Marquardt inner solve's du/dp, one per parameter): after
  // the first slow one the factorization pays for itself.
  const bool repeated = !factorizationExact && iterationsAtThisTangent > 3;
  if ((!haveFactorization || refactorNext || repeated) && !Factorize(!exact))
  {
    return false;
  }
  unsigned int iterations = 0;
  if (!factorizationExact)
  {
    const bool converged = PreconditionedCG(b, x, iterations, tolerance);
    statistics.conjugateGradientIterations += iterations;
    iterationsAtThisTangent += iterations;
    if (!converged)
    {
      if (!Factorize(!exact))
      {
        return false;
      }
    }
    refactorNext = converged && iterations > 10;
  }
  if (factorizationExact || iterations == 0 || !std::isfinite(x.squaredNorm()) || x.size() != b.size())
  {
    x = solver.solve(b);
  }
  out.assign(ndof, 0.0);
  for (std::size_t i = 0; i < ndof; ++i)
  {
    if (freeIndex[i] >= 0)
    {
      out[i] = x[freeIndex[i]];
    }
  }
  return true;
}

namespace {
double
FreeDot(const std::vector<double> & a, const std::vector<double> & b, const std::vector<char> & constrained)
{
  double s = 0.0;
  for (std::size_t i = 0; i < a.size(); ++i)
  {
    s += constrained[i] ? 0.0 : a[i] * b[i];
  }
  return s;
}
} // namespace

// The Newton step at u for the residual r (zero on the constrained dofs) and the prescribed part \a step:
// K_T du = r - K_T step on the free dofs, du = step on the constrained ones.
bool
NeoHookeanForwardModel::Impl::NewtonStep(const std::vector<double> & u,
                                         const std::vector<double> & r,
                                         const std::vector<double> & step,
                                         double                      forcing,
                                         std::vector<double> &       du)
{
  AssembleTangent(u);
  ++statistics.iterations;
  std::vector<double> Kstep, rhs(r);
  fem::SymmetricProduct(pattern, tangent, step, Kstep);
  for (std::size_t i = 0; i < ndof; ++i)
  {
    rhs[i] -= Kstep[i];
  }
  if (!SolveTangent(rhs, du, false, forcing))
  {
    return false;
  }
  for (std::size_t i = 0; i < ndof; ++i)
  {
    du[i] = constrained[i] ? step[i] : du[i];
  }
  return true;
}

// u += alpha du for the largest alpha = 2^-k with no inverted element and an Armijo decrease of the total
// potential (with a rounding allowance: near the solution Pi changes below its own precision). A step that
// moves the prescribed dofs (\a jump) is taken whole or not at all: when it inverts an element the load
// increment is too large, and halving the increment (one solve) is cheaper than creeping towards the
// prescribed values over many iterations.
bool
NeoHookeanForwardModel::Impl::LineSearch(std::vector<double> &       u,
                                         const std::vector<double> & du,
                                         const std::vector<double> & f,
                                         double                      decrement,
                                         bool                        jump,
                                         IncrementFailure &          failure) const
{
  const double        energy = Energy(u);
  const double        potential = energy - FreeDot(f, u, constrained);
  const double        allowance = 1e-12 * std::abs(energy);
  std::vector<double> trial(ndof);
  for (int halving = 0; halving < (jump ? 1 : 20); ++halving)
  {
    const double alpha = std::ldexp(1.0, -halving);
    for (std::size_t i = 0; i < ndof; ++i)
    {
      trial[i] = u[i] + alpha * du[i];
    }
    const double trialEnergy = Energy(trial, &failure.worstElement, &failure.worstJ);
    if (!std::isfinite(trialEnergy))
    {
      failure.reason =
        jump ? "the increment's prescribed motion inverts an element" : "every trial step inverts an element";
      continue;
    }
    if (jump || trialEnergy - FreeDot(f, trial, constrained) <= potential - 1e-4 * alpha * decrement + allowance)
    {
      u.swap(trial);
      return true;
    }
    failure.reason = "the line search found no decrease of the potential energy";
  }
  return false;
}

// Newton's method from u to the equilibrium under the loads (f, prescribed): the first iteration also moves
// the constrained dofs to their prescribed values; converged on the residual or the Newton decrement.
bool
NeoHookeanForwardModel::Impl::NewtonIncrement(std::vector<double> &       u,
                                              const std::vector<double> & f,
                                              const std::vector<double> & prescribed,
                                              IncrementFailure &          failure)
{
  if (nfree == 0)
  {
    // Everything prescribed: the state is the prescribed one, if no element is inverted there.
    const bool feasible = std::isfinite(Energy(prescribed, &failure.worstElement, &failure.worstJ));
    failure.reason = "the prescribed displacements invert an element";
    u = prescribed;
    return feasible;
  }
  std::vector<double> residuals;
  double              firstDecrement = 0.0;
  for (unsigned int it = 0; it < settings.maximumIterations; ++it)
  {
    std::vector<double> step(ndof, 0.0);
    bool                jump = false;
    for (std::size_t i = 0; i < ndof; ++i)
    {
      if (constrained[i] && prescribed[i] != u[i])
      {
        step[i] = prescribed[i] - u[i];
        jump = true;
      }
    }
    const std::vector<double> internal = Forces(u);
    std::vector<double>       r(ndof, 0.0);
    for (std::size_t i = 0; i < ndof; ++i)
    {
      r[i] = constrained[i] ? 0.0 : f[i] - internal[i];
    }
    const double scale = std::max(std::sqrt(FreeDot(f, f, constrained)), Norm(internal));
    const double relative = scale > 0.0 ? Norm(r) / scale : 0.0;
    residuals.push_back(relative);
    if (!jump && relative <= settings.residualTolerance)
    {
      statistics.lastResiduals = residuals;
      return true;
    }
    std::vector<double> du;
    // Inexact Newton: the step's linear solve only as accurate as the residual it corrects (forcing term
    // eta = min(1e-2, relative residual) keeps the quadratic rate); a prescribed jump is solved fully, since
    // its linear predictor decides whether the trial inverts an element.
    const double forcing = jump ? 1e-12 : std::clamp(relative, 1e-12, 1e-2);
    if (!NewtonStep(u, r, step, forcing, du))
    {
      failure.reason = "the tangent stiffness could not be factorized even after shifting its diagonal";
      return false;
    }
    const double decrement = FreeDot(du, r, constrained);
    if (!jump && firstDecrement == 0.0)
    {
      firstDecrement = std::abs(decrement);
    }
    if (!LineSearch(u, du, f, decrement, jump, failure))
    {
      return false;
    }
    if (!jump && firstDecrement > 0.0 && std::abs(decrement) <= settings.energyTolerance * firstDecrement)
    {
      residuals.push_back(0.0); // converged on the energy criterion; the residual is not recomputed
      statistics.lastResiduals = residuals;
      return true;
    }
  }
  failure.reason = "Newton did not converge in " + std::to_string(settings.maximumIterations) + " iterations";
  return false;
}

// Applies the loads along (f0, g0) -> (f1, g1) from u in adaptive increments; \a reached is the fraction done.
bool
NeoHookeanForwardModel::Impl::FollowPath(std::vector<double> &       u,
                                         const std::vector<double> & f0,
                                         const std::vector<double> & g0,
                                         const std::vector<double> & f1,
                                         const std::vector<double> & g1,
                                         double &                    reached,
                                         IncrementFailure &          failure)
{
  reached = 0.0;
  double              increment = settings.initialIncrement;
  std::vector<double> f(ndof), g(ndof), trial;
  while (reached < 1.0)
  {
    const double t = std::min(1.0, reached + increment);
    for (std::size_t i = 0; i < ndof; ++i)
    {
      f[i] = f0[i] + t * (f1[i] - f0[i]);
      g[i] = t == 1.0 ? g1[i] : g0[i] + t * (g1[i] - g0[i]);
    }
    trial = u;
    const unsigned int before = statistics.iterations;
    if (NewtonIncrement(trial, f, g, failure))
    {
      u.swap(trial);
      reached = t;
      ++statistics.acceptedIncrements;
      if (statistics.iterations - before <= settings.easyIterations)
      {
        increment = std::min(1.0, 2.0 * increment);
      }
      continue;
    }
    ++statistics.rejectedIncrements;
    increment *= 0.5;
    if (increment < settings.minimumIncrement)
    {
      return false;
    }
  }
  return true;
}

} // namespace bmr
