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
#ifndef bmrFemAssembly_h
#define bmrFemAssembly_h

// What the finite element models of src/fem share (private to src/fem): element geometry, the sparse
// pattern of the assembled 3N x 3N matrices, their products, the free block as an Eigen matrix, and the
// checks that a model can be solved at all. The system Eigen 3.4 and CHOLMOD are used only in src/fem.
#include "bmrTetrahedralMesh.h"

#include <Eigen/SparseCore>
#include <cholmod.h>

#include <cstdint>
#include <mutex>
#include <string>
#include <vector>

namespace bmr {
namespace fem {

/** Gradients g[a] of the four barycentric coordinates of element \a e (reference configuration) and its
 * volume [mm^3]. */
double
ElementGradients(const TetrahedralMesh & mesh, std::size_t e, double g[4][3]);

/** Lame parameters [kPa] of modulus E [kPa] and Poisson's ratio nu. */
void
LameParameters(double E, double nu, double & lambda, double & mu);

/** The von Mises stress sqrt(3/2 s:s) of the symmetric stress \a sigma [kPa], s its deviator. */
double
VonMises(const double sigma[3][3]);

/** Why the material of \a label is not usable (E not positive and finite, nu outside (-1, 0.5)), or "" when it is. */
std::string
MaterialProblem(std::int32_t label, double youngsModulus, double poissonRatio);

/** While it lives, the calling thread's OpenMP parallel regions (CHOLMOD's copy loops) run on that thread alone,
 * the thread's previous OpenMP setting restored after; a per-thread setting, so the host process is left as it
 * was (the BLAS's thread count is the program's choice: bmr::ConfigureNumerics()). Wrap every CHOLMOD call in one
 * (see the definitions). */
class SingleThreadedCholmod
{
public:
  SingleThreadedCholmod();
  ~SingleThreadedCholmod();
  SingleThreadedCholmod(const SingleThreadedCholmod &) = delete;
  SingleThreadedCholmod &
  operator=(const SingleThreadedCholmod &) = delete;

private:
  int m_Previous{ -1 }; // -1: no OpenMP runtime
};

/** Orders the factorizations of \a common by METIS nested dissection alone (see the definition). */
void
OrderByNestedDissection(cholmod_common & common);

/** Held around every symbolic analysis (see the definition): concurrent analyses would make the ordering depend
 * on the threads' timing. */
std::unique_lock<std::mutex>
LockOrdering();

/** Each node with itself and its neighbors of higher or equal index. */
using NodeAdjacency = std::vector<std::vector<std::int32_t>>;

/** The node couplings of the elements of \a mesh (unsorted, with repeats). */
NodeAdjacency
ElementNodeAdjacency(const TetrahedralMesh & mesh);

/** Sorts and deduplicates every row; throws (naming \a who and the node) when a node has no element. */
void
SortAdjacencyAndCheckNodesUsed(NodeAdjacency & upper, const std::string & who);

/** Lower triangle of a symmetric 3N x 3N matrix, compressed by column: column 3n+c holds the rows
 * 3m+r >= 3n+c of every neighbor m >= n. */
struct LowerPattern
{
  std::vector<std::int64_t> colStart;
  std::vector<std::int32_t> rowIndex;

