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
// NeoHookeanForwardModel's assembly: the element loops for the stored energy, internal forces and tangent.
#include "bmrNeoHookeanForwardModelInternal.h"

#include "bmrError.h"

#include <algorithm>
#include <limits>
#include <sstream>

namespace bmr {
using neohookean::kWho;

bool
NeoHookeanForwardModel::Impl::Deform(std::size_t e, const std::vector<double> & u, fem::ElementDeformation & d) const
{
  const std::int32_t * t = &mesh.tetrahedra[4 * e];
  const double * const ua[4] = { &u[3 * t[0]], &u[3 * t[1]], &u[3 * t[2]], &u[3 * t[3]] };
  return fem::DeformElement(reinterpret_cast<const double(*)[3]>(gradients[e].data()), ua, d);
}

double
NeoHookeanForwardModel::Impl::Energy(const std::vector<double> & u, std::int64_t * worst, double * worstJ) const
{
  double sum = 0.0, smallestJ = std::numeric_limits<double>::infinity();
  for (std::size_t e = 0; e < volumes.size(); ++e)
  {
    if (passive[e])
    {
      continue;
    }
    fem::ElementDeformation d;
    Deform(e, u, d);
    if (d.J < smallestJ)
    {
      smallestJ = d.J;
      if (worst)
      {
        *worst = static_cast<std::int64_t>(e);
      }
    }
    sum += volumes[e] * fem::StoredEnergyDensity(d, mu[e], lambda[e]);
  }
  if (worstJ)
  {
    *worstJ = smallestJ;
  }
  return sum;
}

std::vector<double>
NeoHookeanForwardModel::Impl::Forces(const std::vector<double> & u, std::int32_t onlyLabel) const
{
  std::vector<double> f(ndof, 0.0);
  for (std::size_t e = 0; e < volumes.size(); ++e)
  {
    if (onlyLabel >= 0 && mesh.labels[e] != onlyLabel)
    {
      continue;
    }
    fem::ElementDeformation d;
    if (!Deform(e, u, d) && passive[e])
    {
      continue; // inverted by the prescribed motion alone: no reaction to report
    }
    if (d.J <= 0.0)
    {
      std::ostringstream msg;
      msg << "element " << e << " is inverted (J = " << d.J << "): no neo-Hookean internal forces";
      Fail(kWho, msg.str());
    }
    double fe[4][3];
    fem::ElementForces(d, reinterpret_cast<const double(*)[3]>(gradients[e].data()), volumes[e], mu[e], lambda[e], fe);
    for (int a = 0; a < 4; ++a)
    {
      for (int i = 0; i < 3; ++i)
      {
        f[3 * mesh.tetrahedra[4 * e + a] + i] += fe[a][i];
      }
    }
  }
  return f;
}

void
NeoHookeanForwardModel::Impl::AssembleTangent(const std::vector<double> & u)
{
  std::fill(tangent.begin(), tangent.end(), 0.0);
  for (std::size_t e = 0; e < volumes.size(); ++e)
  {
    if (passive[e])
    {
      continue;
    }
    fem::ElementDeformation d;
    if (!Deform(e, u, d))
    {
      std::ostringstream msg;
      msg << "element " << e << " is inverted (J = " << d.J << "): no neo-Hookean tangent";
      Fail(kWho, msg.str());
    }
    double K[12][12];
    fem::ElementTangent(d, reinterpret_cast<const double(*)[3]>(gradients[e].data()), volumes[e], mu[e], lambda[e], K);
    const std::int64_t * entries = &elementEntries[144 * e];
    for (int r = 0; r < 12; ++r)
    {
      for (int c = 0; c < 12; ++c)
      {
        if (entries[12 * r + c] >= 0)
        {
          tangent[entries[12 * r + c]] += K[r][c];
        }
      }
    }
  }
  CopyTangentToFreeBlock();
  factorizationExact = false;
  iterationsAtThisTangent = 0;
}

} // namespace bmr
