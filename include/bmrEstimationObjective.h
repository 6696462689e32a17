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
#ifndef bmrEstimationObjective_h
#define bmrEstimationObjective_h

#include "bmrCompressionBarrier.h"
#include "bmrDataTerm.h"
#include "bmrForwardModel.h"
#include "bmrLoadParameterization.h"

#include <memory>

namespace bmr {

/** Result of an inner solve at fixed E: the loads' optimum. */
struct BiomechanicalRegistration_EXPORT LoadSolution
{
  std::vector<double> parameters;         ///< p (mm for wall loads)
  double              value{ 0.0 };       ///< Phi* [mm^2]
  std::vector<double> gradient;           ///< dPhi/dp at the optimum
  std::vector<double> logModulusGradient; ///< dPhi*/dlog E (envelope theorem) [mm^2]
  unsigned int        iterations{ 0 };
  std::string         stop;
  SolverWork          work; ///< the model's solves during it (filled by the estimator)
};

/** \brief The estimation objective composed of a forward model, a load parameterization and data terms,
 * with its adjoint gradients.
 *
 * \f[ \Phi(E, p) = \sum_t \Phi_t(u) + \Phi_b(u) + R(p), \f]
 * \f[ f_{int}(u; E) = f(p) \text{ on free dofs},\ u = \bar u(p) \text{ on constrained dofs}, \f]
 * with \f$g = \partial(\sum_t\Phi_t + \Phi_b)/\partial u\f$; \f$\Phi_b\f$ is the CompressionBarrier of a
 * nonlinear model (0 for a linear one). Adjoint (one solve with the cached factorization):
 * \f$K_T\lambda = g\f$ on the free dofs, \f$\lambda = 0\f$ on the constrained ones; then
 * \f[ \partial\Phi/\partial p = \Big(\frac{\partial\bar u}{\partial p}\Big)^T (g - K_T\lambda)_c
 *     + \Big(\frac{\partial f}{\partial p}\Big)^T \lambda + \nabla R, \qquad
 *     \partial\Phi/\partial \log E_m = -E_m\, \lambda^T \partial f_{int}/\partial E_m. \f]
 * Both solves compute only the dofs the evaluation reads (SetObservedSolves(), on by default: the same numbers).
 * The parts are referenced, not owned; they must outlive the objective.
 * Units: u in mm; E in kPa; Phi in mm^2.
 * \ingroup BiomechanicalRegistration BiomechanicalRegistrationEstimation
 */
class BiomechanicalRegistration_EXPORT EstimationObjective
{
public:
  /** \a unknownLabels: the labels whose modulus is estimated. Throws when there is nothing to estimate
   * (no load parameter and no unknown modulus) or no data term. */
  EstimationObjective(ForwardModel &                model,
                      LoadParameterization &        loads,
                      std::vector<const DataTerm *> terms,
                      std::vector<std::int32_t>     unknownLabels);
  virtual ~EstimationObjective();
  EstimationObjective(const EstimationObjective &) = delete;
  EstimationObjective &
  operator=(const EstimationObjective &) = delete;

  std::size_t
  GetNumberOfParameters() const;
  /** Labels whose modulus is estimated. */
  const std::vector<std::int32_t> &
  GetUnknownLabels() const;
  /** Moduli [kPa] of the unknown labels (in GetUnknownLabels() order). */
  void
  SetYoungsModuli(const std::vector<double> & moduli);

  /** Phi(E, p) [mm^2]; fills the gradients when not null (with respect to p, and one per unknown label
   * [mm^2 per unit log E]). When a nonlinear model cannot reach the loads of p (ForwardModel::TrySolveState()),
   * p is infeasible: the value is 2 |Phi_last| + 1 above the last feasible value, the gradients zero, and
   * GetNumberOfInfeasibleEvaluations() counts it, so that an optimizer's line search shortens its step. */
  double
  Evaluate(const std::vector<double> & p, std::vector<double> * gradientP, std::vector<double> * gradientLogE);
  /** Nodal displacement [mm] (3N) for the load parameters \a p. */
  std::vector<double>
  ComputeDisplacement(const std::vector<double> & p);
  /** Elements turned inside out (deformed volume <= 0) by the displacement of the last Evaluate() (solving for
   * the whole state when that evaluation solved the observed dofs alone). */
  std::size_t
  GetNumberOfInvertedElements();
  /** Whether Evaluate() solves for the state and the adjoint only at the dofs it reads (default on): the data
   * terms' nodes (DataTerm::GetObservedNodes()) and the unknown materials', and the free dofs the pull-back to the
   * loads reads (ForwardModel::TrySolveObservedState(), SolveObservedAdjoint()). Its values and gradients are the
   * same bit for bit; on the demo pair the triangular solves then skip about half the factor. Off, every solve is
   * whole, as a caller counting inverted elements after every evaluation needs. Without effect when a data term
   * may read any node, or with a nonlinear model (whose barrier reads every element). Changing it drops the
   * kept last evaluation (setting the value it has keeps it). */
  void
  SetObservedSolves(bool observed);
  bool
  GetObservedSolves() const
  {
    return m_ObservedSolves;
  }
  /** The dofs (3N indices, ascending) of the state that observed solves compute when they are on; empty when a data
   * term may read any node or the model is nonlinear (every state solve whole). */
  const std::vector<std::int32_t> &
  GetObservedStateDofs() const
  {
    return m_StateDofs;
  }
  /** Evaluations whose loads the model could not reach, since construction. */
  std::size_t
  GetNumberOfInfeasibleEvaluations() const
  {
    return m_Infeasible;
  }
  /** The loads [mN] (3N) the boundary exerts on the tissue in the state \a u. */
  std::vector<double>
  ComputeBoundaryForces(const std::vector<double> & u) const;
  /** Residual statistics of every data term in the state \a u [mm]. */
  std::vector<ResidualStatistics>
  ComputeStatistics(const std::vector<double> & u) const;
  /** Initial load parameters: the data terms' model-free displacement (MatchDisplacement()), fitted by the load
   * parameterization. */
  std::vector<double>
  EstimateInitialParameters() const;
  /** The data terms' model-free displacement [mm] (3N): each term moves its own nodes onto its data (surface
   * matching for the surface distances), the held nodes stay. The examples a trained wall basis learns from. */
  std::vector<double>
  MatchDisplacement() const;

