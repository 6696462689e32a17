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
#include "bmrDenseTiles.h"

#include "bmrParallel.h"

#include <algorithm>
#include <utility>
#include <vector>

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

int
FactorDiagonal(int k, double * a, int ld)
{
  int info = 0;
  dpotrf_("L", &k, a, &ld, &info);
  return info;
}

void
SolveBelow(int rows, int k, const double * l, int ld, double * b, int ldb)
{
  const double one = 1.0;
  dtrsm_("R", "L", "T", "N", &rows, &k, &one, l, &ld, b, &ldb);
}

void
SymmetricUpdate(int n, int k, double alpha, const double * a, int lda, double beta, double * c, int ldc)
{
  dsyrk_("L", "N", &n, &k, &alpha, a, &lda, &beta, c, &ldc);
}

void
MultiplyTransposed(int            m,
                   int            n,
                   int            k,
                   double         alpha,
                   const double * a,
                   int            lda,
                   const double * b,
                   int            ldb,
                   double         beta,
                   double *       c,
                   int            ldc)
{
  dgemm_("N", "T", &m, &n, &k, &alpha, a, &lda, b, &ldb, &beta, c, &ldc);
}

namespace {

/** Row tiles of a panel: the column tiles of its k x k diagonal block, then the rows below it in tiles. */
struct PanelTiles
{
  int k, rows, columnTiles, rowTiles;

  PanelTiles(int columns, int allRows)
    : k(columns)
    , rows(allRows)
    , columnTiles((columns + TileSize - 1) / TileSize)
    , rowTiles(columnTiles + (allRows - columns + TileSize - 1) / TileSize)
  {}
  int
  Start(int tile) const
  {
    return tile < columnTiles ? tile * TileSize : k + (tile - columnTiles) * TileSize;
  }
  int
  Height(int tile) const
  {
    return tile < columnTiles ? std::min(TileSize, k - tile * TileSize)
                              : std::min(TileSize, rows - k - (tile - columnTiles) * TileSize);
  }
};

} // namespace

int
FactorizePanelInTiles(double * block, int k, int rows, unsigned threads)
{
  const PanelTiles tiles(k, rows);
  const auto       at = [block, rows, &tiles](int i, int j) {
    return block + static_cast<std::size_t>(j) * TileSize * rows + tiles.Start(i);
  };
  std::vector<std::pair<int, int>> trailing;
  for (int kt = 0; kt < tiles.columnTiles; ++kt)
  {
    const int width = tiles.Height(kt);
    const int info = FactorDiagonal(width, at(kt, kt), rows);
    if (info != 0)
    {
      return kt * TileSize + info;
    }
    ParallelFor("panel: tiles below", tiles.rowTiles - kt - 1, threads, [&](int task, int) {
      const int it = kt + 1 + task;
      SolveBelow(tiles.Height(it), width, at(kt, kt), rows, at(it, kt), rows);
    });
    trailing.clear();
    for (int jt = kt + 1; jt < tiles.columnTiles; ++jt)
    {
      for (int it = jt; it < tiles.rowTiles; ++it)
      {
        trailing.emplace_back(it, jt);
      }
    }
    ParallelFor("panel: trailing tiles", static_cast<int>(trailing.size()), threads, [&](int task, int) {
      const auto [it, jt] = trailing[task];
      if (it == jt)
      {
        SymmetricUpdate(tiles.Height(it), width, -1.0, at(it, kt), rows, 1.0, at(it, it), rows);
      }
      else
      {
        MultiplyTransposed(
          tiles.Height(it), tiles.Height(jt), width, -1.0, at(it, kt), rows, at(jt, kt), rows, 1.0, at(it, jt), rows);
      }
    });
  }
  return 0;
}

void
OuterProductInTiles(const double * b, int ldb, int n, int k, double * c, unsigned threads)
{
  const int                        tiles = (n + TileSize - 1) / TileSize;
  std::vector<std::pair<int, int>> lower;
  for (int jt = 0; jt < tiles; ++jt)
  {
    for (int it = jt; it < tiles; ++it)
    {
      lower.emplace_back(it, jt);
    }
  }
  ParallelFor("update: tiles", static_cast<int>(lower.size()), threads, [&](int task, int) {
    const auto [it, jt] = lower[task];
    const int i0 = it * TileSize, j0 = jt * TileSize;
    const int height = std::min(TileSize, n - i0), width = std::min(TileSize, n - j0);
    double *  tile = c + static_cast<std::size_t>(j0) * n + i0;
    if (it == jt)
    {
      SymmetricUpdate(height, k, 1.0, b + i0, ldb, 0.0, tile, n);
    }
    else
    {
      MultiplyTransposed(height, width, k, 1.0, b + i0, ldb, b + j0, ldb, 0.0, tile, n);
    }
  });
}

} // namespace fem
} // namespace bmr
