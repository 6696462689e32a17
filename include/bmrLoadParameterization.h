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
#ifndef bmrLoadParameterization_h
#define bmrLoadParameterization_h

#include "bmrTetrahedralMesh.h"

#include <iosfwd>
#include <memory>
#include <string>

namespace bmr {

struct WallMotionBasis;

/** Boundary conditions of one forward solve: nodal forces [mN] (3N, or empty for none) and the
 * prescribed displacements [mm] (3N, read on the constrained dofs only). */
struct BiomechanicalRegistration_EXPORT BoundaryLoad
{
  std::vector<double> forces;
  std::vector<double> prescribed;
};

/** \brief Maps the unknown load parameters p to the boundary conditions of the forward model, and
 * owns the choice between prescribing displacements (Dirichlet) and applying forces.
 *
 * The constrained nodes (GetConstrainedNodes()) do not depend on p, so the forward model's
 * factorization is reused over every p. The estimator minimizes
 * \f$ \Phi(u(p)) + R(p) \f$ with the parameterization's prior R (EvaluatePrior()); the chain rule
 * through the boundary conditions is PullBackGradient().
 * \ingroup BiomechanicalRegistration BiomechanicalRegistrationEstimation
 */
class BiomechanicalRegistration_EXPORT LoadParameterization
{
public:
  virtual ~LoadParameterization() = default;

  virtual std::size_t
  GetNumberOfParameters() const = 0;
  /** Every node whose displacement is prescribed, sorted (held nodes and load-controlled ones). */
  virtual const std::vector<std::int32_t> &
  GetConstrainedNodes() const = 0;
  /** Nodes held at a prescribed value that does not depend on p (bone walls: u = 0). */
  virtual const std::vector<std::int32_t> &
  GetHeldNodes() const = 0;
  /** The boundary conditions for parameters \a p; throws when p has the wrong size. */
  virtual BoundaryLoad
  Apply(const std::vector<double> & p) const = 0;
  /** True when Apply() is affine in p; then Direction() gives its constant derivative. */
  virtual bool
  IsAffine() const = 0;
  /** Apply(p + e_j) - Apply(p) for an affine parameterization (forces empty when they do not depend on p). */
  virtual BoundaryLoad
  Direction(std::size_t j) const = 0;
  /** \f$\partial\Phi/\partial p\f$ from the sensitivities of Phi to the prescribed displacements (3N,
   * constrained dofs; 0 at the held nodes, whose values do not depend on p) and to the forces (3N, free dofs), plus
   * the prior's gradient. */
  virtual std::vector<double>
  PullBackGradient(const std::vector<double> & p,
                   const std::vector<double> & prescribedSensitivity,
                   const std::vector<double> & forceSensitivity) const = 0;
  /** Whether PullBackGradient() reads \a forceSensitivity (the adjoint state), at any free dof: true (the default)
   * unless p sets only prescribed displacements. */
  virtual bool
  ReadsForceSensitivity() const
  {
    return true;
  }
  /** Whether p is a reduced basis, with few parameters for the boundary's nodes: the estimator then solves its inner
   * problem by Levenberg-Marquardt (one solve per parameter), otherwise by L-BFGS. False by default. */
  virtual bool
  IsReducedBasis() const
  {
    return false;
  }
  /** The prior R(p) [mm^2] added to the data terms (0 when there is none). */
  virtual double
  EvaluatePrior(const std::vector<double> & p) const = 0;
  /** Parameters whose boundary conditions best reproduce the nodal displacement \a u [mm] (3N) at the
   * load-controlled nodes: the initial guess from a displacement such as surface matching's. */
  virtual std::vector<double>
  FitDisplacement(const std::vector<double> & u) const = 0;
  /** The loads [mN] (3N) the boundary exerts on the tissue in the state with internal forces \a internal
   * (3N): f_int - f at the load-controlled nodes, zero elsewhere. */
  virtual std::vector<double>
  BoundaryForces(const std::vector<double> & internal) const = 0;
};

/** The loads [mN] (3N) a boundary exerts on the tissue at its \a nodes in the state with internal forces \a internal
 * (3N): f_int - f there (\a forces 3N, or empty for none), zero elsewhere. */
BiomechanicalRegistration_EXPORT std::vector<double>
                                 ReactionForcesAt(const std::vector<std::int32_t> & nodes,
                                                  const std::vector<double> &       internal,
                                                  const std::vector<double> &       forces);

/** The ridge prior alpha/2 |p|^2 of WallLoads and OrganSurfaceForces [mm^2 for p in mm]. */
inline double
RidgePrior(double alpha, const std::vector<double> & p)
{
  double pp = 0.0;
  for (double x : p)
  {
    pp += x * x;
  }
  return 0.5 * alpha * pp;
}

/** How the loaded walls may move (WallLoads). */
enum class WallMotionEnum : std::uint8_t
{
  /** Every wall node moves along its wall's normal: one scalar per control point. */
  AlongNormals,
  /** Every wall node moves in any direction: three parameters per control point. */
  Free,
  /** The walls are not prescribed: each control point carries an unknown traction along the wall's normal (a
   * lumen pressure that may vary along the wall), and the walls move as the tissue lets them. */
  NormalTraction,
  /** NormalTraction with one unknown per wall, uniform along it: the pressure of a lumen filled with fluid at rest
   * (urine, gas), whose hydrostatic variation over the organ (about 0.01 kPa per cm) is negligible. The control
   * spacing and the prior do not apply: there is no near-null direction to pick from, and the ridge on the
   * orthonormal parameter, sqrt(N) s for a wall of N nodes, would pull every pressure toward zero (on one pelvis pair
   * alpha = 0.01 read the prostate 7 % softer than none). */
  UniformPressure
};
BiomechanicalRegistration_EXPORT std::ostream &
                                 operator<<(std::ostream & os, WallMotionEnum value);

/** The settings of WallLoads in an estimation; the defaults are FEMElasticityOptimizer's and biomechreg's. */
struct BiomechanicalRegistration_EXPORT WallLoadSettings
{
  double controlSpacing{ 0.0 }; ///< mm; 0: one control point per wall node (not used by UniformPressure)
  /** alpha of the prior alpha/2 |p|^2: small, it picks the least-displacement optimum along the walls'
   * near-null directions so that Phi*(E) is smooth (docs/history/benchmarks.md, "What the walls do to the estimate").
   */
  double         regularization{ 0.01 };
  WallMotionEnum motion{ WallMotionEnum::AlongNormals };
  /** A basis of wall motion learned from examples (TrainedWallLoads), or null (default): the walls move in it instead
   * of along their normals; controlSpacing, regularization and motion (along the normals or free) then do not apply.
   */
  std::shared_ptr<const WallMotionBasis> trainedBasis;
  std::size_t                            basisModes{ 0 }; ///< the trained basis's modes used (0: all)
  double basisPriorWeight{ 0.25 };                        ///< w of the trained basis's prior [mm^2] (TrainedWallLoads)

