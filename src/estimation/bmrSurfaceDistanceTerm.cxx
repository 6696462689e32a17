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
#include "bmrDataTerm.h"

#include "bmrError.h"

#include <algorithm>
#include <cmath>

namespace bmr {
namespace {
/** x_n + u_n [mm]. */
inline void
DeformedPoint(const TetrahedralMesh & mesh, const std::vector<double> & u, std::int32_t n, double x[3])
{
  for (int c = 0; c < 3; ++c)
  {
    x[c] = mesh.points[3 * static_cast<std::size_t>(n) + c] + u[3 * static_cast<std::size_t>(n) + c];
  }
}

/** Which surfaces each node is on. */
std::vector<std::vector<std::size_t>>
SurfacesOfNodes(const TetrahedralMesh & mesh, const std::vector<ObjectiveSurface> & surfaces)
{
  std::vector<std::vector<std::size_t>> onSurface(mesh.GetNumberOfPoints());
  for (std::size_t s = 0; s < surfaces.size(); ++s)
  {
    for (std::int32_t n : surfaces[s].nodes)
    {
      onSurface[n].push_back(s);
    }
  }
  return onSurface;
}

/** The neighbors of every surface node along element edges on a common surface (sorted, unique). */
std::vector<std::vector<std::int32_t>>
SurfaceNeighbors(const TetrahedralMesh & mesh, const std::vector<std::vector<std::size_t>> & onSurface)
{
  const auto shareSurface = [&](std::int32_t a, std::int32_t b) {
    for (std::size_t s : onSurface[a])
    {
      if (std::find(onSurface[b].begin(), onSurface[b].end(), s) != onSurface[b].end())
      {
        return true;
      }
    }
    return false;
  };
  std::vector<std::vector<std::int32_t>> neighbors(mesh.GetNumberOfPoints());
  for (std::size_t e = 0; e < mesh.GetNumberOfTetrahedra(); ++e)
  {
    const std::int32_t * t = &mesh.tetrahedra[4 * e];
    for (int a = 0; a < 4; ++a)
    {
      for (int b = 0; b < 4; ++b)
      {
        if (a != b && !onSurface[t[a]].empty() && shareSurface(t[a], t[b]))
        {
          neighbors[t[a]].push_back(t[b]);
        }
      }
    }
  }
  for (auto & nb : neighbors)
  {
    std::sort(nb.begin(), nb.end());
    nb.erase(std::unique(nb.begin(), nb.end()), nb.end());
  }
  return neighbors;
}
} // namespace

SurfaceDistanceTerm::SurfaceDistanceTerm(const TetrahedralMesh & mesh, std::vector<ObjectiveSurface> surfaces)
  : m_Mesh(mesh)
  , m_Surfaces(std::move(surfaces))
{
  if (m_Surfaces.empty())
  {
    Fail("SurfaceDistanceTerm", "the scene's objective is empty: nothing to match");
  }
}

double
SurfaceDistanceTerm::Evaluate(const std::vector<double> & u, std::vector<double> * gradient) const
{
  double phiSum = 0.0;
  for (const ObjectiveSurface & s : m_Surfaces)
  {
    for (std::int32_t n : s.nodes)
    {
      double x[3], grad[3];
      DeformedPoint(m_Mesh, u, n, x);
      const double phi = s.distance->Evaluate(x, grad);
      phiSum += 0.5 * s.weight * phi * phi;
      if (gradient != nullptr)
      {
        for (int c = 0; c < 3; ++c)
        {
          (*gradient)[3 * static_cast<std::size_t>(n) + c] += s.weight * phi * grad[c];
        }
      }
    }
  }
  return phiSum;
}

void
SurfaceDistanceTerm::EvaluateResiduals(const std::vector<double> & u,
                                       std::vector<double> &       r,
                                       ResidualJacobian *          jacobian) const
{
  r.clear();
  if (jacobian != nullptr)
  {
    *jacobian = ResidualJacobian();
    jacobian->rowStart.push_back(0);
  }
  for (const ObjectiveSurface & s : m_Surfaces)
  {
    const double sw = std::sqrt(s.weight);
    for (std::int32_t n : s.nodes)
    {
      double x[3], grad[3];
      DeformedPoint(m_Mesh, u, n, x);
      r.push_back(sw * s.distance->Evaluate(x, grad));
      if (jacobian != nullptr)
      {
        for (int c = 0; c < 3; ++c)
        {
          jacobian->dofs.push_back(3 * n + c);
          jacobian->values.push_back(sw * grad[c]);
        }
        jacobian->rowStart.push_back(jacobian->dofs.size());
      }
    }
  }
}

std::vector<ResidualStatistics>
SurfaceDistanceTerm::ComputeStatistics(const std::vector<double> & u) const
{
  std::vector<ResidualStatistics> stats;
  for (const ObjectiveSurface & s : m_Surfaces)
  {
    ResidualStatistics st;
    st.name = s.name;
    st.count = s.nodes.size();
    st.weight = s.weight;
    double sum = 0.0;
    for (std::int32_t n : s.nodes)
    {
      double x[3];
      DeformedPoint(m_Mesh, u, n, x);
      const double phi = s.distance->Evaluate(x, nullptr);
      sum += phi * phi;
      st.mean += phi / static_cast<double>(s.nodes.size());
      st.maximum = std::max(st.maximum, std::abs(phi));
    }
    st.rms = std::sqrt(sum / static_cast<double>(s.nodes.size()));
    stats.push_back(st);
  }
  return stats;
}

std::optional<std::vector<std::int32_t>>
SurfaceDistanceTerm::GetObservedNodes() const
{
  std::vector<std::int32_t> nodes;
  for (const ObjectiveSurface & surface : m_Surfaces)
  {
    nodes.insert(nodes.end(), surface.nodes.begin(), surface.nodes.end());
  }
  return UniqueNodes(std::move(nodes));
}

std::vector<double>
SurfaceDistanceTerm::MatchDisplacement(const std::vector<char> & held) const
{
  const std::size_t                            N = m_Mesh.GetNumberOfPoints();
  const std::vector<std::vector<std::size_t>>  onSurface = SurfacesOfNodes(m_Mesh, m_Surfaces);
  const std::vector<std::vector<std::int32_t>> neighbors = SurfaceNeighbors(m_Mesh, onSurface);
  std::vector<std::int32_t>                    active;
  for (std::size_t n = 0; n < N; ++n)
  {
    if (!onSurface[n].empty() && !held[n])
    {
      active.push_back(static_cast<std::int32_t>(n));
    }
  }
  // alpha: fraction of the distance closed per step; beta: spring stiffness towards the neighbors' mean.
  const double        alpha = 0.5, beta = 0.25;
  std::vector<double> v(3 * N, 0.0), next(3 * N, 0.0);
  for (unsigned int it = 0; it < m_MatchingIterations; ++it)
  {
    for (std::int32_t n : active)
    {
      double pull[3] = { 0.0, 0.0, 0.0 };
      for (std::size_t s : onSurface[n])
      {
        double x[3], grad[3];
        DeformedPoint(m_Mesh, v, n, x);
        const double phi = m_Surfaces[s].distance->Evaluate(x, grad);
        for (int c = 0; c < 3; ++c)
        {
          pull[c] -= phi * grad[c] / static_cast<double>(onSurface[n].size());
        }
      }
      double mean[3] = { 0.0, 0.0, 0.0 };
      for (std::int32_t m : neighbors[n])
      {
        for (int c = 0; c < 3; ++c)
        {
          mean[c] += v[3 * m + c] / static_cast<double>(neighbors[n].size());
        }
      }
      for (int c = 0; c < 3; ++c)
      {
        const double vc = v[3 * n + c];
        next[3 * n + c] = vc + alpha * pull[c] + (neighbors[n].empty() ? 0.0 : beta * (mean[c] - vc));
      }
    }
    for (std::int32_t n : active)
    {
      for (int c = 0; c < 3; ++c)
      {
        v[3 * n + c] = next[3 * n + c];
      }
    }
  }
  return v;
}

} // namespace bmr
