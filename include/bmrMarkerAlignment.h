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
#ifndef bmrMarkerAlignment_h
#define bmrMarkerAlignment_h

#include "BiomechanicalRegistrationExport.h"

#include <array>
#include <vector>

namespace bmr {

using Point3 = std::array<double, 3>;

/** x ↦ R x + t [mm], R a rotation (row-major 3 x 3). */
struct BiomechanicalRegistration_EXPORT RigidTransform
{
  std::array<double, 9> rotation{ { 1, 0, 0, 0, 1, 0, 0, 0, 1 } };
  Point3                translation{ { 0, 0, 0 } };

  Point3
  Apply(const Point3 & x) const;
  /** R^T (y - t). */
  Point3
  ApplyInverse(const Point3 & y) const;
};

/** \brief The least-squares rigid motion carrying the markers \a from onto \a to (Kabsch / Umeyama without
 * scale): the clinical standard of marker-based set-up.
 *
 * \f$ \min_{R,t} \sum_k |R a_k + t - b_k|^2 \f$: t from the centroids, R = V diag(1, 1, det(VU^T)) U^T from the
 * SVD \f$ U \Sigma V^T \f$ of \f$ \sum_k (a_k - \bar a)(b_k - \bar b)^T \f$ (no reflection). When the markers do
 * not fix a rotation (two markers, or collinear ones) R is the smallest rotation turning the line of \a from
 * into that of \a to; one marker gives a translation. Throws when the sets differ in size, are empty or hold
 * a non-finite coordinate.
 * \ingroup BiomechanicalRegistration BiomechanicalRegistrationEvaluation
 */
BiomechanicalRegistration_EXPORT RigidTransform
FitRigidTransform(const std::vector<Point3> & from, const std::vector<Point3> & to);

/** \brief The 3-D thin-plate spline through marker pairs: the smooth interpolating warp of the markers.
 *
 * \f[ y(x) = x + a_0 + A (x - c) + \sum_k w_k\, |x - a_k|, \f]
 * U(r) = r being the biharmonic kernel in three dimensions (the bending energy's Green's function), c the
 * markers' centroid; w and the affine part solve \f$ [K\ P;\ P^T\ 0] [w; a] = [b - a; 0] \f$ with
 * \f$K_{jk} = |a_j - a_k|\f$, \f$P_k = (1, a_k - c)\f$. With fewer than four markers, or coplanar ones, the
 * affine part is not determined by the markers; the minimum-norm solution (complete orthogonal
 * decomposition) then leaves the undetermined directions unstretched. Exact at the markers.
 * \ingroup BiomechanicalRegistration BiomechanicalRegistrationEvaluation
 */
class BiomechanicalRegistration_EXPORT ThinPlateSpline
{
public:
  /** Throws as FitRigidTransform(), and when two markers of \a from coincide. */
  ThinPlateSpline(const std::vector<Point3> & from, const std::vector<Point3> & to);
  Point3
  Apply(const Point3 & x) const;

private:
  std::vector<Point3>    m_Centers;
  std::vector<Point3>    m_Weights;
  Point3                 m_Centroid{ { 0, 0, 0 } };
  std::array<double, 12> m_Affine{}; ///< per output coordinate c: a_0, then the three gradients
};

} // namespace bmr

#endif
