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
#include "bmrGridGeometry.h"

#include "bmrError.h"

#include <cmath>
#include <sstream>
#include <string>

namespace bmr {
namespace {

/** Row-major 3x3 matrix M = D diag(spacing): column c of D scaled by spacing[c].
 * Kept as one helper so that IndexToPoint and PointToIndex use exactly the same
 * matrix and are therefore inverses of each other up to rounding. */
std::array<double, 9>
IndexToPhysicalMatrix(const GridGeometry & grid)
{
  std::array<double, 9> m{};
  for (unsigned int r = 0; r < 3; ++r)
  {
    for (unsigned int c = 0; c < 3; ++c)
    {
      m[3 * r + c] = grid.direction[3 * r + c] * grid.spacing[c];
    }
  }
  return m;
}

/** Determinant of a row-major 3x3 matrix (cofactor expansion along row 0). */
double
Determinant3(const std::array<double, 9> & m)
{
  return m[0] * (m[4] * m[8] - m[5] * m[7]) - m[1] * (m[3] * m[8] - m[5] * m[6]) + m[2] * (m[3] * m[7] - m[4] * m[6]);
}

/** Formats "what: message" so every validation error names the offending grid. */
std::string
GridMessage(const char * what, const std::string & message)
{
  std::ostringstream os;
  os << (what != nullptr ? what : "grid") << ": " << message;
  return os.str();
}

} // namespace

std::array<double, 3>
GridGeometry::IndexToPoint(const std::array<double, 3> & index) const
{
  const std::array<double, 9> m = IndexToPhysicalMatrix(*this);
  std::array<double, 3>       point{};
  for (unsigned int r = 0; r < 3; ++r)
  {
    point[r] = this->origin[r] + m[3 * r] * index[0] + m[3 * r + 1] * index[1] + m[3 * r + 2] * index[2];
  }
  return point;
}

std::array<double, 3>
GridGeometry::PointToIndex(const std::array<double, 3> & point) const
{
  // The full inverse of D diag(spacing) is used rather than diag(1/spacing) D^T,
  // because direction matrices read from files are often only approximately
  // orthonormal and the contract is to be the exact inverse of IndexToPoint.
  const std::array<double, 9> m = IndexToPhysicalMatrix(*this);
  const double                det = Determinant3(m);
  if (!(std::abs(det) > 0.0) || !std::isfinite(det))
  {
    Fail("GridGeometry::PointToIndex", "the index-to-physical matrix is singular");
  }

  // Inverse = adjugate / det; the adjugate is the transposed cofactor matrix.
  std::array<double, 9> inv{};
  inv[0] = (m[4] * m[8] - m[5] * m[7]) / det;
  inv[1] = (m[2] * m[7] - m[1] * m[8]) / det;
  inv[2] = (m[1] * m[5] - m[2] * m[4]) / det;
  inv[3] = (m[5] * m[6] - m[3] * m[8]) / det;
  inv[4] = (m[0] * m[8] - m[2] * m[6]) / det;
  inv[5] = (m[2] * m[3] - m[0] * m[5]) / det;
  inv[6] = (m[3] * m[7] - m[4] * m[6]) / det;
  inv[7] = (m[1] * m[6] - m[0] * m[7]) / det;
  inv[8] = (m[0] * m[4] - m[1] * m[3]) / det;

  const std::array<double, 3> d{
    { point[0] - this->origin[0], point[1] - this->origin[1], point[2] - this->origin[2] }
  };
  std::array<double, 3> index{};
  for (unsigned int r = 0; r < 3; ++r)
  {
    index[r] = inv[3 * r] * d[0] + inv[3 * r + 1] * d[1] + inv[3 * r + 2] * d[2];
  }
  return index;
}

void
GridGeometry::Validate(const char * what) const
{
  const char * where = "GridGeometry::Validate";
  for (unsigned int a = 0; a < 3; ++a)
  {
    if (this->size[a] == 0)
    {
      std::ostringstream os;
      os << "size[" << a << "] is 0 (size " << this->size[0] << " x " << this->size[1] << " x " << this->size[2] << ")";
      FailInput(where, GridMessage(what, os.str()));
    }
    if (!std::isfinite(this->spacing[a]) || !(this->spacing[a] > 0.0))
    {
      std::ostringstream os;
      os << "spacing[" << a << "] = " << this->spacing[a] << " is not positive and finite";
      FailInput(where, GridMessage(what, os.str()));
    }
    if (!std::isfinite(this->origin[a]))
    {
      std::ostringstream os;
      os << "origin[" << a << "] = " << this->origin[a] << " is not finite";
      FailInput(where, GridMessage(what, os.str()));
    }
  }
  for (unsigned int e = 0; e < 9; ++e)
  {
    if (!std::isfinite(this->direction[e]))
    {
      std::ostringstream os;
      os << "direction[" << e << "] = " << this->direction[e] << " is not finite";
      FailInput(where, GridMessage(what, os.str()));
    }
  }
  const double det = Determinant3(this->direction);
  if (!(std::abs(det) >= 1e-6))
  {
    std::ostringstream os;
    os << "the direction matrix is singular (|det| = " << std::abs(det) << " < 1e-6)";
    FailInput(where, GridMessage(what, os.str()));
  }
}

GridGeometry
CenteredGrid(const std::array<std::size_t, 3> & size, const std::array<double, 3> & spacing, double rotationZ)
{
  GridGeometry g;
  g.size = size;
  g.spacing = spacing;
  g.direction = { std::cos(rotationZ), -std::sin(rotationZ), 0, std::sin(rotationZ), std::cos(rotationZ), 0, 0, 0, 1 };
  std::array<double, 3> half;
  for (int i = 0; i < 3; ++i)
  {
    half[i] = 0.5 * (static_cast<double>(size[i]) - 1.0) * spacing[i];
  }
  for (int r = 0; r < 3; ++r)
  {
    g.origin[r] = -(g.direction[3 * r] * half[0] + g.direction[3 * r + 1] * half[1] + g.direction[3 * r + 2] * half[2]);
  }
  return g;
}

} // namespace bmr
