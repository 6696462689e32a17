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
// Internal to src/fem: LinearElasticModel's state (its Impl), shared by the model's assembly, solve and interface.
#ifndef bmrLinearElasticModelInternal_h
#define bmrLinearElasticModelInternal_h

// The system Eigen 3.4 and CHOLMOD are used only in src/fem; no ITK header that bundles ITK's own Eigen may be
// included here.
#include "bmrLinearElasticModel.h"

#include "bmrError.h"
#include "bmrFemAssembly.h"
#include "bmrSupernodalFactorize.h"
#include "bmrSupernodalSolve.h"

#include <Eigen/CholmodSupport>
#include <Eigen/SparseCore>

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <map>
#include <set>
#include <string>
#include <vector>

namespace bmr {

struct LinearElasticModel::Impl
{
  /** CHOLMOD's supernodal LL^T through Eigen, with its factor readable (for fem::SupernodalSolver). */
  class SupernodalLLT : public Eigen::CholmodSupernodalLLT<Eigen::SparseMatrix<double>, Eigen::Lower>
  {
  public:
    cholmod_factor *
    Factor()
    {
      return this->m_cholmodFactor;
    }
  };

  const TetrahedralMesh &                     mesh;
  std::map<std::int32_t, MaterialParameters>  materials;
  std::size_t                                 ndof{ 0 };
  fem::LowerPattern                           pattern;              // of the full 3N x 3N stiffness
  std::map<std::int32_t, std::vector<double>> unitValues;           // Khat_m per label, on the shared pattern
  bool                                        accumulated{ false }; // unitValues and values allocated and summed
  std::vector<double>                         values;               // sum_m E_m Khat_m
  bool                                        valuesCurrent{ false };
  std::vector<char>                           constrained;
  std::vector<double>                         prescribed; // 3N
  std::vector<std::int32_t>                   freeIndex;  // dof -> free index or -1
  fem::CouplingRows                           coupling;   // the free-constrained block, by row
  bool                                        couplingCurrent{ false };
  bool                                        freeBlockCurrent{ false };   // Kff holds the current values
  bool                                        freePatternCurrent{ false }; // Kff and freePositions: this analysis
  std::vector<std::int64_t>                   freePositions; // of each pattern entry in Kff's values, or -1
  std::size_t                                 nfree{ 0 };
  Eigen::SparseMatrix<double>                 Kff;
  SupernodalLLT                               solver;
  fem::SupernodalSolver                       triangular;                // solves with solver's factor
  fem::SupernodalFactorizer                   factorizer;                // computes solver's factor
  bool                                        triangularCut{ false };    // its tree cut for the current analysis
  bool                                        ownFactorization{ false }; // factorizer set for the current analysis
  bool                                        triangularReady{ false };  // and the factor computed
  bool                                        referenceOnly{ false };    // CHOLMOD's factorization and solves
  unsigned                                    solveThreads{ 1 };
  bool                                        analyzed{ false };
  bool                                        factorized{ false };
  SolverTimings                               timings;
  // The factorization of K_ff at factorModuli, kept when the moduli change by less than refactorizeAbove:
  // Solve() then iterates with it as the preconditioner (PreconditionedSolve) instead of refactorizing. Before the
  // first factorization factorModuli holds the moduli the model was built with.
  bool                           hasFactor{ false };
  std::map<std::int32_t, double> factorModuli;
  double                         refactorizeAbove{ 0.003 };
  // The labels whose moduli the factorizer's kept fixed part leaves out (fem::SupernodalFactorizer::
  // FactorizeVarying), the other labels' moduli it was computed with, and the two parts' values on K_ff.
  std::set<std::int32_t>         varyingLabels;
  std::map<std::int32_t, double> fixedPartModuli;
  std::vector<double>            fixedFree, varyingFree;
  double                         refactorizedShare{ 0.0 }; // of the last factorization's work

  explicit Impl(const TetrahedralMesh & m)
    : mesh(m)
  {}

  /** The elements of one material around one node, and their nodes (sorted): the support of the node's
   * averaged volumetric strain in the nodal-averaged pressure formulation. */
  struct AveragingPatch
  {
    std::int32_t              label{ 0 };
    std::vector<std::int32_t> elements;
    std::vector<std::int32_t> nodes;
  };
  std::vector<AveragingPatch> patches; // of the averaged materials, until their bulk stiffness is accumulated

