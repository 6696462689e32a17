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
// bmr::PointLocator (a bucket grid of the elements of a tetrahedral mesh) and the FE displacement at a point.
#include "bmrDisplacementFieldRasterizer.h"

#include "bmrError.h"
#include "bmrMatrix3.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

namespace bmr {
namespace {
/** The bounding box [lower, upper] of \a points (3 values per point). */
void
BoundingBox(const std::vector<double> & points, std::array<double, 3> & lower, std::array<double, 3> & upper)
{
  for (int i = 0; i < 3; ++i)
  {
    lower[i] = std::numeric_limits<double>::max();
    upper[i] = std::numeric_limits<double>::lowest();
  }
  for (std::size_t n = 0; n < points.size() / 3; ++n)
  {
    for (int i = 0; i < 3; ++i)
    {
      lower[i] = std::min(lower[i], points[3 * n + i]);
      upper[i] = std::max(upper[i], points[3 * n + i]);
    }
  }
}

/** The range [lo, hi] of the cells (\a cells of \a cellSize from \a lower) that element \a e's bounding box overlaps.
 */
void
ElementCellRange(const std::vector<double> &        points,
                 const std::vector<std::int32_t> &  tetrahedra,
                 const std::array<double, 3> &      lower,
                 const std::array<double, 3> &      cellSize,
                 const std::array<std::size_t, 3> & cells,
                 std::size_t                        e,
                 std::size_t                        lo[3],
                 std::size_t                        hi[3])
{
  for (int i = 0; i < 3; ++i)
  {
    double a = std::numeric_limits<double>::max(), b = std::numeric_limits<double>::lowest();
    for (int k = 0; k < 4; ++k)
    {
      const double x = points[3 * tetrahedra[4 * e + k] + i];
      a = std::min(a, x);
      b = std::max(b, x);
    }
    lo[i] = std::min(cells[i] - 1, static_cast<std::size_t>(std::max(0.0, (a - lower[i]) / cellSize[i])));
    hi[i] = std::min(cells[i] - 1, static_cast<std::size_t>(std::max(0.0, (b - lower[i]) / cellSize[i])));
  }
}
} // namespace

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
  BoundingBox(points, m_Lower, upper);
  // About two elements per cell on average.
  const double volume = std::max(1e-12, (upper[0] - m_Lower[0]) * (upper[1] - m_Lower[1]) * (upper[2] - m_Lower[2]));
  const double h = std::cbrt(volume / (static_cast<double>(M) / 2.0));
  for (int i = 0; i < 3; ++i)
  {
    m_Cells[i] = std::max<std::size_t>(1, static_cast<std::size_t>(std::ceil((upper[i] - m_Lower[i]) / h)));
    m_CellSize[i] = std::max(1e-12, (upper[i] - m_Lower[i]) / static_cast<double>(m_Cells[i]));
  }
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
      ElementCellRange(m_Points, m_Tetrahedra, m_Lower, m_CellSize, m_Cells, e, lo, hi);
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
  const double det = field::Invert3(m, inv);
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

} // namespace bmr
