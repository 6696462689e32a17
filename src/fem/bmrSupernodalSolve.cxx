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
#include "bmrSupernodalSolve.h"

#include "bmrParallel.h"
#include "bmrSupernodes.h"

#include <algorithm>
#include <cstring>
#include <limits>
#include <numeric>

namespace bmr {
namespace fem {
namespace {


/** One supernode's block: nsrow x nscol, column-major (leading dimension ld), its first nscol rows the diagonal
 * block (the columns first, first + 1, ...), then the rows below it (rowsBelow, ascending). */
struct SupernodeBlock
{
  int            nscol;
  int            nsrow;
  std::size_t    ld;
  const double * block;
  int            first;
  const int *    rowsBelow;

  SupernodeBlock(const cholmod_factor & L, std::int32_t s)
  {
    const Supernodes S(L);
    nscol = S.Columns(s);
    nsrow = S.Rows(s);
    ld = static_cast<std::size_t>(nsrow);
    block = S.Block(s);
    first = S.first[s];
    rowsBelow = S.rows + S.rowsAt[s] + nscol;
  }
};

// The block kernels work on groups of four columns of a column-major block (leading dimension ld) at once, so that
// the vector they update or read is loaded once per group instead of once per column. The order of every sum is
// written out here (GCC's vector extension for pairs of doubles, no BLAS): the same on any thread and any x86-64.
using Pair = double __attribute__((vector_size(16)));

inline Pair
LoadPair(const double * p)
{
  Pair v;
  std::memcpy(&v, p, sizeof v);
  return v;
}

/** y_i -= c_i x, i < m. */
inline void
SubtractColumn(const double * __restrict c, double x, double * __restrict y, int m)
{
  for (int i = 0; i < m; ++i)
  {
    y[i] -= c[i] * x;
  }
}

/** y_i = (((y_i - c0_i x0) - c1_i x1) - c2_i x2) - c3_i x3 for the four columns ck = c + k ld, i < m. */
inline void
SubtractFourColumns(const double * __restrict c, std::size_t ld, const double * x, double * __restrict y, int m)
{
  const double * __restrict c1 = c + ld;
  const double * __restrict c2 = c + 2 * ld;
  const double * __restrict c3 = c + 3 * ld;
  const double x0 = x[0], x1 = x[1], x2 = x[2], x3 = x[3];
  for (int i = 0; i < m; ++i)
  {
    y[i] = (((y[i] - c[i] * x0) - c1[i] * x1) - c2[i] * x2) - c3[i] * x3;
  }
}

/** sum_i c_i b_i, i < m: the even and the odd terms summed apart, then added, then the last odd term. */
inline double
Dot(const double * __restrict c, const double * __restrict b, int m)
{
  Pair sum{ 0.0, 0.0 };
  int  i = 0;
  for (; i + 2 <= m; i += 2)
  {
    sum += LoadPair(c + i) * LoadPair(b + i);
  }
  double d = sum[0] + sum[1];
  if (i < m)
  {
    d += c[i] * b[i];
  }
  return d;
}

/** Dot() of each of the four columns c + k ld with b, into d[0..3], b read once. */
inline void
FourDots(const double * __restrict c, std::size_t ld, const double * __restrict b, int m, double * d)
{
  const double * __restrict c1 = c + ld;
  const double * __restrict c2 = c + 2 * ld;
  const double * __restrict c3 = c + 3 * ld;
  Pair s0{ 0.0, 0.0 }, s1{ 0.0, 0.0 }, s2{ 0.0, 0.0 }, s3{ 0.0, 0.0 };
  int  i = 0;
  for (; i + 2 <= m; i += 2)
  {
    const Pair bi = LoadPair(b + i);
    s0 += LoadPair(c + i) * bi;
    s1 += LoadPair(c1 + i) * bi;
    s2 += LoadPair(c2 + i) * bi;
    s3 += LoadPair(c3 + i) * bi;
  }
  d[0] = s0[0] + s0[1];
  d[1] = s1[0] + s1[1];
  d[2] = s2[0] + s2[1];
  d[3] = s3[0] + s3[1];
  if (i < m)
  {
    d[0] += c[i] * b[i];
    d[1] += c1[i] * b[i];
    d[2] += c2[i] * b[i];
    d[3] += c3[i] * b[i];
  }
}

/** Asks for the first two cache lines of the \a count columns from \a c on (stride ld), read soon: the first touch of
 * each of a block's many short columns would otherwise wait on memory. */
inline void
PrefetchColumns(const double * c, std::size_t ld, int count)
{
  for (int k = 0; k < count; ++k)
  {
    __builtin_prefetch(c + k * ld);
    __builtin_prefetch(c + k * ld + 8);
  }
}

/** The supernodal elimination tree: each supernode's parent (the supernode of its first row below the diagonal
 * block, -1 for a root), its size (entries of its block) and the size of its subtree. */
struct SupernodeTree
{
  std::vector<std::int32_t>              parent;
  std::vector<std::vector<std::int32_t>> children;
  std::vector<std::int32_t>              roots;
  std::vector<double>                    size;
  std::vector<double>                    subtree;