  std::vector<AveragingPatch>
  BuildAveragingPatches() const;
  void
  BuildPattern();
  /** The element stiffnesses on the pattern (unitValues), once: deferred from the construction to the first use,
   * so that Analyze() can compute them alongside the fill-reducing order. */
  void
  AccumulateStiffnesses();
  // Pieces of BuildPattern.
  using NodeAdjacency = fem::NodeAdjacency;
  static void
  AddPatchNodeCouplings(const std::vector<AveragingPatch> & patches, NodeAdjacency & upper);
  void
  AccumulateUnitElementStiffnesses();
  void
  AccumulateAveragedBulkStiffnesses(const std::vector<AveragingPatch> & patches);
  void
  CheckElements() const;
  void
  UpdateValues();
  /** unitValues of \a label, accumulated first if they are not yet. */
  const std::vector<double> &
  UnitValues(std::int32_t label);
  void
  SymmetricProduct(const std::vector<double> & x, std::vector<double> & y) const
  {
    fem::SymmetricProduct(pattern, values, x, y);
  }
  /** K_ff with the current moduli, rebuilt only when they or the constrained set changed. */
  void
  UpdateFreeBlock()
  {
    UpdateValues();
    if (freeBlockCurrent)
    {
      return;
    }
    if (freePatternCurrent)
    {
      double * entries = Kff.valuePtr();
      for (std::size_t k = 0; k < values.size(); ++k)
      {
        if (freePositions[k] >= 0)
        {
          entries[freePositions[k]] = values[k];
        }
      }
    }
    else
    {
      Kff = fem::FreeBlock(pattern, values, freeIndex, nfree, &freePositions);
      freePatternCurrent = true;
    }
    freeBlockCurrent = true;
  }
  int
  FactorizeOwn();
  void
  SplitFreeValues(bool varyingOnly);
  std::vector<char>
  VaryingEntries() const;
  /** Whether every modulus lies within refactorizeAbove (relative) of the kept factorization's. */
  bool
  FactorStillPreconditions() const
  {
    if (!hasFactor || refactorizeAbove <= 0.0)
    {
      return false;
    }
    for (const auto & [label, material] : materials)
    {
      if (!(std::abs(std::log(material.youngsModulus / factorModuli.at(label))) <= std::log1p(refactorizeAbove)))
      {
        return false;
      }
    }
    return true;
  }
  /** After an analysis: the factor's values allocated, its elimination tree cut (fem::SupernodalSolver) and
   * K_ff's entries placed in it (fem::SupernodalFactorizer); CHOLMOD's own factorization and solves stay for a
   * factor these do not take. */
  void
  CutTree()
  {
    cholmod_factor * factor = solver.Factor();
    if (factor != nullptr && factor->is_super && factor->xtype == CHOLMOD_PATTERN)
    {
      cholmod_change_factor(CHOLMOD_REAL, true, true, true, true, factor, &solver.cholmod());
    }
    triangularCut = !referenceOnly && triangular.SetFactor(factor);
    Kff.makeCompressed();
    ownFactorization = triangularCut && factorizer.SetStructure(factor,
                                                                solver.cholmod(),
                                                                static_cast<int>(nfree),
                                                                Kff.outerIndexPtr(),
                                                                Kff.innerIndexPtr(),
                                                                triangular.GetBins());
  }
  bool
  PreconditionedSolve(const Eigen::VectorXd & b, Eigen::VectorXd & x);
  /** The prescribed displacements on the constrained dofs (0 elsewhere), each checked finite. */
  std::vector<double>
  ConstrainedValues(const std::vector<double> & prescribedAll) const;
  /** f - K g on the free dofs, in their numbering, for the forces \a forces (checked finite) and the prescribed
   * displacements \a prescribed (0 on the free dofs). */
  Eigen::VectorXd
  FreeRightHandSide(const std::vector<double> & forces, const std::vector<double> & prescribed);
  /** K_ff^-1 b with the current factorization: fem::SupernodalSolver on solveThreads threads (the same result on
   * any number), or CHOLMOD's own solve for a factor it does not take. */
  Eigen::VectorXd
  TriangularSolve(const Eigen::VectorXd & b, const std::vector<std::int32_t> * observedFree = nullptr)
  {
    if (!triangularReady)
    {
      return solver.solve(b);
    }
    Eigen::VectorXd x(b.size());
    if (observedFree != nullptr)
    {
      triangular.Solve(b.data(), x.data(), solveThreads, *observedFree);
    }
    else
    {
      triangular.Solve(b.data(), x.data(), solveThreads);
    }
    return x;
  }
  /** The free indices of the free dofs among \a dofs (3N indices; throws on one out of range). */
  std::vector<std::int32_t>
  FreeIndices(const std::vector<std::int32_t> & dofs) const
  {
    std::vector<std::int32_t> free;
    free.reserve(dofs.size());
    for (const std::int32_t dof : dofs)
    {
      if (dof < 0 || static_cast<std::size_t>(dof) >= ndof)
      {
        Fail("LinearElasticModel::Solve", "observed degree of freedom " + std::to_string(dof) + " is out of range");
      }
      if (freeIndex[dof] >= 0)
      {
        free.push_back(freeIndex[dof]);
      }
    }
    return free;
  }

  /** The free-constrained block's pattern, built once per constrained set. */
  const fem::CouplingRows &
  Coupling()
  {
    if (!couplingCurrent)
    {
      coupling = fem::BuildCouplingRows(pattern, constrained);
      couplingCurrent = true;
    }
    return coupling;
  }
  /** K_fc x_c at the free dofs (\a constrainedRows false) or K_cf x_f at the constrained ones (true). */
  void
  CouplingProduct(const std::vector<double> & x, bool constrainedRows, std::vector<double> & y)
  {
    Coupling();
    UpdateValues();
    fem::CouplingProduct(coupling, values, constrained, constrainedRows, x, y);
  }
};

} // namespace bmr

#endif
