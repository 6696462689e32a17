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
#ifndef bmrNeoHookeanForwardModel_h
#define bmrNeoHookeanForwardModel_h

#include "bmrForwardModel.h"

#include <memory>

namespace bmr {

/** Stopping rules and load stepping of NeoHookeanForwardModel's Newton solver. */
struct BiomechanicalRegistration_EXPORT NewtonSettings
{
  /** Converged when the free residual \f$\|f - f_{int}(u)\|_f \le\f$ this times the force scale, the larger
   * of the applied forces' and the internal forces' norms (the reactions count: a displacement load has no
   * applied force). */
  double residualTolerance{ 1e-9 };
  /** ... or when the Newton decrement \f$\delta = \Delta u^T r\f$ falls to this fraction of the increment's
   * first decrement (the energy criterion; \f$\delta\f$ is quadratic in the residual, hence the square). */
  double energyTolerance{ 1e-18 };
  /** Newton iterations per load increment before the increment is halved. */
  unsigned int maximumIterations{ 30 };
  /** Fraction of the load path tried as the first increment (1: all at once). */
  double initialIncrement{ 1.0 };
  /** Smallest increment tried before the solve fails. */
  double minimumIncrement{ 1.0 / 4096.0 };
  /** An increment that converged in at most this many iterations doubles the next one. */
  unsigned int easyIterations{ 5 };
  /** When the path from the last equilibrium fails, try the loads again from u = 0. An estimator turns it off:
   * its trial points whose warm path fails are declared infeasible at once (on the pelvis such restarts failed as
   * well, at the cost of a whole load path each). */
  bool restartFromRest{ true };
};

/** What the last NeoHookeanForwardModel::SolveState() did. */
struct BiomechanicalRegistration_EXPORT NewtonStatistics
{
  unsigned int acceptedIncrements{ 0 };
  unsigned int rejectedIncrements{ 0 }; ///< halved after an inverted trial, a failed line search or no convergence
  unsigned int iterations{ 0 };         ///< Newton iterations of the accepted and the rejected increments
  unsigned int shiftedTangents{ 0 };    ///< tangents that were not positive definite and were shifted
  unsigned int factorizations{ 0 };     ///< numeric Cholesky factorizations (including the adjoints' since)
  unsigned int conjugateGradientIterations{ 0 }; ///< preconditioned CG iterations that replaced factorizations
  bool         warmStart{ false };               ///< the path started from the previous equilibrium (else from u = 0)
  /** Relative residual (NewtonSettings::residualTolerance's measure) before each Newton iteration of the last
   * accepted increment, and after it: the convergence history that shows Newton's quadratic rate. */
  std::vector<double> lastResiduals;
  double              seconds{ 0.0 };
};

/** \brief Geometrically nonlinear, compressible neo-Hookean tissue on P1 tetrahedra (total Lagrangian;
 * dissertation section 3.3.5).
 *
 * Per material, with \f$F = I + \nabla_X u\f$, \f$J = \det F\f$, \f$I_1 = \mathrm{tr}(F^T F)\f$ and the Lame
 * parameters \f$\mu, \lambda\f$ of (E, nu), the stored energy density [kPa] is
 * \f[ W(F) = \frac{\mu}{2}(I_1 - 3) - \mu \ln J + \frac{\lambda}{2} (\ln J)^2 , \f]
 * whose linearization at F = I is linear elasticity with the same E and nu (so that both models share a
 * scene's materials and agree for small loads), and which is linear in E at fixed nu. The first
 * Piola-Kirchhoff stress and the tangent are
 * \f[ P = \mu (F - F^{-T}) + \lambda \ln J\, F^{-T}, \qquad
 *     \frac{\partial P_{iJ}}{\partial F_{kL}} = \mu \delta_{ik}\delta_{JL} + (\mu - \lambda \ln J) F^{-1}_{Li}
 *     F^{-1}_{Jk} + \lambda F^{-1}_{Ji} F^{-1}_{Lk} . \f]
 * With the reference gradients \f$g_a\f$ of the barycentric coordinates, the element volume V and
 * \f$q_a = F^{-T} g_a\f$, element e contributes \f$f_{a} = V P g_a\f$ to the internal forces and
 * \f$K_{ai,bk} = V [\mu \delta_{ik}\, g_a \cdot g_b + (\mu - \lambda \ln J) q_{b,i} q_{a,k} + \lambda q_{a,i}
 * q_{b,k}]\f$ to the tangent. Since \f$W \propto E\f$, \f$\partial f_{int}/\partial E_m = f_{int,m}/E_m\f$, the
 * internal forces of the elements of material m divided by their modulus.
 *
 * Equilibrium \f$f_{int}(u) = f\f$ on the free dofs (u prescribed on the constrained ones) is found by
 * Newton's method on the total potential \f$\Pi(u) = \sum_e V_e W(F_e) - f^T u\f$: each iteration solves
 * \f$K_T \Delta u = r\f$ (a sparse Cholesky factorization, CHOLMOD: the symbolic analysis once per
 * constrained set; the numeric factorization only when needed: a solve first runs conjugate gradients on the
 * current tangent preconditioned by the last factorization, which between nearby states converge in a few
 * iterations, and factorizes when they do not, or after a slow one), then backtracks \f$u + \alpha \Delta u\f$ until
 * no element is inverted (J > 0) and \f$\Pi\f$ decreases (Armijo); the first step of an increment, which moves
 * the prescribed dofs, is taken whole, or the increment is halved. A tangent that is not positive definite is
 * shifted by a multiple of its mean diagonal, which keeps \f$\Delta u\f$ a descent direction. The loads are
 * applied along a path from the last equilibrium (or from u = 0) in increments: the first one the whole path
 * (NewtonSettings::initialIncrement), an increment that fails is halved, an easy one doubles the next. No
 * state with an inverted element is ever accepted. When the path cannot be followed, from the last
 * equilibrium and then from u = 0, SolveState() throws an itk::ExceptionObject naming the load fraction
 * reached and the element with the smallest J of the last trial.
 *
 * An element whose four nodes are all constrained cannot move: it takes no part in the free equilibrium, the
 * line search or the tangent (ApplyTangent() omits it, which changes nothing for vectors that vanish on the
 * constrained dofs, as adjoints do), and adds its internal forces (reactions) only while it is not inverted.
 * Prescribed wall motion may flatten such a boundary sliver without making the tissue's state infeasible.
 *
 * SolveAdjoint() and ApplyTangent() use the tangent at the last equilibrium (assembled there, unshifted; an
 * adjoint at an unstable equilibrium, where it is not positive definite, throws).
 * Units: u in mm, f in mN, E and stress in kPa, energy in kPa mm^3 = mN mm (= microjoule).
 * Errors as LinearElasticModel's, and the nodal-averaged pressure formulation, which this model does not
 * implement, is rejected. \a mesh must outlive the model.
 * \ingroup BiomechanicalRegistration BiomechanicalRegistrationFEM
 */
class BiomechanicalRegistration_EXPORT NeoHookeanForwardModel : public ForwardModel
{
public:
  NeoHookeanForwardModel(const TetrahedralMesh &                            mesh,
                         const std::map<std::int32_t, MaterialParameters> & materials,
                         const NewtonSettings &                             settings = {});
  ~NeoHookeanForwardModel() override;

