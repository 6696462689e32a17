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
#ifndef bmrSupernodalSolve_h
#define bmrSupernodalSolve_h

// The triangular solves of a CHOLMOD supernodal Cholesky factor on a thread budget (private to src/fem).
#include <cholmod.h>

#include <cstdint>
#include <vector>

namespace bmr {
namespace fem {

/** \brief Solves A x = b with a supernodal CHOLMOD factor L L^T = P A P^T, its elimination tree cut into a fixed
 * number of bins that run side by side, with the same result bit for bit on any number of threads.
 *
 * The forward solve L y = P b visits the supernodes children first; supernode s solves its diagonal block,
 * \f$ y_s \leftarrow L_{ss}^{-1} y_s \f$, and subtracts \f$ L_{rs} y_s \f$ from the rows r below it, which are
 * its ancestors in the elimination tree. The backward solve \f$ L^T z = y \f$ visits them parents first,
 * \f$ z_s = L_{ss}^{-T} (y_s - L_{rs}^T z_r) \f$, and x = P^T z. Disjoint subtrees touch disjoint rows except their
 * common ancestors', so the tree is cut once (SetFactor()): the "top" supernodes, ancestors of everything else,
 * and below them subtrees dealt to NumberOfBins bins of about equal size (the parts of the nested-dissection order,
 * split further where that balances them). The number of bins is a constant, not the thread count: each bin's
 * forward solve adds what it subtracts from the top's rows into its own accumulator; the top then takes the bins'
 * in bin order and is solved alone; the backward solve does the top first, then the bins, which only read the
 * top's rows. Every value is computed by the same operations in the same order whether the bins run one after the
 * other or all at once: the result does not depend on the thread count (and differs from CHOLMOD's own solve only
 * by rounding).
 *
 * Sparse right-hand sides and partial solutions: a supernode that no nonzero of P b reaches (in its own rows or a
 * descendant's) keeps y_s = 0, and the forward solve skips it; with observed rows (the second Solve()) the backward
 * solve computes only their supernodes and those supernodes' ancestors, which are all their z_s depends on. On the
 * demo pair's fine mesh (78,642 free dofs, a 252 MB factor) an estimation's state solve (loads on the walls, state
 * read on the organ surfaces and the prostate) reads 66 % of the factor forward and 33 % backward, its adjoint solve
 * (residuals on the surfaces, read next to the loaded walls and in the prostate) 33 % and 67 %: two passes over the
 * factor per evaluation instead of four.
 *
 * Bandwidth-bound: each solve reads the factor twice, so threads help until they share the memory bandwidth. The
 * block operations are
 * plain loops over four columns at a time (no BLAS, whose threading would change the order of sums); the dot
 * products sum their even and odd terms apart, in a fixed order. */
class SupernodalSolver
{
public:
  /** Reads the supernodal structure of \a factor (LL^T, real, int indices; false otherwise, and Solve() must not be
   * called) and cuts its tree. The factor must stay alive; its values may change (a refactorization on the same
   * analysis) but not its structure: call again after a new analysis. */
  bool
  SetFactor(const cholmod_factor * factor);

  /** The bins of every cut; more threads than bins help only the top's dense root (in the factorization). */
  static constexpr int NumberOfBins = 8;

  /** x = A^{-1} b (n values each; \a x may alias \a b) on \a threads threads (NumberOfBins used at most). */
  void
  Solve(const double * b, double * x, unsigned threads);

  /** As Solve(), but x only at the rows \a observed (indices into b and x, any order); its other rows are set to 0.
   * The backward solve computes the supernodes holding observed rows and their ancestors alone, each value by the
   * same operations as Solve(), so x is the same bit for bit at the observed rows. */
  void
  Solve(const double * b, double * x, unsigned threads, const std::vector<std::int32_t> & observed);

  /** The bins of the cut: their supernodes, ascending (children before parents). */
  const std::vector<std::vector<std::int32_t>> &
  GetBins() const
  {
    return m_Bin;
  }

  /** The fraction of the factor's entries in the bins, which run in parallel. */
  double
  GetParallelShare() const
  {
    return m_ParallelShare;
  }

private:
  void
  Run(const double * b, double * x, unsigned threads, const std::vector<std::int32_t> * observed);
  void
  MarkWithAncestors(std::int32_t s, std::vector<char> & marks) const;
  void
  CutTree();
  void
  ForwardBin(int bin, int worker);
  void
  BackwardBin(int bin, int worker);
  void
  RunBins(void (SupernodalSolver::*pass)(int, int), unsigned threads, const char * name);
  void
  ForwardSupernode(std::int32_t s, double * shared, std::vector<double> & work);
  void
  BackwardSupernode(std::int32_t s, std::vector<double> & work);

  const cholmod_factor *                 m_Factor{ nullptr };
  std::vector<std::vector<std::int32_t>> m_Bin; // supernodes of each bin, ascending (children before parents)
  std::vector<std::int32_t>              m_Top; // ancestors of the bins, ascending
  std::vector<std::int32_t>              m_TopColumns;
  std::vector<char>                      m_ColumnInTop;
  double                                 m_ParallelShare{ 0.0 };
  std::vector<std::int32_t>              m_Parent;      // of each supernode in the elimination tree, -1 for a root
  std::vector<std::int32_t>              m_SupernodeOf; // of each (permuted) column
  std::vector<std::int32_t>              m_PermutedRow; // the column of each row of b
  std::vector<char>   m_Reached; // supernodes a nonzero of b reaches: the forward solve's (the others stay 0)
  std::vector<char>   m_Needed;  // supernodes the backward solve computes
  std::vector<double> m_Y;       // the permuted right-hand side, then the solution, in place
  std::vector<std::vector<double>> m_Shared; // each bin's updates of the top's rows
  std::vector<std::vector<double>> m_Work;   // each worker's block workspace (the top uses worker 0's)
};

} // namespace fem
} // namespace bmr

#endif
