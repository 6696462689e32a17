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
#include "bmrLandmarkTerm.h"

#include "bmrError.h"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace bmr {
namespace {
double
Determinant(const double a[3], const double b[3], const double c[3])
{
  return a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) + a[2] * (b[0] * c[1] - b[1] * c[0]);
}

/** Barycentric coordinates of \a p in element \a e (Cramer's rule on the edge vectors). */
std::array<double, 4>
Barycentric(const TetrahedralMesh & mesh, std::size_t e, const std::array<double, 3> & p)
{
  const std::int32_t * t = &mesh.tetrahedra[4 * e];
  const double *       x0 = &mesh.points[3 * static_cast<std::size_t>(t[0])];
  double               edge[3][3], rhs[3];
  for (int c = 0; c < 3; ++c)
  {
    for (int k = 0; k < 3; ++k)
    {
      edge[k][c] = mesh.points[3 * static_cast<std::size_t>(t[k + 1]) + c] - x0[c];
    }
    rhs[c] = p[c] - x0[c];
  }
  // Columns are the edges: det[e1 e2 e3] written with rows as the transposed vectors (same determinant).
  const double det = Determinant(edge[0], edge[1], edge[2]);
  if (det == 0.0)
  {
    return { { -1, -1, -1, -1 } };
  }
  const double l1 = Determinant(rhs, edge[1], edge[2]) / det;
  const double l2 = Determinant(edge[0], rhs, edge[2]) / det;
  const double l3 = Determinant(edge[0], edge[1], rhs) / det;
  return { { 1.0 - l1 - l2 - l3, l1, l2, l3 } };
}

std::string
Describe(const LandmarkTarget & m, std::size_t k)
{
  std::ostringstream os;
  os << "marker " << (m.name.empty() ? std::to_string(k + 1) : "\"" + m.name + "\"");
  return os.str();
}
} // namespace

bool
LocateInMesh(const TetrahedralMesh & mesh, const std::array<double, 3> & point, MeshLocation & location)
{
  constexpr double tolerance = 1e-9;
  for (std::size_t e = 0; e < mesh.GetNumberOfTetrahedra(); ++e)
  {
    const std::array<double, 4> n = Barycentric(mesh, e, point);
    if (n[0] >= -tolerance && n[1] >= -tolerance && n[2] >= -tolerance && n[3] >= -tolerance)
    {
      location.element = e;
      location.shape = n;
      return true;
    }
  }
  return false;
}

LandmarkTerm::LandmarkTerm(const TetrahedralMesh & mesh, std::vector<LandmarkTarget> markers)
  : m_Mesh(mesh)
  , m_Markers(std::move(markers))
{
  if (m_Markers.empty())
  {
    Fail("LandmarkTerm", "no markers");
  }
  double totalWeight = 0.0;
  for (std::size_t k = 0; k < m_Markers.size(); ++k)
  {
    const LandmarkTarget & m = m_Markers[k];
    for (int c = 0; c < 3; ++c)
    {
      if (!std::isfinite(m.moving[c]) || !std::isfinite(m.target[c]))
      {
        Fail("LandmarkTerm", Describe(m, k) + ": a coordinate is not finite");
      }
    }
    if (!std::isfinite(m.weight) || m.weight < 0.0)
    {
      Fail("LandmarkTerm", Describe(m, k) + ": the weight must be finite and >= 0");
    }
    totalWeight += m.weight;
    MeshLocation where;
    if (!LocateInMesh(mesh, m.moving, where))
    {
      std::ostringstream os;
      os << Describe(m, k) << " at (" << m.moving[0] << ", " << m.moving[1] << ", " << m.moving[2]
         << ") mm lies outside the mesh";
      Fail("LandmarkTerm", os.str());
    }
    m_Locations.push_back(where);
  }
  if (totalWeight <= 0.0)
  {
    Fail("LandmarkTerm", "every marker has weight 0: nothing to fit");
  }
}

std::vector<std::array<double, 3>>
LandmarkTerm::DeformedPositions(const std::vector<double> & u) const
{
  std::vector<std::array<double, 3>> positions;
  for (std::size_t k = 0; k < m_Markers.size(); ++k)
  {
    std::array<double, 3> x = m_Markers[k].moving;
    const std::int32_t *  t = &m_Mesh.tetrahedra[4 * m_Locations[k].element];
    for (int i = 0; i < 4; ++i)
    {
      for (int c = 0; c < 3; ++c)
      {
        x[c] += m_Locations[k].shape[i] * u[3 * static_cast<std::size_t>(t[i]) + c];
      }
    }
    positions.push_back(x);
  }
  return positions;
}

