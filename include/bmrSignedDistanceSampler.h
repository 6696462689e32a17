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
#ifndef bmrSignedDistanceSampler_h
#define bmrSignedDistanceSampler_h

#include "bmrGridGeometry.h"

#include <vector>

namespace bmr {

/** \brief A sampled signed distance map [mm] evaluated with its exact gradient.
 *
 * The samples phi_i (negative inside the organ, positive outside, physical mm,
 * as itk::SignedMaurerDistanceMapImageFilter makes them) are the coefficients of
 * the uniform cubic B-spline
 * \f[ \phi(x) = \sum_{i} \phi_i\, \beta^3(\xi_0 - i_0)\, \beta^3(\xi_1 - i_1)\, \beta^3(\xi_2 - i_2),
 *     \qquad \xi = M^{-1}(x - o),\ M = D\,\mathrm{diag}(s), \f]
 * and its gradient is \f$ \nabla\phi(x) = M^{-T} \nabla_\xi \phi \f$.
 * This quasi-interpolant is C2 and reproduces affine functions exactly, so the
 * distance to a flat surface is unbiased while the staircase of a voxelized
 * label is smoothed; unlike trilinear interpolation its gradient is continuous
 * and is the exact derivative of the value, which is what the adjoint gradient
 * of the registration objective and its finite-difference check need.
 * Outside the grid the continuous index is clamped to the border (value of the
 * border, zero gradient along the clamped axes).
 * \ingroup BiomechanicalRegistration BiomechanicalRegistrationEstimation
 */
class BiomechanicalRegistration_EXPORT SignedDistanceSampler
{
public:
  /** \a values holds one sample per voxel of \a grid (index 0 fastest); they
   * must be finite. Throws itk::ExceptionObject naming \a what otherwise. */
  SignedDistanceSampler(const GridGeometry & grid, std::vector<float> values, const char * what);

  /** phi at the physical point \a x [mm]; the gradient goes to \a gradient when not null. */
  double
  Evaluate(const double x[3], double gradient[3]) const;

  const GridGeometry &
  GetGrid() const
  {
    return m_Grid;
  }

private:
  GridGeometry          m_Grid;
  std::vector<float>    m_Values;
  std::array<double, 9> m_PhysicalToIndex; ///< row-major M^{-1}
};

} // namespace bmr

#endif