  SupernodeTree(const cholmod_factor & L, const Supernodes & S)
  {
    const auto                nsuper = static_cast<std::int32_t>(L.nsuper);
    std::vector<std::int32_t> supernodeOf(L.n);
    for (std::int32_t s = 0; s < nsuper; ++s)
    {
      std::fill(supernodeOf.begin() + S.first[s], supernodeOf.begin() + S.first[s + 1], s);
    }
    parent.assign(nsuper, -1);
    children.resize(nsuper);
    size.resize(nsuper);
    subtree.assign(nsuper, 0.0);
    // A parent's columns follow its children's, so one ascending pass sums the subtrees.
    for (std::int32_t s = 0; s < nsuper; ++s)
    {
      size[s] = static_cast<double>(S.Columns(s)) * S.Rows(s);
      subtree[s] += size[s];
      if (S.Rows(s) > S.Columns(s))
      {
        parent[s] = supernodeOf[S.rows[S.rowsAt[s] + S.Columns(s)]];
        subtree[parent[s]] += subtree[s];
        children[parent[s]].push_back(s);
      }
      else
      {
        roots.push_back(s);
      }
    }
  }
};

/** Candidate subtrees (by root) dealt to \a bins bins, largest first, each to the lightest bin (ties to the lowest
 * bin). */
struct Deal
{
  std::vector<std::pair<std::int32_t, int>> binOf;
  std::vector<double>                       load;

