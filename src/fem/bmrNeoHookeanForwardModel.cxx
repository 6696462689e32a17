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
// The system Eigen 3.4 and CHOLMOD are used only in src/fem; no ITK header that bundles ITK's own Eigen may
// be included here. Setup (constructor, SetConstrainedNodes), assembly (element loops), solve (Newton along
// the load path) and the adjoint, in that order.
#include "bmrNeoHookeanForwardModel.h"

#include "bmrError.h"
#include "bmrFemAssembly.h"
#include "bmrNeoHookeanElement.h"
#include "bmrStopwatch.h"

#include <Eigen/CholmodSupport>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <sstream>

namespace bmr {

namespace {
const char * const kWho = "NeoHookeanForwardModel";

double
Norm(const std::vector<double> & v)
{
  return std::sqrt(std::inner_product(v.begin(), v.end(), v.begin(), 0.0));
}

/** One trial of a load increment that did not work, and why (for the error message). */
struct IncrementFailure
{
  std::string  reason;
  std::int64_t worstElement{ -1 };
  double       worstJ{ 0.0 };
};
} // namespace

struct NeoHookeanForwardModel::Impl
{
  const TetrahedralMesh &                    mesh;
  std::map<std::int32_t, MaterialParameters> materials;
  NewtonSettings                             settings;
  std::size_t                                ndof{ 0 };
  // Reference geometry, per element.
  std::vector<std::array<double, 12>> gradients; // g[a][i] at 3a+i
  std::vector<double>                 volumes;
  std::vector<double>                 mu, lambda; // per element [kPa], from its material
  // Elements whose four nodes are all constrained: they cannot move, so they take no part in the free
  // equilibrium (no residual, no tangent on free dofs) and in the line search; one that the prescribed motion
  // alone inverts (a boundary sliver) would otherwise make every state infeasible.
  std::vector<char> passive;
  // The tangent on the full lower pattern, and where each element's 4x4 node blocks go in it.
  fem::LowerPattern         pattern;
  std::vector<std::int64_t> elementEntries; // 144 per element: position of K[3a+i][3b+k] or -1 (upper part)
  std::vector<double>       tangent;
  // The free block and its factorization.
  std::vector<char>                                                      constrained;
  std::vector<std::int32_t>                                              freeIndex;
  std::size_t                                                            nfree{ 0 };
  Eigen::SparseMatrix<double>                                            Kff;
  std::vector<std::int64_t>                                              freePositions;
  std::vector<std::int64_t>                                              freeDiagonal; // positions in Kff
  Eigen::CholmodSupernodalLLT<Eigen::SparseMatrix<double>, Eigen::Lower> solver;
  bool                                                                   analyzed{ false };
  bool haveFactorization{ false };  // the solver holds a factorization of a recent tangent (this constrained set)
  bool factorizationExact{ false }; // ... of the current tangent, unshifted: solves are direct
  bool refactorNext{ false };       // the last preconditioned solve was slow: factorize before the next one
  unsigned int iterationsAtThisTangent{ 0 }; // CG iterations spent on the current tangent (repeated solves)
  // The last equilibrium and its loads (the warm start), and the tangent's state.
  bool                hasState{ false };
  std::vector<double> state, stateForces, statePrescribed;
  NewtonStatistics    statistics;
  SolverWork          earlierWork; // of the solves before the one \a statistics describes
  std::string         lastFailure;

  Impl(const TetrahedralMesh & m, const std::map<std::int32_t, MaterialParameters> & mats, const NewtonSettings & s);

  /** The work of every solve so far: the earlier ones and the current statistics (its adjoints included). */
  SolverWork
  Work() const
  {
    SolverWork w = earlierWork;
    w.newtonIterations += statistics.iterations;
    w.factorizations += statistics.factorizations;
    w.conjugateGradientIterations += statistics.conjugateGradientIterations;
    w.rejectedIncrements += statistics.rejectedIncrements;
    return w;
  }

