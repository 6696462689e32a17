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
// The system Eigen 3.4 and CHOLMOD are used only in src/fem; no ITK header that bundles ITK's own Eigen
// may be included here.
#include "bmrFemAssembly.h"

#include <metis.h>

#include "bmrError.h"
#include "bmrRuntimeSetting.h"


#include <algorithm>
#include <cmath>
#include <mutex>
#include <numeric>
#include <set>
#include <sstream>

namespace bmr {
namespace fem {

/** Gradients of the four barycentric coordinates of element e and its volume. */
double
ElementGradients(const TetrahedralMesh & mesh, std::size_t e, double g[4][3])
{
  const std::int32_t * t = &mesh.tetrahedra[4 * e];
  const double *       x0 = &mesh.points[3 * t[0]];
  double               J[3][3]; // columns x1-x0, x2-x0, x3-x0
  for (int c = 0; c < 3; ++c)
  {
    const double * xc = &mesh.points[3 * t[c + 1]];
    for (int r = 0; r < 3; ++r)
    {
      J[r][c] = xc[r] - x0[r];
    }
  }
  const double det = J[0][0] * (J[1][1] * J[2][2] - J[1][2] * J[2][1]) -
                     J[0][1] * (J[1][0] * J[2][2] - J[1][2] * J[2][0]) +
                     J[0][2] * (J[1][0] * J[2][1] - J[1][1] * J[2][0]);
  // Rows of J^{-1} are the gradients of barycentric coordinates 1..3.
  const double inv = 1.0 / det;
  g[1][0] = (J[1][1] * J[2][2] - J[1][2] * J[2][1]) * inv;
  g[1][1] = (J[0][2] * J[2][1] - J[0][1] * J[2][2]) * inv;
  g[1][2] = (J[0][1] * J[1][2] - J[0][2] * J[1][1]) * inv;
  g[2][0] = (J[1][2] * J[2][0] - J[1][0] * J[2][2]) * inv;
  g[2][1] = (J[0][0] * J[2][2] - J[0][2] * J[2][0]) * inv;
  g[2][2] = (J[0][2] * J[1][0] - J[0][0] * J[1][2]) * inv;
  g[3][0] = (J[1][0] * J[2][1] - J[1][1] * J[2][0]) * inv;
  g[3][1] = (J[0][1] * J[2][0] - J[0][0] * J[2][1]) * inv;
  g[3][2] = (J[0][0] * J[1][1] - J[0][1] * J[1][0]) * inv;
  for (int i = 0; i < 3; ++i)
  {
    g[0][i] = -(g[1][i] + g[2][i] + g[3][i]);
  }
  return det / 6.0;
}

namespace {
/** The OpenMP runtime's max active levels (both null without an OpenMP runtime). */
const RuntimeIntSetting &
Levels()
{
  static const RuntimeIntSetting levels =
    FindRuntimeIntSetting("omp_get_max_active_levels", "omp_set_max_active_levels");
  return levels;
}
} // namespace

/** The calling thread's OpenMP parallel regions on that thread alone (the BLAS's threads are the host's:
 * bmr::ConfigureNumerics()). Debian's CHOLMOD runs the copy loops of its supernodal factorization in teams of 4 OpenMP
 * threads (CHOLMOD_OMP_NUM_THREADS) whose idle workers spin. The estimation factorizes on two threads at once (the
 * sweep's coarse model and the fine one) beside the mesher, so those teams take CPU from the work that matters
 * (measured in docs/history/benchmarks.md). The loops only copy, so the results are the same bit for bit. Max active
 * levels 0 makes every parallel region of the calling thread run on that thread alone; it is a per-thread setting,
 * restored on exit so that a program's own OpenMP on that thread is left as it was. */
SingleThreadedCholmod::SingleThreadedCholmod()
{
  if (Levels().get)
  {
    m_Previous = Levels().get();
    Levels().set(0);
  }
}

SingleThreadedCholmod::~SingleThreadedCholmod()
{
  if (m_Previous >= 0)
  {
    Levels().set(m_Previous);
  }
}

/** CHOLMOD's default analysis orders by AMD and, when AMD's fill is large, tries METIS as well and keeps the
 * better one. On 3-D meshes nested dissection needs several times fewer flops than AMD, so CHOLMOD keeps METIS
 * and the AMD ordering is computed only to be discarded; the factors, and so the results, are the same.
 * METIS is deterministic (fixed seed). */
void
OrderByNestedDissection(cholmod_common & common)
{
  common.nmethods = 1;
  common.method[0].ordering = CHOLMOD_METIS;
  common.postorder = 1;
}

/** METIS draws from GKlib's process-wide random generator, which it reseeds at the start of every call: two
 * analyses at once (the concurrent rescans of ModulusInterval) interleave their draws, and the ordering, and
 * with it the rounding of every result, then depends on the threads' timing (seen as rescans that differed in
 * the last bits between two runs with the same seed). The analysis is a fraction of a factorization, so
 * serializing it costs little. */
std::unique_lock<std::mutex>
LockOrdering()
{
  static std::mutex ordering;
  return std::unique_lock<std::mutex>(ordering);
}

void
LameParameters(double E, double nu, double & lambda, double & mu)
{
  lambda = E * nu / ((1.0 + nu) * (1.0 - 2.0 * nu));
  mu = E / (2.0 * (1.0 + nu));
}
// Node adjacency (each node with itself and its element neighbors of higher or equal index).
std::string
MaterialProblem(std::int32_t label, double youngsModulus, double poissonRatio)
{
  std::ostringstream msg;
  if (!(std::isfinite(youngsModulus) && youngsModulus > 0.0))
  {
    msg << "label " << label << ": Young's modulus must be positive and finite, got " << youngsModulus << " kPa";
  }
  else if (!(std::isfinite(poissonRatio) && poissonRatio > -1.0 && poissonRatio < 0.5))
  {
    msg << "label " << label << ": Poisson's ratio must lie in (-1, 0.5), got " << poissonRatio;
  }
  return msg.str();
}

double
VonMises(const double sigma[3][3])
{
  const double p = (sigma[0][0] + sigma[1][1] + sigma[2][2]) / 3.0;
  double       j2 = 0.0;
  for (int i = 0; i < 3; ++i)
  {
    for (int j = 0; j < 3; ++j)
    {
      const double dev = sigma[i][j] - (i == j ? p : 0.0);
      j2 += dev * dev;
    }
  }
  return std::sqrt(1.5 * j2);
}

NodeAdjacency
ElementNodeAdjacency(const TetrahedralMesh & mesh)
{
  const std::size_t N = mesh.GetNumberOfPoints();
  const std::size_t M = mesh.GetNumberOfTetrahedra();
  NodeAdjacency     upper(N);
  for (std::size_t e = 0; e < M; ++e)
  {
    const std::int32_t * t = &mesh.tetrahedra[4 * e];
    for (int a = 0; a < 4; ++a)
    {
      for (int b = 0; b < 4; ++b)
      {
        if (t[b] >= t[a])
        {
          upper[t[a]].push_back(t[b]);
        }
      }
    }
  }
  return upper;
}

void
SortAdjacencyAndCheckNodesUsed(NodeAdjacency & upper, const std::string & who)
{
  const std::size_t N = upper.size();
  std::vector<char> used(N, 0);
  for (std::size_t n = 0; n < N; ++n)
  {
    auto & v = upper[n];
    std::sort(v.begin(), v.end());
    v.erase(std::unique(v.begin(), v.end()), v.end());
    used[n] = !v.empty();
  }
  for (std::size_t n = 0; n < N; ++n)
  {
    if (!used[n])
    {
      std::ostringstream msg;
      msg << "node " << n << " belongs to no element (its stiffness would be singular)";
      Fail(who, msg.str());
    }
  }
}

std::size_t
LowerPattern::EntryIndex(std::size_t row, std::size_t col) const
{
  const auto first = rowIndex.begin() + colStart[col];
  const auto last = rowIndex.begin() + colStart[col + 1];
  return static_cast<std::size_t>(std::lower_bound(first, last, static_cast<std::int32_t>(row)) - rowIndex.begin());
}

std::size_t
NumberFreeDofs(const std::vector<char> & constrained, std::vector<std::int32_t> & freeIndex)
{
  freeIndex.assign(constrained.size(), -1);
  std::size_t nfree = 0;
  for (std::size_t i = 0; i < constrained.size(); ++i)
  {
    if (!constrained[i])
    {
      freeIndex[i] = static_cast<std::int32_t>(nfree++);
    }
  }
  return nfree;
}

std::size_t
NumberFreeDofsByNestedDissection(const LowerPattern &        pattern,
                                 const std::vector<char> &   constrained,
                                 std::vector<std::int32_t> & freeIndex)
{
  const std::size_t nodes = constrained.size() / 3;
  // The free nodes (a node's three dofs are constrained together) and their graph, from column 3n's rows 3m.
  std::vector<idx_t>       nodeOf(nodes, -1);
  std::vector<std::size_t> freeNodes;
  for (std::size_t n = 0; n < nodes; ++n)
  {
    if (!constrained[3 * n])
    {
      nodeOf[n] = static_cast<idx_t>(freeNodes.size());
      freeNodes.push_back(n);
    }
  }
  freeIndex.assign(constrained.size(), -1);
  if (freeNodes.empty())
  {
    return 0;
  }
  std::vector<std::vector<idx_t>> adjacent(freeNodes.size());
  std::size_t                     edges = 0;
  for (std::size_t a = 0; a < freeNodes.size(); ++a)
  {
    const std::size_t col = 3 * freeNodes[a];
    for (std::int64_t k = pattern.colStart[col]; k < pattern.colStart[col + 1]; ++k)
    {
      const auto  row = static_cast<std::size_t>(pattern.rowIndex[k]);
      const idx_t b = nodeOf[row / 3];
      if (row % 3 == 0 && b >= 0 && static_cast<std::size_t>(b) != a)
      {
        adjacent[a].push_back(b);
        adjacent[static_cast<std::size_t>(b)].push_back(static_cast<idx_t>(a));
        edges += 2;
      }
    }
  }
  std::vector<idx_t> xadj(1, 0), adjncy, perm(freeNodes.size()), iperm(freeNodes.size());
  adjncy.reserve(edges);
  for (auto & list : adjacent)
  {
    std::sort(list.begin(), list.end());
    adjncy.insert(adjncy.end(), list.begin(), list.end());
    xadj.push_back(static_cast<idx_t>(adjncy.size()));
  }
  idx_t vertices = static_cast<idx_t>(freeNodes.size());
  idx_t options[METIS_NOPTIONS];
  METIS_SetDefaultOptions(options);
  const bool ordered =
    edges > 0 &&
    METIS_NodeND(&vertices, xadj.data(), adjncy.data(), nullptr, options, perm.data(), iperm.data()) == METIS_OK;
  for (std::size_t a = 0; a < freeNodes.size(); ++a)
  {
    const std::size_t position = ordered ? static_cast<std::size_t>(iperm[a]) : a;
    for (int c = 0; c < 3; ++c)
    {
      freeIndex[3 * freeNodes[a] + c] = static_cast<std::int32_t>(3 * position + c);
    }
  }
  return 3 * freeNodes.size();
}

void
OrderAsNumbered(cholmod_common & common)
{
  common.nmethods = 1;
  common.method[0].ordering = CHOLMOD_NATURAL;
  common.postorder = 1;
}

// Built directly in compressed form: the kept entries counted per column of the free numbering, placed by a
// counting sort on that column, then each column sorted by row; a position is where its entry lands. The
// nested-dissection numbering turns entries around (a pattern entry may become an upper one), so the pattern's order
// is not the result's.
Eigen::SparseMatrix<double>
FreeBlock(const LowerPattern &              pattern,
          const std::vector<double> &       values,
          const std::vector<std::int32_t> & freeIndex,
          std::size_t                       nfree,
          std::vector<std::int64_t> *       positions)
{
  using StorageIndex = Eigen::SparseMatrix<double>::StorageIndex;
  const std::size_t         columns = pattern.colStart.size() - 1;
  std::vector<std::int64_t> start(nfree + 1, 0);
  const auto                forEachKept = [&](const auto & visit) {
    for (std::size_t col = 0; col < columns; ++col)
    {
      const std::int32_t fc = freeIndex[col];
      for (std::int64_t k = pattern.colStart[col]; fc >= 0 && k < pattern.colStart[col + 1]; ++k)
      {
        const std::int32_t fr = freeIndex[pattern.rowIndex[k]];
        if (fr >= 0)
        {
          // The lower triangle in the free numbering.
          visit(k, std::max(fr, fc), std::min(fr, fc));
        }
      }
    }
  };
  forEachKept([&](std::int64_t, std::int32_t, std::int32_t column) { ++start[static_cast<std::size_t>(column) + 1]; });
  std::partial_sum(start.begin(), start.end(), start.begin());
  const auto                  nonZeros = static_cast<std::size_t>(start.back());
  Eigen::SparseMatrix<double> block(static_cast<Eigen::Index>(nfree), static_cast<Eigen::Index>(nfree));
  block.resizeNonZeros(static_cast<Eigen::Index>(nonZeros));
  StorageIndex *            rows = block.innerIndexPtr();
  std::vector<std::int64_t> entryAt(nonZeros); // the pattern entry of each slot
  std::vector<std::int64_t> next(start.begin(), start.end() - 1);
  forEachKept([&](std::int64_t k, std::int32_t row, std::int32_t column) {
    const auto at = static_cast<std::size_t>(next[static_cast<std::size_t>(column)]++);
    rows[at] = static_cast<StorageIndex>(row);
    entryAt[at] = k;
  });
  std::vector<std::pair<StorageIndex, std::int64_t>> column; // (row, pattern entry), sorted by row
  for (std::size_t c = 0; c < nfree; ++c)
  {
    block.outerIndexPtr()[c] = static_cast<StorageIndex>(start[c]);
    const auto first = static_cast<std::size_t>(start[c]), last = static_cast<std::size_t>(start[c + 1]);
    column.clear();
    for (std::size_t at = first; at < last; ++at)
    {
      column.emplace_back(rows[at], entryAt[at]);
    }
    std::sort(column.begin(), column.end()); // rows are distinct within a column
    for (std::size_t i = 0; i < column.size(); ++i)
    {
      rows[first + i] = column[i].first;
      entryAt[first + i] = column[i].second;
    }
  }
  if (positions)
  {
    positions->assign(pattern.Size(), -1);
  }
  for (std::size_t at = 0; at < nonZeros; ++at)
  {
    block.valuePtr()[at] = values[static_cast<std::size_t>(entryAt[at])];
    if (positions)
    {
      (*positions)[static_cast<std::size_t>(entryAt[at])] = static_cast<std::int64_t>(at);
    }
  }
  block.outerIndexPtr()[nfree] = static_cast<StorageIndex>(nonZeros);
  return block;
}

// Column 3n+c holds rows 3m+r >= 3n+c for every neighbor m >= n.
LowerPattern
BuildColumnPattern(const NodeAdjacency & upper)
{
  const std::size_t N = upper.size();
  const std::size_t ndof = 3 * N;
  LowerPattern      pattern;
  auto &            colStart = pattern.colStart;
  auto &            rowIndex = pattern.rowIndex;
  colStart.assign(ndof + 1, 0);
  for (std::size_t n = 0; n < N; ++n)
  {
    for (int c = 0; c < 3; ++c)
    {
      colStart[3 * n + c + 1] = colStart[3 * n + c] + static_cast<std::int64_t>(3 * upper[n].size() - c);
    }
  }
  rowIndex.resize(static_cast<std::size_t>(colStart[ndof]));
  for (std::size_t n = 0; n < N; ++n)
  {
    for (int c = 0; c < 3; ++c)
    {
      std::int64_t k = colStart[3 * n + c];
      for (std::int32_t m : upper[n])
      {
        for (int r = 0; r < 3; ++r)
        {
          const std::size_t row = 3 * static_cast<std::size_t>(m) + r;
          if (row >= 3 * n + c)
          {
            rowIndex[k++] = static_cast<std::int32_t>(row);
          }
        }
      }
    }
  }
  return pattern;
}

void
SymmetricProduct(const LowerPattern &        pattern,
                 const std::vector<double> & vals,
                 const std::vector<double> & x,
                 std::vector<double> &       y)
{
  const auto &      start = pattern.colStart;
  const auto &      rows = pattern.rowIndex;
  const std::size_t n = start.size() - 1;
  y.assign(n, 0.0);
  for (std::size_t col = 0; col < n; ++col)
  {
    for (std::int64_t k = start[col]; k < start[col + 1]; ++k)
    {
      const std::size_t row = static_cast<std::size_t>(rows[k]);
      y[row] += vals[k] * x[col];
      if (row != col)
      {
        y[col] += vals[k] * x[row];
      }
    }
  }
}

// Scans the lower triangle by column and row, both ascending: every row's list then comes out ascending (its
// entries left of the diagonal first, while their columns are scanned, then those below it in its own column).
CouplingRows
BuildCouplingRows(const LowerPattern & pattern, const std::vector<char> & constrained)
{
  const std::size_t n = pattern.colStart.size() - 1;
  CouplingRows      coupling;
  coupling.rowStart.assign(n + 1, 0);
  const auto forEachCoupling = [&](const auto & visit) {
    for (std::size_t col = 0; col < n; ++col)
    {
      for (std::int64_t k = pattern.colStart[col]; k < pattern.colStart[col + 1]; ++k)
      {
        const auto row = static_cast<std::size_t>(pattern.rowIndex[k]);
        if (constrained[row] != constrained[col])
        {
          visit(row, col, k);
          visit(col, row, k);
        }
      }
    }
  };
  forEachCoupling([&](std::size_t i, std::size_t, std::int64_t) { ++coupling.rowStart[i + 1]; });
  for (std::size_t i = 0; i < n; ++i)
  {
    coupling.rowStart[i + 1] += coupling.rowStart[i];
  }
  coupling.column.resize(static_cast<std::size_t>(coupling.rowStart[n]));
  coupling.entry.resize(coupling.column.size());
  std::vector<std::int64_t> next(coupling.rowStart.begin(), coupling.rowStart.end() - 1);
  forEachCoupling([&](std::size_t i, std::size_t j, std::int64_t k) {
    const auto at = static_cast<std::size_t>(next[i]++);
    coupling.column[at] = static_cast<std::int32_t>(j);
    coupling.entry[at] = k;
  });
  return coupling;
}

void
CouplingProduct(const CouplingRows &        coupling,
                const std::vector<double> & values,
                const std::vector<char> &   constrained,
                bool                        constrainedRows,
                const std::vector<double> & x,
                std::vector<double> &       y)
{
  const std::size_t n = coupling.rowStart.size() - 1;
  y.assign(n, 0.0);
  for (std::size_t i = 0; i < n; ++i)
  {
    if ((constrained[i] != 0) != constrainedRows)
    {
      continue;
    }
    for (std::int64_t a = coupling.rowStart[i]; a < coupling.rowStart[i + 1]; ++a)
    {
      y[i] += values[static_cast<std::size_t>(coupling.entry[a])] * x[static_cast<std::size_t>(coupling.column[a])];
    }
  }
}

void
CheckRigidBodyModes(const TetrahedralMesh & mesh, const std::vector<char> & constrained, const std::string & who)
{
  std::vector<std::int32_t> component;
  const std::size_t         ncomp = ConnectedComponents(mesh, &component);
  const std::size_t         N = mesh.GetNumberOfPoints();
  for (std::size_t c = 0; c < ncomp; ++c)
  {
    // A component is held when its fully constrained nodes are not all on one line.
    std::vector<std::size_t> held;
    for (std::size_t n = 0; n < N; ++n)
    {
      if (component[n] == static_cast<std::int32_t>(c) && constrained[3 * n] && constrained[3 * n + 1] &&
          constrained[3 * n + 2])
      {
        held.push_back(n);
      }
    }
    bool ok = false;
    if (held.size() >= 3)
    {
      const double * p0 = &mesh.points[3 * held[0]];
      std::size_t    far = held[0];
      double         best = -1;
      for (std::size_t n : held)
      {
        const double * p = &mesh.points[3 * n];
        const double   d = std::hypot(p[0] - p0[0], p[1] - p0[1], p[2] - p0[2]);
        if (d > best)
        {
          best = d;
          far = n;
        }
      }
      const double * p1 = &mesh.points[3 * far];
      const double   axis[3] = { p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2] };
      for (std::size_t n : held)
      {
        const double * p = &mesh.points[3 * n];
        const double   v[3] = { p[0] - p0[0], p[1] - p0[1], p[2] - p0[2] };
        const double   cx = axis[1] * v[2] - axis[2] * v[1];
        const double   cy = axis[2] * v[0] - axis[0] * v[2];
        const double   cz = axis[0] * v[1] - axis[1] * v[0];
        if (std::sqrt(cx * cx + cy * cy + cz * cz) > 1e-6 * best * best)
        {
          ok = true;
          break;
        }
      }
    }
    if (!ok)
    {
      std::set<std::int32_t> labels;
      for (std::size_t e = 0; e < mesh.GetNumberOfTetrahedra(); ++e)
      {
        if (component[mesh.tetrahedra[4 * e]] == static_cast<std::int32_t>(c))
        {
          labels.insert(mesh.labels[e]);
        }
      }
      std::ostringstream msg;
      msg << "nothing prevents rigid-body motion of the connected mesh component " << c << " (labels";
      for (auto l : labels)
      {
        msg << ' ' << l;
      }
      msg << "): it has " << held.size()
          << " fixed nodes, at least 3 not on one line are needed (add a fixed label or fix the ROI boundary)";
      Fail(who, msg.str());
    }
  }
}

} // namespace fem
} // namespace bmr