  double
  Heaviest() const
  {
    return *std::max_element(load.begin(), load.end());
  }
};

Deal
DealSubtrees(std::vector<std::int32_t> candidates, const SupernodeTree & tree, int bins)
{
  std::sort(candidates.begin(), candidates.end(), [&tree](std::int32_t a, std::int32_t b) {
    return tree.subtree[a] != tree.subtree[b] ? tree.subtree[a] > tree.subtree[b] : a < b;
  });
  Deal deal;
  deal.load.assign(bins, 0.0);
  for (const std::int32_t c : candidates)
  {
    const int bin = static_cast<int>(std::min_element(deal.load.begin(), deal.load.end()) - deal.load.begin());
    deal.load[bin] += tree.subtree[c];
    deal.binOf.emplace_back(c, bin);
  }
  return deal;
}

} // namespace

bool
SupernodalSolver::SetFactor(const cholmod_factor * factor)
{
  m_Factor = nullptr;
  if (factor == nullptr || !factor->is_super || !factor->is_ll || factor->xtype != CHOLMOD_REAL ||
      factor->itype != CHOLMOD_INT || factor->dtype != CHOLMOD_DOUBLE || factor->n == 0 || factor->nsuper == 0)
  {
    return false;
  }
  m_Factor = factor;
  CutTree();
  const std::size_t n = factor->n;
  const Supernodes  S(*factor);
  m_SupernodeOf.resize(n);
  for (std::int32_t s = 0; s < static_cast<std::int32_t>(factor->nsuper); ++s)
  {
    std::fill(m_SupernodeOf.begin() + S.first[s], m_SupernodeOf.begin() + S.first[s + 1], s);
  }
  const int * perm = static_cast<const int *>(factor->Perm);
  m_PermutedRow.resize(n);
  for (std::size_t k = 0; k < n; ++k)
  {
    m_PermutedRow[perm != nullptr ? perm[k] : k] = static_cast<std::int32_t>(k);
  }
  m_Y.assign(n, 0.0);
  m_Shared.assign(NumberOfBins, std::vector<double>(n, 0.0));
  return true;
}

/** Starting from the roots as candidate subtrees, moves the largest candidate's root into the top, one at a time
 * (256 moves at most: a few levels of nested dissection), deals the candidates to the bins after each move, and
 * keeps the cut with the least estimated critical path with every bin on a thread of its own: the top's size plus
 * the heaviest bin's. */
void
SupernodalSolver::CutTree()
{
  const Supernodes    S(*m_Factor);
  const SupernodeTree tree(*m_Factor, S);
  m_Parent = tree.parent;
  std::vector<std::int32_t> candidates = tree.roots;
  std::vector<std::int32_t> moved;
  double                    topSize = 0.0;
  double                    bestCost = std::numeric_limits<double>::infinity();
  std::size_t               bestMoves = 0;
  Deal                      best;
  for (int round = 0; round <= 256 && !candidates.empty(); ++round)
  {
    Deal         deal = DealSubtrees(candidates, tree, NumberOfBins);
    const double cost = topSize + deal.Heaviest();
    if (cost < bestCost)
    {
      bestCost = cost;
      bestMoves = moved.size();
      best = std::move(deal);
    }
    const std::int32_t largest =
      *std::max_element(candidates.begin(), candidates.end(), [&tree](std::int32_t a, std::int32_t b) {
        return tree.subtree[a] != tree.subtree[b] ? tree.subtree[a] < tree.subtree[b] : a > b;
      });
    if (tree.children[largest].empty())
    {
      break;
    }
    candidates.erase(std::find(candidates.begin(), candidates.end(), largest));
    candidates.insert(candidates.end(), tree.children[largest].begin(), tree.children[largest].end());
    moved.push_back(largest);
    topSize += tree.size[largest];
  }
  // Owners, parents first: a moved supernode is the top's (-1), a dealt root its bin's, the rest their parent's.
  const auto                nsuper = static_cast<std::int32_t>(m_Factor->nsuper);
  std::vector<std::int32_t> owner(nsuper, -2);
  for (std::size_t k = 0; k < bestMoves; ++k)
  {
    owner[moved[k]] = -1;
  }
  for (const auto & [root, bin] : best.binOf)
  {
    owner[root] = bin;
  }
  m_Top.clear();
  m_Bin.assign(NumberOfBins, {});
  m_TopColumns.clear();
  m_ColumnInTop.assign(m_Factor->n, 0);
  for (std::int32_t s = nsuper - 1; s >= 0; --s)
  {
    if (owner[s] == -2)
    {
      owner[s] = owner[tree.parent[s]];
    }
  }
  for (std::int32_t s = 0; s < nsuper; ++s)
  {
    if (owner[s] >= 0)
    {
      m_Bin[owner[s]].push_back(s);
      continue;
    }
    m_Top.push_back(s);
    for (int k = S.first[s]; k < S.first[s + 1]; ++k)
    {
      m_ColumnInTop[k] = 1;
      m_TopColumns.push_back(k);
    }
  }
  double total = 0.0;
  for (const double v : tree.size)
  {
    total += v;
  }
  const double dealt = std::accumulate(best.load.begin(), best.load.end(), 0.0);
  m_ParallelShare = total > 0.0 ? dealt / total : 0.0;
}

/** y_s <- L_ss^-1 y_s and the update -L_rs y_s of the rows r below the diagonal block, in a workspace v = (y_s, 0)
 * of all the block's rows, four columns at a time: their 4 x 4 triangle, then their update of every row below it
 * (one stream per column). The update is then added to \a shared for the top's rows when it is given, to y
 * otherwise. */
void
SupernodalSolver::ForwardSupernode(std::int32_t s, double * shared, std::vector<double> & work)
{
  const auto & [nscol, nsrow, ld, block, first, rowsBelow] = SupernodeBlock(*m_Factor, s);
  double * y = m_Y.data() + first;
  work.assign(nsrow, 0.0);
  double * v = work.data();
  std::copy(y, y + nscol, v);
  for (int j = 0; j < nscol; j += 4)
  {
    const int end = std::min(j + 4, nscol);
    PrefetchColumns(block + end * ld + end, ld, std::min(4, nscol - end));
    for (int k = j; k < end; ++k)
    {
      const double * column = block + k * ld;
      v[k] /= column[k];
      SubtractColumn(column + k + 1, v[k], v + k + 1, end - k - 1);
    }
    if (end - j == 4)
    {
      SubtractFourColumns(block + j * ld + end, ld, v + j, v + end, nsrow - end);
      continue;
    }
    for (int k = j; k < end; ++k)
    {
      SubtractColumn(block + k * ld + end, v[k], v + end, nsrow - end);
    }
  }
  std::copy(v, v + nscol, y);
  for (int i = 0; i < nsrow - nscol; ++i)
  {
    const int r = rowsBelow[i];
    if (shared != nullptr && m_ColumnInTop[r])
    {
      shared[r] += v[nscol + i];
    }
    else
    {
      m_Y[r] += v[nscol + i];
    }
  }
}

/** z_s = L_ss^-T (y_s - L_rs^T z_r), the rows r below the diagonal block already solved, in a workspace
 * v = (y_s, z_r): groups of four columns from the last, each column's dot with v over the rows after its group
 * (one stream per column), then the group's 4 x 4 triangle. */
void
SupernodalSolver::BackwardSupernode(std::int32_t s, std::vector<double> & work)
{
  const auto & [nscol, nsrow, ld, block, first, rowsBelow] = SupernodeBlock(*m_Factor, s);
  double * z = m_Y.data() + first;
  work.resize(nsrow);
  double * v = work.data();
  std::copy(z, z + nscol, v);
  for (int i = 0; i < nsrow - nscol; ++i)
  {
    v[nscol + i] = m_Y[rowsBelow[i]];
  }
  for (int start = (nscol - 1) / 4 * 4; start >= 0; start -= 4)
  {
    const int end = std::min(start + 4, nscol);
    if (start >= 4)
    {
      PrefetchColumns(block + (start - 4) * ld + start - 4, ld, 4);
    }
    double after[4];
    if (end - start == 4)
    {
      FourDots(block + start * ld + end, ld, v + end, nsrow - end, after);
    }
    else
    {
      for (int k = start; k < end; ++k)
      {
        after[k - start] = Dot(block + k * ld + end, v + end, nsrow - end);
      }
    }
    for (int k = end - 1; k >= start; --k)
    {
      const double * column = block + k * ld;
      double         inGroup = 0.0;
      for (int i = k + 1; i < end; ++i)
      {
        inGroup += column[i] * v[i];
      }
      v[k] = ((v[k] - after[k - start]) - inGroup) / column[k];
    }
  }
  std::copy(v, v + nscol, z);
}

void
SupernodalSolver::ForwardBin(int bin, int worker)
{
  for (const std::int32_t s : m_Bin[bin])
  {
    if (m_Reached[s])
    {
      ForwardSupernode(s, m_Shared[bin].data(), m_Work[worker]);
    }
  }
}

void
SupernodalSolver::BackwardBin(int bin, int worker)
{
  for (auto it = m_Bin[bin].rbegin(); it != m_Bin[bin].rend(); ++it)
  {
    if (m_Needed[*it])
    {
      BackwardSupernode(*it, m_Work[worker]);
    }
  }
}

/** Marks supernode \a s and its ancestors, up to the first one marked before (whose ancestors are). */
void
SupernodalSolver::MarkWithAncestors(std::int32_t s, std::vector<char> & marks) const
{
  for (; s >= 0 && !marks[s]; s = m_Parent[s])
  {
    marks[s] = 1;
  }
}

/** The bins side by side on \a threads threads, or one after the other: the same operations either way. */
void
SupernodalSolver::RunBins(void (SupernodalSolver::*pass)(int, int), unsigned threads, const char * name)
{
  const int bins = static_cast<int>(m_Bin.size());
  if (m_Work.size() < ParallelWorkers(bins, threads))
  {
    m_Work.resize(ParallelWorkers(bins, threads));
  }
  ParallelFor(name, bins, threads, [this, pass](int bin, int worker) { (this->*pass)(bin, worker); });
}

void
SupernodalSolver::Solve(const double * b, double * x, unsigned threads)
{
  Run(b, x, threads, nullptr);
}

void
SupernodalSolver::Solve(const double * b, double * x, unsigned threads, const std::vector<std::int32_t> & observed)
{
  Run(b, x, threads, &observed);
}

void
SupernodalSolver::Run(const double * b, double * x, unsigned threads, const std::vector<std::int32_t> * observed)
{
  const std::size_t n = m_Factor->n;
  const int *       perm = static_cast<const int *>(m_Factor->Perm);
  m_Reached.assign(m_Factor->nsuper, 0);
  for (std::size_t k = 0; k < n; ++k)
  {
    m_Y[k] = perm != nullptr ? b[perm[k]] : b[k];
    if (m_Y[k] != 0.0)
    {
      MarkWithAncestors(m_SupernodeOf[k], m_Reached);
    }
  }
  m_Needed.assign(m_Factor->nsuper, observed == nullptr ? 1 : 0);
  if (observed != nullptr)
  {
    for (const std::int32_t row : *observed)
    {
      MarkWithAncestors(m_SupernodeOf[m_PermutedRow[row]], m_Needed);
    }
  }
  RunBins(&SupernodalSolver::ForwardBin, threads, "solve: forward bins");
  for (const std::int32_t r : m_TopColumns)
  {
    for (std::vector<double> & shared : m_Shared)
    {
      m_Y[r] += shared[r];
      shared[r] = 0.0;
    }
  }
  for (const std::int32_t s : m_Top)
  {
    if (m_Reached[s])
    {
      ForwardSupernode(s, nullptr, m_Work[0]);
    }
  }
  for (auto it = m_Top.rbegin(); it != m_Top.rend(); ++it)
  {
    if (m_Needed[*it])
    {
      BackwardSupernode(*it, m_Work[0]);
    }
  }
  RunBins(&SupernodalSolver::BackwardBin, threads, "solve: backward bins");
  for (std::size_t k = 0; k < n; ++k)
  {
    x[perm != nullptr ? perm[k] : k] = m_Needed[m_SupernodeOf[k]] ? m_Y[k] : 0.0;
  }
}

} // namespace fem
} // namespace bmr