  // Setup.
  void
  ValidateMaterials() const;
  void
  ComputeGeometry();
  void
  UpdateLameParameters();
  void
  BuildPatternAndEntries();
  // Assembly.
  bool
  Deform(std::size_t e, const std::vector<double> & u, fem::ElementDeformation & d) const;
  double
  Energy(const std::vector<double> & u, std::int64_t * worst = nullptr, double * worstJ = nullptr) const;
  std::vector<double>
  Forces(const std::vector<double> & u, std::int32_t onlyLabel = -1) const;
  void
  AssembleTangent(const std::vector<double> & u);
  // Solve.
  void
  CopyTangentToFreeBlock();
  bool
  Factorize(bool allowShift);
  bool
  PreconditionedCG(const Eigen::VectorXd & b, Eigen::VectorXd & x, unsigned int & iterations, double tolerance) const;
  bool
  SolveTangent(const std::vector<double> & rhs, std::vector<double> & out, bool exact, double tolerance = 1e-12);
  bool
  NewtonStep(const std::vector<double> & u,
             const std::vector<double> & r,
             const std::vector<double> & step,
             double                      forcing,
             std::vector<double> &       du);
  bool
  LineSearch(std::vector<double> &       u,
             const std::vector<double> & du,
             const std::vector<double> & f,
             double                      decrement,
             bool                        jump,
             IncrementFailure &          failure) const;
  bool
  NewtonIncrement(std::vector<double> &       u,
                  const std::vector<double> & f,
                  const std::vector<double> & prescribed,
                  IncrementFailure &          failure);
  bool
  FollowPath(std::vector<double> &       u,
             const std::vector<double> & f0,
             const std::vector<double> & g0,
             const std::vector<double> & f1,
             const std::vector<double> & g1,
             double &                    reached,
             IncrementFailure &          failure);
};

// ---------------------------------------------------------------------------------------------- setup

NeoHookeanForwardModel::Impl::Impl(const TetrahedralMesh &                            m,
                                   const std::map<std::int32_t, MaterialParameters> & mats,
                                   const NewtonSettings &                             s)
  : mesh(m)
  , materials(mats)
  , settings(s)
  , ndof(3 * m.GetNumberOfPoints())
{
  ValidateMaterials();
  for (std::size_t e = 0; e < mesh.GetNumberOfTetrahedra(); ++e)
  {
    if (materials.find(mesh.labels[e]) == materials.end())
    {
      std::ostringstream msg;
      msg << "element " << e << " has label " << mesh.labels[e] << ", which has no material (E, nu) in the scene";
      Fail(kWho, msg.str());
    }
  }
  ValidateMesh(mesh);
  ComputeGeometry();
  UpdateLameParameters();
  BuildPatternAndEntries();
  constrained.assign(ndof, 0);
  passive.assign(mesh.GetNumberOfTetrahedra(), 0);
  // A tangent that is not positive definite is expected (and shifted) here: no CHOLMOD warning on stdout.
  solver.cholmod().print = 0;
}

void
NeoHookeanForwardModel::Impl::ValidateMaterials() const
{
  for (const auto & kv : materials)
  {
    const MaterialParameters & m = kv.second;
    std::ostringstream         msg;
    msg << fem::MaterialProblem(kv.first, m.youngsModulus, m.poissonRatio);
    if (msg.str().empty() && m.formulation != ElementFormulationEnum::Standard)
    {
      msg << "label " << kv.first << ": the neo-Hookean model has only the standard P1 formulation (got "
          << m.formulation << "); use the linear model for the nodal-averaged pressure";
    }
    if (!msg.str().empty())
    {
      Fail(kWho, msg.str());
    }
  }
  if (!(settings.residualTolerance > 0.0 && settings.energyTolerance >= 0.0 && settings.maximumIterations > 0 &&
        settings.initialIncrement > 0.0 && settings.initialIncrement <= 1.0 && settings.minimumIncrement > 0.0 &&
        settings.minimumIncrement <= settings.initialIncrement))
  {
    Fail(kWho, "Newton settings out of range (tolerances > 0, 0 < minimum increment <= initial increment <= 1)");
  }
}

void
NeoHookeanForwardModel::Impl::ComputeGeometry()
{
  const std::size_t M = mesh.GetNumberOfTetrahedra();
  gradients.resize(M);
  volumes.resize(M);
  for (std::size_t e = 0; e < M; ++e)
  {
    double g[4][3];
    volumes[e] = fem::ElementGradients(mesh, e, g);
    std::copy(&g[0][0], &g[0][0] + 12, gradients[e].begin());
  }
}

void
NeoHookeanForwardModel::Impl::UpdateLameParameters()
{
  const std::size_t M = mesh.GetNumberOfTetrahedra();
  mu.resize(M);
  lambda.resize(M);
  for (std::size_t e = 0; e < M; ++e)
  {
    const MaterialParameters & m = materials.at(mesh.labels[e]);
    fem::LameParameters(m.youngsModulus, m.poissonRatio, lambda[e], mu[e]);
  }
}

void
NeoHookeanForwardModel::Impl::BuildPatternAndEntries()
{
  fem::NodeAdjacency upper = fem::ElementNodeAdjacency(mesh);
  fem::SortAdjacencyAndCheckNodesUsed(upper, kWho);
  pattern = fem::BuildColumnPattern(upper);
  const std::size_t M = mesh.GetNumberOfTetrahedra();
  elementEntries.assign(144 * M, -1);
  for (std::size_t e = 0; e < M; ++e)
  {
    const std::int32_t * t = &mesh.tetrahedra[4 * e];
    for (int a = 0; a < 4; ++a)
    {
      for (int b = 0; b < 4; ++b)
      {
        for (int i = 0; i < 3; ++i)
        {
          for (int k = 0; k < 3; ++k)
          {
            const std::size_t row = 3 * static_cast<std::size_t>(t[a]) + i;
            const std::size_t col = 3 * static_cast<std::size_t>(t[b]) + k;
            if (row >= col)
            {
              elementEntries[144 * e + 12 * (3 * a + i) + 3 * b + k] =
                static_cast<std::int64_t>(pattern.EntryIndex(row, col));
            }
          }
        }
      }
    }
  }
  tangent.assign(pattern.Size(), 0.0);
}

// ------------------------------------------------------------------------------------------- assembly

bool
NeoHookeanForwardModel::Impl::Deform(std::size_t e, const std::vector<double> & u, fem::ElementDeformation & d) const
{
  const std::int32_t * t = &mesh.tetrahedra[4 * e];
  const double * const ua[4] = { &u[3 * t[0]], &u[3 * t[1]], &u[3 * t[2]], &u[3 * t[3]] };
  return fem::DeformElement(reinterpret_cast<const double(*)[3]>(gradients[e].data()), ua, d);
}

double
NeoHookeanForwardModel::Impl::Energy(const std::vector<double> & u, std::int64_t * worst, double * worstJ) const
{
  double sum = 0.0, smallestJ = std::numeric_limits<double>::infinity();
  for (std::size_t e = 0; e < volumes.size(); ++e)
  {
    if (passive[e])
    {
      continue;
    }
    fem::ElementDeformation d;
    Deform(e, u, d);
    if (d.J < smallestJ)
    {
      smallestJ = d.J;
      if (worst)
      {
        *worst = static_cast<std::int64_t>(e);
      }
    }
    sum += volumes[e] * fem::StoredEnergyDensity(d, mu[e], lambda[e]);
  }
  if (worstJ)
  {
    *worstJ = smallestJ;
  }
  return sum;
}

std::vector<double>
NeoHookeanForwardModel::Impl::Forces(const std::vector<double> & u, std::int32_t onlyLabel) const
{
  std::vector<double> f(ndof, 0.0);
  for (std::size_t e = 0; e < volumes.size(); ++e)
  {
    if (onlyLabel >= 0 && mesh.labels[e] != onlyLabel)
    {
      continue;
    }
    fem::ElementDeformation d;
    if (!Deform(e, u, d) && passive[e])
    {
      continue; // inverted by the prescribed motion alone: no reaction to report
    }
    if (d.J <= 0.0)
    {
      std::ostringstream msg;
      msg << "element " << e << " is inverted (J = " << d.J << "): no neo-Hookean internal forces";
      Fail(kWho, msg.str());
    }
    double fe[4][3];
    fem::ElementForces(d, reinterpret_cast<const double(*)[3]>(gradients[e].data()), volumes[e], mu[e], lambda[e], fe);
    for (int a = 0; a < 4; ++a)
    {
      for (int i = 0; i < 3; ++i)
      {
        f[3 * mesh.tetrahedra[4 * e + a] + i] += fe[a][i];
      }
    }
  }
  return f;
}

void
NeoHookeanForwardModel::Impl::AssembleTangent(const std::vector<double> & u)
{
  std::fill(tangent.begin(), tangent.end(), 0.0);
  for (std::size_t e = 0; e < volumes.size(); ++e)
  {
    if (passive[e])
    {
      continue;
    }
    fem::ElementDeformation d;
    if (!Deform(e, u, d))
    {
      std::ostringstream msg;
      msg << "element " << e << " is inverted (J = " << d.J << "): no neo-Hookean tangent";
      Fail(kWho, msg.str());
    }
    double K[12][12];
    fem::ElementTangent(d, reinterpret_cast<const double(*)[3]>(gradients[e].data()), volumes[e], mu[e], lambda[e], K);
    const std::int64_t * entries = &elementEntries[144 * e];
    for (int r = 0; r < 12; ++r)
    {
      for (int c = 0; c < 12; ++c)
      {
        if (entries[12 * r + c] >= 0)
        {
          tangent[entries[12 * r + c]] += K[r][c];
        }
      }
    }
  }
  CopyTangentToFreeBlock();
  factorizationExact = false;
  iterationsAtThisTangent = 0;
}

// ---------------------------------------------------------------------------------------------- solve

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

// ------------------------------------------------------------------------------------------- interface

NeoHookeanForwardModel::NeoHookeanForwardModel(const TetrahedralMesh &                            mesh,
                                               const std::map<std::int32_t, MaterialParameters> & materials,
                                               const NewtonSettings &                             settings)
  : m_Impl(new Impl(mesh, materials, settings))
{
  m_Impl->AssembleTangent(std::vector<double>(m_Impl->ndof, 0.0));
}

NeoHookeanForwardModel::~NeoHookeanForwardModel() = default;

const TetrahedralMesh &
NeoHookeanForwardModel::GetMesh() const
{
  return m_Impl->mesh;
}

void
NeoHookeanForwardModel::SetConstrainedNodes(const std::vector<std::int32_t> & nodes)
{
  Impl &            d = *m_Impl;
  const std::size_t N = d.mesh.GetNumberOfPoints();
  d.constrained.assign(d.ndof, 0);
  for (std::int32_t n : nodes)
  {
    if (n < 0 || static_cast<std::size_t>(n) >= N)
    {
      Fail(kWho,
           "constrained node index " + std::to_string(n) + " is outside the mesh (" + std::to_string(N) + " nodes)");
    }
    d.constrained[3 * n] = d.constrained[3 * n + 1] = d.constrained[3 * n + 2] = 1;
  }
  fem::CheckRigidBodyModes(d.mesh, d.constrained, kWho);
  for (std::size_t e = 0; e < d.passive.size(); ++e)
  {
    const std::int32_t * t = &d.mesh.tetrahedra[4 * e];
    d.passive[e] =
      d.constrained[3 * t[0]] && d.constrained[3 * t[1]] && d.constrained[3 * t[2]] && d.constrained[3 * t[3]];
  }
  d.nfree = fem::NumberFreeDofs(d.constrained, d.freeIndex);
  d.Kff = fem::FreeBlock(d.pattern, d.tangent, d.freeIndex, d.nfree, &d.freePositions);
  d.freeDiagonal.clear();
  for (std::size_t i = 0; i < d.ndof; ++i)
  {
    if (d.freeIndex[i] >= 0)
    {
      d.freeDiagonal.push_back(d.freePositions[d.pattern.EntryIndex(i, i)]);
    }
  }
  d.analyzed = false;
  d.haveFactorization = d.factorizationExact = d.refactorNext = false;
  d.hasState = false;
}

void
NeoHookeanForwardModel::SetYoungsModulus(std::int32_t label, double youngsModulus)
{
  auto it = m_Impl->materials.find(label);
  if (it == m_Impl->materials.end())
  {
    Fail(kWho, "label " + std::to_string(label) + " has no material");
  }
  if (!(std::isfinite(youngsModulus) && youngsModulus > 0.0))
  {
    std::ostringstream msg;
    msg << "label " << label << ": Young's modulus must be positive and finite, got " << youngsModulus << " kPa";
    Fail(kWho, msg.str());
  }
  if (it->second.youngsModulus != youngsModulus)
  {
    it->second.youngsModulus = youngsModulus;
    m_Impl->UpdateLameParameters();
    m_Impl->AssembleTangent(m_Impl->hasState ? m_Impl->state : std::vector<double>(m_Impl->ndof, 0.0));
  }
}

double
NeoHookeanForwardModel::GetYoungsModulus(std::int32_t label) const
{
  auto it = m_Impl->materials.find(label);
  if (it == m_Impl->materials.end())
  {
    Fail(kWho, "label " + std::to_string(label) + " has no material");
  }
  return it->second.youngsModulus;
}

std::vector<double>
NeoHookeanForwardModel::SolveState(const std::vector<double> & forces, const std::vector<double> & prescribed)
{
  std::vector<double> u;
  if (!TrySolveState(forces, prescribed, u))
  {
    Fail(kWho, m_Impl->lastFailure);
  }
  return u;
}

bool
NeoHookeanForwardModel::TrySolveState(const std::vector<double> & forces,
                                      const std::vector<double> & prescribed,
                                      std::vector<double> &       u)
{
  Impl & d = *m_Impl;
  if ((!forces.empty() && forces.size() != d.ndof) || prescribed.size() != d.ndof)
  {
    Fail(kWho, "the force and prescribed displacement vectors must hold 3 values per node");
  }
  const auto          start = SteadyClock::now();
  std::vector<double> f1(d.ndof, 0.0), g1(d.ndof, 0.0);
  for (std::size_t i = 0; i < d.ndof; ++i)
  {
    const double value = d.constrained[i] ? prescribed[i] : (forces.empty() ? 0.0 : forces[i]);
    if (!std::isfinite(value))
    {
      Fail(kWho, "load at degree of freedom " + std::to_string(i) + " is not finite");
    }
    (d.constrained[i] ? g1 : f1)[i] = value;
  }
  d.earlierWork = d.Work();
  ++d.earlierWork.stateSolves;
  d.statistics = NewtonStatistics();
  IncrementFailure failure;
  double           reached = 0.0;
  bool             ok = false;
  if (d.hasState)
  {
    u = d.state;
    d.statistics.warmStart = true;
    ok = d.FollowPath(u, d.stateForces, d.statePrescribed, f1, g1, reached, failure);
  }
  if (!ok && (!d.hasState || d.settings.restartFromRest))
  {
    d.earlierWork.coldStarts += d.hasState; // a warm start was tried and failed
    d.statistics.warmStart = false;
    u.assign(d.ndof, 0.0);
    const std::vector<double> zero(d.ndof, 0.0);
    ok = d.FollowPath(u, zero, zero, f1, g1, reached, failure);
  }
  d.statistics.seconds = SecondsSince(start);
  if (!ok)
  {
    std::ostringstream msg;
    msg << "the loads could not be applied: equilibrium reached up to load fraction " << reached << " of 1, then "
        << failure.reason << " (smallest J " << failure.worstJ << " in element " << failure.worstElement;
    if (failure.worstElement >= 0)
    {
      // Which element, and whether its free nodes could have saved it: what a user needs to change the loads.
      const std::int32_t * t = &d.mesh.tetrahedra[4 * failure.worstElement];
      int                  prescribedNodes = 0;
      for (int a = 0; a < 4; ++a)
      {
        prescribedNodes += d.constrained[3 * t[a]];
      }
      msg << ", label " << d.mesh.labels[failure.worstElement] << ", " << prescribedNodes
          << " of its 4 nodes prescribed";
    }
    msg << ") with increments down to " << d.settings.minimumIncrement;
    d.lastFailure = msg.str();
    if (d.hasState)
    {
      d.AssembleTangent(d.state); // the tangent belongs to the last equilibrium again
    }
    return false;
  }
  d.state = u;
  d.stateForces = f1;
  d.statePrescribed = g1;
  d.hasState = true;
  d.AssembleTangent(u);
  return true;
}

std::vector<double>
NeoHookeanForwardModel::SolveAdjoint(const std::vector<double> & g)
{
  Impl & d = *m_Impl;
  if (g.size() != d.ndof)
  {
    Fail(kWho, "the adjoint right-hand side must hold 3 values per node");
  }
  if (!d.hasState)
  {
    Fail(kWho, "SolveAdjoint() needs an equilibrium: call SolveState() first");
  }
  if (d.nfree == 0)
  {
    return std::vector<double>(d.ndof, 0.0);
  }
  std::vector<double> lambda;
  d.SolveTangent(g, lambda, true);
  return lambda;
}

std::vector<double>
NeoHookeanForwardModel::ApplyTangent(const std::vector<double> & v) const
{
  if (v.size() != m_Impl->ndof)
  {
    Fail(kWho, "the vector must hold 3 values per node");
  }
  std::vector<double> y;
  fem::SymmetricProduct(m_Impl->pattern, m_Impl->tangent, v, y);
  return y;
}

std::vector<double>
NeoHookeanForwardModel::InternalForces(const std::vector<double> & u) const
{
  if (u.size() != m_Impl->ndof)
  {
    Fail(kWho, "the displacement vector must hold 3 values per node");
  }
  return m_Impl->Forces(u);
}

std::vector<double>
NeoHookeanForwardModel::ModulusDerivative(std::int32_t label, const std::vector<double> & u) const
{
  if (u.size() != m_Impl->ndof)
  {
    Fail(kWho, "the displacement vector must hold 3 values per node");
  }
  std::vector<double> f = m_Impl->Forces(u, label);
  const double        E = GetYoungsModulus(label);
  for (double & x : f)
  {
    x /= E;
  }
  return f;
}

double
NeoHookeanForwardModel::StoredEnergy(const std::vector<double> & u) const
{
  if (u.size() != m_Impl->ndof)
  {
    Fail(kWho, "the displacement vector must hold 3 values per node");
  }
  return m_Impl->Energy(u);
}

std::vector<double>
NeoHookeanForwardModel::FirstPiolaKirchhoffStress(const std::vector<double> & u) const
{
  const Impl & d = *m_Impl;
  if (u.size() != d.ndof)
  {
    Fail(kWho, "the displacement vector must hold 3 values per node");
  }
  std::vector<double> stress(9 * d.volumes.size());
  for (std::size_t e = 0; e < d.volumes.size(); ++e)
  {
    fem::ElementDeformation def;
    if (!d.Deform(e, u, def))
    {
      Fail(kWho, "element " + std::to_string(e) + " is inverted: no stress");
    }
    fem::FirstPiolaStress(def, d.mu[e], d.lambda[e], reinterpret_cast<double(*)[3]>(&stress[9 * e]));
  }
  return stress;
}

std::vector<double>
NeoHookeanForwardModel::VonMisesStress(const std::vector<double> & u) const
{
  return NeoHookeanVonMisesStress(m_Impl->mesh, m_Impl->materials, u);
}

std::vector<double>
NeoHookeanVonMisesStress(const TetrahedralMesh &                            mesh,
                         const std::map<std::int32_t, MaterialParameters> & materials,
                         const std::vector<double> &                        u)
{
  if (u.size() != 3 * mesh.GetNumberOfPoints())
  {
    Fail(kWho, "the displacement vector must hold 3 values per node");
  }
  std::vector<double> vonMises(mesh.GetNumberOfTetrahedra(), 0.0);
  for (std::size_t e = 0; e < vonMises.size(); ++e)
  {
    double                  g[4][3], mu, lambda, P[3][3], sigma[3][3];
    const std::int32_t *    t = &mesh.tetrahedra[4 * e];
    const double * const    ua[4] = { &u[3 * t[0]], &u[3 * t[1]], &u[3 * t[2]], &u[3 * t[3]] };
    fem::ElementDeformation def;
    fem::ElementGradients(mesh, e, g);
    if (!fem::DeformElement(g, ua, def))
    {
      continue; // 0: an element inverted by prescribed motion alone (see the class documentation)
    }
    const MaterialParameters & m = materials.at(mesh.labels[e]);
    fem::LameParameters(m.youngsModulus, m.poissonRatio, lambda, mu);
    fem::FirstPiolaStress(def, mu, lambda, P);
    for (int i = 0; i < 3; ++i)
    {
      for (int j = 0; j < 3; ++j)
      {
        sigma[i][j] = (P[i][0] * def.F[j][0] + P[i][1] * def.F[j][1] + P[i][2] * def.F[j][2]) / def.J;
      }
    }
    vonMises[e] = fem::VonMises(sigma);
  }
  return vonMises;
}

void
NeoHookeanForwardModel::ForgetState()
{
  // The factorization too: it preconditions the next solves, whose last bits would depend on it.
  m_Impl->hasState = false;
  m_Impl->haveFactorization = m_Impl->factorizationExact = m_Impl->refactorNext = false;
}

const std::string &
NeoHookeanForwardModel::GetLastFailure() const
{
  return m_Impl->lastFailure;
}

const NewtonStatistics &
NeoHookeanForwardModel::GetStatistics() const
{
  return m_Impl->statistics;
}

SolverWork
NeoHookeanForwardModel::GetSolverWork() const
{
  return m_Impl->Work();
}

} // namespace bmr
