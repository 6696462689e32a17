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
#ifndef bmrNeoHookeanElement_h
#define bmrNeoHookeanElement_h

// The compressible neo-Hookean P1 tetrahedron of NeoHookeanForwardModel (private to src/fem): kinematics,
// energy, first Piola-Kirchhoff stress and tangent of one element (equations in bmrNeoHookeanForwardModel.h).
#include <cmath>
#include <limits>

namespace bmr {
namespace fem {

/** The deformation of one element: F = I + sum_a u_a g_a^T, J = det F and F^{-1}. */
struct ElementDeformation
{
  double F[3][3];
  double Finv[3][3];
  double J{ 0.0 };
};

/** Fills \a d from the reference gradients \a g and the nodal displacements \a ua (3 per node); returns false
 * when J <= 0 (inverted or flat: no neo-Hookean state), leaving Finv unset. */
inline bool
DeformElement(const double g[4][3], const double * const ua[4], ElementDeformation & d)
{
  for (int i = 0; i < 3; ++i)
  {
    for (int J = 0; J < 3; ++J)
    {
      d.F[i][J] =
        (i == J ? 1.0 : 0.0) + ua[0][i] * g[0][J] + ua[1][i] * g[1][J] + ua[2][i] * g[2][J] + ua[3][i] * g[3][J];
    }
  }
  const double(&F)[3][3] = d.F;
  const double c00 = F[1][1] * F[2][2] - F[1][2] * F[2][1];
  const double c01 = F[1][2] * F[2][0] - F[1][0] * F[2][2];
  const double c02 = F[1][0] * F[2][1] - F[1][1] * F[2][0];
  d.J = F[0][0] * c00 + F[0][1] * c01 + F[0][2] * c02;
  if (!(d.J > 0.0))
  {
    return false;
  }
  const double inv = 1.0 / d.J;
  d.Finv[0][0] = c00 * inv;
  d.Finv[1][0] = c01 * inv;
  d.Finv[2][0] = c02 * inv;
  d.Finv[0][1] = (F[0][2] * F[2][1] - F[0][1] * F[2][2]) * inv;
  d.Finv[1][1] = (F[0][0] * F[2][2] - F[0][2] * F[2][0]) * inv;
  d.Finv[2][1] = (F[0][1] * F[2][0] - F[0][0] * F[2][1]) * inv;
  d.Finv[0][2] = (F[0][1] * F[1][2] - F[0][2] * F[1][1]) * inv;
  d.Finv[1][2] = (F[0][2] * F[1][0] - F[0][0] * F[1][2]) * inv;
  d.Finv[2][2] = (F[0][0] * F[1][1] - F[0][1] * F[1][0]) * inv;
  return true;
}

/** W(F) = mu/2 (I1 - 3) - mu ln J + lambda/2 (ln J)^2 [kPa]; infinite for J <= 0. */
inline double
StoredEnergyDensity(const ElementDeformation & d, double mu, double lambda)
{
  if (!(d.J > 0.0))
  {
    return std::numeric_limits<double>::infinity();
  }
  double I1 = 0.0;
  for (int i = 0; i < 3; ++i)
  {
    for (int J = 0; J < 3; ++J)
    {
      I1 += d.F[i][J] * d.F[i][J];
    }
  }
  const double lnJ = std::log(d.J);
  return 0.5 * mu * (I1 - 3.0) - mu * lnJ + 0.5 * lambda * lnJ * lnJ;
}

/** P = mu (F - F^{-T}) + lambda ln J F^{-T} [kPa]. */
inline void
FirstPiolaStress(const ElementDeformation & d, double mu, double lambda, double P[3][3])
{
  const double c = lambda * std::log(d.J) - mu;
  for (int i = 0; i < 3; ++i)
  {
    for (int J = 0; J < 3; ++J)
    {
      P[i][J] = mu * d.F[i][J] + c * d.Finv[J][i];
    }
  }
}

/** The element's internal forces f_a = V P g_a [mN], 3 per node. */
inline void
ElementForces(const ElementDeformation & d, const double g[4][3], double V, double mu, double lambda, double f[4][3])
{
  double P[3][3];
  FirstPiolaStress(d, mu, lambda, P);
  for (int a = 0; a < 4; ++a)
  {
    for (int i = 0; i < 3; ++i)
    {
      f[a][i] = V * (P[i][0] * g[a][0] + P[i][1] * g[a][1] + P[i][2] * g[a][2]);
    }
  }
}

/** The element tangent K[3a+i][3b+k] = V [mu delta_ik g_a.g_b + (mu - lambda ln J) q_b,i q_a,k + lambda q_a,i q_b,k]
 * with q_a = F^{-T} g_a [mN/mm]. */
inline void
ElementTangent(const ElementDeformation & d, const double g[4][3], double V, double mu, double lambda, double K[12][12])
{
  double q[4][3];
  for (int a = 0; a < 4; ++a)
  {
    for (int i = 0; i < 3; ++i)
    {
      q[a][i] = d.Finv[0][i] * g[a][0] + d.Finv[1][i] * g[a][1] + d.Finv[2][i] * g[a][2];
    }
  }
  const double geometric = mu - lambda * std::log(d.J);
  for (int a = 0; a < 4; ++a)
  {
    for (int b = 0; b < 4; ++b)
    {
      const double gab = g[a][0] * g[b][0] + g[a][1] * g[b][1] + g[a][2] * g[b][2];
      for (int i = 0; i < 3; ++i)
      {
        for (int k = 0; k < 3; ++k)
        {
          K[3 * a + i][3 * b + k] =
            V * ((i == k ? mu * gab : 0.0) + geometric * q[b][i] * q[a][k] + lambda * q[a][i] * q[b][k]);
        }
      }
    }
  }
}

} // namespace fem
} // namespace bmr

#endif
