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
#include "bmrWallBasis.h"

#include "bmrError.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace bmr {

namespace {
using WallNodes = std::vector<std::pair<std::int32_t, std::int32_t>>; // (parameter-node index, mesh node id)

const double *
NodePoint(const std::vector<double> & points, std::int32_t node)
{
  return &points[3 * static_cast<std::size_t>(node)];
}

double
Distance2(const double * a, const double * b)
{
  return (a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]);
}

// Appends the control points of one (non-empty) wall to controls; returns the index of the first one.
std::size_t
SampleWallControlPoints(const std::vector<double> &          points,
                        const WallNodes &                    wall,
                        double                               spacing,
                        std::vector<std::array<double, 3>> & controls)
{
  double centroid[3] = { 0, 0, 0 };
  for (const auto & n : wall)
  {
    for (int c = 0; c < 3; ++c)
    {
      centroid[c] += NodePoint(points, n.second)[c] / static_cast<double>(wall.size());
    }
  }
  // Farthest-point sampling; ties go to the first node in wall order.
  std::vector<double> nearest(wall.size(), std::numeric_limits<double>::max());
  std::size_t         next = 0;
  double              best = -1.0;
  for (std::size_t i = 0; i < wall.size(); ++i)
  {
    const double d = Distance2(NodePoint(points, wall[i].second), centroid);
    if (d > best)
    {
      best = d;
      next = i;
    }
  }
  const std::size_t first = controls.size();
  while (true)
  {
    const double * p = NodePoint(points, wall[next].second);
    controls.push_back({ { p[0], p[1], p[2] } });
    best = -1.0;
    for (std::size_t i = 0; i < wall.size(); ++i)
    {
      nearest[i] = std::min(nearest[i], Distance2(NodePoint(points, wall[i].second), p));
      if (nearest[i] > best)
      {
        best = nearest[i];
        next = i;
      }
    }
    if (best <= spacing * spacing)
    {
      break;
    }
  }
  return first;
}

// Unnormalized Gaussian weights of the wall's nodes for the wall's control points controls[first..].
void
AddWallGaussianWeights(const std::vector<double> &                points,
                       const WallNodes &                          wall,
                       double                                     spacing,
                       const std::vector<std::array<double, 3>> & controls,
                       std::size_t                                first,
                       std::vector<std::vector<double>> &         raw,
                       std::vector<std::vector<std::int32_t>> &   rawControl)
{
  const double s2 = 2.0 * spacing * spacing;
  for (const auto & n : wall)
  {
    const double * x = NodePoint(points, n.second);
    for (std::size_t j = first; j < controls.size(); ++j)
    {
      raw[n.first].push_back(std::exp(-Distance2(x, controls[j].data()) / s2));
      rawControl[n.first].push_back(static_cast<std::int32_t>(j));
    }
  }
}

// Adds the ridge 1e-8 trace / m to the diagonal of the m x m row-major Gram matrix A and overwrites A
// with its lower Cholesky factor.
void
AddRidgeAndFactorizeGram(std::vector<double> & A, std::size_t m)
{
  double trace = 0.0;
  for (std::size_t i = 0; i < m; ++i)
  {
    trace += A[i * m + i];
  }
  for (std::size_t i = 0; i < m; ++i)
  {
    A[i * m + i] += 1e-8 * trace / static_cast<double>(m);
  }
  for (std::size_t j = 0; j < m; ++j)
  {
    double s = A[j * m + j];
    for (std::size_t k = 0; k < j; ++k)
    {
      s -= A[j * m + k] * A[j * m + k];
    }
    if (!(s > 0.0))
    {
      Fail("WallBasis", "the Gram matrix of the wall basis is singular");
    }
    A[j * m + j] = std::sqrt(s);
    for (std::size_t i = j + 1; i < m; ++i)
    {
      double t = A[i * m + j];
      for (std::size_t k = 0; k < j; ++k)
      {
        t -= A[i * m + k] * A[j * m + k];
      }
      A[i * m + j] = t / A[j * m + j];
      A[j * m + i] = 0.0;
    }
  }
}
} // namespace

