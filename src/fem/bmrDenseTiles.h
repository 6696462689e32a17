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
#ifndef bmrDenseTiles_h
#define bmrDenseTiles_h

// Dense block operations of the supernodal factorization, one BLAS call each or in tiles (private to src/fem).
namespace bmr {
namespace fem {

/** Tiles of the large supernodes: 192 x 192 (a dgemm of 7 M multiply-adds: fine enough to share a separator of a
 * few thousand columns among threads, coarse enough for the BLAS to run at its speed). */
constexpr int TileSize = 192;

/** L_kk = chol(A_kk) in place (lower); 0, or LAPACK's info (> 0: the leading minor of that order is not positive). */
int
FactorDiagonal(int k, double * a, int ld);

/** B <- B L^-T for the rows x k block B below the k x k factor L. */
void
SolveBelow(int rows, int k, const double * l, int ld, double * b, int ldb);

/** C <- beta C + alpha A A^T (lower triangle) for the n x k block A. */
void
SymmetricUpdate(int n, int k, double alpha, const double * a, int lda, double beta, double * c, int ldc);

/** C <- beta C + alpha A B^T for the m x k block A and the n x k block B. */
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
                   int            ldc);

/** The panel of a supernode, its k x k diagonal block over the rows - k rows below it (column-major, leading
 * dimension rows), factorized in place in tiles, right-looking: for each tile column, the diagonal tile's Cholesky
 * factor, every tile below it solved (one task each), then the trailing tiles updated (one task each). The row tiles
 * are the column tiles, then the rows below the diagonal block in tiles of their own, so that no tile straddles the
 * two. Each task is one single-threaded BLAS call on fixed tile boundaries: the same bits on any number of
 * \a threads. Returns 0, or the column (1-based, as LAPACK's info) at which the block is not positive definite. */
int
FactorizePanelInTiles(double * block, int k, int rows, unsigned threads);

/** C = B B^T (the lower triangle of the n x n block C, leading dimension n) for the n x k block B (leading dimension
 * ldb), in tiles of C (one dsyrk or dgemm of depth k each): the same bits on any number of \a threads. */
void
OuterProductInTiles(const double * b, int ldb, int n, int k, double * c, unsigned threads);

} // namespace fem
} // namespace bmr

#endif