  /** Fewer load parameters than wall nodes (a smooth basis, one pressure per wall, or a trained basis): the
   * estimator then solves the inner problem by Levenberg-Marquardt, one solve per parameter. */
  bool
  ReducedBasis() const
  {
    return controlSpacing > 0.0 || motion == WallMotionEnum::UniformPressure || trainedBasis != nullptr;
  }
  /** Throws itk::InvalidArgumentError (bmr::FailInput) for a negative or non-finite control spacing or
   * regularization; with a trained basis, for more modes than it has, a prior weight not positive, a control spacing
   * or tractions (the basis prescribes the walls' motion). */
  void
  Validate() const;
};

/** A loaded wall of WallLoads: its mesh nodes, and the boundary-face label whose faces give its normals. */
struct BiomechanicalRegistration_EXPORT LoadedWall
{
  std::string               name;
  std::vector<std::int32_t> nodes;
  std::int32_t              faceLabel{ 0 };
};

/** \brief Unknown loads on the loaded walls (the control nodes), as the wall displacements they cause or as
 * normal tractions, dissertation ch. 3.
 *
 * For a given E the map between the wall displacement d and the nodal forces F on the walls is the
 * (invertible) Schur complement, F = S(E) d, so \f$\min_F \Phi(E,F) = \min_d \Phi(E,d)\f$: both give the
 * same envelope \f$\Phi^*(E)\f$, but in d the walls' own distance terms are diagonal and the inner
 * problem is well conditioned whatever E is. The forces F = K u - f at the control nodes [mN] are
 * BoundaryForces().
 *
 * - d = W p with \f$W\f$ the identity (one parameter per control node and direction) or the smooth
 *   Gaussian basis of bmr::WallBasis (SetControlSpacing());
 * - WallMotionEnum::AlongNormals (default): \f$ d_k = n_k (W s)_k \f$, one scalar per control point,
 *   n_k the unit wall normal at control node k: area-weighted face normals averaged over 4 mm of the same
 *   wall, which removes the tilt of the voxel staircase. The distance objective sees only the normal part
 *   of a wall's motion; left free, the tangential part shapes the stiff organ's surface and biases E;
 * - WallMotionEnum::NormalTraction: the walls are free dofs loaded by the nodal forces
 *   \f$ f_k = \kappa_k A_k n_k (W s)_k \f$ [mN], with \f$A_k\f$ the node's share of its wall's area [mm²]
 *   (a third of each adjacent face's) and \f$\kappa_k = 4\mu / a_w\f$ [kPa per unit s] for the wall w of
 *   node k, \f$a_w = \sqrt{A_w / 4\pi}\f$ its equivalent radius and \f$\mu\f$ the surrounding tissue's
 *   shear modulus (SetTractionShearModulus()): the pressure that moves the wall of a spherical cavity in an
 *   infinite medium by s mm (Lamé's solution, u = p a / 4μ), so that s reads as millimetres of wall motion
 *   and the same prior weight serves both. A lumen under pressure moves its wall this way, tangentially as
 *   well, where prescribed normal motions force the tissue to follow the normal. Only the held nodes are
 *   constrained, so some label must be held (a fixed bone, or a fixed region-of-interest boundary);
 * - WallMotionEnum::UniformPressure: one parameter per wall (W one column per wall, all of whose nodes it
 *   weighs 1; a node on two walls 1/2 each) and, in place of \f$A_k n_k\f$, the node's share of its faces' own
 *   area vectors: \f$ f_k = \kappa_w s_w \sum_{f \ni k} a_f n_f / 3 \f$, the consistent P1 load of one pressure
 *   \f$ p_w = \kappa_w s_w \f$ per lumen, whose staircase tilts cancel over the wall as a real pressure's do.
 *   A lumen filled with fluid at rest is loaded this way; a pressure that varies along the wall can instead shape
 *   the organs next to it for any modulus (docs/estimation.md);
 * - prior \f$ R(p) = \tfrac{\alpha}{2} |p|^2 \f$ (SetRegularization()): independent of E, so it does not
 *   push the moduli one way, and it picks the least-displacement optimum along the near-null directions
 *   of a wall sliding along itself.
 *
 * Held nodes (u = 0 on fixed walls, and the prescribed values of the scene's own loads) keep their
 * values; a wall node that is also held is not a control node. Forces (the scene's pressure loads) do
 * not depend on p.
 * \ingroup BiomechanicalRegistration BiomechanicalRegistrationEstimation
 */
class BiomechanicalRegistration_EXPORT WallLoads : public LoadParameterization
{
public:
  /** \a held: held nodes with 3 values each [mm]; \a forces: constant nodal forces [mN] (3N or empty).
   * Throws when a wall has no node that is not held. \a mesh must outlive the object. */
  WallLoads(const TetrahedralMesh &           mesh,
            const std::vector<std::int32_t> & heldNodes,
            const std::vector<double> &       heldValues,
            std::vector<double>               forces,
            const std::vector<LoadedWall> &   walls);
  ~WallLoads() override;

