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
#ifndef bmrForwardModel_h
#define bmrForwardModel_h

#include "bmrLinearElasticModel.h"

#include <cstdint>
#include <memory>

namespace bmr {

/** What a model's solves cost since it was constructed: counts, for speed studies and progress reports.
 * \ingroup BiomechanicalRegistration BiomechanicalRegistrationFEM
 */
struct BiomechanicalRegistration_EXPORT SolverWork
{
  std::uint64_t stateSolves{ 0 };                 ///< SolveState() / TrySolveState() calls
  std::uint64_t newtonIterations{ 0 };            ///< a nonlinear model's Newton iterations (0 for a linear one)
  std::uint64_t factorizations{ 0 };              ///< numeric sparse Cholesky factorizations (nonlinear models)
  std::uint64_t conjugateGradientIterations{ 0 }; ///< preconditioned CG iterations that replaced factorizations
  std::uint64_t rejectedIncrements{ 0 };          ///< load increments halved (nonlinear models)
  std::uint64_t coldStarts{ 0 };                  ///< solves whose warm start failed and that began again at u = 0
};

/** \brief The forward model of an estimation: the state u for given loads and moduli, and what the
 * adjoint gradients need from it.
 *
 * The model's equilibrium is \f$ f_{int}(u; E) = f \f$ on the free degrees of freedom, with u
 * prescribed on the constrained ones (SetConstrainedNodes()). For the gradient of a function
 * \f$\Phi(u)\f$ with \f$g = \partial\Phi/\partial u\f$ the estimator solves one adjoint system with
 * the tangent at the last state, \f$ K_T \lambda = g \f$ on the free dofs (\f$\lambda = 0\f$ on the
 * constrained ones), and then
 * \f[ \frac{\partial\Phi}{\partial f} = \lambda, \qquad
 *     \frac{\partial\Phi}{\partial \bar u_c} = g_c - (K_T \lambda)_c, \qquad
 *     \frac{\partial\Phi}{\partial E_m} = -\lambda^T \frac{\partial f_{int}}{\partial E_m} \f]
 * for the forces f, the prescribed displacements \f$\bar u\f$ and the moduli E_m.
 * Units: u in mm, f in mN, E in kPa.
 * \ingroup BiomechanicalRegistration BiomechanicalRegistrationFEM
 */
class BiomechanicalRegistration_EXPORT ForwardModel
{
public:
  virtual ~ForwardModel() = default;

  virtual const TetrahedralMesh &
  GetMesh() const = 0;
  /** The nodes whose displacement is prescribed in every SolveState(); changing them refactorizes. */
  virtual void
  SetConstrainedNodes(const std::vector<std::int32_t> & nodes) = 0;
  /** Does ahead what depends only on the mesh and the constrained nodes (a sparse symbolic analysis), e.g. on
   * another thread while other work runs; results are the same with or without it. The default does nothing. */
  virtual void
  Prepare()
  {}
  /** Does ahead what the next solve at the current moduli needs (a factorization), e.g. on another thread while
   * other work runs; results are the same with or without it. The default does nothing. */
  virtual void
  PrepareSolves()
  {}
  /** The threads the solves may use (e.g. 2 while a core is otherwise idle); results are the same bit for bit
   * whatever the number. The default ignores it. */
  virtual void
  SetNumberOfSolveThreads(unsigned)
  {}
  /** Modulus [kPa] of every element of \a label. */
  virtual void
  SetYoungsModulus(std::int32_t label, double youngsModulus) = 0;
  virtual double
  GetYoungsModulus(std::int32_t label) const = 0;

