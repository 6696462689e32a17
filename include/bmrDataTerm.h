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
#ifndef bmrDataTerm_h
#define bmrDataTerm_h

#include "bmrSignedDistanceSampler.h"
#include "bmrTetrahedralMesh.h"

#include <memory>
#include <optional>
#include <string>

namespace bmr {

/** How well one group of residuals (an organ surface, a set of landmarks) is matched [mm]. */
struct BiomechanicalRegistration_EXPORT ResidualStatistics
{
  std::string name;
  std::size_t count{ 0 }; ///< residuals (surface nodes, landmarks)
  double      weight{ 1.0 };
  double      rms{ 0.0 };
  double      maximum{ 0.0 }; ///< of the absolute value
  double      mean{ 0.0 };    ///< signed: > 0 when a surface lies outside the fixed organ on average
};

/** Derivatives of residuals with respect to the nodal displacement, one sparse row per residual:
 * row k holds (dofs[i], values[i]) for i in [rowStart[k], rowStart[k+1]). */
struct BiomechanicalRegistration_EXPORT ResidualJacobian
{
  std::vector<std::size_t>  rowStart;
  std::vector<std::int32_t> dofs;
  std::vector<double>       values;
};

/** \brief A term of the estimation objective: weighted residuals of the deformed moving anatomy,
 * \f$ \Phi_d(u) = \tfrac12 |r(u)|^2 \f$, and their derivatives with respect to the nodal displacement u.
 * \ingroup BiomechanicalRegistration BiomechanicalRegistrationEstimation
 */
class BiomechanicalRegistration_EXPORT DataTerm
{
public:
  virtual ~DataTerm() = default;

  /** Phi_d(u) [mm^2]; adds \f$\partial\Phi_d/\partial u\f$ (3N) to \a gradient when not null. */
  virtual double
  Evaluate(const std::vector<double> & u, std::vector<double> * gradient) const = 0;
  /** The residuals r(u) [mm, weighted], and their rows \f$\partial r/\partial u\f$ when \a jacobian is not null. */
  virtual void
  EvaluateResiduals(const std::vector<double> & u, std::vector<double> & r, ResidualJacobian * jacobian) const = 0;
  /** Statistics of the unweighted residuals, per group. */
  virtual std::vector<ResidualStatistics>
  ComputeStatistics(const std::vector<double> & u) const = 0;
  /** A nodal displacement (3N) that moves the term's nodes towards their targets without a model, as a
   * starting point for the loads; nodes flagged in \a held stay put. */
  virtual std::vector<double>
  MatchDisplacement(const std::vector<char> & held) const = 0;
  /** The nodes whose displacement Evaluate() and EvaluateResiduals() read (ascending), or nothing when they may read
   * any node (the default). With every term's nodes known, an estimation solves for the state at these nodes alone
   * (ForwardModel::TrySolveObservedState()). */
  virtual std::optional<std::vector<std::int32_t>>
  GetObservedNodes() const
  {
    return std::nullopt;
  }
};

/** One organ surface of the objective: the mesh nodes on it, its weight and the signed distance map
 * [mm] of the same organ in the fixed label image. */
struct BiomechanicalRegistration_EXPORT ObjectiveSurface
{
  std::string                                  name;
  std::int32_t                                 label{ 0 };
  double                                       weight{ 1.0 };
  std::vector<std::int32_t>                    nodes;
  std::shared_ptr<const SignedDistanceSampler> distance;
};

/** \brief The surface-distance term of dissertation chapter 3.
 *
 * Over the nodes l of every objective surface s:
 * \f[ \Phi_d(u) = \tfrac12 \sum_s w_s \sum_{l \in s} \phi_s(x_l + u_l)^2, \qquad
 *     \partial\Phi_d/\partial u_l = w_s\, \phi_s \nabla\phi_s, \f]
 * with residuals \f$ r = \sqrt{w_s}\,\phi_s \f$ (\f$\phi\nabla\phi\f$ is the dissertation's vector
 * distance). MatchDisplacement() is the surface matching of dissertation 5.3.1.1: every node is pulled
 * along \f$-\phi\nabla\phi\f$ while springs to its neighbors on the same surface keep the displacement
 * smooth, \f$ v \leftarrow v - \alpha \phi\nabla\phi + \beta(\bar v_{nb} - v) \f$, alpha = 0.5,
 * beta = 0.25, for SetMatchingIterations() steps (default 200).
 * \ingroup BiomechanicalRegistration BiomechanicalRegistrationEstimation
 */
class BiomechanicalRegistration_EXPORT SurfaceDistanceTerm : public DataTerm
{
public:
  /** Throws when \a surfaces is empty. \a mesh must outlive the term. */
  SurfaceDistanceTerm(const TetrahedralMesh & mesh, std::vector<ObjectiveSurface> surfaces);

  double
  Evaluate(const std::vector<double> & u, std::vector<double> * gradient) const override;
  void
  EvaluateResiduals(const std::vector<double> & u, std::vector<double> & r, ResidualJacobian * jacobian) const override;
  std::vector<ResidualStatistics>
  ComputeStatistics(const std::vector<double> & u) const override;
  std::vector<double>
  MatchDisplacement(const std::vector<char> & held) const override;
  /** The nodes of every surface. */
  std::optional<std::vector<std::int32_t>>
  GetObservedNodes() const override;
  void
  SetMatchingIterations(unsigned int iterations)
  {
    m_MatchingIterations = iterations;
  }
  const std::vector<ObjectiveSurface> &
  GetSurfaces() const
  {
    return m_Surfaces;
  }

private:
  const TetrahedralMesh &       m_Mesh;
  std::vector<ObjectiveSurface> m_Surfaces;
  unsigned int                  m_MatchingIterations{ 200 };
};

} // namespace bmr

#endif
