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
#ifndef bmrOrganSurfaceForces_h
#define bmrOrganSurfaceForces_h

#include "bmrLoadParameterization.h"

namespace bmr {

/** \brief Unknown loads as nodal forces on the surface of an organ inside tissue, in a static box
 * (dissertation §4.3): the load parameterization of marker-driven deformation.
 *
 * The surface nodes S of the organ (its interface with the surrounding tissue) carry forces
 * \f[ f_S = \kappa\, W L^{-T} q, \qquad R(q) = \tfrac{\alpha}{2} |q|^2, \f]
 * with W L^{-T} the orthonormalized Gaussian blend of bmr::WallBasis over control points picked every
 * \c controlSpacing mm on the surface (three parameters per control point), and every held node (the box's
 * faces, bone) at its prescribed value. Because the columns of W L^{-T} are orthonormal,
 * \f$ |q| = |f_S| / \kappa \f$: the prior asks for the smallest surface loads that explain the data, which
 * prefers loads spread over the surface to point forces and the least deformation of the tissue. Three
 * markers give 9 equations for hundreds of nodal forces; the Gaussian basis removes wiggles shorter than
 * the spacing and the prior picks one solution among the rest.
 *
 * The scale \f$\kappa\f$ [mN per unit q] makes q read as millimetres: a rigid inclusion of radius a in a
 * medium of shear modulus \f$\mu\f$ needs a total force of about \f$ 10\,\mu a \f$ per millimetre of
 * translation (Kelvin's solution for a sphere), spread over the |S| nodes as \f$ |f_S| = F/\sqrt{|S|} \f$, so
 * \f$ \kappa = 10\,\mu a / \sqrt{|S|} \f$ (SetForceScale(); the pipeline computes it from the organ's surface
 * area A, \f$ a = \sqrt{A / 4\pi} \f$, and the surrounding tissue's modulus). With q in mm, alpha is
 * dimensionless and the same default serves any organ size and stiffness.
 * Affine in q; forces only (no prescribed value depends on q).
 * \ingroup BiomechanicalRegistration BiomechanicalRegistrationEstimation
 */
class BiomechanicalRegistration_EXPORT OrganSurfaceForces : public LoadParameterization
{
public:
  /** \a heldNodes with 3 values each [mm]; \a surfaceNodes: the organ surface (held ones are dropped).
   * Throws when no surface node is free or the shapes disagree. \a mesh must outlive the object. */
  OrganSurfaceForces(const TetrahedralMesh &           mesh,
                     const std::vector<std::int32_t> & heldNodes,
                     const std::vector<double> &       heldValues,
                     const std::vector<std::int32_t> & surfaceNodes,
                     double                            controlSpacing);
  ~OrganSurfaceForces() override;

  /** kappa [mN per unit parameter], > 0 (default 1). */
  void
  SetForceScale(double kappa);
  /** alpha [1] of the prior alpha/2 |q|^2, finite and >= 0 (default 0). */
  void
  SetRegularization(double alpha);
  /** The free surface nodes that carry forces, sorted. */
  const std::vector<std::int32_t> &
  GetSurfaceNodes() const;

  std::size_t
  GetNumberOfParameters() const override;
  const std::vector<std::int32_t> &
  GetConstrainedNodes() const override;
  const std::vector<std::int32_t> &
  GetHeldNodes() const override;
  BoundaryLoad
  Apply(const std::vector<double> & p) const override;
  bool
  IsAffine() const override
  {
    return true;
  }
  BoundaryLoad
  Direction(std::size_t j) const override;
  std::vector<double>
  PullBackGradient(const std::vector<double> & p,
                   const std::vector<double> & prescribedSensitivity,
                   const std::vector<double> & forceSensitivity) const override;
  double
  EvaluatePrior(const std::vector<double> & p) const override;
  /** Zero: forces cannot be read off a displacement without the model; the linear solve starts from rest. */
  std::vector<double>
  FitDisplacement(const std::vector<double> & u) const override;
  /** The reactions f_int at the held nodes (what the box and the bone exert) [mN]. */
  std::vector<double>
  BoundaryForces(const std::vector<double> & internal) const override;

private:
  struct Impl;
  std::unique_ptr<Impl> m_Impl;
};

} // namespace bmr

#endif