  /** min_p Phi(E, p) at the current E by Levenberg-Marquardt, for an affine parameterization of a linear
   * model: u = u0 + A p, so A (3 rows per data node, one column per parameter) is computed once with one
   * solve per parameter on the cached factorization; every iteration then only evaluates the residuals:
   * \f$ (J^TJ + \mu\,\mathrm{diag}(J^TJ))\,\delta = -J^T r - \nabla R \f$ with \f$ J = \partial r/\partial u\, A \f$.
   * Stops when \f$\|J^T r + \nabla R\| \le\f$ tolerance max(1, |p|), when Phi no longer decreases
   * (relative 1e-10), or after maximumIterations. Meant for reduced bases (tens to hundreds of parameters).
   * The prior must have no cross terms (the ridge alpha/2 |p|^2, a trained basis's w/2 sum p_k^2/lambda_k): its Hessian
   * is taken as diag(2 R(e_k)). With a nonlinear model (the neo-Hookean) every trial p is a Newton solve (an infeasible
   * one is rejected like a rise of Phi), and A = du/dp is recomputed from the tangent at each accepted p: one
   * back-substitution per parameter. */
  LoadSolution
  SolveLoadsLevenbergMarquardt(const std::vector<double> & start, unsigned int maximumIterations, double tolerance);

  /** The barrier against crushed elements added to Phi with a nonlinear model (CompressionBarrier, J_0 = 0.25,
   * w = 0.1); null with a linear model, whose states may invert elements. In SolveLoadsLevenbergMarquardt() it is part
   * of the value that accepts a step, not of the residuals' Jacobian. */
  const CompressionBarrier *
  GetCompressionBarrier() const
  {
    return m_Barrier.get();
  }

  ForwardModel &
  GetForwardModel()
  {
    return m_Model;
  }
  const LoadParameterization &
  GetLoads() const
  {
    return m_Loads;
  }

private:
  double
  InfeasibleValue(std::vector<double> * gradientP, std::vector<double> * gradientLogE);

  ForwardModel &                m_Model;
  LoadParameterization &        m_Loads;
  std::vector<const DataTerm *> m_Terms;
  std::vector<std::int32_t>     m_UnknownLabels;
  std::size_t                   m_Inverted{ 0 };
  bool                          m_InvertedKnown{ true };
  bool                          m_ObservedSolves{ true };
  std::vector<std::int32_t>     m_StateDofs, m_MaterialDofs;             // the observed dofs (FindObservedDofs())
  std::vector<std::int32_t>     m_AdjointDofs, m_AdjointDofsConstrained; // AdjointDofs() and its constrained nodes
  std::size_t                   m_Infeasible{ 0 };
  double                        m_LastFeasibleValue{ 0.0 };
  std::unique_ptr<CompressionBarrier> m_Barrier;

  /** The last feasible evaluation. An inner solve ends by evaluating, now with the modulus gradient, the point
   * its optimizer evaluated last: that evaluation is then reused (the same state and adjoint, so the same
   * numbers), which saves a forward and an adjoint solve per inner solve. It is keyed on the parameters and the
   * unknown moduli: the model's other settings must not change while the objective is in use. */
  struct Evaluation
  {
    bool                valid{ false };
    bool                withAdjoint{ false };
    std::vector<double> parameters, moduli; ///< where it was made
    std::vector<double> u, lambda, gradientP;
    double              value{ 0.0 };
    std::size_t         inverted{ 0 };
    bool                observed{ false }; ///< u and lambda exact at the observed dofs only
  };
  Evaluation m_Last;

  std::vector<double>
  CurrentModuli() const;
  void
  FindObservedDofs();
  const std::vector<std::int32_t> &
  AdjointDofs();
  /** Solves at \a p (and the adjoint when \a adjoint) into m_Last; false when the model cannot reach p. */
  bool
  EvaluateAt(const std::vector<double> & p, bool adjoint);
  std::vector<double>
  ModulusGradient(const std::vector<double> & u, const std::vector<double> & lambda) const;
};

} // namespace bmr

#endif
