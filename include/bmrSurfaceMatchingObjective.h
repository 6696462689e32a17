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
#ifndef bmrSurfaceMatchingObjective_h
#define bmrSurfaceMatchingObjective_h

#include "bmrLinearElasticModel.h"
#include "bmrScene.h"
#include "bmrSignedDistanceSampler.h"

#include <memory>

namespace bmr {

/** One organ surface of the objective: the mesh nodes on it, its weight and the
 * signed distance map [mm] of the same organ in the fixed label image. */
struct BiomechanicalRegistration_EXPORT ObjectiveSurface
{
  std::string                                  name;
  std::int32_t                                 label{ 0 };
  double                                       weight{ 1.0 };
  std::vector<std::int32_t>                    nodes;
  std::shared_ptr<const SignedDistanceSampler> distance;
};

/** Distance of the deformed surface nodes to the fixed organ surface [mm]. */
struct BiomechanicalRegistration_EXPORT SurfaceDistanceStatistics
{
  std::string name;
  std::size_t nodes{ 0 };
  double      rms{ 0.0 };
  double      maximum{ 0.0 };
  double      mean{ 0.0 }; ///< signed: > 0 when the nodes lie outside the fixed organ on average
};

/** The objective surfaces of \a scene on \a mesh: for a simulated organ the nodes
 * of its label surface, for a hollow, fixed or outside label the nodes of its
 * wall. \a maps gives the distance map of every objective label (by value).
 * Throws when a map is missing or a surface has no node. */
BiomechanicalRegistration_EXPORT std::vector<ObjectiveSurface>
                                 SceneObjectiveSurfaces(const Scene &                                                                scene,
                                                        const TetrahedralMesh &                                                      mesh,
                                                        const std::map<std::int32_t, std::shared_ptr<const SignedDistanceSampler>> & maps);

/** Result of SurfaceMatchingObjective::SolveWalls(): the inner optimum at fixed E. */
struct BiomechanicalRegistration_EXPORT WallSolution
{
  std::vector<double> parameters;         ///< p [mm]
  double              value{ 0.0 };       ///< Phi* [mm^2]
  std::vector<double> gradient;           ///< dPhi/dp at the optimum [mm]
  std::vector<double> logModulusGradient; ///< dPhi*/dlog E (envelope theorem) [mm^2]
  unsigned int        iterations{ 0 };
  std::string         stop;
};

/** \brief The registration objective of dissertation chapter 3 and its adjoint gradients.
 *
 * Forward model: linear elasticity K(E) u = f with u = 0 on the walls of fixed
 * labels and u = d on the walls of the scene's force surfaces (the "control
 * nodes"). The unknown boundary loads are represented by these wall
 * displacements d: for a given E the map between d and the nodal forces F on
 * the walls is the (invertible) Schur complement, F = S(E) d, so
 * \f$\min_F \Phi(E,F) = \min_d \Phi(E,d)\f$ and both give the same envelope
 * \f$\Phi^*(E)\f$, but in d the walls' own distance terms are diagonal and the
 * inner problem is well conditioned whatever E is. The forces F = (K u - f) at
 * the control nodes [mN] are reported with ComputeBoundaryForces().
 *
 * Optionally the wall displacement is spanned by a smooth reduced basis,
 * d = W p (SetWallControlSpacing(), bmr::WallBasis).
 *
 * Objective, over the nodes l of every objective surface s:
 * \f[ \Phi(E, d) = \tfrac12 \sum_s w_s \sum_{l \in s} \phi_s(x_l + u_l)^2 \f]
 * with \f$g = \partial\Phi/\partial u\f$, \f$g_l = w_s \phi_s \nabla\phi_s\f$.
 * Adjoint (one solve with the cached factorisation): \f$K_{ff}\lambda_f = g_f\f$,
 * \f$\lambda\f$ = 0 on constrained dofs, then
 * \f[ \partial\Phi/\partial d = g_c - (K\lambda)_c, \qquad
 *     \partial\Phi/\partial \log E_m = -E_m\, \lambda^T \hat K_m u. \f]
 *
 * Units: d, u in mm; E in kPa; Phi in mm^2.
 * \ingroup BiomechanicalRegistration
 */
class BiomechanicalRegistration_EXPORT SurfaceMatchingObjective
{
public:
  /** \a mesh must outlive the objective. Throws when the scene has nothing to
   * estimate (no unknown modulus and no force surface), a force surface has no
   * wall in the mesh, or the objective is empty. */
  SurfaceMatchingObjective(const TetrahedralMesh & mesh, const Scene & scene, std::vector<ObjectiveSurface> surfaces);
  ~SurfaceMatchingObjective();
  SurfaceMatchingObjective(const SurfaceMatchingObjective &) = delete;
  SurfaceMatchingObjective &
  operator=(const SurfaceMatchingObjective &) = delete;

