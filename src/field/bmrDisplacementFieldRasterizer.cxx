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
// bmr::DisplacementFieldRasterizer: the FE displacement on the voxels of a grid that the mesh covers.
#include "bmrDisplacementFieldRasterizer.h"

#include <ostream>

#include "bmrError.h"
#include "bmrMatrix3.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#if defined(__linux__)
#  include <sys/mman.h>
#endif

namespace bmr {
namespace {
constexpr double InsideTolerance = 1e-10;

/** Refuses an invalid \a grid and a \a displacement that is not 3 finite values per node of \a mesh. */
void
CheckRasterizerInput(const TetrahedralMesh & mesh, const std::vector<double> & displacement, const GridGeometry & grid)
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
}

/** The nodes of element \a e and the continuous indices in \a grid of its vertices (displaced for PullBack). */
void
ElementVertexIndices(const TetrahedralMesh &     mesh,
                     const std::vector<double> & displacement,
                     const GridGeometry &        grid,
                     FieldKindEnum               kind,
                     std::size_t                 e,
                     std::int32_t                nodes[4],
                     double                      v[4][3])
{
  for (int a = 0; a < 4; ++a)
  {
    nodes[a] = mesh.tetrahedra[4 * e + a];
    std::array<double, 3> x;
    for (int i = 0; i < 3; ++i)
    {
      x[i] = mesh.points[3 * nodes[a] + i] + (kind == FieldKindEnum::PullBack ? displacement[3 * nodes[a] + i] : 0.0);
    }
    const std::array<double, 3> idx = grid.PointToIndex(x);
    std::copy(idx.begin(), idx.end(), v[a]);
  }
}

/** The voxel box [lo, hi] (inclusive, clipped to \a grid) of the vertices \a v; false when it is empty. */
bool
VoxelBox(const double v[4][3], const GridGeometry & grid, std::int64_t lo[3], std::int64_t hi[3])
{
  bool outside = false;
  for (int i = 0; i < 3; ++i)
  {
    const double vlo = std::min({ v[0][i], v[1][i], v[2][i], v[3][i] });
    const double vhi = std::max({ v[0][i], v[1][i], v[2][i], v[3][i] });
    lo[i] = std::max<std::int64_t>(0, static_cast<std::int64_t>(std::ceil(vlo - 1e-9)));
    hi[i] = std::min<std::int64_t>(static_cast<std::int64_t>(grid.size[i]) - 1,
                                   static_cast<std::int64_t>(std::floor(vhi + 1e-9)));
    outside = outside || lo[i] > hi[i];
  }
  return !outside;
}

/** The box [boxLo, boxHi] clipped to the region [regionLo, regionHi] as [lo, hi]; false when that is empty. */
bool
ClipBox(const std::int64_t boxLo[3],
        const std::int64_t boxHi[3],
        const std::int64_t regionLo[3],
        const std::int64_t regionHi[3],
        std::int64_t       lo[3],
        std::int64_t       hi[3])
{
  bool skip = false;
  for (int i = 0; i < 3; ++i)
  {
    lo[i] = std::max(boxLo[i], regionLo[i]);
    hi[i] = std::min(boxHi[i], regionHi[i]);
    skip = skip || lo[i] > hi[i];
  }
  return !skip;
}

/** The barycentric coordinates \a b of voxel (i, j, k) in the element of first vertex \a v0 and inverse \a inv;
 * false when the exact test puts the voxel outside. */
bool
VoxelBarycentric(const double v0[3], const double inv[9], std::int64_t i, std::int64_t j, std::int64_t k, double b[4])
{
  const double d[3] = { i - v0[0], j - v0[1], k - v0[2] };
  b[1] = inv[0] * d[0] + inv[1] * d[1] + inv[2] * d[2];
  b[2] = inv[3] * d[0] + inv[4] * d[1] + inv[5] * d[2];
  b[3] = inv[6] * d[0] + inv[7] * d[1] + inv[8] * d[2];
  b[0] = 1.0 - b[1] - b[2] - b[3];
  return !(b[0] < -InsideTolerance || b[1] < -InsideTolerance || b[2] < -InsideTolerance || b[3] < -InsideTolerance);
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
  CheckRasterizerInput(mesh, displacement, grid);
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
  const double gridHandedness = field::Invert3(grid.direction.data(), unusedInverse);
  for (std::size_t e = 0; e < M; ++e)
  {
    Element el;
    double  v[4][3];
    ElementVertexIndices(mesh, displacement, grid, kind, e, el.nodes, v);
    double m[9];
    for (int r = 0; r < 3; ++r)
    {
      for (int c = 0; c < 3; ++c)
      {
        m[3 * r + c] = v[c + 1][r] - v[0][r];
      }
    }
    const double det = field::Invert3(m, el.inv);
    // The orientation in index space flips with a left-handed direction matrix; only a sign change
    // relative to the grid's own handedness (or a collapsed element) means inversion.
    if (!(det * gridHandedness > 0.0) || !std::isfinite(det))
    {
      ++m_Inverted;
      continue;
    }
    std::copy(v[0], v[0] + 3, el.v0);
    if (VoxelBox(v, grid, el.lo, el.hi))
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
    if (!ClipBox(el.lo, el.hi, rlo, rhi, lo, hi))
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
          double b[4];
          if (!VoxelBarycentric(el.v0, el.inv, i, j, k, b))
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

std::ostream &
operator<<(std::ostream & os, FieldKindEnum value)
{
  return os << (value == FieldKindEnum::Push ? "bmr::FieldKindEnum::Push" : "bmr::FieldKindEnum::PullBack");
}

} // namespace bmr