WallBasis::WallBasis(const std::vector<double> &                                             points,
                     const std::vector<std::vector<std::pair<std::int32_t, std::int32_t>>> & walls,
                     std::size_t                                                             numberOfNodes,
                     double                                                                  spacing)
  : m_NumberOfNodes(numberOfNodes)
  , m_Rows(numberOfNodes)
{
  if (!(spacing > 0.0) || numberOfNodes == 0)
  {
    m_Identity = true;
    m_NumberOfControlPoints = numberOfNodes;
    return;
  }
  std::vector<std::array<double, 3>>     controls;
  std::vector<std::vector<double>>       raw(numberOfNodes);
  std::vector<std::vector<std::int32_t>> rawControl(numberOfNodes);
  for (const auto & wall : walls)
  {
    if (wall.empty())
    {
      continue;
    }
    const std::size_t first = SampleWallControlPoints(points, wall, spacing, controls);
    AddWallGaussianWeights(points, wall, spacing, controls, first, raw, rawControl);
  }
  m_NumberOfControlPoints = controls.size();
  for (std::size_t k = 0; k < numberOfNodes; ++k)
  {
    if (raw[k].empty())
    {
      Fail("WallBasis", "node " + std::to_string(k) + " of the wall parameters belongs to no wall");
    }
    const double largest = *std::max_element(raw[k].begin(), raw[k].end());
    double       sum = 0.0;
    for (std::size_t i = 0; i < raw[k].size(); ++i)
    {
      if (raw[k][i] >= 1e-4 * largest)
      {
        m_Rows[k].push_back({ rawControl[k][i], raw[k][i] });
        sum += raw[k][i];
      }
    }
    for (Entry & e : m_Rows[k])
    {
      e.weight /= sum;
    }
  }
  // Cholesky factor of the Gram matrix W^T W (+ a tiny ridge): the parameters are q = L^T c, so that
  // the columns of W L^{-T} are orthonormal and L-BFGS sees a well-conditioned wall term.
  const std::size_t m = m_NumberOfControlPoints;
  m_Cholesky.assign(m * m, 0.0);
  std::vector<double> & A = m_Cholesky;
  for (const auto & row : m_Rows)
  {
    for (const Entry & a : row)
    {
      for (const Entry & b : row)
      {
        A[static_cast<std::size_t>(a.control) * m + static_cast<std::size_t>(b.control)] += a.weight * b.weight;
      }
    }
  }
  AddRidgeAndFactorizeGram(A, m);
}

void
WallBasis::SolveLower(std::vector<double> & x) const
{
  const std::size_t m = m_NumberOfControlPoints;
  for (int a = 0; a < 3; ++a)
  {
    for (std::size_t i = 0; i < m; ++i)
    {
      double t = x[3 * i + a];
      for (std::size_t k = 0; k < i; ++k)
      {
        t -= m_Cholesky[i * m + k] * x[3 * k + a];
      }
      x[3 * i + a] = t / m_Cholesky[i * m + i];
    }
  }
}

void
WallBasis::SolveUpper(std::vector<double> & x) const
{
  const std::size_t m = m_NumberOfControlPoints;
  for (int a = 0; a < 3; ++a)
  {
    for (std::size_t i = m; i-- > 0;)
    {
      double t = x[3 * i + a];
      for (std::size_t k = i + 1; k < m; ++k)
      {
        t -= m_Cholesky[k * m + i] * x[3 * k + a];
      }
      x[3 * i + a] = t / m_Cholesky[i * m + i];
    }
  }
}

std::vector<double>
WallBasis::Expand(const std::vector<double> & q) const
{
  if (m_Identity)
  {
    return q;
  }
  std::vector<double> c(q);
  SolveUpper(c); // c = L^{-T} q
  std::vector<double> d(3 * m_NumberOfNodes, 0.0);
  for (std::size_t k = 0; k < m_NumberOfNodes; ++k)
  {
    for (const Entry & e : m_Rows[k])
    {
      for (int a = 0; a < 3; ++a)
      {
        d[3 * k + a] += e.weight * c[3 * static_cast<std::size_t>(e.control) + a];
      }
    }
  }
  return d;
}

std::vector<double>
WallBasis::ExpandTranspose(const std::vector<double> & g) const
{
  if (m_Identity)
  {
    return g;
  }
  std::vector<double> r(3 * m_NumberOfControlPoints, 0.0);
  for (std::size_t k = 0; k < m_NumberOfNodes; ++k)
  {
    for (const Entry & e : m_Rows[k])
    {
      for (int a = 0; a < 3; ++a)
      {
        r[3 * static_cast<std::size_t>(e.control) + a] += e.weight * g[3 * k + a];
      }
    }
  }
  SolveLower(r); // L^{-1} W^T g
  return r;
}

std::vector<double>
WallBasis::Fit(const std::vector<double> & d) const
{
  // q = L^T c with c = (W^T W)^{-1} W^T d, i.e. q = L^{-1} W^T d.
  return ExpandTranspose(d);
}

} // namespace bmr