  /** Equilibrium state u [mm] (3N) for nodal forces [mN] (3N, or empty for none; ignored on constrained
   * dofs) and prescribed displacements [mm] (3N, read on the constrained dofs only). */
  virtual std::vector<double>
  SolveState(const std::vector<double> & forces, const std::vector<double> & prescribed) = 0;
  /** As SolveState(), but returns false instead of throwing when no equilibrium can be reached for these
   * loads (a nonlinear model whose every path inverts an element), leaving the last equilibrium as it was:
   * for an optimizer, an infeasible trial point. The default (a model that always reaches its loads) calls
   * SolveState(). */
  virtual bool
  TrySolveState(const std::vector<double> & forces, const std::vector<double> & prescribed, std::vector<double> & u)
  {
    u = SolveState(forces, prescribed);
    return true;
  }
  /** lambda with K_T lambda = g on the free dofs and lambda = 0 on the constrained ones, K_T the tangent
   * at the last state (3N in, 3N out). */
  virtual std::vector<double>
  SolveAdjoint(const std::vector<double> & g) = 0;
  /** As TrySolveState(), but \a u need only be exact at the dofs \a observedDofs (3N indices, any order) and the
   * constrained ones: a model may leave the other dofs 0 to save work (an estimation reads the state on the organ
   * surfaces and the unknown materials alone). The default computes every dof. */
  virtual bool
  TrySolveObservedState(const std::vector<double> &       forces,
                        const std::vector<double> &       prescribed,
                        const std::vector<std::int32_t> & observedDofs,
                        std::vector<double> &             u)
  {
    (void)observedDofs;
    return TrySolveState(forces, prescribed, u);
  }
  /** As SolveAdjoint(), but lambda need only be exact at the dofs \a observedDofs; a model may leave the others 0.
   * The default computes every dof. */
  virtual std::vector<double>
  SolveObservedAdjoint(const std::vector<double> & g, const std::vector<std::int32_t> & observedDofs)
  {
    (void)observedDofs;
    return SolveAdjoint(g);
  }
  /** K_T v at every dof (3N): the tangent applied to a nodal vector. */
  virtual std::vector<double>
  ApplyTangent(const std::vector<double> & v) const = 0;
  /** The free dofs (3N indices) whose values ApplyTangentAtConstrained() reads for its values at the constrained
   * \a nodes: what an observed adjoint (SolveObservedAdjoint()) must hold for the pull-back to those nodes. The
   * default: every dof. */
  virtual std::vector<std::int32_t>
  CoupledFreeDofs(const std::vector<std::int32_t> & nodes) const
  {
    (void)nodes;
    std::vector<std::int32_t> all(3 * GetMesh().GetNumberOfPoints());
    for (std::size_t i = 0; i < all.size(); ++i)
    {
      all[i] = static_cast<std::int32_t>(i);
    }
    return all;
  }
  /** K_T v at the constrained dofs for a \a v that vanishes there (an adjoint state, 3N); the values at the free
   * dofs are unspecified. The adjoint's pull-back to the prescribed displacements needs only these, which a
   * model may compute from its free-constrained block alone; the default applies the whole tangent. */
  virtual std::vector<double>
  ApplyTangentAtConstrained(const std::vector<double> & v) const
  {
    return ApplyTangent(v);
  }
  /** f_int(u) at every dof [mN] (3N). */
  virtual std::vector<double>
  InternalForces(const std::vector<double> & u) const = 0;
  /** \f$\partial f_{int}/\partial E_m\f$ at u [mN per kPa] (3N), m the material of \a label. */
  virtual std::vector<double>
  ModulusDerivative(std::int32_t label, const std::vector<double> & u) const = 0;
  /** Drops what the model keeps from earlier solves to start the next SolveState() from (a nonlinear model's
   * last equilibrium), so that the next state depends on its arguments alone and not on the order of earlier
   * solves: bit-for-bit results when solves from several threads are serialized in any order. */
  virtual void
  ForgetState()
  {}
  /** True when u is affine in the forces and prescribed displacements at fixed moduli, so that
   * du/dp can be computed once per modulus (the Levenberg-Marquardt inner solver needs it). */
  virtual bool
  IsLinear() const = 0;
  /** The work of every solve since construction (zeros for a model that does not count it). */
  virtual SolverWork
  GetSolverWork() const
  {
    return {};
  }
};

/** \brief The linear-elastic forward model: P1 tetrahedra, standard or nodal-averaged pressure per
 * material (bmr::LinearElasticModel), \f$ f_{int} = K(E) u = \sum_m E_m \hat K_m u \f$, so
 * \f$K_T = K\f$ and \f$\partial f_{int}/\partial E_m = \hat K_m u\f$. One sparse Cholesky factorization
 * per value of the moduli serves every state and adjoint solve.
 * \ingroup BiomechanicalRegistration BiomechanicalRegistrationFEM
 */
class BiomechanicalRegistration_EXPORT LinearForwardModel : public ForwardModel
{
public:
  /** \a mesh must outlive the model. */
  LinearForwardModel(const TetrahedralMesh & mesh, const std::map<std::int32_t, MaterialParameters> & materials);
  ~LinearForwardModel() override;

  const TetrahedralMesh &
  GetMesh() const override
  {
    return m_Mesh;
  }
  void
  SetConstrainedNodes(const std::vector<std::int32_t> & nodes) override;
  /** LinearElasticModel::Analyze(). */
  void
  Prepare() override;
  /** LinearElasticModel::Factorize() at the current moduli. */
  void
  PrepareSolves() override;
  /** LinearElasticModel::SetNumberOfSolveThreads(). */
  void
  SetNumberOfSolveThreads(unsigned threads) override;
  void
  SetYoungsModulus(std::int32_t label, double youngsModulus) override;
  double
  GetYoungsModulus(std::int32_t label) const override;
  std::vector<double>
  SolveState(const std::vector<double> & forces, const std::vector<double> & prescribed) override;
  std::vector<double>
  SolveAdjoint(const std::vector<double> & g) override;
  /** LinearElasticModel::Solve() with \a observedDofs: the same values bit for bit at those dofs. */
  bool
  TrySolveObservedState(const std::vector<double> &       forces,
                        const std::vector<double> &       prescribed,
                        const std::vector<std::int32_t> & observedDofs,
                        std::vector<double> &             u) override;
  /** LinearElasticModel::Solve() observing \a observedDofs. */
  std::vector<double>
  SolveObservedAdjoint(const std::vector<double> & g, const std::vector<std::int32_t> & observedDofs) override;
  /** LinearElasticModel::GetCoupledFreeDegreesOfFreedom(). */
  std::vector<std::int32_t>
  CoupledFreeDofs(const std::vector<std::int32_t> & nodes) const override;
  /** The state solves (observed or whole) since construction; the other counts are 0. */
  SolverWork
  GetSolverWork() const override
  {
    return m_Work;
  }
  std::vector<double>
  ApplyTangent(const std::vector<double> & v) const override;
  /** LinearElasticModel::ComputeCouplingForces(): K_cf v_f, bit for bit K v at the constrained dofs. */
  std::vector<double>
  ApplyTangentAtConstrained(const std::vector<double> & v) const override;
  std::vector<double>
  InternalForces(const std::vector<double> & u) const override;
  std::vector<double>
  ModulusDerivative(std::int32_t label, const std::vector<double> & u) const override;
  bool
  IsLinear() const override
  {
    return true;
  }

  /** The underlying assembled model (stress, per-element moduli, timings). */
  const LinearElasticModel &
  GetModel() const
  {
    return *m_Model;
  }

private:
  const TetrahedralMesh &             m_Mesh;
  std::unique_ptr<LinearElasticModel> m_Model;
  SolverWork                          m_Work;
};

} // namespace bmr

#endif
