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
#include "bmrSupernodalFactorize.h"

#include "bmrDenseTiles.h"
#include "bmrParallel.h"
#include "bmrSupernodes.h"

#include <algorithm>
#include <utility>

namespace bmr {
namespace fem {

bool
SupernodalFactorizer::SetStructure(cholmod_factor *                               factor,
                                   cholmod_common &                               common,
                                   int                                            n,
                                   const int *                                    columnStarts,
                                   const int *                                    rowIndices,
                                   const std::vector<std::vector<std::int32_t>> & bins)
{
  m_Factor = nullptr;
  if (factor == nullptr || !factor->is_super || factor->itype != CHOLMOD_INT || factor->dtype != CHOLMOD_DOUBLE ||
      factor->n != static_cast<std::size_t>(n) || factor->nsuper == 0 || bins.empty())
  {
    return false;
  }
  // A symbolic factor (after the analysis) gets its values array; the layout stays.
  if (factor->xtype == CHOLMOD_PATTERN && !cholmod_change_factor(CHOLMOD_REAL, true, true, true, true, factor, &common))
  {
    return false;
  }
  if (!factor->is_ll || factor->xtype != CHOLMOD_REAL)
  {
    return false;
  }
  const Supernodes L(*factor);
  const auto       nsuper = static_cast<std::int32_t>(factor->nsuper);
  const int        topPart = static_cast<int>(bins.size());
  std::vector<int> owner(nsuper, topPart); // a bin, or the top
  m_Bin = bins;
  for (int b = 0; b < topPart; ++b)
  {
    for (const std::int32_t s : m_Bin[b])
    {
      owner[s] = b;
    }
  }
  m_Top.clear();
  for (std::int32_t s = 0; s < nsuper; ++s)
  {
    if (owner[s] == topPart)
    {
      m_Top.push_back(s);
    }
  }
  m_SupernodeOf.assign(n, 0);
  for (std::int32_t s = 0; s < nsuper; ++s)
  {
    std::fill(m_SupernodeOf.begin() + L.first[s], m_SupernodeOf.begin() + L.first[s + 1], s);
  }
  m_Factor = factor;
  if (!PlaceEntries(n, columnStarts, rowIndices, owner) || !UpdatesFit())
  {
    m_Factor = nullptr;
    return false;
  }
  FindPulls(owner);
  // The workspaces hold their part's largest update, so that each is allocated once per analysis.
  m_LargestBelow[0] = m_LargestBelow[1] = 0;
  for (std::int32_t s = 0; s < nsuper; ++s)
  {
    std::size_t & part = m_LargestBelow[owner[s] == topPart ? 1 : 0];
    part = std::max(part, static_cast<std::size_t>(L.Rows(s) - L.Columns(s)));
  }
  m_BinWork.clear();
  m_PullWork.clear();
  m_TopUpdate.clear();
  m_Entries = static_cast<std::size_t>(columnStarts[n]);
  SetVaryingEntries({});
  return true;
}

/** For each bin supernode d, where its rows below reach the top (m_TopRowsFrom: its ancestors in the bin come
 * first, their columns precede the top's), and for each top supernode t the bin supernodes whose rows reach its
 * columns, with the range of those rows (m_Pulls, ascending in d). */
void
SupernodalFactorizer::FindPulls(const std::vector<int> & owner)
{
  const Supernodes L(*m_Factor);
  const auto       nsuper = static_cast<std::int32_t>(m_Factor->nsuper);
  const int        topPart = static_cast<int>(m_Bin.size());
  m_TopRowsFrom.assign(nsuper, 0);
  m_Pulls.assign(nsuper, {});
  for (std::int32_t d = 0; d < nsuper; ++d)
  {
    const int   rowsBelow = L.Rows(d) - L.Columns(d);
    const int * below = L.rows + L.rowsAt[d] + L.Columns(d);
    int         j = 0;
    while (j < rowsBelow && owner[m_SupernodeOf[below[j]]] != topPart)
    {
      ++j;
    }
    m_TopRowsFrom[d] = j;
    if (owner[d] == topPart)
    {
      continue;
    }
    while (j < rowsBelow)
    {
      const std::int32_t t = m_SupernodeOf[below[j]];
      const int          begin = j;
      while (j < rowsBelow && below[j] < L.first[t + 1])
      {
        ++j;
      }
      m_Pulls[t].push_back({ d, begin, j });
    }
  }
}

void
SupernodalFactorizer::SetVaryingEntries(const std::vector<char> & varies)
{
  std::vector<char> supernodeVaries(m_Factor->nsuper, 0);
  m_VaryingEntries.clear();
  for (std::size_t p = 0; p < std::min(varies.size(), m_EntrySupernode.size()); ++p)
  {
    if (varies[p])
    {
      supernodeVaries[m_EntrySupernode[p]] = 1;
      m_VaryingEntries.push_back(p);
    }
  }
  SplitByVariation(std::move(supernodeVaries));
}

/** Marks the ancestors of every varying supernode (its parent holds the first row below its diagonal block, and
 * parents come after children) and splits each part's supernodes into the fixed and the varying, in order. */
void
SupernodalFactorizer::SplitByVariation(std::vector<char> varies)
{
  const Supernodes L(*m_Factor);
  double           all = 0.0, varying = 0.0;
  for (std::int32_t s = 0; s < static_cast<std::int32_t>(m_Factor->nsuper); ++s)
  {
    const double k = L.Columns(s), b = L.Rows(s) - L.Columns(s);
    const double multiplyAdds = k * k * k / 3.0 + b * k * k / 2.0 + b * b * k / 2.0;
    all += multiplyAdds;
    if (varies[s])
    {
      varying += multiplyAdds;
      if (b > 0)
      {
        varies[m_SupernodeOf[L.rows[L.rowsAt[s] + L.Columns(s)]]] = 1;
      }
    }
  }
  m_VaryingShare = all > 0.0 ? varying / all : 0.0;
  m_Varies = varies;
  const auto split = [&varies](const std::vector<std::int32_t> & part,
                               std::vector<std::int32_t> &       fixed,
                               std::vector<std::int32_t> &       varying) {
    fixed.clear();
    varying.clear();
    for (const std::int32_t s : part)
    {
      (varies[s] ? varying : fixed).push_back(s);
    }
  };
  m_FixedBin.resize(m_Bin.size());
  m_VaryingBin.resize(m_Bin.size());
  for (std::size_t b = 0; b < m_Bin.size(); ++b)
  {
    split(m_Bin[b], m_FixedBin[b], m_VaryingBin[b]);
  }
  split(m_Top, m_FixedTop, m_VaryingTop);
  m_FixedPartKept = false;
}

/** Where each entry of A goes in L: column min(i', j'), row max(i', j') of the permuted matrix, in the block of
 * that column's supernode (the row found by bisection in the supernode's ascending row list), and the entries of
 * each part (the bins, then the top), so that each bin writes only its own blocks. False when an entry lies outside L's
 * pattern (not CHOLMOD's analysis of this matrix). */
bool
SupernodalFactorizer::PlaceEntries(int                      n,
                                   const int *              columnStarts,
                                   const int *              rowIndices,
                                   const std::vector<int> & owner)
{
  const Supernodes L(*m_Factor);
  const int *      perm = static_cast<const int *>(m_Factor->Perm);
  std::vector<int> inverse(n);
  for (int k = 0; k < n; ++k)
  {
    inverse[perm ? perm[k] : k] = k;
  }
  const auto entries = static_cast<std::size_t>(columnStarts[n]);
  m_Position.resize(entries);
  m_EntriesOf.assign(m_Bin.size() + 1, {});
  m_EntrySupernode.resize(entries);
  for (int j = 0; j < n; ++j)
  {
    for (int p = columnStarts[j]; p < columnStarts[j + 1]; ++p)
    {
      const int          a = inverse[rowIndices[p]], b = inverse[j];
      const int          column = std::min(a, b), row = std::max(a, b);
      const std::int32_t s = m_SupernodeOf[column];
      const int *        rows = L.rows + L.rowsAt[s];
      const int *        at = std::lower_bound(rows, rows + L.Rows(s), row);
      if (at == rows + L.Rows(s) || *at != row)
      {
        return false;
      }
      m_Position[p] = L.valuesAt[s] + (column - L.first[s]) * L.Rows(s) + static_cast<int>(at - rows);
      m_EntriesOf[owner[s]].push_back(static_cast<std::size_t>(p));
      m_EntrySupernode[p] = s;
    }
  }
  return true;
}

/** Writes A's entries of \a part (a bin, or the top: the number of bins) into L. */
void
SupernodalFactorizer::PlaceValues(int part, const double * values)
{
  const Supernodes L(*m_Factor);
  for (const std::size_t p : m_EntriesOf[part])
  {
    L.values[m_Position[p]] = values[p];
  }
}

/** Whether the rows below every supernode's diagonal block lie, from each of its target columns on, in the row list
 * of the target's supernode (the supernodal pattern's closure, which Scatter() relies on instead of checking). */
bool
SupernodalFactorizer::UpdatesFit() const
{
  const Supernodes L(*m_Factor);
  for (std::int32_t s = 0; s < static_cast<std::int32_t>(m_Factor->nsuper); ++s)
  {
    const int   b = L.Rows(s) - L.Columns(s);
    const int * below = L.rows + L.rowsAt[s] + L.Columns(s);
    for (int j = 0; j < b;)
    {
      const std::int32_t t = m_SupernodeOf[below[j]];
      if (t <= s)
      {
        return false;
      }
      const int * rows = L.rows + L.rowsAt[t];
      for (int i = j, q = 0; i < b; ++i, ++q)
      {
        while (q < L.Rows(t) && rows[q] != below[i])
        {
          ++q;
        }
        if (q == L.Rows(t))
        {
          return false;
        }
      }
      while (j < b && below[j] < L.first[t + 1])
      {
        ++j;
      }
    }
  }
  return true;
}

int
SupernodalFactorizer::Factorize(const double * fixedValues, const double * varyingValues, unsigned threads)
{
  m_FixedPartKept = false;
  const int  n = static_cast<int>(m_Factor->n);
  const int  column = FactorizeParts(m_FixedBin, m_FixedTop, fixedValues, false, threads);
  const bool noneVaries =
    m_VaryingTop.empty() &&
    std::all_of(m_VaryingBin.begin(), m_VaryingBin.end(), [](const auto & bin) { return bin.empty(); });
  if (column < n || noneVaries)
  {
    return column;
  }
  KeepVaryingBlocks(false);
  m_FixedPartKept = true;
  return FactorizeVarying(varyingValues, threads, false);
}

int
SupernodalFactorizer::FactorizeVarying(const double * varyingValues, unsigned threads)
{
  if (!m_FixedPartKept)
  {
    return -1;
  }
  return FactorizeVarying(varyingValues, threads, true);
}

int
SupernodalFactorizer::FactorizeVarying(const double * varyingValues, unsigned threads, bool restore)
{
  if (restore)
  {
    KeepVaryingBlocks(true);
  }
  if (varyingValues != nullptr)
  {
    const Supernodes L(*m_Factor);
    for (const std::size_t p : m_VaryingEntries)
    {
      L.values[m_Position[p]] += varyingValues[p];
    }
  }
  return FactorizeParts(m_VaryingBin, m_VaryingTop, nullptr, true, threads);
}

/** Copies the varying supernodes' blocks into m_KeptBlocks, or back (\a restore). */
void
SupernodalFactorizer::KeepVaryingBlocks(bool restore)
{
  const Supernodes                               L(*m_Factor);
  std::size_t                                    size = 0;
  std::vector<const std::vector<std::int32_t> *> parts;
  for (const auto & bin : m_VaryingBin)
  {
    parts.push_back(&bin);
  }
  parts.push_back(&m_VaryingTop);
  for (const auto * part : parts)
  {
    for (const std::int32_t s : *part)
    {
      size += L.BlockSize(s);
    }
  }
  m_KeptBlocks.resize(size);
  double * kept = m_KeptBlocks.data();
  for (const auto * part : parts)
  {
    for (const std::int32_t s : *part)
    {
      if (restore)
      {
        std::copy(kept, kept + L.BlockSize(s), L.Block(s));
      }
      else
      {
        std::copy(L.Block(s), L.Block(s) + L.BlockSize(s), kept);
      }
      kept += L.BlockSize(s);
    }
  }
}

/** The supernodes \a bins (each a subsequence of that bin's) side by side, the top blocks' pulls, then \a top in
 * order. With \a values, every block is first set to A's entries and every top block pulls (the fixed pass);
 * without, the blocks hold what they hold and only \a top's pull. Pulled are the bin supernodes of this pass: the
 * varying (\a varyingPass) or the others. */
int
SupernodalFactorizer::FactorizeParts(const std::vector<std::vector<std::int32_t>> & bins,
                                     const std::vector<std::int32_t> &              top,
                                     const double *                                 values,
                                     bool                                           varyingPass,
                                     unsigned                                       threads)
{
  const Supernodes L(*m_Factor);
  const int        n = static_cast<int>(m_Factor->n);
  if (values != nullptr)
  {
    for (const std::int32_t s : m_Top)
    {
      std::fill(L.Block(s), L.Block(s) + L.BlockSize(s), 0.0);
    }
    PlaceValues(static_cast<int>(m_Bin.size()), values);
  }
  const int        count = static_cast<int>(bins.size());
  std::vector<int> failed(count, n);
  for (unsigned w = 0; w < ParallelWorkers(count, threads); ++w)
  {
    WorkspaceFor(m_BinWork, w, m_LargestBelow[0] * m_LargestBelow[0], m_LargestBelow[0]);
  }
  ParallelFor("factorize: bins", count, threads, [&](int bin, int worker) {
    failed[bin] = FactorizeBin(bin, bins[bin], values, m_BinWork[worker]);
  });
  const int firstFailed = *std::min_element(failed.begin(), failed.end());
  if (firstFailed < n)
  {
    return firstFailed;
  }
  PullBinUpdates(values != nullptr ? m_Top : top, varyingPass, threads);
  for (const std::int32_t s : top)
  {
    const int column = FactorizeTopSupernode(s, threads);
    if (column < n)
    {
      return column;
    }
  }
  m_Factor->minor = m_Factor->n;
  return n;
}

/** The workspace of \a worker in \a pool, made (once) with room for \a updateSize values and \a rows rows. */
SupernodalFactorizer::Workspace &
SupernodalFactorizer::WorkspaceFor(std::vector<Workspace> & pool,
                                   std::size_t              worker,
                                   std::size_t              updateSize,
                                   std::size_t              rows)
{
  if (pool.size() <= worker)
  {
    pool.resize(worker + 1);
  }
  Workspace & work = pool[worker];
  if (work.update.size() < updateSize)
  {
    work.update.resize(updateSize);
  }
  if (work.relative.size() < rows)
  {
    work.relative.resize(rows);
  }
  return work;
}

/** With \a values, the bin's blocks from A; then \a supernodes (of this bin) in order (children before parents). */
int
SupernodalFactorizer::FactorizeBin(int                               bin,
                                   const std::vector<std::int32_t> & supernodes,
                                   const double *                    values,
                                   Workspace &                       work)
{
  const Supernodes L(*m_Factor);
  if (values != nullptr)
  {
    for (const std::int32_t s : m_Bin[bin])
    {
      std::fill(L.Block(s), L.Block(s) + L.BlockSize(s), 0.0);
    }
    PlaceValues(bin, values);
  }
  const int n = static_cast<int>(m_Factor->n);
  for (const std::int32_t s : supernodes)
  {
    const int column = FactorizeBinSupernode(s, work);
    if (column < n)
    {
      return column;
    }
  }
  return n;
}

/** L_ss = chol(B_ss), L_rs = B_rs L_ss^-T, and the update L_rs L_rs^T of the ancestors in the bin: its columns
 * before m_TopRowsFrom[s] (dsyrk over those rows, dgemm for the rows below them), scattered into their blocks. */
int
SupernodalFactorizer::FactorizeBinSupernode(std::int32_t s, Workspace & work)
{
  const Supernodes L(*m_Factor);
  const int        k = L.Columns(s), m = L.Rows(s), b = m - k, inBin = m_TopRowsFrom[s];
  double *         block = L.Block(s);
  const int        info = FactorDiagonal(k, block, m);
  if (info != 0)
  {
    return L.first[s] + std::max(info, 1) - 1;
  }
  if (b > 0)
  {
    SolveBelow(b, k, block, m, block + k, m);
  }
  if (inBin > 0)
  {
    double * update = work.update.data(); // b x b fits: SetStructure()
    SymmetricUpdate(inBin, k, 1.0, block + k, m, 0.0, update, b);
    if (b > inBin)
    {
      MultiplyTransposed(b - inBin, inBin, k, 1.0, block + k + inBin, m, block + k, m, 0.0, update + inBin, b);
    }
    ScatterColumns(s, update, 0, inBin, work.relative.data());
  }
  return static_cast<int>(m_Factor->n);
}

/** Each block of \a top pulls the updates of its bin descendants of this pass, in tiles of its columns side by
 * side. */
void
SupernodalFactorizer::PullBinUpdates(const std::vector<std::int32_t> & top, bool varyingPass, unsigned threads)
{
  const Supernodes                 L(*m_Factor);
  std::vector<std::pair<int, int>> tasks; // (index in top, first column of the tile)
  for (std::size_t i = 0; i < top.size(); ++i)
  {
    if (m_Pulls[top[i]].empty())
    {
      continue;
    }
    for (int c = 0; c < L.Columns(top[i]); c += TileSize)
    {
      tasks.emplace_back(static_cast<int>(i), c);
    }
  }
  for (unsigned w = 0; w < ParallelWorkers(static_cast<int>(tasks.size()), threads); ++w)
  {
    WorkspaceFor(m_PullWork, w, m_LargestBelow[0] * TileSize, m_LargestBelow[0]);
  }
  ParallelFor("factorize: pulls", static_cast<int>(tasks.size()), threads, [&](int task, int worker) {
    const auto [index, column] = tasks[task];
    const std::int32_t t = top[index];
    PullColumns(t, column, std::min(column + TileSize, L.Columns(t)), varyingPass, m_PullWork[worker]);
  });
}

/** Columns [firstColumn, endColumn) of top supernode t minus, for each bin descendant d of this pass in ascending
 * order, L_{r,d} L_{j,d}^T: j the rows of d in those columns, r those and every row of d after them (one dgemm). */
void
SupernodalFactorizer::PullColumns(std::int32_t t, int firstColumn, int endColumn, bool varyingPass, Workspace & work)
{
  const Supernodes L(*m_Factor);
  const int *      rowsOfT = L.rows + L.rowsAt[t];
  const int        ld = L.Rows(t);
  double *         target = L.Block(t);
  for (const Pull & pull : m_Pulls[t])
  {
    const std::int32_t d = pull.from;
    if ((!m_Varies.empty() && m_Varies[d] != 0) != varyingPass)
    {
      continue;
    }
    const int   k = L.Columns(d), m = L.Rows(d), b = m - k;
    const int * below = L.rows + L.rowsAt[d] + k;
    const int   j0 =
      static_cast<int>(std::lower_bound(below + pull.begin, below + pull.end, L.first[t] + firstColumn) - below);
    const int j1 = static_cast<int>(std::lower_bound(below + j0, below + pull.end, L.first[t] + endColumn) - below);
    if (j0 == j1)
    {
      continue;
    }
    const int      rows = b - j0, columns = j1 - j0;
    const double * lower = L.Block(d) + k + j0;
    double *       product = work.update.data(); // rows x columns fits: PullBinUpdates()
    MultiplyTransposed(rows, columns, k, 1.0, lower, m, lower, m, 0.0, product, rows);
    int * relative = work.relative.data();
    for (int i = j0, q = 0; i < b; ++i, ++q)
    {
      while (rowsOfT[q] != below[i]) // present: UpdatesFit()
      {
        ++q;
      }
      relative[i - j0] = q;
    }
    for (int j = j0; j < j1; ++j)
    {
      double *       column = target + static_cast<std::size_t>(below[j] - L.first[t]) * ld;
      const double * c = product + static_cast<std::size_t>(j - j0) * rows;
      for (int i = j - j0; i < rows; ++i)
      {
        column[relative[i]] -= c[i];
      }
    }
  }
}

/** A top supernode in tiles: its panel (FactorizePanelInTiles()), then its update of its ancestors in tiles
 * (OuterProductInTiles()) scattered in tiles of its columns, side by side (each column of C into one target). */
int
SupernodalFactorizer::FactorizeTopSupernode(std::int32_t s, unsigned threads)
{
  const Supernodes L(*m_Factor);
  const int        k = L.Columns(s), m = L.Rows(s), b = m - k;
  double *         block = L.Block(s);
  const int        info = FactorizePanelInTiles(block, k, m, threads);
  if (info != 0)
  {
    return L.first[s] + std::max(info, 1) - 1;
  }
  if (b == 0)
  {
    return static_cast<int>(m_Factor->n);
  }
  m_TopUpdate.resize(std::max(m_TopUpdate.size(), m_LargestBelow[1] * m_LargestBelow[1]));
  OuterProductInTiles(block + k, m, b, k, m_TopUpdate.data(), threads);
  const int tiles = (b + TileSize - 1) / TileSize;
  for (unsigned w = 0; w < ParallelWorkers(tiles, threads); ++w)
  {
    WorkspaceFor(m_PullWork, w, 0, m_LargestBelow[1]);
  }
  ParallelFor("factorize: scatter", tiles, threads, [&](int tile, int worker) {
    ScatterColumns(
      s, m_TopUpdate.data(), tile * TileSize, std::min(b, (tile + 1) * TileSize), m_PullWork[worker].relative.data());
  });
  return static_cast<int>(m_Factor->n);
}

/** Subtracts columns [begin, end) of the b x b update C (lower triangle, leading dimension b) of supernode s from
 * the blocks of its ancestors: the columns that fall in one ancestor t at a time, each row placed by its position
 * in t's row list (\a relative: room for b rows). */
void
SupernodalFactorizer::ScatterColumns(std::int32_t s, const double * update, int begin, int end, int * relative)
{
  const Supernodes L(*m_Factor);
  const int        b = L.Rows(s) - L.Columns(s);
  const int *      below = L.rows + L.rowsAt[s] + L.Columns(s);
  for (int j = begin; j < end;)
  {
    const std::int32_t t = m_SupernodeOf[below[j]];
    const int *        rows = L.rows + L.rowsAt[t];
    for (int i = j, q = 0; i < b; ++i, ++q)
    {
      while (rows[q] != below[i]) // present: UpdatesFit()
      {
        ++q;
      }
      relative[i] = q;
    }
    const int ld = L.Rows(t);
    double *  target = L.Block(t);
    for (; j < end && below[j] < L.first[t + 1]; ++j)
    {
      double *       column = target + static_cast<std::size_t>(below[j] - L.first[t]) * ld;
      const double * c = update + static_cast<std::size_t>(j) * b;
      for (int i = j; i < b; ++i)
      {
        column[relative[i]] -= c[i];
      }
    }
  }
}

} // namespace fem
} // namespace bmr
