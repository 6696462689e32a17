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
#include "bmrCompressionBarrier.h"

#include "bmrError.h"
#include "../fem/bmrFemAssembly.h"

#include <cmath>

namespace bmr {
namespace {
/** det F and cof(F) = J F^{-T} of F = I + sum_a u_a g_a^T. */
double
DeformationCofactor(const double * g, const double * const ua[4], double cof[3][3])
{
  double F[3][3];
  for (int i = 0; i < 3; ++i)
  {
    for (int j = 0; j < 3; ++j)
    {
      F[i][j] = (i == j ? 1.0 : 0.0);
      for (int a = 0; a < 4; ++a)
      {
        F[i][j] += ua[a][i] * g[3 * a + j];
      }
    }
  }
  for (int i = 0; i < 3; ++i)
  {
    const int i1 = (i + 1) % 3, i2 = (i + 2) % 3;
    for (int j = 0; j < 3; ++j)
    {
      const int j1 = (j + 1) % 3, j2 = (j + 2) % 3;
      cof[i][j] = F[i1][j1] * F[i2][j2] - F[i1][j2] * F[i2][j1];
    }
  }
  return F[0][0] * cof[0][0] + F[0][1] * cof[0][1] + F[0][2] * cof[0][2];
}
} // namespace

CompressionBarrier::CompressionBarrier(const TetrahedralMesh & mesh, double threshold, double weight)
  : m_Mesh(mesh)
  , m_Threshold(threshold)
  , m_Weight(weight)
{
  if (!(threshold > 0.0 && threshold < 1.0))
  {
    Fail("CompressionBarrier", "the threshold J_0 must lie in (0, 1), got " + std::to_string(threshold));
  }
  if (!(weight >= 0.0 && std::isfinite(weight)))
  {
    Fail("CompressionBarrier", "the weight must be finite and non-negative, got " + std::to_string(weight));
  }
  const std::size_t ne = mesh.GetNumberOfTetrahedra();
  m_Gradients.resize(12 * ne);
  m_Lengths.resize(ne);
  for (std::size_t e = 0; e < ne; ++e)
  {
    double       g[4][3];
    const double volume = fem::ElementGradients(mesh, e, g);
    for (int a = 0; a < 4; ++a)
    {
      for (int c = 0; c < 3; ++c)
      {
        m_Gradients[12 * e + 3 * a + c] = g[a][c];
      }
    }
    m_Lengths[e] = std::cbrt(std::abs(volume));
  }
}

double
CompressionBarrier::Evaluate(const std::vector<double> & u, std::vector<double> * gradient) const
{
  if (u.size() != 3 * m_Mesh.GetNumberOfPoints() || (gradient != nullptr && gradient->size() != u.size()))
  {
    Fail("CompressionBarrier::Evaluate", "the displacement and gradient vectors must hold 3 values per node");
  }
  if (m_Weight == 0.0)
  {
    return 0.0;
  }
  const double lowest = m_Threshold / 16.0; // J_1: below it psi continues along its tangent
  double       value = 0.0;
  for (std::size_t e = 0; e < m_Lengths.size(); ++e)
  {
    const std::int32_t * t = &m_Mesh.tetrahedra[4 * e];
    const double * const ua[4] = { &u[3 * t[0]], &u[3 * t[1]], &u[3 * t[2]], &u[3 * t[3]] };
    double               cof[3][3];
    const double         J = DeformationCofactor(&m_Gradients[12 * e], ua, cof);
    if (J >= m_Threshold)
    {
      continue;
    }
    const double psi = J >= lowest ? std::log(J / m_Threshold) : std::log(lowest / m_Threshold) + (J - lowest) / lowest;
    const double dpsi = 1.0 / std::max(J, lowest);
    const double r = m_Lengths[e] * psi;
    value += 0.5 * m_Weight * r * r;
    if (gradient == nullptr)
    {
      continue;
    }
    // dPhi_b/du_a = w r l psi'(J) cof(F) g_a
    const double   scale = m_Weight * r * m_Lengths[e] * dpsi;
    const double * g = &m_Gradients[12 * e];
    for (int a = 0; a < 4; ++a)
    {
      for (int i = 0; i < 3; ++i)
      {
        (*gradient)[3 * t[a] + i] +=
          scale * (cof[i][0] * g[3 * a] + cof[i][1] * g[3 * a + 1] + cof[i][2] * g[3 * a + 2]);
      }
    }
  }
  return value;
}

std::size_t
CompressionBarrier::CountCompressed(const std::vector<double> & u) const
{
  if (u.size() != 3 * m_Mesh.GetNumberOfPoints())
  {
    Fail("CompressionBarrier::CountCompressed", "the displacement vector must hold 3 values per node");
  }
  std::size_t count = 0;
  for (std::size_t e = 0; e < m_Lengths.size(); ++e)
  {
    const std::int32_t * t = &m_Mesh.tetrahedra[4 * e];
    const double * const ua[4] = { &u[3 * t[0]], &u[3 * t[1]], &u[3 * t[2]], &u[3 * t[3]] };
    double               cof[3][3];
    count += DeformationCofactor(&m_Gradients[12 * e], ua, cof) < m_Threshold;
  }
  return count;
}

} // namespace bmr
