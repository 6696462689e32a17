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
#include "bmrSignedDistanceSampler.h"

#include "bmrError.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <utility>

namespace bmr {
namespace {
/** Uniform cubic B-spline weights of the four samples around t in [0, 1) and their derivatives. */
void
CubicWeights(double t, double w[4], double dw[4])
{
  const double s = 1.0 - t;
  w[0] = s * s * s / 6.0;
  w[1] = (3.0 * t * t * t - 6.0 * t * t + 4.0) / 6.0;
  w[2] = (-3.0 * t * t * t + 3.0 * t * t + 3.0 * t + 1.0) / 6.0;
  w[3] = t * t * t / 6.0;
  dw[0] = -0.5 * s * s;
  dw[1] = 0.5 * (3.0 * t * t - 4.0 * t);
  dw[2] = 0.5 * (-3.0 * t * t + 2.0 * t + 1.0);
  dw[3] = 0.5 * t * t;
}
} // namespace

SignedDistanceSampler::SignedDistanceSampler(const GridGeometry & grid, std::vector<float> values, const char * what)
  : m_Grid(grid)
  , m_Values(std::move(values))
{
  m_Grid.Validate(what);
  if (m_Values.size() != m_Grid.GetNumberOfVoxels() || m_Values.empty())
  {
    std::ostringstream msg;
    msg << what << ": expected " << m_Grid.GetNumberOfVoxels() << " samples, got " << m_Values.size();
    Fail("SignedDistanceSampler", msg.str());
  }
  for (std::size_t i = 0; i < m_Values.size(); ++i)
  {
    if (!std::isfinite(m_Values[i]))
    {
      std::ostringstream msg;
      msg << what << ": sample " << i << " is not finite";
      Fail("SignedDistanceSampler", msg.str());
    }
  }
  // Column j of M^{-1} is the continuous index of origin + e_j.
  for (int j = 0; j < 3; ++j)
  {
    std::array<double, 3> p = m_Grid.origin;
    p[j] += 1.0;
    const std::array<double, 3> c = m_Grid.PointToIndex(p);
    for (int r = 0; r < 3; ++r)
    {
      m_PhysicalToIndex[3 * r + j] = c[r];
    }
  }
}

double
SignedDistanceSampler::Evaluate(const double x[3], double gradient[3]) const
{
  const std::array<double, 3> xi = m_Grid.PointToIndex({ { x[0], x[1], x[2] } });
  double                      w[3][4], dw[3][4];
  std::int64_t                base[3];
  bool                        clamped[3];
  for (int d = 0; d < 3; ++d)
  {
    const double hi = static_cast<double>(m_Grid.size[d] - 1);
    const double c = std::min(std::max(xi[d], 0.0), hi);
    clamped[d] = c != xi[d];
    const double f = std::floor(c);
    base[d] = static_cast<std::int64_t>(f) - 1;
    CubicWeights(c - f, w[d], dw[d]);
  }
  const auto at = [this](std::int64_t i, int d) {
    return static_cast<std::size_t>(
      std::min<std::int64_t>(std::max<std::int64_t>(i, 0), static_cast<std::int64_t>(m_Grid.size[d]) - 1));
  };
  double value = 0.0, g[3] = { 0.0, 0.0, 0.0 };
  for (int c = 0; c < 4; ++c)
  {
    const std::size_t k = at(base[2] + c, 2);
    for (int b = 0; b < 4; ++b)
    {
      const std::size_t j = at(base[1] + b, 1);
      const std::size_t row = m_Grid.size[0] * (j + m_Grid.size[1] * k);
      for (int a = 0; a < 4; ++a)
      {
        const double v = m_Values[row + at(base[0] + a, 0)];
        value += v * w[0][a] * w[1][b] * w[2][c];
        g[0] += v * dw[0][a] * w[1][b] * w[2][c];
        g[1] += v * w[0][a] * dw[1][b] * w[2][c];
        g[2] += v * w[0][a] * w[1][b] * dw[2][c];
      }
    }
  }
  if (gradient != nullptr)
  {
    for (int d = 0; d < 3; ++d)
    {
      if (clamped[d])
      {
        g[d] = 0.0;
      }
    }
    // d phi / d x_j = sum_r d phi / d xi_r * d xi_r / d x_j.
    for (int j = 0; j < 3; ++j)
    {
      gradient[j] = g[0] * m_PhysicalToIndex[j] + g[1] * m_PhysicalToIndex[3 + j] + g[2] * m_PhysicalToIndex[6 + j];
    }
  }
  return value;
}

} // namespace bmr