  /** Position of the entry (row >= col) in rowIndex and in every value array on this pattern. */
  std::size_t
  EntryIndex(std::size_t row, std::size_t col) const;
  /** The entries of the node block (m, n), m >= n, with one search: (3m + i, 3n + j) sits at
   * colStart[3n + j] + NodeBlockOffset(m, n) + i - j (i >= j when m == n), since every column of node n lists
   * node n's remaining rows and then three rows per neighbour, in the same order. */
  std::size_t
  NodeBlockOffset(std::size_t m, std::size_t n) const
  {
    return EntryIndex(3 * m, 3 * n) - static_cast<std::size_t>(colStart[3 * n]);
  }
  std::size_t
  NodeBlockEntry(std::size_t offset, std::size_t n, int i, int j) const
  {
    return static_cast<std::size_t>(colStart[3 * n + j]) + offset + i - j;
  }
  std::size_t
  Size() const
  {
    return rowIndex.size();
  }
};

LowerPattern
BuildColumnPattern(const NodeAdjacency & upper);

/** y = A x for the symmetric matrix whose lower triangle \a values holds on \a pattern. */
void
SymmetricProduct(const LowerPattern &        pattern,
                 const std::vector<double> & values,
                 const std::vector<double> & x,
                 std::vector<double> &       y);

/** The entries of a symmetric matrix (lower triangle on a LowerPattern) that couple a free dof with a constrained
 * one, by row: for every dof, the dofs of the other kind it couples to (ascending) and the entries' positions
 * on the pattern. The constrained-free block is what a solve with prescribed values (K_fc g_c) and an adjoint's
 * pull-back to the constrained dofs (K_cf lambda_f) need, a small part of the whole matrix. */
struct CouplingRows
{
  std::vector<std::int64_t> rowStart; ///< 3N + 1
  std::vector<std::int32_t> column;
  std::vector<std::int64_t> entry;
};

CouplingRows
BuildCouplingRows(const LowerPattern & pattern, const std::vector<char> & constrained);

/** y_i = sum_j A_ij x_j over the coupling entries of every row i that is constrained (\a constrainedRows) or
 * free (otherwise), j ascending; y = 0 at the other rows. For x that vanishes on the dofs of row i's kind this is
 * SymmetricProduct's y_i bit for bit: both sum A_ij x_j in ascending j, and the skipped terms are exact zeros. */
void
CouplingProduct(const CouplingRows &        coupling,
                const std::vector<double> & values,
                const std::vector<char> &   constrained,
                bool                        constrainedRows,
                const std::vector<double> & x,
                std::vector<double> &       y);

/** Dof -> free index (or -1) for the dofs not \a constrained; the numbering is monotone, so the free block
 * of a lower triangle stays lower triangular. Returns the number of free dofs. */
std::size_t
NumberFreeDofs(const std::vector<char> & constrained, std::vector<std::int32_t> & freeIndex);

/** As NumberFreeDofs(), but numbered node by node in a nested-dissection order of the free nodes' graph (METIS on
 * the node adjacency of \a pattern, a graph nine times smaller in edges than the dofs' that CHOLMOD would order,
 * with the same kind of fill): the three dofs of a node stay consecutive. Every node's dofs must be constrained
 * together. With OrderAsNumbered() CHOLMOD then factorizes in this order. Deterministic (METIS's fixed seed; call
 * it under LockOrdering()). */
std::size_t
NumberFreeDofsByNestedDissection(const LowerPattern &        pattern,
                                 const std::vector<char> &   constrained,
                                 std::vector<std::int32_t> & freeIndex);

/** CHOLMOD's analysis keeps the matrix's own order (only postordered): for a matrix numbered by
 * NumberFreeDofsByNestedDissection(). */
void
OrderAsNumbered(cholmod_common & common);

/** The free block of the matrix (lower triangle \a values on \a pattern) as a compressed Eigen matrix, each entry
 * in the lower triangle of the free numbering (any numbering); \a positions (if not null) receives, for every
 * pattern entry, its index in the result's value array or -1, so that later values can be copied in place without
 * rebuilding the matrix. */
Eigen::SparseMatrix<double>
FreeBlock(const LowerPattern &              pattern,
          const std::vector<double> &       values,
          const std::vector<std::int32_t> & freeIndex,
          std::size_t                       nfree,
          std::vector<std::int64_t> *       positions = nullptr);

/** Throws (naming \a who and the component's labels) when a connected component of the mesh has fewer
 * than three fully \a constrained nodes not on one line: nothing holds it against rigid-body motion. */
void
CheckRigidBodyModes(const TetrahedralMesh & mesh, const std::vector<char> & constrained, const std::string & who);

} // namespace fem
} // namespace bmr

#endif