  const TetrahedralMesh &
  GetMesh() const override;
  void
  SetConstrainedNodes(const std::vector<std::int32_t> & nodes) override;
  void
  SetYoungsModulus(std::int32_t label, double youngsModulus) override;
  double
  GetYoungsModulus(std::int32_t label) const override;
  std::vector<double>
  SolveState(const std::vector<double> & forces, const std::vector<double> & prescribed) override;
  bool
  TrySolveState(const std::vector<double> & forces,
                const std::vector<double> & prescribed,
                std::vector<double> &       u) override;
  std::vector<double>
  SolveAdjoint(const std::vector<double> & g) override;
  std::vector<double>
  ApplyTangent(const std::vector<double> & v) const override;
  std::vector<double>
  InternalForces(const std::vector<double> & u) const override;
  std::vector<double>
  ModulusDerivative(std::int32_t label, const std::vector<double> & u) const override;
  bool
  IsLinear() const override
  {
    return false;
  }

  /** Stored energy \f$\sum_e V_e W(F_e)\f$ of the state u [kPa mm^3]; infinite when an element is inverted. */
  double
  StoredEnergy(const std::vector<double> & u) const;
  /** First Piola-Kirchhoff stress of every element at u [kPa], 9 per element, row-major \f$P_{iJ}\f$. */
  std::vector<double>
  FirstPiolaKirchhoffStress(const std::vector<double> & u) const;
  /** Von Mises stress of the Cauchy stress \f$\sigma = J^{-1} P F^T\f$ of every element at u [kPa]; 0 for an
   * inverted element (only a passive one, all of whose nodes are prescribed, can be inverted at equilibrium). */
  std::vector<double>
  VonMisesStress(const std::vector<double> & u) const;
  /** Why the last TrySolveState() failed: the load fraction reached, the reason, the worst element. */
  const std::string &
  GetLastFailure() const;
  /** Forgets the last equilibrium and the factorization: the next SolveState() starts from u = 0 and its result
   * depends on its arguments alone. */
  void
  ForgetState() override;
  const NewtonStatistics &
  GetStatistics() const;
  SolverWork
  GetSolverWork() const override;

private:
  struct Impl;
  std::unique_ptr<Impl> m_Impl;
};

/** The von Mises stress of the Cauchy stress of every element of \a mesh in the state \a u [mm] under the
 * neo-Hookean \a materials [kPa] (0 for an inverted element), element by element: no model is assembled. */
BiomechanicalRegistration_EXPORT std::vector<double>
                                 NeoHookeanVonMisesStress(const TetrahedralMesh &                            mesh,
                                                          const std::map<std::int32_t, MaterialParameters> & materials,
                                                          const std::vector<double> &                        u);

} // namespace bmr

#endif
