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

#include "bmrSupernodes.h"

#include <algorithm>
#include <atomic>
#include <memory>
#include <numeric>
#include <system_error>
#include <thread>
#include <utility>

// LAPACK and BLAS (Fortran interface), as CHOLMOD declares them.
extern "C" {
void
dpotrf_(const char * uplo, const int * n, double * a, const int * lda, int * info);
void
dtrsm_(const char *   side,
       const char *   uplo,
       const char *   transa,
       const char *   diag,
       const int *    m,
       const int *    n,
       const double * alpha,
       const double * a,
       const int *    lda,
       double *       b,
       const int *    ldb);
void
dsyrk_(const char *   uplo,
       const char *   trans,
       const int *    n,
       const int *    k,
       const double * alpha,
       const double * a,
       const int *    lda,
       const double * beta,
       double *       c,
       const int *    ldc);
void
dgemm_(const char *   transa,
       const char *   transb,
       const int *    m,
       const int *    n,
       const int *    k,
       const double * alpha,
       const double * a,
       const int *    lda,
       const double * b,
       const int *    ldb,
       const double * beta,
       double *       c,
       const int *    ldc);
}

namespace bmr {
namespace fem {
namespace {

/** Tiles of the dense root separator: 192 x 192 (a dgemm of 7 M multiply-adds, ~0.3 ms: fine enough to share a
 * 2316-column root among two threads, coarse enough for the BLAS to run at its speed). */
constexpr int TileSize = 192;


/** L_kk = chol(A_kk) in place (lower); 0, or LAPACK's info (> 0: the leading minor of that order is not positive). */
int
FactorDiagonal(int k, double * a, int ld)
{
  int info = 0;
  dpotrf_("L", &k, a, &ld, &info);
  return info;
}

/** B <- B L^-T for the rows x k block B below the k x k factor L. */
void
SolveBelow(int rows, int k, const double * l, int ld, double * b, int ldb)
{
  const double one = 1.0;
  dtrsm_("R", "L", "T", "N", &rows, &k, &one, l, &ld, b, &ldb);
}

/** C <- beta C + alpha A A^T (lower triangle) for the n x k block A. */
void
SymmetricUpdate(int n, int k, double alpha, const double * a, int lda, double beta, double * c, int ldc)
{
  dsyrk_("L", "N", &n, &k, &alpha, a, &lda, &beta, c, &ldc);
}

/** C <- C - A B^T for the m x k block A and the n x k block B. */
void
SubtractProduct(int m, int n, int k, const double * a, int lda, const double * b, int ldb, double * c, int ldc)
{
  const double minusOne = -1.0, one = 1.0;
  dgemm_("N", "T", &m, &n, &k, &minusOne, a, &lda, b, &ldb, &one, c, &ldc);
}

/** task(0), ..., task(count - 1), each once, on \a threads threads (2 at most); the tasks must be independent. */
template<typename TTask>
void
RunTasks(int count, unsigned threads, const TTask & task)
{
  std::atomic<int> next{ 0 };
  const auto       work = [&next, &task, count]() {
    for (int i = next.fetch_add(1); i < count; i = next.fetch_add(1))
    {
      task(i);
    }
  };
  std::thread helper;
  if (threads >= 2 && count > 1)
  {
    try
    {
      helper = std::thread(work);
    }
    catch (const std::system_error &)
    {
      // No thread to be had: the same tasks on this one.
    }
  }
  work();
  if (helper.joinable())
  {
    helper.join();
  }
}

} // namespace

bool
SupernodalFactorizer::SetStructure(cholmod_factor *                  factor,
                                   cholmod_common &                  common,
                                   int                               n,
                                   const int *                       columnStarts,
                                   const int *                       rowIndices,
                                   const std::vector<std::int32_t> * bins)
{
  m_Factor = nullptr;
  if (factor == nullptr || !factor->is_super || factor->itype != CHOLMOD_INT || factor->dtype != CHOLMOD_DOUBLE ||
      factor->n != static_cast<std::size_t>(n) || factor->nsuper == 0)
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
  std::vector<int> owner(nsuper, 2); // bin 0, bin 1, or the top (2)
  for (int b = 0; b < 2; ++b)
  {
    m_Bin[b] = bins[b];
    for (const std::int32_t s : m_Bin[b])
    {
      owner[s] = b;
    }
  }
  m_Top.clear();
  m_AccumulatorAt.assign(nsuper, -1);
  std::int64_t accumulated = 0;
  for (std::int32_t s = 0; s < nsuper; ++s)
  {
    if (owner[s] == 2)
    {
      m_Top.push_back(s);
      m_AccumulatorAt[s] = accumulated;
      accumulated += static_cast<std::int64_t>(L.BlockSize(s));
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
  // Not written here: bin 1 zeroes the accumulator in every factorization, beside bin 0, and the dsyrk overwrites
  // the update workspaces (first writes cost page faults). Each workspace holds its part's largest update, so that
  // it is allocated once per analysis (the top uses bin 0's).
  std::size_t largest[2] = { 0, 0 }; // rows below the diagonal block
  for (std::int32_t s = 0; s < nsuper; ++s)
  {
    std::size_t & part = largest[owner[s] == 1 ? 1 : 0];
    part = std::max(part, static_cast<std::size_t>(L.Rows(s) - L.Columns(s)));
  }
  for (int b = 0; b < 2; ++b)
  {
    m_Update[b].reset(new double[std::max<std::size_t>(largest[b] * largest[b], 1)]);
    m_Relative[b].assign(largest[b], 0);
  }
  m_Accumulator.reset(new double[static_cast<std::size_t>(accumulated)]);
  m_AccumulatorSize = static_cast<std::size_t>(accumulated);
  m_Entries = static_cast<std::size_t>(columnStarts[n]);
  SetVaryingEntries({});
  return true;
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
  split(m_Bin[0], m_FixedBin[0], m_VaryingBin[0]);
  split(m_Bin[1], m_FixedBin[1], m_VaryingBin[1]);
  split(m_Top, m_FixedTop, m_VaryingTop);
  m_FixedPartKept = false;
}

/** Where each entry of A goes in L: column min(i', j'), row max(i', j') of the permuted matrix, in the block of
 * that column's supernode (the row found by bisection in the supernode's ascending row list), and which part owns
 * that block, so that each bin writes only its own. False when an entry lies outside L's pattern (not CHOLMOD's
 * analysis of this matrix). */
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
  m_Owner.resize(entries);
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
      m_Owner[p] = static_cast<char>(owner[s]);
      m_EntrySupernode[p] = s;
    }
  }
  return true;
}

/** Writes A's entries of \a part (bin 0, bin 1, the top: 2) into L. */
void
SupernodalFactorizer::PlaceValues(int part, const double * values)
{
  const Supernodes L(*m_Factor);
  for (std::size_t p = 0; p < m_Position.size(); ++p)
  {
    if (m_Owner[p] == part)
    {
      L.values[m_Position[p]] = values[p];
    }
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
  const int n = static_cast<int>(m_Factor->n);
  const int column = FactorizeParts(m_FixedBin, m_FixedTop, fixedValues, threads);
  if (column < n || (m_VaryingTop.empty() && m_VaryingBin[0].empty() && m_VaryingBin[1].empty()))
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
  return FactorizeParts(m_VaryingBin, m_VaryingTop, nullptr, threads);
}

/** Copies the varying supernodes' blocks into m_KeptBlocks, or back (\a restore). */
void
SupernodalFactorizer::KeepVaryingBlocks(bool restore)
{
  const Supernodes L(*m_Factor);
  std::size_t      size = 0;
  for (const auto * part : { &m_VaryingBin[0], &m_VaryingBin[1], &m_VaryingTop })
  {
    for (const std::int32_t s : *part)
    {
      size += L.BlockSize(s);
    }
  }
  m_KeptBlocks.resize(size);
  double * kept = m_KeptBlocks.data();
  for (const auto * part : { &m_VaryingBin[0], &m_VaryingBin[1], &m_VaryingTop })
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

/** The supernodes \a bins (each a subsequence of that bin's) side by side, then \a top in order. With \a values,
 * every block is first set to A's entries (\a values) and the accumulated updates of bin 1 are subtracted from every
 * top block; without, the blocks hold what they hold and only \a top's receive them. */
int
SupernodalFactorizer::FactorizeParts(const std::vector<std::int32_t> * bins,
                                     const std::vector<std::int32_t> & top,
                                     const double *                    values,
                                     unsigned                          threads)
{
  const Supernodes L(*m_Factor);
  const int        n = static_cast<int>(m_Factor->n);
  if (values != nullptr)
  {
    for (const std::int32_t s : m_Top)
    {
      std::fill(L.Block(s), L.Block(s) + L.BlockSize(s), 0.0);
    }
    PlaceValues(2, values);
  }
  int         failed[2] = { n, n };
  const auto  runBin = [this, bins, values, &failed](int bin) { failed[bin] = FactorizeBin(bin, bins[bin], values); };
  std::thread helper;
  if (threads >= 2 && !m_Bin[0].empty() && !m_Bin[1].empty())
  {
    try
    {
      helper = std::thread(runBin, 1);
    }
    catch (const std::system_error &)
    {
      // No thread to be had: the same work in sequence.
    }
  }
  runBin(0);
  if (helper.joinable())
  {
    helper.join();
  }
  else
  {
    runBin(1);
  }
  if (std::min(failed[0], failed[1]) < n)
  {
    return std::min(failed[0], failed[1]);
  }
  for (const std::int32_t s : values != nullptr ? m_Top : top)
  {
    double *       block = L.Block(s);
    const double * accumulated = m_Accumulator.get() + m_AccumulatorAt[s];
    const auto     size = L.BlockSize(s);
    for (std::size_t e = 0; e < size; ++e)
    {
      block[e] -= accumulated[e];
    }
  }
  for (const std::int32_t s : top)
  {
    const bool dense = L.Rows(s) == L.Columns(s) && L.Columns(s) > 2 * TileSize;
    const int  column = dense ? FactorizeDenseRoot(s, threads) : FactorizeSupernode(s, 0);
    if (column < n)
    {
      return column;
    }
  }
  m_Factor->minor = m_Factor->n;
  return n;
}

/** With \a values, the bin's blocks from A; then \a supernodes (of this bin) in order (children before parents). */
int
SupernodalFactorizer::FactorizeBin(int bin, const std::vector<std::int32_t> & supernodes, const double * values)
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
  if (bin == 1)
  {
    std::fill(m_Accumulator.get(), m_Accumulator.get() + m_AccumulatorSize, 0.0);
  }
  const int n = static_cast<int>(m_Factor->n);
  for (const std::int32_t s : supernodes)
  {
    const int column = FactorizeSupernode(s, bin);
    if (column < n)
    {
      return column;
    }
  }
  return n;
}

/** L_ss = chol(B_ss), L_rs = B_rs L_ss^-T, and the update L_rs L_rs^T of the ancestors (Scatter()). */
int
SupernodalFactorizer::FactorizeSupernode(std::int32_t s, int bin)
{
  const Supernodes L(*m_Factor);
  const int        k = L.Columns(s), m = L.Rows(s), b = m - k;
  double *         block = L.Block(s);
  const int        info = FactorDiagonal(k, block, m);
  if (info != 0)
  {
    return L.first[s] + std::max(info, 1) - 1;
  }
  if (b > 0)
  {
    SolveBelow(b, k, block, m, block + k, m);
    double * update = m_Update[bin].get(); // b x b fits: SetStructure()
    SymmetricUpdate(b, k, 1.0, block + k, m, 0.0, update, b);
    Scatter(s, update, bin);
  }
  return static_cast<int>(m_Factor->n);
}

/** Subtracts the b x b update C (lower triangle) of supernode s from the blocks of its ancestors: the columns of C
 * that fall in one ancestor t at a time, each row placed by its position in t's row list. Bin 1 adds its updates
 * of the top into the accumulator instead. */
void
SupernodalFactorizer::Scatter(std::int32_t s, const double * update, int bin)
{
  const Supernodes L(*m_Factor);
  const int        b = L.Rows(s) - L.Columns(s);
  const int *      below = L.rows + L.rowsAt[s] + L.Columns(s);
  int *            relative = m_Relative[bin].data(); // b fit: SetStructure()
  for (int j = 0; j < b;)
  {
    const std::int32_t t = m_SupernodeOf[below[j]];
    const int *        rows = L.rows + L.rowsAt[t];
    const int          ld = L.Rows(t);
    for (int i = j, q = 0; i < b; ++i, ++q)
    {
      while (rows[q] != below[i]) // present: UpdatesFit()
      {
        ++q;
      }
      relative[i] = q;
    }
    const bool accumulate = bin == 1 && m_AccumulatorAt[t] >= 0; // bin 1 and a top supernode
    double *   target = accumulate ? m_Accumulator.get() + m_AccumulatorAt[t] : L.Block(t);
    for (; j < b && below[j] < L.first[t + 1]; ++j)
    {
      double *       column = target + static_cast<std::size_t>(below[j] - L.first[t]) * ld;
      const double * c = update + static_cast<std::size_t>(j) * b;
      if (accumulate)
      {
        for (int i = j; i < b; ++i)
        {
          column[relative[i]] += c[i];
        }
      }
      else
      {
        for (int i = j; i < b; ++i)
        {
          column[relative[i]] -= c[i];
        }
      }
    }
  }
}

/** The dense root (no rows below its diagonal block) in tiles, right-looking: for each tile column kt, the
 * diagonal tile's factor, the tiles below it solved (one task each), then the trailing tiles (i >= j > kt) updated
 * (one task each). The tasks of a step are independent and each one BLAS call: the same result on any thread. */
int
SupernodalFactorizer::FactorizeDenseRoot(std::int32_t s, unsigned threads)
{
  const Supernodes L(*m_Factor);
  const int        k = L.Columns(s), ld = L.Rows(s), tiles = (k + TileSize - 1) / TileSize;
  double *         a = L.Block(s);
  const auto       tile = [a, ld](int i, int j) {
    return a + static_cast<std::size_t>(j) * TileSize * ld + static_cast<std::size_t>(i) * TileSize;
  };
  const auto                       width = [k](int i) { return std::min(TileSize, k - i * TileSize); };
  std::vector<std::pair<int, int>> trailing;
  for (int kt = 0; kt < tiles; ++kt)
  {
    const int info = FactorDiagonal(width(kt), tile(kt, kt), ld);
    if (info != 0)
    {
      return L.first[s] + kt * TileSize + std::max(info, 1) - 1;
    }
    RunTasks(tiles - kt - 1, threads, [&](int task) {
      const int it = kt + 1 + task;
      SolveBelow(width(it), width(kt), tile(kt, kt), ld, tile(it, kt), ld);
    });
    trailing.clear();
    for (int jt = kt + 1; jt < tiles; ++jt)
    {
      for (int it = jt; it < tiles; ++it)
      {
        trailing.emplace_back(it, jt);
      }
    }
    RunTasks(static_cast<int>(trailing.size()), threads, [&](int task) {
      const auto [it, jt] = trailing[task];
      if (it == jt)
      {
        SymmetricUpdate(width(it), width(kt), -1.0, tile(it, kt), ld, 1.0, tile(it, it), ld);
      }
      else
      {
        SubtractProduct(width(it), width(jt), width(kt), tile(it, kt), ld, tile(jt, kt), ld, tile(it, jt), ld);
      }
    });
  }
  return static_cast<int>(m_Factor->n);
}

} // namespace fem
} // namespace bmr
