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
#ifndef bmrSupernodalFactorize_h
#define bmrSupernodalFactorize_h

// The numeric supernodal Cholesky factorization into a CHOLMOD factor on a thread budget (private to src/fem).
#include <cholmod.h>

#include <cstdint>
#include <memory>
#include <vector>

namespace bmr {
namespace fem {

/** \brief A = L L^T into the supernodal factor CHOLMOD's analysis laid out, on any number of threads with the same
 * bits.
 *
 * CHOLMOD's numeric factorization runs on one thread here (its BLAS pinned to one: a multithreaded BLAS rounds
 * differently for different thread counts). This one takes the supernodal elimination tree cut of
 * SupernodalSolver: a fixed number of bins of subtrees, independent of each other, and a top (their ancestors).
 * - The bins run side by side, right-looking: each supernode s's block, which holds (A - the updates of its
 *   descendants) by then, is factorized, L_ss = chol(B_ss) and L_rs = B_rs L_ss^-T (LAPACK dpotrf, BLAS dtrsm),
 *   and its update C = L_rs L_rs^T (dsyrk, dgemm) is subtracted from its ancestors in the bin. Its update of the
 *   top is not computed there.
 * - Then each top block pulls the updates of its descendants in the bins, left-looking: in tiles of its columns
 *   (the tiles side by side), for each bin descendant d in ascending order, L_{t,d} L_{j,d}^T over the rows of d
 *   in t (one dgemm). Each entry thus receives its updates in an order fixed by the tree, whichever thread
 *   computes it, and no bin writes outside itself.
 * - The top's supernodes follow in order, each in tiles (FactorizePanelInTiles(): dpotrf of a diagonal tile,
 *   dtrsm of the tiles below it, dsyrk/dgemm of the trailing tiles), its update of its ancestors in tiles of C
 *   (OuterProductInTiles()) and scattered in column tiles, each tile operation one single-threaded BLAS call,
 *   whichever thread runs it.
 * So the factor does not depend on the thread count. It differs from CHOLMOD's own in the last bits (other
 * blockings of the same sums); both are backward stable.
 *
 * Refactorizations that change only some entries of A (an estimator's unknown modulus: A = A_fixed + A_varying,
 * A_varying nonzero on the entries of one organ's elements) redo only the supernodes that hold a varying entry and
 * their ancestors (SetVaryingEntries()). The others, whose blocks and updates depend on A_fixed alone, are computed
 * first; each varying block, by then A_fixed minus their updates, is kept; a refactorization restores those blocks,
 * adds A_varying and factorizes the varying supernodes alone (FactorizeVarying()). On the 140k-tetrahedron pelvis a
 * prostate modulus varies the supernodes of 49.5 % of the factorization's multiply-adds: the root separators above
 * the prostate and its subtrees. The factor is the same sums in another order (the fixed descendants' updates
 * first): the same bits on any number of threads, and the same bits for the same A_fixed + A_varying whichever
 * factorization came before.
 */
class SupernodalFactorizer
{
public:
  /** Once per analysis: \a factor (supernodal LL^T with int indices, symbolic or numeric; made numeric here),
   * \a common its CHOLMOD workspace, the lower triangle of A in CSC form in the original numbering (\a n columns,
   * \a columnStarts, \a rowIndices), and the tree cut (\a bins, \a top: SupernodalSolver). False when the factor is
   * not of that kind or A's pattern not the one analyzed: factorize with CHOLMOD then. The top is every
   * supernode in no bin. */
  bool
  SetStructure(cholmod_factor *                               factor,
               cholmod_common &                               common,
               int                                            n,
               const int *                                    columnStarts,
               const int *                                    rowIndices,
               const std::vector<std::vector<std::int32_t>> & bins);

  /** Marks the entries of A (one flag per entry of the pattern given to SetStructure; empty: none) whose values
   * later factorizations change. Forgets the kept fixed part. */
  void
  SetVaryingEntries(const std::vector<char> & varies);

  /** L from the values of A = \a fixedValues + \a varyingValues (on the pattern given to SetStructure;
   * \a varyingValues nonzero only on the varying entries, or null for none) on \a threads threads, keeping the fixed
   * part for FactorizeVarying(). Returns n on success, else the (permuted) column at which A is not positive definite.
   */
  int
  Factorize(const double * fixedValues, const double * varyingValues, unsigned threads);
  int
  Factorize(const double * values, unsigned threads)
  {
    return Factorize(values, nullptr, threads);
  }

