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
// LinearElasticModel's analysis, factorization (own supernodal or CHOLMOD's) and solves.
#include "bmrLinearElasticModelInternal.h"

#include "bmrParallel.h"
#include "bmrStopwatch.h"

#include <algorithm>
#include <cmath>
#include <utility>

namespace bmr {
using Clock = SteadyClock;

/** Conjugate gradients on K_ff x = b preconditioned with the kept factorization of K_ff(E_f). With every modulus
 * within a factor 1 + t of E_f, K(E) = sum_m E_m Khat_m gives x^T K(E) x / x^T K(E_f) x in [1/(1+t), 1+t], so the
 * preconditioned matrix has condition number at most (1 + t)^2 and the error falls by at least
 * (sqrt(kappa) - 1) / (sqrt(kappa) + 1) = t / (2 + t) per iteration: for t = 1 %, from 1 % after the first solve to
 * the tolerance, 1e-13 of |x|, in at most about 5 iterations (3 for the demo's last step of 0.2 % in E), each a pair
 * of triangular solves and a product with K_ff. The stopping test is the preconditioned residual |M^-1 r|, which is
 * the error to within that same factor: the direct solve's accuracy, not the residual's. Sequential and in a fixed
 * order: deterministic. False (x then undefined) when 8 iterations do not reach the tolerance. */
bool
LinearElasticModel::Impl::PreconditionedSolve(const Eigen::VectorXd & b, Eigen::VectorXd & x)
{
  UpdateFreeBlock();
  const auto       K = Kff.selfadjointView<Eigen::Lower>();
  constexpr int    maximumIterations = 8;
  constexpr double tolerance = 1e-13;
  x = TriangularSolve(b);
  Eigen::VectorXd r = b - K * x;
  Eigen::VectorXd z = TriangularSolve(r);
  Eigen::VectorXd p = z;
  double          rz = r.dot(z);
  for (int k = 0; k < maximumIterations; ++k)
  {
    if (!(z.norm() > tolerance * x.norm()))
    {
      return x.allFinite();
    }
    const Eigen::VectorXd q = K * p;
    const double          alpha = rz / p.dot(q);
    x += alpha * p;
    r -= alpha * q;
    z = TriangularSolve(r);
    const double next = r.dot(z);
    p = z + (next / rz) * p;
    rz = next;
  }
  return !(z.norm() > tolerance * x.norm()) && x.allFinite();
}

/** K_ff = L L^T by fem::SupernodalFactorizer. When only the moduli of varyingLabels changed since its kept fixed part
 * was computed, only the supernodes they reach are refactorized (on the 140k pelvis, 49.5 % of the work for the
 * prostate). Otherwise the labels whose moduli changed since the last factorization (before the first: since the
 * model was built, as an estimator sets its start moduli) become varyingLabels, as an estimator changes the same
 * unknown moduli again and again, and the whole factor is computed, keeping the new fixed part; with no change to
 * learn from, it is the plain factorization. */
int
LinearElasticModel::Impl::FactorizeOwn()
{
  bool fixedPartHolds = factorizer.HasFixedPart() && !varyingLabels.empty();
  for (const auto & [label, material] : materials)
  {
    const auto kept = fixedPartModuli.find(label);
    fixedPartHolds = fixedPartHolds && (varyingLabels.count(label) > 0 ||
                                        (kept != fixedPartModuli.end() && kept->second == material.youngsModulus));
  }
  if (fixedPartHolds)
  {
    SplitFreeValues(true);
    refactorizedShare = factorizer.GetVaryingShare();
    return factorizer.FactorizeVarying(varyingFree.data(), solveThreads);
  }
  refactorizedShare = 1.0;
  varyingLabels.clear();
  for (const auto & [label, material] : materials)
  {
    const auto factored = factorModuli.find(label);
    if (factored != factorModuli.end() && factored->second != material.youngsModulus)
    {
      varyingLabels.insert(label);
    }
    fixedPartModuli[label] = material.youngsModulus;
  }
  factorizer.SetVaryingEntries(VaryingEntries());
  if (varyingLabels.empty())
  {
    return factorizer.Factorize(Kff.valuePtr(), solveThreads);
  }
  SplitFreeValues(false);
  const int factorized = factorizer.Factorize(fixedFree.data(), varyingFree.data(), solveThreads);
  std::vector<double>().swap(fixedFree); // kept by the factorizer where it is needed again
  return factorized;
}

/** K_ff's values split into varyingLabels' sum_m E_m Khat_m (varyingFree) and, unless \a varyingOnly, the other
 * labels' (fixedFree), each summed in label order like Impl::values. */
void
LinearElasticModel::Impl::SplitFreeValues(bool varyingOnly)
{
  const auto entries = static_cast<std::size_t>(Kff.nonZeros());
  varyingFree.assign(entries, 0.0);
  if (!varyingOnly)
  {
    fixedFree.assign(entries, 0.0);
  }
  for (const auto & [label, unit] : unitValues)
  {
    const bool varies = varyingLabels.count(label) > 0;
    if (varyingOnly && !varies)
    {
      continue;
    }
    std::vector<double> & target = varies ? varyingFree : fixedFree;
    const double          E = materials.at(label).youngsModulus;
    for (std::size_t k = 0; k < unit.size(); ++k)
    {
      if (freePositions[k] >= 0)
      {
        target[freePositions[k]] += E * unit[k];
      }
    }
  }
}

/** Which entries of K_ff a modulus of varyingLabels enters (a nonzero unit stiffness there). */
std::vector<char>
LinearElasticModel::Impl::VaryingEntries() const
{
  std::vector<char> varies;
  if (varyingLabels.empty())
  {
    return varies;
  }
  varies.assign(static_cast<std::size_t>(Kff.nonZeros()), 0);
  for (const std::int32_t label : varyingLabels)
  {
    const auto found = unitValues.find(label);
    if (found == unitValues.end())
    {
      continue;
    }
    const std::vector<double> & unit = found->second;
    for (std::size_t k = 0; k < unit.size(); ++k)
    {
      if (unit[k] != 0.0 && freePositions[k] >= 0)
      {
        varies[freePositions[k]] = 1;
      }
    }
  }
  return varies;
}

void
LinearElasticModel::Analyze()
{
  Impl & d = *m_Impl;
  if (d.analyzed)
  {
    return;
  }
  const fem::SingleThreadedCholmod serial;
  auto                             t0 = Clock::now();
  fem::CheckRigidBodyModes(d.mesh, d.constrained, "LinearElasticModel");
  d.timings.assemble += SecondsSince(t0);
  t0 = Clock::now();
  // Two tasks on the solves' budget (side by side when it has two threads, else one after the other): the
  // fill-reducing order from the node graph (nine times fewer edges than CHOLMOD's dof graph), given to CHOLMOD as
  // the free dofs' numbering, and the element stiffnesses' sums. Neither reads what the other writes.
  const bool accumulate = !d.accumulated;
  bmr::ParallelFor(
    "analysis: ordering beside the stiffness sums", accumulate ? 2 : 1, d.solveThreads, [&d](int task, int) {
      if (task == 1)
      {
        d.AccumulateStiffnesses();
        return;
      }
      const auto serialized = fem::LockOrdering();
      d.nfree = fem::NumberFreeDofsByNestedDissection(d.pattern, d.constrained, d.freeIndex);
    });
  d.freePatternCurrent = false; // K_ff in the new numbering
  d.freeBlockCurrent = false;
  if (d.nfree == 0)
  {
    d.analyzed = true;
    d.timings.analyze = SecondsSince(t0);
    return;
  }
  const double ordering = SecondsSince(t0);
  t0 = Clock::now();
  d.UpdateFreeBlock();
  d.timings.assemble += SecondsSince(t0);
  t0 = Clock::now();
  fem::OrderAsNumbered(d.solver.cholmod());
  d.solver.analyzePattern(d.Kff);
  d.triangularCut = false;
  d.ownFactorization = false;
  d.analyzed = true;
  d.timings.analyze = ordering + SecondsSince(t0);
}

void
LinearElasticModel::Factorize()
{
  Impl & d = *m_Impl;
  if (d.factorized)
  {
    return;
  }
  Analyze();
  if (d.nfree == 0)
  {
    d.factorized = true;
    return;
  }
  const fem::SingleThreadedCholmod serial;
  auto                             t0 = Clock::now();
  d.UpdateFreeBlock();
  d.timings.assemble += SecondsSince(t0);
  t0 = Clock::now();
  d.hasFactor = false;
  d.triangularReady = false;
  // The tree is cut once per analysis: a refactorization keeps the factor's structure.
  if (!d.triangularCut || (d.ownFactorization && d.factorizer.GetNumberOfEntries() != d.Kff.nonZeros()))
  {
    d.CutTree();
  }
  bool positiveDefinite = true;
  if (d.ownFactorization)
  {
    positiveDefinite = d.FactorizeOwn() == static_cast<int>(d.nfree);
  }
  else
  {
    d.refactorizedShare = 1.0;
    d.solver.factorize(d.Kff);
    positiveDefinite = d.solver.info() == Eigen::Success;
  }
  d.timings.factorize = SecondsSince(t0);
  if (!positiveDefinite)
  {
    Fail("LinearElasticModel::Factorize",
         "the stiffness matrix is not positive definite (the Cholesky factorization failed): the model is singular "
         "or ill-conditioned; check the fixed labels and the element quality");
  }
  d.factorized = true;
  d.hasFactor = true;
  d.triangularReady = d.triangularCut;
  for (const auto & [label, material] : d.materials)
  {
    d.factorModuli[label] = material.youngsModulus;
  }
}

double
LinearElasticModel::GetRefactorizedShare() const
{
  return m_Impl->refactorizedShare;
}

bool
LinearElasticModel::IsFactorized() const
{
  return m_Impl->factorized;
}

std::vector<double>
LinearElasticModel::Solve(const std::vector<double> & forces)
{
  return Solve(forces, m_Impl->prescribed);
}

std::vector<double>
LinearElasticModel::Solve(const std::vector<double> & forces, const std::vector<double> & prescribedAll)
{
  return SolveObserving(forces, prescribedAll, nullptr);
}

std::vector<double>
LinearElasticModel::Solve(const std::vector<double> &       forces,
                          const std::vector<double> &       prescribedAll,
                          const std::vector<std::int32_t> & observedDofs)
{
  return SolveObserving(forces, prescribedAll, &observedDofs);
}

std::vector<std::int32_t>
LinearElasticModel::GetCoupledFreeDegreesOfFreedom(const std::vector<std::int32_t> & nodes) const
{
  Impl &                    d = *m_Impl;
  const fem::CouplingRows & coupling = d.Coupling();
  std::vector<std::int32_t> coupled;
  for (const std::int32_t node : nodes)
  {
    for (std::size_t i = 3 * static_cast<std::size_t>(node); i < 3 * static_cast<std::size_t>(node) + 3; ++i)
    {
      if (i < d.ndof && d.constrained[i])
      {
        coupled.insert(coupled.end(),
                       coupling.column.begin() + coupling.rowStart[i],
                       coupling.column.begin() + coupling.rowStart[i + 1]);
      }
    }
  }
  return UniqueNodes(std::move(coupled));
}

std::vector<double>
LinearElasticModel::Impl::ConstrainedValues(const std::vector<double> & prescribedAll) const
{
  std::vector<double> prescribed(ndof, 0.0);
  for (std::size_t i = 0; i < ndof; ++i)
  {
    if (constrained[i])
    {
      if (!std::isfinite(prescribedAll[i]))
      {
        Fail("LinearElasticModel::Solve",
             "prescribed displacement at degree of freedom " + std::to_string(i) + " is not finite");
      }
      prescribed[i] = prescribedAll[i];
    }
  }
  return prescribed;
}

Eigen::VectorXd
LinearElasticModel::Impl::FreeRightHandSide(const std::vector<double> & forces, const std::vector<double> & prescribed)
{
  // Only the free rows of K g are read and g vanishes on the free dofs: the coupling block K_fc g_c gives them
  // bit for bit (fem::CouplingProduct), and nothing when g = 0 (an adjoint).
  std::vector<double> Kg(ndof, 0.0);
  if (std::any_of(prescribed.begin(), prescribed.end(), [](double v) { return v != 0.0; }))
  {
    CouplingProduct(prescribed, false, Kg);
  }
  Eigen::VectorXd b(static_cast<Eigen::Index>(nfree));
  for (std::size_t i = 0; i < ndof; ++i)
  {
    const std::int32_t f = freeIndex[i];
    if (f >= 0)
    {
      const double fi = forces.empty() ? 0.0 : forces[i];
      if (!std::isfinite(fi))
      {
        Fail("LinearElasticModel::Solve", "force at degree of freedom " + std::to_string(i) + " is not finite");
      }
      b[f] = fi - Kg[i];
    }
  }
  return b;
}

std::vector<double>
LinearElasticModel::SolveObserving(const std::vector<double> &       forces,
                                   const std::vector<double> &       prescribedAll,
                                   const std::vector<std::int32_t> * observedDofs)
{
  Impl &                           d = *m_Impl;
  const fem::SingleThreadedCholmod serial;
  if (!forces.empty() && forces.size() != d.ndof)
  {
    Fail("LinearElasticModel::Solve", "the force vector must hold 3 values per node");
  }
  if (prescribedAll.size() != d.ndof)
  {
    Fail("LinearElasticModel::Solve", "the prescribed displacement vector must hold 3 values per node");
  }
  std::vector<double> prescribed = d.ConstrainedValues(prescribedAll);
  // A small change of the moduli since the last factorization is solved with it as the preconditioner.
  const bool iterate = !d.factorized && d.nfree > 0 && d.analyzed && d.FactorStillPreconditions();
  if (!iterate)
  {
    Factorize();
  }
  const std::vector<std::int32_t> observedFree =
    observedDofs ? d.FreeIndices(*observedDofs) : std::vector<std::int32_t>{};
  const auto            t0 = Clock::now();
  const Eigen::VectorXd b = d.FreeRightHandSide(forces, prescribed);
  std::vector<double>   u(std::move(prescribed));
  if (d.nfree > 0)
  {
    Eigen::VectorXd x;
    // Conjugate gradients need every dof of each iterate; a direct solve only the observed ones (and their
    // ancestors in the elimination tree).
    if (!iterate || !d.PreconditionedSolve(b, x))
    {
      Factorize();
      x = d.TriangularSolve(b, observedDofs ? &observedFree : nullptr);
    }
    if (d.solver.info() != Eigen::Success || !x.allFinite())
    {
      Fail("LinearElasticModel::Solve", "the triangular solves failed or produced non-finite displacements");
    }
    for (std::size_t i = 0; i < d.ndof; ++i)
    {
      if (d.freeIndex[i] >= 0)
      {
        u[i] = x[d.freeIndex[i]];
      }
    }
  }
  d.timings.solve = SecondsSince(t0);
  return u;
}

} // namespace bmr