  /** Spacing [mm] of the control points of the smooth wall basis; 0 (default): every control node. Kept, but not
   * used, while the motion is UniformPressure (one control point per wall). */
  void
  SetControlSpacing(double spacing);
  /** Weight alpha [1] of the prior alpha/2 |p|^2 (default 0); finite and >= 0. Kept, but not used, while the motion
   * is UniformPressure. */
  void
  SetRegularization(double alpha);
  /** Along the normals, free, normal tractions or one pressure per wall; GetConstrainedNodes() changes with it (the
   * held nodes only for NormalTraction and UniformPressure), so set it before the forward model takes the constrained
   * nodes. Throws for those two when no node is held (nothing would keep the mesh in place). */
  void
  SetMotion(WallMotionEnum motion);
  WallMotionEnum
  GetMotion() const;
  /** mu [kPa] of the traction scale of NormalTraction and UniformPressure (default 1): the tissue around the walls. */
  void
  SetTractionShearModulus(double mu);
  /** The load-controlled wall nodes, sorted. */
  const std::vector<std::int32_t> &
  GetControlNodes() const;

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
  /** Only with NormalTraction and UniformPressure, whose p sets forces. */
  bool
  ReadsForceSensitivity() const override;
  /** A smooth basis (ControlSpacing > 0) or one pressure per wall (UniformPressure). */
  bool
  IsReducedBasis() const override;
  double
  EvaluatePrior(const std::vector<double> & p) const override;
  std::vector<double>
  FitDisplacement(const std::vector<double> & u) const override;
  std::vector<double>
  BoundaryForces(const std::vector<double> & internal) const override;

private:
  struct Impl;
  std::unique_ptr<Impl> m_Impl;
};

} // namespace bmr

#endif