std::optional<std::vector<std::int32_t>>
LandmarkTerm::GetObservedNodes() const
{
  std::vector<std::int32_t> nodes;
  for (const MeshLocation & location : m_Locations)
  {
    const std::int32_t * t = &m_Mesh.tetrahedra[4 * location.element];
    nodes.insert(nodes.end(), t, t + 4);
  }
  return UniqueNodes(std::move(nodes));
}

double
LandmarkTerm::Evaluate(const std::vector<double> & u, std::vector<double> * gradient) const
{
  const auto positions = DeformedPositions(u);
  double     value = 0.0;
  for (std::size_t k = 0; k < m_Markers.size(); ++k)
  {
    const double         w = m_Markers[k].weight;
    const std::int32_t * t = &m_Mesh.tetrahedra[4 * m_Locations[k].element];
    for (int c = 0; c < 3; ++c)
    {
      const double offset = positions[k][c] - m_Markers[k].target[c];
      value += 0.5 * w * offset * offset;
      if (gradient)
      {
        for (int i = 0; i < 4; ++i)
        {
          (*gradient)[3 * static_cast<std::size_t>(t[i]) + c] += w * m_Locations[k].shape[i] * offset;
        }
      }
    }
  }
  return value;
}

void
LandmarkTerm::EvaluateResiduals(const std::vector<double> & u,
                                std::vector<double> &       r,
                                ResidualJacobian *          jacobian) const
{
  const auto positions = DeformedPositions(u);
  r.assign(3 * m_Markers.size(), 0.0);
  if (jacobian)
  {
    *jacobian = ResidualJacobian();
    jacobian->rowStart.push_back(0);
  }
  for (std::size_t k = 0; k < m_Markers.size(); ++k)
  {
    const double         root = std::sqrt(m_Markers[k].weight);
    const std::int32_t * t = &m_Mesh.tetrahedra[4 * m_Locations[k].element];
    for (int c = 0; c < 3; ++c)
    {
      r[3 * k + c] = root * (positions[k][c] - m_Markers[k].target[c]);
      if (jacobian)
      {
        for (int i = 0; i < 4; ++i)
        {
          jacobian->dofs.push_back(3 * t[i] + c);
          jacobian->values.push_back(root * m_Locations[k].shape[i]);
        }
        jacobian->rowStart.push_back(jacobian->dofs.size());
      }
    }
  }
}

std::vector<ResidualStatistics>
LandmarkTerm::ComputeStatistics(const std::vector<double> & u) const
{
  const auto         positions = DeformedPositions(u);
  ResidualStatistics st;
  st.name = "markers";
  st.count = m_Markers.size();
  double sum = 0.0;
  for (std::size_t k = 0; k < m_Markers.size(); ++k)
  {
    const auto & T = m_Markers[k].target;
    const double d = std::hypot(positions[k][0] - T[0], positions[k][1] - T[1], positions[k][2] - T[2]);
    sum += d * d;
    st.mean += d / static_cast<double>(m_Markers.size());
    st.maximum = std::max(st.maximum, d);
  }
  st.rms = std::sqrt(sum / static_cast<double>(m_Markers.size()));
  return { st };
}

std::vector<double>
LandmarkTerm::MatchDisplacement(const std::vector<char> & held) const
{
  std::vector<double> u(3 * m_Mesh.GetNumberOfPoints(), 0.0);
  std::vector<double> count(m_Mesh.GetNumberOfPoints(), 0.0);
  for (std::size_t k = 0; k < m_Markers.size(); ++k)
  {
    if (m_Markers[k].weight <= 0.0)
    {
      continue;
    }
    const std::int32_t * t = &m_Mesh.tetrahedra[4 * m_Locations[k].element];
    for (int i = 0; i < 4; ++i)
    {
      if (held[t[i]])
      {
        continue;
      }
      count[t[i]] += 1.0;
      for (int c = 0; c < 3; ++c)
      {
        u[3 * static_cast<std::size_t>(t[i]) + c] += m_Markers[k].target[c] - m_Markers[k].moving[c];
      }
    }
  }
  for (std::size_t n = 0; n < count.size(); ++n)
  {
    for (int c = 0; c < 3 && count[n] > 0.0; ++c)
    {
      u[3 * n + c] /= count[n];
    }
  }
  return u;
}

} // namespace bmr