  /** L from A = the last Factorize()'s \a fixedValues + \a varyingValues: only the supernodes that hold a varying
   * entry and their ancestors are computed. Returns as Factorize(), or -1 without HasFixedPart(). */
  int
  FactorizeVarying(const double * varyingValues, unsigned threads);

  /** Whether the last Factorize() succeeded with varying entries, so that FactorizeVarying() may follow. */
  bool
  HasFixedPart() const
  {
    return m_FixedPartKept;
  }

  /** The fraction of the factorization's multiply-adds in the varying supernodes (0 with none varying). */
  double
  GetVaryingShare() const
  {
    return m_VaryingShare;
  }

  /** The number of entries of A the structure was set for (a changed pattern needs SetStructure again). */
  std::size_t
  GetNumberOfEntries() const
  {
    return m_Entries;
  }

private:
  /** A bin supernode whose updates a top supernode t pulls: the rows below its diagonal block from `begin` on lie in
   * t's row list, and those before `end` are t's columns. */
  struct Pull
  {
    std::int32_t from;
    int          begin;
    int          end;
  };
  /** Per worker: the update or product workspace and a row map. */
  struct Workspace
  {
    std::vector<double> update;
    std::vector<int>    relative;
  };

  bool
  PlaceEntries(int n, const int * columnStarts, const int * rowIndices, const std::vector<int> & owner);
  bool
  UpdatesFit() const;
  void
  FindPulls(const std::vector<int> & owner);
  void
  PlaceValues(int part, const double * values);
  void
  SplitByVariation(std::vector<char> varies);
  int
  FactorizeVarying(const double * varyingValues, unsigned threads, bool restore);
  int
  FactorizeParts(const std::vector<std::vector<std::int32_t>> & bins,
                 const std::vector<std::int32_t> &              top,
                 const double *                                 values,
                 bool                                           varyingPass,
                 unsigned                                       threads);
  int
  FactorizeBin(int bin, const std::vector<std::int32_t> & supernodes, const double * values, Workspace & work);
  int
  FactorizeBinSupernode(std::int32_t s, Workspace & work);
  void
  PullBinUpdates(const std::vector<std::int32_t> & top, bool varyingPass, unsigned threads);
  void
  PullColumns(std::int32_t t, int firstColumn, int endColumn, bool varyingPass, Workspace & work);
  int
  FactorizeTopSupernode(std::int32_t s, unsigned threads);
  void
  ScatterColumns(std::int32_t s, const double * update, int begin, int end, int * relative);
  void
  KeepVaryingBlocks(bool restore);
  Workspace &
  WorkspaceFor(std::vector<Workspace> & pool, std::size_t worker, std::size_t updateSize, std::size_t rows);

  cholmod_factor *                       m_Factor{ nullptr };
  std::size_t                            m_Entries{ 0 };
  std::vector<std::vector<std::int32_t>> m_Bin;
  std::vector<std::int32_t>              m_Top;
  std::vector<std::int32_t>              m_SupernodeOf; // of each column
  std::vector<int>                       m_Position;    // of each entry of A in L's values
  std::vector<std::vector<std::size_t>>  m_EntriesOf;   // of each part (the bins, then the top): its entries of A
  std::vector<int>                       m_TopRowsFrom; // of each bin supernode: its first row below in the top
  std::vector<std::vector<Pull>>         m_Pulls;       // of each top supernode: the bin supernodes, ascending
  std::size_t                            m_LargestBelow[2]{ 0, 0 }; // rows below a diagonal block: in bins, in the top
  std::vector<Workspace>                 m_BinWork;                 // per worker of the bins
  std::vector<Workspace>                 m_PullWork;                // per worker of the pulls and the top's scatter
  std::vector<double>                    m_TopUpdate;               // a top supernode's update of its ancestors
  // The split for refactorizations (SetVaryingEntries): each part's supernodes, in order, without and with a
  // varying entry in themselves or a descendant.
  std::vector<char>                      m_Varies; // of each supernode
  std::vector<std::vector<std::int32_t>> m_FixedBin, m_VaryingBin;
  std::vector<std::int32_t>              m_FixedTop, m_VaryingTop;
  std::vector<std::int32_t>              m_EntrySupernode; // of each entry of A
  std::vector<std::size_t>               m_VaryingEntries; // the entries of A marked varying
  std::vector<double>                    m_KeptBlocks;     // the varying blocks after the fixed supernodes' updates
  bool                                   m_FixedPartKept{ false };
  double                                 m_VaryingShare{ 0.0 };
};

} // namespace fem
} // namespace bmr

#endif
