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
#ifndef bmrTwoLayerSphere_h
#define bmrTwoLayerSphere_h

#include <array>
#include <cmath>

namespace bmr {

/** \brief Closed-form radial displacement of a two-layer elastic sphere under external pressure.
 *
 * A solid core (r < a; E1, nu1) bonded to a shell (a < r < b; E2, nu2), loaded by
 * a uniform pressure p [kPa] on r = b. Radially symmetric linear elasticity
 * (Lamé's problem; e.g. Timoshenko & Goodier, Theory of Elasticity, 3rd ed.,
 * section 141, "Spherical container under internal or external uniform pressure",
 * extended to a bonded core) gives u1(r) = A1 r and u2(r) = A2 r + B2 / r^2 with
 * sigma_rr = 3 K A - 4 mu B / r^3 (K bulk, mu shear modulus) and the conditions
 * u1(a) = u2(a), sigma_rr1(a) = sigma_rr2(a), sigma_rr2(b) = -p.
 * Header-only: used by the tests and the benchmarks.
 * \ingroup BiomechanicalRegistration
 */
class TwoLayerSphereSolution
{
public:
  TwoLayerSphereSolution(double a, double b, double E1, double nu1, double E2, double nu2, double p)
    : m_A(a)
  {
    const double K1 = E1 / (3.0 * (1.0 - 2.0 * nu1));
    const double K2 = E2 / (3.0 * (1.0 - 2.0 * nu2));
    const double mu2 = E2 / (2.0 * (1.0 + nu2));
    // Unknowns A1, A2, B2. From continuity: A1 = A2 + B2 / a^3.
    // Traction at a: 3 K1 (A2 + B2/a^3) = 3 K2 A2 - 4 mu2 B2 / a^3
    //   => B2 = 3 (K2 - K1) A2 a^3 / (3 K1 + 4 mu2)
    const double c = 3.0 * (K2 - K1) / (3.0 * K1 + 4.0 * mu2); // B2 = c A2 a^3
    // Traction at b: 3 K2 A2 - 4 mu2 c A2 a^3 / b^3 = -p
    m_A2 = -p / (3.0 * K2 - 4.0 * mu2 * c * a * a * a / (b * b * b));
    m_B2 = c * m_A2 * a * a * a;
    m_A1 = m_A2 + m_B2 / (a * a * a);
  }

  /** Radial displacement [mm] at radius r [mm]; \a inCore selects the formula
   * (lets a discretized interface be evaluated on its own side). */
  double
  RadialDisplacement(double r, bool inCore) const
  {
    return inCore ? m_A1 * r : m_A2 * r + m_B2 / (r * r);
  }
  double
  RadialDisplacement(double r) const
  {
    return RadialDisplacement(r, r < m_A);
  }

  /** Displacement vector [mm] at a point relative to the center. */
  std::array<double, 3>
  Displacement(const std::array<double, 3> & x, bool inCore) const
  {
    const double r = std::sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]);
    if (r == 0.0)
    {
      return { { 0.0, 0.0, 0.0 } };
    }
    const double s = RadialDisplacement(r, inCore) / r;
    return { { s * x[0], s * x[1], s * x[2] } };
  }

private:
  double m_A;
  double m_A1{ 0 }, m_A2{ 0 }, m_B2{ 0 };
};

} // namespace bmr

#endif
