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

#include <algorithm>
#include <cmath>
#include <limits>

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
      m_Elements.push_back(el);
    }
  }
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
        for (std::int64_t i = lo[0]; i <= hi[0]; ++i)
        {
          const std::size_t off =
            static_cast<std::size_t>(i) + nx * static_cast<std::size_t>(j) + nxy * static_cast<std::size_t>(k);
          if (inside[off])
          {
            continue;
          }
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
            const std::array<double, 3> x =
              m_Grid.IndexToPoint({ { static_cast<double>(i), static_cast<double>(j), static_cast<double>(k) } });
            for (int c = 0; c < 3; ++c)
            {
              const double X = b[0] * m_Mesh.points[3 * el.nodes[0] + c] + b[1] * m_Mesh.points[3 * el.nodes[1] + c] +
                               b[2] * m_Mesh.points[3 * el.nodes[2] + c] + b[3] * m_Mesh.points[3 * el.nodes[3] + c];
              out[c] = X - x[c];
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
// 0 on the border; returns whether any coarse node is covered.
bool
ComputeCoarseDirichletData(const GridGeometry &  grid,
                           const double *        field,
                           const unsigned char * inside,
                           std::size_t           c,
                           const std::size_t (&m)[3],
                           std::vector<char> &   fixed,
                           std::vector<double> & value)
{
  const auto &       n = grid.size;
  const std::int64_t half = static_cast<std::int64_t>(c / 2);
  bool               any = false;
  for (std::size_t K = 0; K < m[2]; ++K)
  {
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
          any = true;
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
  }
  return any;
}

/** The coarse lattice of FillOutsideHarmonic (m[0] x m[1] x m[2] = M nodes) and the weights of its Laplacian. */
struct CoarseLaplacian
{
  std::size_t               m[3];
  std::size_t               M;
  const std::vector<char> & fixed;
  double                    w[3];
  std::int64_t              stride[3];
  std::size_t               coord[3];
};

// y = A x on free nodes; A is the negative Laplacian, with fixed neighbors taken from bc (or 0).
void
ApplyCoarseLaplacian(const CoarseLaplacian &     A,
                     const std::vector<double> & x,
                     std::vector<double> &       y,
                     const std::vector<double> * bc)
{
  for (std::size_t node = 0; node < A.M; ++node)
  {
    if (A.fixed[node])
    {
      y[node] = 0.0;
      continue;
    }
    double acc = 0.0;
    for (int d = 0; d < 3; ++d)
    {
      const std::size_t pos = (node / A.coord[d]) % A.m[d];
      for (int s = -1; s <= 1; s += 2)
      {
        if ((s < 0 && pos == 0) || (s > 0 && pos + 1 == A.m[d]))
        {
          continue;
        }
        const std::size_t nb = static_cast<std::size_t>(static_cast<std::int64_t>(node) + s * A.stride[d]);
        const double      xn = A.fixed[nb] ? (bc ? (*bc)[nb] : 0.0) : x[nb];
        acc += A.w[d] * (x[node] - xn);
      }
    }
    y[node] = acc;
  }
}

// Conjugate gradients for component comp of the coarse harmonic field; the solution is left in x
// (r, p, Ap and bc are work vectors, kept by the caller across the components).
void
SolveCoarseComponent(const CoarseLaplacian &     A,
                     const std::vector<double> & value,
                     int                         comp,
                     std::vector<double> &       x,
                     std::vector<double> &       r,
                     std::vector<double> &       p,
                     std::vector<double> &       Ap,
                     std::vector<double> &       bc)
{
  const std::size_t         M = A.M;
  const std::vector<char> & fixed = A.fixed;
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
  for (double v : r)
  {
    rr += v * v;
  }
  const double stop = 1e-20 * std::max(rr, 1e-300);
  for (int it = 0; it < 5000 && rr > stop; ++it)
  {
    ApplyCoarseLaplacian(A, p, Ap, nullptr);
    double pAp = 0.0;
    for (std::size_t node = 0; node < M; ++node)
    {
      pAp += p[node] * Ap[node];
    }
    if (!(pAp > 0.0))
    {
      break;
    }
    const double alpha = rr / pAp;
    double       rrNew = 0.0;
    for (std::size_t node = 0; node < M; ++node)
    {
      if (!fixed[node])
      {
        x[node] += alpha * p[node];
        r[node] -= alpha * Ap[node];
        rrNew += r[node] * r[node];
      }
    }
    const double beta = rrNew / rr;
    rr = rrNew;
    for (std::size_t node = 0; node < M; ++node)
    {
      p[node] = fixed[node] ? 0.0 : r[node] + beta * p[node];
    }
  }
}

// Trilinear interpolation of the coarse solution into the uncovered voxels.
void
InterpolateCoarseSolution(const GridGeometry &        grid,
                          const unsigned char *       inside,
                          std::size_t                 c,
                          const CoarseLaplacian &     A,
                          const std::vector<double> & coarse,
                          double *                    field)
{
  const auto & n = grid.size;
  const auto & m = A.m;
  const auto & coord = A.coord;
  for (std::size_t k = 0; k < n[2]; ++k)
  {
    for (std::size_t j = 0; j < n[1]; ++j)
    {
      for (std::size_t i = 0; i < n[0]; ++i)
      {
        const std::size_t off = i + n[0] * (j + n[1] * k);
        if (inside[off])
        {
          continue;
        }
        const std::size_t f[3] = { i, j, k };
        std::size_t       base[3];
        double            t[3];
        for (int d = 0; d < 3; ++d)
        {
          base[d] = std::min(f[d] / c, m[d] - 1);
          t[d] = static_cast<double>(f[d] - base[d] * c) / static_cast<double>(c);
          if (base[d] + 1 >= m[d])
          {
            t[d] = 0.0;
          }
        }
        double out[3] = { 0, 0, 0 };
        for (int corner = 0; corner < 8; ++corner)
        {
          double      weight = 1.0;
          std::size_t node = 0;
          for (int d = 0; d < 3; ++d)
          {
            const int bit = (corner >> d) & 1;
            weight *= bit ? t[d] : 1.0 - t[d];
            node += (base[d] + (bit && t[d] > 0.0 ? 1 : 0)) * coord[d];
          }
          if (weight == 0.0)
          {
            continue;
          }
          for (int d = 0; d < 3; ++d)
          {
            out[d] += weight * coarse[3 * node + d];
          }
        }
        for (int d = 0; d < 3; ++d)
        {
          field[3 * off + d] = out[d];
        }
      }
    }
  }
}

// The uncovered voxels, off the grid's border, within width voxels of the covered ones (found by
// dilating the covered mask), in increasing offset order.
std::vector<std::size_t>
FindBoundaryBand(const GridGeometry & grid, const unsigned char * inside, unsigned int width)
{
  const auto &               n = grid.size;
  const std::size_t          fstride[3] = { 1, n[0], n[0] * n[1] };
  const std::size_t          nvox = grid.GetNumberOfVoxels();
  std::vector<unsigned char> band(inside, inside + nvox);
  for (unsigned int pass = 1; pass <= width; ++pass)
  {
    std::vector<unsigned char> grown(band);
    for (std::size_t off = 0; off < nvox; ++off)
    {
      if (band[off])
      {
        continue;
      }
      const std::size_t f[3] = { off % n[0], (off / n[0]) % n[1], off / (n[0] * n[1]) };
      for (int d = 0; d < 3 && !grown[off]; ++d)
      {
        if ((f[d] > 0 && band[off - fstride[d]]) || (f[d] + 1 < n[d] && band[off + fstride[d]]))
        {
          grown[off] = static_cast<unsigned char>(pass + 1);
        }
      }
    }
    band.swap(grown);
  }
  std::vector<std::size_t> bandVoxels;
  for (std::size_t off = 0; off < nvox; ++off)
  {
    const std::size_t f[3] = { off % n[0], (off / n[0]) % n[1], off / (n[0] * n[1]) };
    const bool border = f[0] == 0 || f[1] == 0 || f[2] == 0 || f[0] + 1 == n[0] || f[1] + 1 == n[1] || f[2] + 1 == n[2];
    if (band[off] && !inside[off] && !border)
    {
      bandVoxels.push_back(off);
    }
  }
  return bandVoxels;
}

// Gauss-Seidel sweeps of the fine-grid Laplacian over bandVoxels, in their (fixed) order.
void
RelaxBoundaryBand(const GridGeometry &             grid,
                  const std::vector<std::size_t> & bandVoxels,
                  unsigned int                     sweeps,
                  double *                         field)
{
  const auto &      n = grid.size;
  const double      fw[3] = { 1.0 / (grid.spacing[0] * grid.spacing[0]),
                              1.0 / (grid.spacing[1] * grid.spacing[1]),
                              1.0 / (grid.spacing[2] * grid.spacing[2]) };
  const std::size_t fstride[3] = { 1, n[0], n[0] * n[1] };
  double            weight = 0.0;
  for (int d = 0; d < 3; ++d)
  {
    weight += 2.0 * fw[d];
  }
  for (unsigned int sweep = 0; sweep < sweeps; ++sweep)
  {
    for (std::size_t off : bandVoxels)
    {
      for (int comp = 0; comp < 3; ++comp)
      {
        double sum = 0.0;
        for (int d = 0; d < 3; ++d)
        {
          sum += fw[d] * (field[3 * (off - fstride[d]) + comp] + field[3 * (off + fstride[d]) + comp]);
        }
        field[3 * off + comp] = sum / weight;
      }
    }
  }
}
} // namespace

void
FillOutsideHarmonic(const GridGeometry & grid, double * field, const unsigned char * inside, unsigned int coarsening)
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
  const bool          any = ComputeCoarseDirichletData(grid, field, inside, c, m, fixed, value);
  if (!any)
  {
    for (std::size_t v = 0; v < grid.GetNumberOfVoxels(); ++v)
    {
      field[3 * v] = field[3 * v + 1] = field[3 * v + 2] = 0.0;
    }
    return;
  }
  // Matrix-free conjugate gradients on the free coarse nodes, one component at a time.
  const CoarseLaplacian A{ { m[0], m[1], m[2] },
                           M,
                           fixed,
                           { 1.0 / std::pow(c * grid.spacing[0], 2),
                             1.0 / std::pow(c * grid.spacing[1], 2),
                             1.0 / std::pow(c * grid.spacing[2], 2) },
                           { 1, static_cast<std::int64_t>(m[0]), static_cast<std::int64_t>(m[0] * m[1]) },
                           { 1, m[0], m[0] * m[1] } };
  std::vector<double>   coarse(3 * M, 0.0);
  std::vector<double>   x(M), r(M), p(M), Ap(M), bc(M);
  for (int comp = 0; comp < 3; ++comp)
  {
    SolveCoarseComponent(A, value, comp, x, r, p, Ap, bc);
    for (std::size_t node = 0; node < M; ++node)
    {
      coarse[3 * node + comp] = x[node];
    }
  }
  InterpolateCoarseSolution(grid, inside, c, A, coarse, field);
  // The coarse interpolation leaves a mismatch at the mesh boundary, within a few coarse cells of
  // it. Gauss-Seidel sweeps of the fine-grid Laplacian on the uncovered voxels of that band (in a
  // fixed order, so deterministic) remove it; the band is found by dilating the covered mask.
  const unsigned int width = 2 * static_cast<unsigned int>(c) + 2;
  RelaxBoundaryBand(grid, FindBoundaryBand(grid, inside, width), 6 * width, field);
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
