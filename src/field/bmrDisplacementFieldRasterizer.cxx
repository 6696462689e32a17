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
#include "bmrDisplacementFieldRasterizer.h"

#include <ostream>

#include "bmrError.h"
#include "itkMultiThreaderBase.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <memory>
#include <thread>
#if defined(__SSE2__)
#  include <emmintrin.h>
#endif
#if defined(__linux__)
#  include <sys/mman.h>
#endif

namespace bmr {
namespace {
/** Inverse of a row-major 3x3 matrix; returns the determinant. */
double
Invert3(const double m[9], double inv[9])
{
  const double det =
    m[0] * (m[4] * m[8] - m[5] * m[7]) - m[1] * (m[3] * m[8] - m[5] * m[6]) + m[2] * (m[3] * m[7] - m[4] * m[6]);
  const double s = 1.0 / det;
  inv[0] = (m[4] * m[8] - m[5] * m[7]) * s;
  inv[1] = (m[2] * m[7] - m[1] * m[8]) * s;
  inv[2] = (m[1] * m[5] - m[2] * m[4]) * s;
  inv[3] = (m[5] * m[6] - m[3] * m[8]) * s;
  inv[4] = (m[0] * m[8] - m[2] * m[6]) * s;
  inv[5] = (m[2] * m[3] - m[0] * m[5]) * s;
  inv[6] = (m[3] * m[7] - m[4] * m[6]) * s;
  inv[7] = (m[1] * m[6] - m[0] * m[7]) * s;
  inv[8] = (m[0] * m[4] - m[1] * m[3]) * s;
  return det;
}

constexpr double InsideTolerance = 1e-10;

/** Calls body(i) for every i in [0, n), on the threader's work units when there is a threader with more
 * than one, else in order on this thread. Every use below gives each i its own output, so the result
 * does not depend on the split. */
void
ParallelFor(itk::MultiThreaderBase * threader, std::size_t n, const std::function<void(std::size_t)> & body)
{
  if (threader == nullptr || threader->GetNumberOfWorkUnits() < 2 || n < 2)
  {
    for (std::size_t i = 0; i < n; ++i)
    {
      body(i);
    }
    return;
  }
  threader->ParallelizeArray(
    0, n, [&body](itk::SizeValueType i) { body(static_cast<std::size_t>(i)); }, nullptr);
}
} // namespace

DisplacementFieldRasterizer::DisplacementFieldRasterizer(const TetrahedralMesh &     mesh,
                                                         const std::vector<double> & displacement,
                                                         const GridGeometry &        grid,
                                                         FieldKindEnum               kind)
  : m_Mesh(mesh)
  , m_Displacement(displacement)
  , m_Grid(grid)
  , m_Kind(kind)
{
  grid.Validate("displacement field reference grid");
  if (displacement.size() != mesh.points.size())
  {
    Fail("DisplacementFieldRasterizer", "the mesh has no nodal displacement (3 values per node expected)");
  }
  for (double d : displacement)
  {
    if (!std::isfinite(d))
    {
      Fail("DisplacementFieldRasterizer", "the nodal displacement holds a non-finite value");
    }
  }
  // The same matrix as GridGeometry::IndexToPoint, so that the inlined x(i) below is bit-identical to it.
  for (int r = 0; r < 3; ++r)
  {
    for (int c = 0; c < 3; ++c)
    {
      m_IndexToPoint[3 * r + c] = grid.direction[3 * r + c] * grid.spacing[c];
    }
  }
  const std::size_t M = mesh.GetNumberOfTetrahedra();
  m_Elements.reserve(M);
  double       unusedInverse[9];
  const double gridHandedness = Invert3(grid.direction.data(), unusedInverse);
  for (std::size_t e = 0; e < M; ++e)
  {
    Element el;
    double  v[4][3];
    for (int a = 0; a < 4; ++a)
    {
      el.nodes[a] = mesh.tetrahedra[4 * e + a];
      std::array<double, 3> x;
      for (int i = 0; i < 3; ++i)
      {
        x[i] = mesh.points[3 * el.nodes[a] + i] +
               (kind == FieldKindEnum::PullBack ? displacement[3 * el.nodes[a] + i] : 0.0);
      }
      const std::array<double, 3> idx = grid.PointToIndex(x);
      std::copy(idx.begin(), idx.end(), v[a]);
    }
    double m[9];
    for (int r = 0; r < 3; ++r)
    {
      for (int c = 0; c < 3; ++c)
      {
        m[3 * r + c] = v[c + 1][r] - v[0][r];
      }
    }
    const double det = Invert3(m, el.inv);
    // The orientation in index space flips with a left-handed direction matrix; only a sign change
    // relative to the grid's own handedness (or a collapsed element) means inversion.
    if (!(det * gridHandedness > 0.0) || !std::isfinite(det))
    {
      ++m_Inverted;
      continue;
    }
    std::copy(v[0], v[0] + 3, el.v0);
    bool outside = false;
    for (int i = 0; i < 3; ++i)
    {
      const double lo = std::min({ v[0][i], v[1][i], v[2][i], v[3][i] });
      const double hi = std::max({ v[0][i], v[1][i], v[2][i], v[3][i] });
      el.lo[i] = std::max<std::int64_t>(0, static_cast<std::int64_t>(std::ceil(lo - 1e-9)));
      el.hi[i] = std::min<std::int64_t>(static_cast<std::int64_t>(grid.size[i]) - 1,
                                        static_cast<std::int64_t>(std::floor(hi + 1e-9)));
      outside = outside || el.lo[i] > el.hi[i];
    }
    if (!outside)
    {
      ComputeRowBounds(el);
      m_Elements.push_back(el);
    }
  }
}

void
DisplacementFieldRasterizer::ComputeRowBounds(Element & el)
{
  // In the element's box, with t = i - v0[0], dy = j - v0[1], dz = k - v0[2]:
  // b_r = a_r t + p_r dy + q_r dz (r = 1..3, the rows of inv) and b_0 = 1 - b_1 - b_2 - b_3.
  // Each condition b_r >= -tolerance bounds t on one side by an affine function of (dy, dz), stored as
  // t >= (or <=) bound[r][0] + bound[r][1] dy + bound[r][2] dz. The slack (1e-7 plus 1e-12 of the terms'
  // magnitude over the box) is far above the rounding of the exact test, so every voxel it accepts
  // satisfies these bounds; a condition whose a_r is too small for its bound to be evaluated to well
  // under a voxel is left out (side 0), which only widens the run.
  double span[3];
  for (int d = 0; d < 3; ++d)
  {
    span[d] = std::max(std::abs(el.lo[d] - el.v0[d]), std::abs(el.hi[d] - el.v0[d])) + 1.0;
  }
  double a[4], p[4], q[4], constant[4], magnitude[4];
  a[0] = p[0] = q[0] = 0.0;
  constant[0] = magnitude[0] = 1.0;
  for (int r = 1; r < 4; ++r)
  {
    a[r] = el.inv[3 * (r - 1)];
    p[r] = el.inv[3 * (r - 1) + 1];
    q[r] = el.inv[3 * (r - 1) + 2];
    constant[r] = 0.0;
    magnitude[r] = std::abs(a[r]) * span[0] + std::abs(p[r]) * span[1] + std::abs(q[r]) * span[2];
    a[0] -= a[r];
    p[0] -= p[r];
    q[0] -= q[r];
    magnitude[0] += magnitude[r];
  }
  for (int r = 0; r < 4; ++r)
  {
    const double slack = 1e-7 + 1e-12 * magnitude[r];
    if (!(std::abs(a[r]) > 1e-9 * (magnitude[r] + 1.0)))
    {
      el.side[r] = 0;
      continue;
    }
    el.side[r] = a[r] > 0.0 ? 1 : -1;
    el.bound[r][0] = (-InsideTolerance - slack - constant[r]) / a[r];
    el.bound[r][1] = -p[r] / a[r];
    el.bound[r][2] = -q[r] / a[r];
  }
}

bool
DisplacementFieldRasterizer::RowRun(const Element & el,
                                    double          dy,
                                    double          dz,
                                    std::int64_t    lo,
                                    std::int64_t    hi,
                                    std::int64_t &  first,
                                    std::int64_t &  last)
{
  double tLo = static_cast<double>(lo) - el.v0[0] - 1.0;
  double tHi = static_cast<double>(hi) - el.v0[0] + 1.0;
  for (int r = 0; r < 4; ++r)
  {
    const double t = el.bound[r][0] + el.bound[r][1] * dy + el.bound[r][2] * dz;
    if (el.side[r] > 0)
    {
      tLo = std::max(tLo, t);
    }
    else if (el.side[r] < 0)
    {
      tHi = std::min(tHi, t);
    }
  }
  if (!(tLo <= tHi))
  {
    return false;
  }
  // One voxel more on each side covers the rounding of the bounds; tLo and tHi stay within
  // [lo - 1, hi + 1] - v0[0] here, so the conversions are safe.
  first = std::max(lo, static_cast<std::int64_t>(std::ceil(el.v0[0] + tLo)) - 1);
  last = std::min(hi, static_cast<std::int64_t>(std::floor(el.v0[0] + tHi)) + 1);
  return first <= last;
}

void
DisplacementFieldRasterizer::RasterizeRegion(const std::array<std::size_t, 3> & start,
                                             const std::array<std::size_t, 3> & size,
                                             double *                           field,
                                             unsigned char *                    inside) const
{
  const std::size_t nx = m_Grid.size[0], nxy = m_Grid.size[0] * m_Grid.size[1];
  std::int64_t      rlo[3], rhi[3];
  for (int i = 0; i < 3; ++i)
  {
    rlo[i] = static_cast<std::int64_t>(start[i]);
    rhi[i] = static_cast<std::int64_t>(start[i] + size[i]) - 1;
  }
  const double * mx = m_IndexToPoint;
  // Elements in increasing index, each voxel taken by the first element that accepts it: a voxel on a
  // shared face belongs to the element of lowest index, whatever the split of the grid into regions.
  for (const Element & el : m_Elements)
  {
    std::int64_t lo[3], hi[3];
    bool         skip = false;
    for (int i = 0; i < 3; ++i)
    {
      lo[i] = std::max(el.lo[i], rlo[i]);
      hi[i] = std::min(el.hi[i], rhi[i]);
      skip = skip || lo[i] > hi[i];
    }
    if (skip)
    {
      continue;
    }
    for (std::int64_t k = lo[2]; k <= hi[2]; ++k)
    {
      for (std::int64_t j = lo[1]; j <= hi[1]; ++j)
      {
        std::int64_t first = 0, last = -1;
        if (!RowRun(el, j - el.v0[1], k - el.v0[2], lo[0], hi[0], first, last))
        {
          continue;
        }
        for (std::int64_t i = first; i <= last; ++i)
        {
          const std::size_t off =
            static_cast<std::size_t>(i) + nx * static_cast<std::size_t>(j) + nxy * static_cast<std::size_t>(k);
          if (inside[off])
          {
            continue;
          }
          // The exact test and value, evaluated as in a scan of the whole bounding box.
          const double d[3] = { i - el.v0[0], j - el.v0[1], k - el.v0[2] };
          double       b[4];
          b[1] = el.inv[0] * d[0] + el.inv[1] * d[1] + el.inv[2] * d[2];
          b[2] = el.inv[3] * d[0] + el.inv[4] * d[1] + el.inv[5] * d[2];
          b[3] = el.inv[6] * d[0] + el.inv[7] * d[1] + el.inv[8] * d[2];
          b[0] = 1.0 - b[1] - b[2] - b[3];
          if (b[0] < -InsideTolerance || b[1] < -InsideTolerance || b[2] < -InsideTolerance || b[3] < -InsideTolerance)
          {
            continue;
          }
          double * out = field + 3 * off;
          if (m_Kind == FieldKindEnum::Push)
          {
            for (int c = 0; c < 3; ++c)
            {
              out[c] = b[0] * m_Displacement[3 * el.nodes[0] + c] + b[1] * m_Displacement[3 * el.nodes[1] + c] +
                       b[2] * m_Displacement[3 * el.nodes[2] + c] + b[3] * m_Displacement[3 * el.nodes[3] + c];
            }
          }
          else
          {
            const double ii = static_cast<double>(i), jj = static_cast<double>(j), kk = static_cast<double>(k);
            for (int c = 0; c < 3; ++c)
            {
              // x = GridGeometry::IndexToPoint(i, j, k), same terms in the same order.
              const double x = m_Grid.origin[c] + mx[3 * c] * ii + mx[3 * c + 1] * jj + mx[3 * c + 2] * kk;
              const double X = b[0] * m_Mesh.points[3 * el.nodes[0] + c] + b[1] * m_Mesh.points[3 * el.nodes[1] + c] +
                               b[2] * m_Mesh.points[3 * el.nodes[2] + c] + b[3] * m_Mesh.points[3 * el.nodes[3] + c];
              out[c] = X - x;
            }
          }
          inside[off] = 1;
        }
      }
    }
  }
}

namespace {
// Dirichlet data of FillOutsideHarmonic: the mean of the covered fine voxels around each coarse node,
// 0 on the border; returns whether any coarse node is covered. Threaded over the coarse planes (each
// node's sum keeps its order).
bool
ComputeCoarseDirichletData(const GridGeometry &  grid,
                           const double *        field,
                           const unsigned char * inside,
                           std::size_t           c,
                           const std::size_t (&m)[3],
                           std::vector<char> &      fixed,
                           std::vector<double> &    value,
                           itk::MultiThreaderBase * threader)
{
  const auto &       n = grid.size;
  const std::int64_t half = static_cast<std::int64_t>(c / 2);
  std::atomic<bool>  any{ false };
  ParallelFor(threader, m[2], [&](std::size_t K) {
    for (std::size_t J = 0; J < m[1]; ++J)
    {
      for (std::size_t I = 0; I < m[0]; ++I)
      {
        const std::size_t node = I + m[0] * (J + m[1] * K);
        const std::size_t ci[3] = { I, J, K };
        double            sum[3] = { 0, 0, 0 };
        std::size_t       count = 0;
        std::int64_t      lo[3], hi[3];
        for (int d = 0; d < 3; ++d)
        {
          const std::int64_t center = std::min<std::int64_t>(static_cast<std::int64_t>(ci[d] * c), n[d] - 1);
          lo[d] = std::max<std::int64_t>(0, center - half);
          hi[d] = std::min<std::int64_t>(static_cast<std::int64_t>(n[d]) - 1, center + half);
        }
        for (std::int64_t k = lo[2]; k <= hi[2]; ++k)
        {
          for (std::int64_t j = lo[1]; j <= hi[1]; ++j)
          {
            for (std::int64_t i = lo[0]; i <= hi[0]; ++i)
            {
              const std::size_t off = i + n[0] * (j + n[1] * k);
              if (inside[off])
              {
                for (int d = 0; d < 3; ++d)
                {
                  sum[d] += field[3 * off + d];
                }
                ++count;
              }
            }
          }
        }
        if (count > 0)
        {
          fixed[node] = 1;
          any.store(true, std::memory_order_relaxed);
          for (int d = 0; d < 3; ++d)
          {
            value[3 * node + d] = sum[d] / static_cast<double>(count);
          }
        }
        else if (I == 0 || J == 0 || K == 0 || I + 1 == m[0] || J + 1 == m[1] || K + 1 == m[2])
        {
          fixed[node] = 1;
        }
      }
    }
  });
  return any.load();
}

/** The coarse lattice of FillOutsideHarmonic (m[0] x m[1] x m[2] = M nodes) and the weights of its Laplacian. */
struct CoarseLaplacian
{
  std::size_t               m[3];
  std::size_t               M;
  const std::vector<char> & fixed;
  double                    w[3];
  std::size_t               stride[3];
};

// y = A x on free nodes (0 on fixed ones); A is the negative Laplacian, with fixed neighbors taken from
// bc (or 0). The lattice position comes from the loop counters (no division per node); each node's
// terms are summed in the order d = 0, 1, 2 and, for each, the lower neighbor first.
void
ApplyCoarseLaplacian(const CoarseLaplacian &     A,
                     const std::vector<double> & x,
                     std::vector<double> &       y,
                     const std::vector<double> * bc)
{
  for (std::size_t K = 0, node = 0; K < A.m[2]; ++K)
  {
    for (std::size_t J = 0; J < A.m[1]; ++J)
    {
      for (std::size_t I = 0; I < A.m[0]; ++I, ++node)
      {
        if (A.fixed[node])
        {
          y[node] = 0.0;
          continue;
        }
        const std::size_t pos[3] = { I, J, K };
        double            acc = 0.0;
        for (int d = 0; d < 3; ++d)
        {
          if (pos[d] > 0)
          {
            const std::size_t nb = node - A.stride[d];
            const double      xn = A.fixed[nb] ? (bc ? (*bc)[nb] : 0.0) : x[nb];
            acc += A.w[d] * (x[node] - xn);
          }
          if (pos[d] + 1 < A.m[d])
          {
            const std::size_t nb = node + A.stride[d];
            const double      xn = A.fixed[nb] ? (bc ? (*bc)[nb] : 0.0) : x[nb];
            acc += A.w[d] * (x[node] - xn);
          }
        }
        y[node] = acc;
      }
    }
  }
}

// y = A p on the free nodes for a p that is 0 on the fixed ones (the CG directions): free nodes are never
// on the lattice's border (it is fixed), so all six neighbors exist and a fixed one contributes
// w (p - 0), as the general form does; returns p . A p summed in node order (the fixed nodes' terms
// are +0 and leave the sum unchanged).
double
ApplyCoarseLaplacianFree(const CoarseLaplacian &          A,
                         const std::vector<std::size_t> & freeNodes,
                         const std::vector<double> &      p,
                         std::vector<double> &            y)
{
  double pAp = 0.0;
  for (std::size_t node : freeNodes)
  {
    double acc = 0.0;
    for (int d = 0; d < 3; ++d)
    {
      acc += A.w[d] * (p[node] - p[node - A.stride[d]]);
      acc += A.w[d] * (p[node] - p[node + A.stride[d]]);
    }
    y[node] = acc;
    pAp += p[node] * acc;
  }
  return pAp;
}

// Conjugate gradients for component comp of the coarse harmonic field; the solution is left in x.
// Only the free nodes are visited (the fixed ones keep x = bc, r = p = 0); the dot products are summed
// in node order, so the iterates do not depend on the threads.
void
SolveCoarseComponent(const CoarseLaplacian &          A,
                     const std::vector<std::size_t> & freeNodes,
                     const std::vector<double> &      value,
                     int                              comp,
                     std::vector<double> &            x)
{
  const std::size_t         M = A.M;
  const std::vector<char> & fixed = A.fixed;
  std::vector<double>       r(M), p(M), Ap(M, 0.0), bc(M);
  x.resize(M);
  for (std::size_t node = 0; node < M; ++node)
  {
    bc[node] = value[3 * node + comp];
    x[node] = fixed[node] ? bc[node] : 0.0;
  }
  // r = b - A x, with b carrying the fixed neighbors' values.
  std::vector<double> zero(M, 0.0);
  ApplyCoarseLaplacian(A, zero, r, &bc); // A(0) with boundary data = -b
  for (std::size_t node = 0; node < M; ++node)
  {
    r[node] = fixed[node] ? 0.0 : -r[node];
  }
  p = r;
  double rr = 0.0;
  for (std::size_t node : freeNodes)
  {
    rr += r[node] * r[node];
  }
  const double stop = 1e-20 * std::max(rr, 1e-300);
  for (int it = 0; it < 5000 && rr > stop; ++it)
  {
    const double pAp = ApplyCoarseLaplacianFree(A, freeNodes, p, Ap);
    if (!(pAp > 0.0))
    {
      break;
    }
    const double alpha = rr / pAp;
    double       rrNew = 0.0;
    for (std::size_t node : freeNodes)
    {
      x[node] += alpha * p[node];
      r[node] -= alpha * Ap[node];
      rrNew += r[node] * r[node];
    }
    const double beta = rrNew / rr;
    rr = rrNew;
    for (std::size_t node : freeNodes)
    {
      p[node] = r[node] + beta * p[node];
    }
  }
}

// Trilinear interpolation of the coarse solution into the uncovered voxels, threaded over the fine
// planes. The per-axis cell and weights are tabulated once; each voxel's weights and sum are formed in
// the same order as a per-voxel evaluation (corners 0..7, zero weights skipped).
void
InterpolateCoarseSolution(const GridGeometry &        grid,
                          const unsigned char *       inside,
                          std::size_t                 c,
                          const CoarseLaplacian &     A,
                          const std::vector<double> & coarse,
                          double *                    field,
                          itk::MultiThreaderBase *    threader)
{
  const auto &             n = grid.size;
  const auto &             m = A.m;
  std::vector<std::size_t> base[3];
  std::vector<double>      t[3];
  for (int d = 0; d < 3; ++d)
  {
    base[d].resize(n[d]);
    t[d].resize(n[d]);
    for (std::size_t f = 0; f < n[d]; ++f)
    {
      base[d][f] = std::min(f / c, m[d] - 1);
      t[d][f] = static_cast<double>(f - base[d][f] * c) / static_cast<double>(c);
      if (base[d][f] + 1 >= m[d])
      {
        t[d][f] = 0.0;
      }
    }
  }
  ParallelFor(threader, n[2], [&](std::size_t k) {
    for (std::size_t j = 0; j < n[1]; ++j)
    {
      for (std::size_t i = 0; i < n[0]; ++i)
      {
        const std::size_t off = i + n[0] * (j + n[1] * k);
        if (inside[off])
        {
          continue;
        }
        // Corner (bx, by, bz) = corner bx + 2 by + 4 bz, weight (1 * w_x) w_y w_z (the 1 * is exact).
        const double wx[2] = { 1.0 - t[0][i], t[0][i] }, wy[2] = { 1.0 - t[1][j], t[1][j] },
                     wz[2] = { 1.0 - t[2][k], t[2][k] };
        const std::size_t nx[2] = { base[0][i], base[0][i] + (t[0][i] > 0.0 ? 1 : 0) };
        const std::size_t ny[2] = { base[1][j] * A.stride[1], (base[1][j] + (t[1][j] > 0.0 ? 1 : 0)) * A.stride[1] };
        const std::size_t nz[2] = { base[2][k] * A.stride[2], (base[2][k] + (t[2][k] > 0.0 ? 1 : 0)) * A.stride[2] };
        double            out[3] = { 0, 0, 0 };
        for (int bz = 0; bz < 2; ++bz)
        {
          for (int by = 0; by < 2; ++by)
          {
            for (int bx = 0; bx < 2; ++bx)
            {
              const double weight = wx[bx] * wy[by] * wz[bz];
              if (weight == 0.0)
              {
                continue;
              }
              const double * value = &coarse[3 * (nx[bx] + ny[by] + nz[bz])];
              for (int d = 0; d < 3; ++d)
              {
                out[d] += weight * value[d];
              }
            }
          }
        }
        for (int d = 0; d < 3; ++d)
        {
          field[3 * off + d] = out[d];
        }
      }
    }
  });
}

/** The uncovered voxels off the grid's border within a distance of the covered ones, plane by plane
 * (planes[k]: those of fine plane k, in increasing offset order). */
struct BoundaryBand
{
  std::vector<std::vector<std::size_t>> planes;
};

// The band within width voxels (6-neighborhood steps) of the covered voxels. width dilations of the
// covered mask by the 6-neighborhood give exactly the voxels at city-block distance <= width (the grid
// is a box), so the distance is computed instead by a separable city-block distance transform: forward
// and backward passes along x, then z, then y (the order of the axes does not matter), saturated at
// width + 1 (in bytes up to a width of 254, the default fill's 10 included, else capped at 65534). The
// y passes of a plane and its band are done together.
template<typename TDistance>
BoundaryBand
FindBoundaryBand(const GridGeometry &     grid,
                 const unsigned char *    inside,
                 unsigned int             width,
                 itk::MultiThreaderBase * threader)
{
  using DistanceType = TDistance;
  const auto &                    n = grid.size;
  const std::size_t               nxy = n[0] * n[1];
  const unsigned int              maximum = std::numeric_limits<DistanceType>::max();
  const DistanceType              cap = static_cast<DistanceType>(std::min(width, maximum - 1) + 1);
  std::unique_ptr<DistanceType[]> dist(new DistanceType[grid.GetNumberOfVoxels()]);
  auto step = [cap](DistanceType v) { return static_cast<DistanceType>(std::min<int>(v + 1, cap)); };
  ParallelFor(threader, n[2], [&](std::size_t k) {
    for (std::size_t j = 0; j < n[1]; ++j)
    {
      DistanceType *        row = dist.get() + nxy * k + n[0] * j;
      const unsigned char * in = inside + nxy * k + n[0] * j;
      DistanceType          run = cap;
      for (std::size_t i = 0; i < n[0]; ++i)
      {
        run = in[i] ? 0 : step(run);
        row[i] = run;
      }
      for (std::size_t i = n[0] - 1; i-- > 0;)
      {
        row[i] = std::min(row[i], step(row[i + 1]));
      }
    }
  });
  ParallelFor(threader, n[1], [&](std::size_t j) {
    DistanceType * column = dist.get() + n[0] * j;
    for (std::size_t k = 1; k < n[2]; ++k)
    {
      for (std::size_t i = 0; i < n[0]; ++i)
      {
        column[nxy * k + i] = std::min(column[nxy * k + i], step(column[nxy * (k - 1) + i]));
      }
    }
    for (std::size_t k = n[2] - 1; k-- > 0;)
    {
      for (std::size_t i = 0; i < n[0]; ++i)
      {
        column[nxy * k + i] = std::min(column[nxy * k + i], step(column[nxy * (k + 1) + i]));
      }
    }
  });
  BoundaryBand band;
  band.planes.resize(n[2]);
  ParallelFor(threader, n[2], [&](std::size_t k) {
    DistanceType * plane = dist.get() + nxy * k;
    for (std::size_t j = 1; j < n[1]; ++j)
    {
      for (std::size_t i = 0; i < n[0]; ++i)
      {
        plane[n[0] * j + i] = std::min(plane[n[0] * j + i], step(plane[n[0] * (j - 1) + i]));
      }
    }
    for (std::size_t j = n[1] - 1; j-- > 0;)
    {
      for (std::size_t i = 0; i < n[0]; ++i)
      {
        plane[n[0] * j + i] = std::min(plane[n[0] * j + i], step(plane[n[0] * (j + 1) + i]));
      }
    }
    if (k == 0 || k + 1 == n[2])
    {
      return;
    }
    for (std::size_t j = 1; j + 1 < n[1]; ++j)
    {
      for (std::size_t i = 1; i + 1 < n[0]; ++i)
      {
        const std::size_t off = i + n[0] * j + nxy * k;
        if (plane[off - nxy * k] < cap && !inside[off])
        {
          band.planes[k].push_back(off);
        }
      }
    }
  });
  return band;
}

// How the band is relaxed. On demo pair 1's pull-back (1.05 M band voxels, width 10), against the band's converged
// solution (3000 Gauss-Seidel sweeps): 60 Gauss-Seidel sweeps (6 w, before) left 0.050 mm at most and 0.010 mm RMS
// over the voxels that differ; 24 sweeps with omega 1.7 leave 0.0125 and 0.0010 mm (1.6: 0.020 and 0.0032; 1.8: 0.023
// and 0.0008) in 40 % of the sweeps.
constexpr double BandOverRelaxation = 1.7;
/** 2.4 w sweeps, rounded up to whole groups of RelaxBoundaryBand's wavefront (4 sweeps). */
unsigned int
BandSweeps(unsigned int width)
{
  const unsigned int sweeps = (12 * width + 4) / 5;
  return (sweeps + 3) / 4 * 4;
}

// Sweeps of successive over-relaxation (SOR: Gauss-Seidel with each update scaled by omega) of the fine-grid
// Laplacian over the band's voxels, in increasing offset order.
// A voxel couples only to the planes next to its own, so sweep s may relax plane k as soon as sweep
// s - 1 has relaxed plane k + 1, and must do so before sweep s + 1 relaxes plane k - 1: every update
// then reads exactly the values of the sequential sweeps, and the result is bit-identical for any
// schedule that respects this. Three uses of that freedom:
// - a worker relaxes a group of consecutive sweeps as a wavefront, sweep s + i two planes behind sweep
//   s + i - 1, so the planes in flight stay in cache across the group instead of the band streaming
//   from memory once per sweep;
// - the planes of one front are then independent (none reads another's plane), and their updates are
//   interleaved voxel by voxel: within a plane each update waits for the one before (its -x neighbor),
//   and interleaving these chains hides the latency of the division;
// - workers on other threads run the next groups, each waiting plane by plane for the group before.
// A worker takes the next group only when it has finished its previous one, so the group it waits for
// is always in progress on a running worker (no deadlock, whatever the thread pool does).
void
RelaxBoundaryBand(const GridGeometry &     grid,
                  const BoundaryBand &     band,
                  unsigned int             sweeps,
                  double                   omega,
                  double *                 field,
                  itk::MultiThreaderBase * threader)
{
  const auto &      n = grid.size;
  const double      fw[3] = { 1.0 / (grid.spacing[0] * grid.spacing[0]),
                              1.0 / (grid.spacing[1] * grid.spacing[1]),
                              1.0 / (grid.spacing[2] * grid.spacing[2]) };
  const std::size_t fstride[3] = { 3, 3 * n[0], 3 * n[0] * n[1] };
  double            sumOfWeights = 0.0;
  for (int d = 0; d < 3; ++d)
  {
    sumOfWeights += 2.0 * fw[d];
  }
  const double weight = sumOfWeights;
  // v_c <- (1 - omega) v_c + omega (0 + fw_0 (v_c[-x] + v_c[+x]) + fw_1 (...) + fw_2 (...)) / weight for each
  // component c.
  const double keep = 1.0 - omega;
#if defined(__SSE2__)
  // Components 0 and 1 in one SSE2 register, 2 in another: the same IEEE operations in the same order
  // per component (bit-identical to the scalar form), with two divisions per voxel instead of three.
  const __m128d zero = _mm_setzero_pd(), weightV = _mm_set1_pd(weight);
  const __m128d omegaV = _mm_set1_pd(omega), keepV = _mm_set1_pd(keep);
  const __m128d fwV[3] = { _mm_set1_pd(fw[0]), _mm_set1_pd(fw[1]), _mm_set1_pd(fw[2]) };
  auto          relaxVoxel = [&](std::size_t off) {
    double * v = field + 3 * off;
    __m128d  sum01 = zero, sum2 = zero;
    for (int d = 0; d < 3; ++d)
    {
      const double * lower = v - fstride[d];
      const double * upper = v + fstride[d];
      sum01 = _mm_add_pd(sum01, _mm_mul_pd(fwV[d], _mm_add_pd(_mm_loadu_pd(lower), _mm_loadu_pd(upper))));
      sum2 = _mm_add_sd(sum2, _mm_mul_sd(fwV[d], _mm_add_sd(_mm_load_sd(lower + 2), _mm_load_sd(upper + 2))));
    }
    const __m128d relaxed01 = _mm_mul_pd(omegaV, _mm_div_pd(sum01, weightV));
    const __m128d relaxed2 = _mm_mul_sd(omegaV, _mm_div_sd(sum2, weightV));
    _mm_storeu_pd(v, _mm_add_pd(_mm_mul_pd(keepV, _mm_loadu_pd(v)), relaxed01));
    _mm_store_sd(v + 2, _mm_add_sd(_mm_mul_sd(keepV, _mm_load_sd(v + 2)), relaxed2));
  };
#else
  auto relaxVoxel = [&](std::size_t off) {
    double * v = field + 3 * off;
    for (int comp = 0; comp < 3; ++comp)
    {
      double sum = 0.0;
      for (int d = 0; d < 3; ++d)
      {
        sum += fw[d] * (v[comp - fstride[d]] + v[comp + fstride[d]]);
      }
      v[comp] = keep * v[comp] + omega * (sum / weight);
    }
  };
#endif
  constexpr unsigned int group = 4; // sweeps per wavefront: 2 group + 1 planes in flight
  auto                   relaxPlanes = [&](const std::size_t * ks, unsigned int count) {
    std::size_t         q[group], end[group];
    const std::size_t * voxels[group];
    for (unsigned int i = 0; i < count; ++i)
    {
      voxels[i] = band.planes[ks[i]].data();
      q[i] = 0;
      end[i] = band.planes[ks[i]].size();
    }
    for (bool active = true; active;)
    {
      active = false;
      for (unsigned int i = 0; i < count; ++i)
      {
        if (q[i] < end[i])
        {
          relaxVoxel(voxels[i][q[i]++]);
          active = true;
        }
      }
    }
  };
  const std::size_t planes = n[2];
  // done[s]: planes relaxed by sweep s (released after the plane's writes).
  std::unique_ptr<std::atomic<std::size_t>[]> done(new std::atomic<std::size_t>[sweeps]);
  for (unsigned int s = 0; s < sweeps; ++s)
  {
    done[s].store(0);
  }
  const unsigned int        groups = (sweeps + group - 1) / group;
  std::atomic<unsigned int> nextGroup{ 0 };
  auto                      worker = [&](std::size_t) {
    for (unsigned int g = nextGroup++; g < groups; g = nextGroup++)
    {
      const unsigned int first = g * group, count = std::min(group, sweeps - first);
      for (std::size_t front = 0; front < planes + 2 * (count - 1); ++front)
      {
        // Sweep first + i relaxes plane front - 2 i.
        std::size_t  ks[group];
        unsigned int sweepOf[group], active = 0;
        for (unsigned int i = 0; i < count; ++i)
        {
          if (front >= 2 * i && front - 2 * i < planes)
          {
            ks[active] = front - 2 * i;
            sweepOf[active++] = first + i;
          }
        }
        // The group's first sweep follows the previous group's last one; the others follow within the group.
        if (first > 0 && front < planes)
        {
          const std::size_t needed = std::min(front + 2, planes);
          while (done[first - 1].load(std::memory_order_acquire) < needed)
          {
            std::this_thread::yield();
          }
        }
        relaxPlanes(ks, active);
        for (unsigned int i = 0; i < active; ++i)
        {
          done[sweepOf[i]].store(ks[i] + 1, std::memory_order_release);
        }
      }
    }
  };
  const std::size_t workers = threader ? std::min<std::size_t>(threader->GetNumberOfWorkUnits(), groups) : 1;
  ParallelFor(threader, std::max<std::size_t>(workers, 1), worker);
}
} // namespace

void
FillOutsideHarmonic(const GridGeometry &     grid,
                    double *                 field,
                    const unsigned char *    inside,
                    unsigned int             coarsening,
                    itk::MultiThreaderBase * threader)
{
  const std::size_t c = std::max(1u, coarsening);
  const auto &      n = grid.size;
  std::size_t       m[3];
  for (int i = 0; i < 3; ++i)
  {
    m[i] = (n[i] - 1 + c - 1) / c + 1;
  }
  const std::size_t M = m[0] * m[1] * m[2];
  // Dirichlet data: mean of the covered fine voxels around each coarse node, 0 on the border.
  std::vector<char>   fixed(M, 0);
  std::vector<double> value(3 * M, 0.0);
  const bool          any = ComputeCoarseDirichletData(grid, field, inside, c, m, fixed, value, threader);
  if (!any)
  {
    for (std::size_t v = 0; v < grid.GetNumberOfVoxels(); ++v)
    {
      field[3 * v] = field[3 * v + 1] = field[3 * v + 2] = 0.0;
    }
    return;
  }
  // Matrix-free conjugate gradients on the free coarse nodes, the three components as independent tasks.
  const CoarseLaplacian    A{ { m[0], m[1], m[2] },
                           M,
                           fixed,
                           { 1.0 / std::pow(c * grid.spacing[0], 2),
                                1.0 / std::pow(c * grid.spacing[1], 2),
                                1.0 / std::pow(c * grid.spacing[2], 2) },
                           { 1, m[0], m[0] * m[1] } };
  std::vector<std::size_t> freeNodes;
  for (std::size_t node = 0; node < M; ++node)
  {
    if (!fixed[node])
    {
      freeNodes.push_back(node);
    }
  }
  std::vector<double> coarse(3 * M, 0.0);
  ParallelFor(threader, 3, [&](std::size_t comp) {
    std::vector<double> x;
    SolveCoarseComponent(A, freeNodes, value, static_cast<int>(comp), x);
    for (std::size_t node = 0; node < M; ++node)
    {
      coarse[3 * node + comp] = x[node];
    }
  });
  InterpolateCoarseSolution(grid, inside, c, A, coarse, field, threader);
  // The coarse interpolation leaves a mismatch at the mesh boundary, within a few coarse cells of
  // it. Over-relaxed Gauss-Seidel sweeps of the fine-grid Laplacian on the uncovered voxels of that band (in a
  // fixed order, so deterministic) remove it.
  const unsigned int width = 2 * static_cast<unsigned int>(c) + 2;
  const BoundaryBand band = width < 255 ? FindBoundaryBand<std::uint8_t>(grid, inside, width, threader)
                                        : FindBoundaryBand<std::uint16_t>(grid, inside, width, threader);
  RelaxBoundaryBand(grid, band, BandSweeps(width), BandOverRelaxation, field, threader);
}

void
AdviseHugePages(void * data, std::size_t bytes)
{
#if defined(__linux__) && defined(MADV_HUGEPAGE)
  // Only the whole 2 MiB blocks inside the buffer; the advice is a hint, its failure harmless.
  constexpr std::uintptr_t block = std::uintptr_t{ 1 } << 21;
  const std::uintptr_t     begin = (reinterpret_cast<std::uintptr_t>(data) + block - 1) & ~(block - 1);
  const std::uintptr_t     end = (reinterpret_cast<std::uintptr_t>(data) + bytes) & ~(block - 1);
  if (end > begin)
  {
    madvise(reinterpret_cast<void *>(begin), end - begin, MADV_HUGEPAGE);
  }
#else
  (void)data;
  (void)bytes;
#endif
}

PointLocator::PointLocator(const std::vector<double> & points, const std::vector<std::int32_t> & tetrahedra)
  : m_Points(points)
  , m_Tetrahedra(tetrahedra)
{
  const std::size_t M = tetrahedra.size() / 4;
  if (M == 0)
  {
    Fail("PointLocator", "the mesh has no element");
  }
  std::array<double, 3> upper;
  for (int i = 0; i < 3; ++i)
  {
    m_Lower[i] = std::numeric_limits<double>::max();
    upper[i] = std::numeric_limits<double>::lowest();
  }
  for (std::size_t n = 0; n < points.size() / 3; ++n)
  {
    for (int i = 0; i < 3; ++i)
    {
      m_Lower[i] = std::min(m_Lower[i], points[3 * n + i]);
      upper[i] = std::max(upper[i], points[3 * n + i]);
    }
  }
  // About two elements per cell on average.
  const double volume = std::max(1e-12, (upper[0] - m_Lower[0]) * (upper[1] - m_Lower[1]) * (upper[2] - m_Lower[2]));
  const double h = std::cbrt(volume / (static_cast<double>(M) / 2.0));
  for (int i = 0; i < 3; ++i)
  {
    m_Cells[i] = std::max<std::size_t>(1, static_cast<std::size_t>(std::ceil((upper[i] - m_Lower[i]) / h)));
    m_CellSize[i] = std::max(1e-12, (upper[i] - m_Lower[i]) / static_cast<double>(m_Cells[i]));
  }
  auto cellRange = [this](std::size_t e, std::size_t lo[3], std::size_t hi[3]) {
    for (int i = 0; i < 3; ++i)
    {
      double a = std::numeric_limits<double>::max(), b = std::numeric_limits<double>::lowest();
      for (int k = 0; k < 4; ++k)
      {
        const double x = m_Points[3 * m_Tetrahedra[4 * e + k] + i];
        a = std::min(a, x);
        b = std::max(b, x);
      }
      lo[i] = std::min(m_Cells[i] - 1, static_cast<std::size_t>(std::max(0.0, (a - m_Lower[i]) / m_CellSize[i])));
      hi[i] = std::min(m_Cells[i] - 1, static_cast<std::size_t>(std::max(0.0, (b - m_Lower[i]) / m_CellSize[i])));
    }
  };
  const std::size_t ncell = m_Cells[0] * m_Cells[1] * m_Cells[2];
  m_CellStart.assign(ncell + 1, 0);
  for (int pass = 0; pass < 2; ++pass)
  {
    std::vector<std::size_t> fill;
    if (pass == 1)
    {
      for (std::size_t c = 0; c < ncell; ++c)
      {
        m_CellStart[c + 1] += m_CellStart[c];
      }
      m_CellElements.resize(m_CellStart[ncell]);
      fill.assign(m_CellStart.begin(), m_CellStart.end() - 1);
    }
    for (std::size_t e = 0; e < M; ++e)
    {
      std::size_t lo[3], hi[3];
      cellRange(e, lo, hi);
      for (std::size_t k = lo[2]; k <= hi[2]; ++k)
      {
        for (std::size_t j = lo[1]; j <= hi[1]; ++j)
        {
          for (std::size_t i = lo[0]; i <= hi[0]; ++i)
          {
            const std::size_t c = i + m_Cells[0] * (j + m_Cells[1] * k);
            if (pass == 0)
            {
              ++m_CellStart[c + 1];
            }
            else
            {
              m_CellElements[fill[c]++] = static_cast<std::int32_t>(e);
            }
          }
        }
      }
    }
  }
}

bool
PointLocator::Barycentric(std::size_t e, const std::array<double, 3> & p, std::array<double, 4> & b) const
{
  const double * x0 = &m_Points[3 * m_Tetrahedra[4 * e]];
  double         m[9], inv[9];
  for (int c = 0; c < 3; ++c)
  {
    const double * xc = &m_Points[3 * m_Tetrahedra[4 * e + c + 1]];
    for (int r = 0; r < 3; ++r)
    {
      m[3 * r + c] = xc[r] - x0[r];
    }
  }
  const double det = Invert3(m, inv);
  if (!(std::abs(det) > 0.0))
  {
    return false;
  }
  const double d[3] = { p[0] - x0[0], p[1] - x0[1], p[2] - x0[2] };
  for (int r = 0; r < 3; ++r)
  {
    b[r + 1] = inv[3 * r] * d[0] + inv[3 * r + 1] * d[1] + inv[3 * r + 2] * d[2];
  }
  b[0] = 1.0 - b[1] - b[2] - b[3];
  return true;
}

std::int64_t
PointLocator::Locate(const std::array<double, 3> & p, std::array<double, 4> & barycentric, double tolerance) const
{
  std::size_t cell[3];
  for (int i = 0; i < 3; ++i)
  {
    const double t = (p[i] - m_Lower[i]) / m_CellSize[i];
    if (!(t >= -1e-9 && t <= static_cast<double>(m_Cells[i]) + 1e-9))
    {
      return -1;
    }
    cell[i] = std::min(m_Cells[i] - 1, static_cast<std::size_t>(std::max(0.0, t)));
  }
  const std::size_t c = cell[0] + m_Cells[0] * (cell[1] + m_Cells[1] * cell[2]);
  std::int64_t      best = -1;
  for (std::size_t k = m_CellStart[c]; k < m_CellStart[c + 1]; ++k)
  {
    const std::size_t     e = static_cast<std::size_t>(m_CellElements[k]);
    std::array<double, 4> b;
    if (Barycentric(e, p, b) && *std::min_element(b.begin(), b.end()) >= -tolerance)
    {
      if (best < 0 || static_cast<std::int64_t>(e) < best)
      {
        best = static_cast<std::int64_t>(e);
        barycentric = b;
      }
    }
  }
  return best;
}

bool
InterpolateDisplacement(const PointLocator &          undeformedLocator,
                        const TetrahedralMesh &       mesh,
                        const std::vector<double> &   displacement,
                        const std::array<double, 3> & X,
                        std::array<double, 3> &       u)
{
  std::array<double, 4> b;
  const std::int64_t    e = undeformedLocator.Locate(X, b);
  if (e < 0)
  {
    return false;
  }
  for (int c = 0; c < 3; ++c)
  {
    u[c] = 0.0;
    for (int a = 0; a < 4; ++a)
    {
      u[c] += b[a] * displacement[3 * mesh.tetrahedra[4 * e + a] + c];
    }
  }
  return true;
}

std::ostream &
operator<<(std::ostream & os, FieldKindEnum value)
{
  return os << (value == FieldKindEnum::Push ? "bmr::FieldKindEnum::Push" : "bmr::FieldKindEnum::PullBack");
}

} // namespace bmr