  /** Number of parameters p of the wall displacement: per control point of the
   * wall basis (per control node without one) 1 with motion along the normals,
   * else 3. */
  std::size_t
  GetNumberOfParameters() const;
  /** Spacing [mm] of the control points of the smooth wall basis (bmr::WallBasis);
   * 0 (default): every control node's displacement is a parameter. */
  void
  SetWallControlSpacing(double spacing);
  /** Weight alpha [1] of the regulariser alpha/2 |p|^2 added to Phi (default 0).
   * A distance objective does not see a wall sliding along itself: without it
   * the inner optimum drifts along such near-null directions and Phi*(E)
   * becomes noisy. The term does not depend on E, so unlike a penalty on the
   * forces or the strain energy (both proportional to E) it does not push the
   * moduli one way; a small alpha only picks the least-displacement optimum. */
  void
  SetWallRegularization(double alpha);
  /** true (default): every wall moves along its own normals, d_k = n_k (W s)_k
   * with one scalar parameter per control point; n_k is the unit wall normal at
   * control node k (area-weighted face normals averaged over 4 mm of the same
   * wall, which removes the tilt of the voxel staircase). false: d = W p, three
   * parameters per control point.
   * Why the default: the distance objective sees only the normal part of a
   * wall's motion. The tangential part is seen only through the organs it
   * drags, where it competes with the unknown moduli; left free it shapes
   * the stiff organ's surface and biases E (a rectal wall sliding 5 mm along
   * itself next to the prostate doubled the estimate on a phantom, README).
   * A lumen that fills or empties moves its wall along the normal. */
  void
  SetWallMotionAlongNormals(bool normal);
  /** Labels whose modulus is estimated, in scene order. */
  const std::vector<std::int32_t> &
  GetUnknownLabels() const;

  /** Moduli [kPa] of the unknown labels (in GetUnknownLabels() order). */
  void
  SetYoungsModuli(const std::vector<double> & moduli);

  /** Phi(E, d) + alpha/2 |p|^2 [mm^2] with d = W p (or n (W s)); fills the gradients when not
   * null (with respect to p [mm], and one per unknown label [mm^2 per unit log E]). */
  double
  Evaluate(const std::vector<double> & d, std::vector<double> * gradientD, std::vector<double> * gradientLogE);

  /** Nodal displacement [mm] (3N) for the wall parameters \a p. */
  std::vector<double>
  ComputeDisplacement(const std::vector<double> & d);
  /** Elements turned inside out (deformed volume <= 0) by the displacement of the last Evaluate(). */
  std::size_t
  GetNumberOfInvertedElements() const;
  /** Nodal forces [mN] (3N): K u - f, the loads the walls exert on the tissue,
   * at the control nodes; zero elsewhere. */
  std::vector<double>
  ComputeBoundaryForces(const std::vector<double> & u) const;
  /** |phi| statistics of the deformed surface nodes [mm]. */
  std::vector<SurfaceDistanceStatistics>
  ComputeSurfaceDistances(const std::vector<double> & u) const;

  /** Initial wall displacements by surface matching (dissertation 5.3.1.1):
   * every objective-surface node is pulled along -phi grad(phi) while springs
   * to its neighbours on the surface keep the displacement smooth,
   * v <- v - alpha phi grad(phi) + beta (mean of neighbours - v); returns the
   * parameters p whose wall displacement W p fits the control nodes' v best. */
  std::vector<double>
  MatchSurfaces(unsigned int iterations = 200) const;

  /** min_p Phi(E, p) at the current E by Levenberg-Marquardt. u is affine in p
   * for fixed E, u = u0 + A p, so A (3 rows per objective node, one column
   * per parameter) is computed once with one solve per parameter on the cached
   * factorisation; every iteration then only samples the distance maps:
   * \f$ (J^TJ + \mu\,\mathrm{diag}(J^TJ))\,\delta = -J^T r \f$ with
   * \f$ r = \sqrt{w}\,\phi \f$, \f$ J = \sqrt{w}\,\nabla\phi^T A \f$.
   * Stops when \f$\|J^T r\| \le\f$ tolerance max(1, |p|), when Phi no longer
   * decreases (relative 1e-12), or after maximumIterations. Meant for the
   * reduced wall basis (tens to hundreds of parameters). */
  WallSolution
  SolveWalls(const std::vector<double> & start, unsigned int maximumIterations, double tolerance);

private:
  struct Impl;
  std::unique_ptr<Impl> m_Impl;
};

} // namespace bmr

#endif
