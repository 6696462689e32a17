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
#ifndef bmrLandmarkTerm_h
#define bmrLandmarkTerm_h

#include "bmrDataTerm.h"

#include <array>

namespace bmr {

/** A marker of the landmark term: its position in the moving (planning) anatomy and its target in the fixed
 * (treatment) anatomy [mm, LPS], with a weight [1]. */
struct BiomechanicalRegistration_EXPORT LandmarkTarget
{
  std::string           name;
  std::array<double, 3> moving{ { 0, 0, 0 } };
  std::array<double, 3> target{ { 0, 0, 0 } };
  double                weight{ 1.0 };
};

/** Where a point lies in a mesh: its element and its four barycentric coordinates (shape functions). */
struct BiomechanicalRegistration_EXPORT MeshLocation
{
  std::size_t           element{ 0 };
  std::array<double, 4> shape{ { 0, 0, 0, 0 } };
};

/** The element of \a mesh containing \a point [mm] and its barycentric coordinates; false when no element
 * contains it (to 1e-9 in the coordinates). The first containing element in element order, so the result is
 * deterministic for a point on a shared face. */
BiomechanicalRegistration_EXPORT bool
LocateInMesh(const TetrahedralMesh & mesh, const std::array<double, 3> & point, MeshLocation & location);

/** \brief The landmark term of dissertation chapter 4: implanted markers that must land on their tracked
 * positions.
 *
 * Marker k lies at X_k in the moving mesh, inside element e_k with barycentric coordinates N_i (so markers
 * need not be nodes); the deformed model carries it to \f$ \hat x_k = X_k + \sum_i N_i(X_k)\, u_{n_i} \f$.
 * \f[ \Phi_L(u) = \tfrac12 \sum_k w_k\, |\hat x_k - T_k|^2, \qquad
 *     \partial\Phi_L/\partial u_{n_i} = w_k N_i (\hat x_k - T_k), \f]
 * residuals \f$ r_{k,c} = \sqrt{w_k}\,(\hat x_k - T_k)_c \f$ [mm], three per marker. A weight of 0 leaves a
 * marker out of the fit but in the statistics (leave-one-out prediction). Usable alone or beside the
 * surface-distance term in one bmr::EstimationObjective.
 * \ingroup BiomechanicalRegistration BiomechanicalRegistrationEstimation
 */
class BiomechanicalRegistration_EXPORT LandmarkTerm : public DataTerm
{
public:
  /** Throws naming the marker when a moving position lies outside the mesh, a coordinate or weight is not
   * finite, a weight is negative, or every weight is 0. \a mesh must outlive the term. */
  LandmarkTerm(const TetrahedralMesh & mesh, std::vector<LandmarkTarget> markers);

  double
  Evaluate(const std::vector<double> & u, std::vector<double> * gradient) const override;
  void
  EvaluateResiduals(const std::vector<double> & u, std::vector<double> & r, ResidualJacobian * jacobian) const override;
  /** The nodes of the elements holding the markers. */
  std::optional<std::vector<std::int32_t>>
  GetObservedNodes() const override;
  /** One group, "markers": count, RMS, maximum and mean of the distances |x̂_k - T_k| [mm] of every marker
   * (weighted 0 included). */
  std::vector<ResidualStatistics>
  ComputeStatistics(const std::vector<double> & u) const override;
  /** The nodes of each marker's element moved by the marker's offset T_k - X_k (the mean where elements share
   * nodes); held nodes stay put. */
  std::vector<double>
  MatchDisplacement(const std::vector<char> & held) const override;

  /** The deformed position x̂_k [mm] of every marker for the nodal displacement \a u [mm] (3N). */
  std::vector<std::array<double, 3>>
  DeformedPositions(const std::vector<double> & u) const;
  const std::vector<LandmarkTarget> &
  GetMarkers() const
  {
    return m_Markers;
  }
  const std::vector<MeshLocation> &
  GetLocations() const
  {
    return m_Locations;
  }

private:
  const TetrahedralMesh &     m_Mesh;
  std::vector<LandmarkTarget> m_Markers;
  std::vector<MeshLocation>   m_Locations;
};

} // namespace bmr

#endif
