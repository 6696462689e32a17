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
#ifndef bmrCompressionBarrier_h
#define bmrCompressionBarrier_h

#include "BiomechanicalRegistrationExport.h"
#include "bmrTetrahedralMesh.h"

#include <vector>

namespace bmr {

/** \brief A barrier against crushed elements in the estimation objective of a nonlinear model.
 *
 * A neo-Hookean state has J = det F > 0 in every element, so wall motions that squeeze tissue between two
 * prescribed walls (or a wall and the bone) to nothing have no state: the objective is infeasible there, and
 * an optimizer whose best fit of noisy, voxelized walls lies at that edge keeps stepping over it. The barrier
 * makes the edge costly before it is reached, so the optimum moves inside:
 * \f[ \Phi_b(u) = \frac{w}{2} \sum_e r_e^2, \qquad r_e = \ell_e\, \psi(J_e), \qquad \ell_e = V_e^{1/3}, \f]
 * \f[ \psi(J) = \begin{cases} 0 & J \ge J_0 \\ \ln(J/J_0) & J_1 \le J < J_0 \\
 *     \ln(J_1/J_0) + (J - J_1)/J_1 & J < J_1 \end{cases}, \qquad J_1 = J_0/16, \f]
 * C¹ in J (the tangent continuation below J_1 keeps it finite for elements whose four nodes are prescribed,
 * which no state can save), with \f$ \partial r_e/\partial u_a = \ell_e\, \psi'(J_e)\, \mathrm{cof}(F_e)\, g_a \f$
 * (cof F = J F^{-T}, g_a the gradient of node a's barycentric coordinate). r_e is in mm, like the
 * surface distances: with w = 0.1 an element at J = J_0/e costs as much as one surface node 0.3 element
 * sizes off its surface, and the cost grows without bound towards J = 0. It vanishes unless an element is
 * compressed below J_0 = 0.25 (a quarter of its volume), so that a fit with no crushed element is unchanged.
 * The weight trades the inner solve's iterations against how close to flat an element may be pushed: on the
 * 37k-tetrahedron pelvis, w = 1 took 70-240 L-BFGS iterations per inner solve, w = 0.1 25-104, and the
 * estimate moved by 2.7 % (40.3 and 41.4 kPa); J_0 = 0.1 or 0.05 took more (a steeper wall near J = 0).
 * Units: u in mm, Phi_b in mm^2.
 * \ingroup BiomechanicalRegistration BiomechanicalRegistrationEstimation
 */
class BiomechanicalRegistration_EXPORT CompressionBarrier
{
public:
  /** Throws when \a threshold is not in (0, 1) or \a weight is negative or not finite. \a mesh must outlive it. */
  CompressionBarrier(const TetrahedralMesh & mesh, double threshold = 0.25, double weight = 0.1);

  /** Phi_b(u) [mm^2]; adds \f$\partial\Phi_b/\partial u\f$ (3N) to \a gradient when not null. */
  double
  Evaluate(const std::vector<double> & u, std::vector<double> * gradient) const;
  /** Elements with J below the threshold in the state \a u. */
  std::size_t
  CountCompressed(const std::vector<double> & u) const;
  double
  GetThreshold() const
  {
    return m_Threshold;
  }
  double
  GetWeight() const
  {
    return m_Weight;
  }

private:
  const TetrahedralMesh & m_Mesh;
  double                  m_Threshold;
  double                  m_Weight;
  std::vector<double>     m_Gradients; ///< 12 per element: g_a of the four nodes
  std::vector<double>     m_Lengths;   ///< V_e^{1/3} [mm]
};

} // namespace bmr

#endif
