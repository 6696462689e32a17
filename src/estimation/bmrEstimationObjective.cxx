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
#include "bmrEstimationObjective.h"

#include "bmrCompressionBarrier.h"
#include "bmrError.h"

#include <Eigen/Dense>

#include <algorithm>
#include <iterator>
#include <cmath>
#include <limits>

namespace bmr {
namespace {
/** dPhi/dp from g = dPhi/du and its adjoint lambda (K_T lambda = g on the free dofs): the sensitivities to the
 * forces (lambda) and to the prescribed displacements (g - K_T lambda on the constrained dofs) pulled back
 * through the parameterization, plus the prior's gradient at \a p. */
std::vector<double>
PullBackThroughLoads(ForwardModel &               model,
                     const LoadParameterization & loads,
                     const std::vector<double> &  p,
                     const std::vector<double> &  g,
                     const std::vector<double> &  lambda)
{
  const std::vector<double> Klambda = model.ApplyTangentAtConstrained(lambda); // read on the constrained dofs
  std::vector<double>       prescribedSensitivity(g.size(), 0.0);
  for (std::int32_t n : loads.GetConstrainedNodes())
  {
    for (int c = 0; c < 3; ++c)
    {
      const std::size_t dof = 3 * static_cast<std::size_t>(n) + c;
      prescribedSensitivity[dof] = g[dof] - Klambda[dof];
    }
  }
  // A held node's value does not depend on p; an observed adjoint does not hold what its sensitivity needs.
  for (std::int32_t n : loads.GetHeldNodes())
  {
    std::fill_n(prescribedSensitivity.begin() + 3 * static_cast<std::ptrdiff_t>(n), 3, 0.0);
  }
  return loads.PullBackGradient(p, prescribedSensitivity, lambda);
}

} // namespace


EstimationObjective::EstimationObjective(ForwardModel &                model,
                                         LoadParameterization &        loads,
                                         std::vector<const DataTerm *> terms,
                                         std::vector<std::int32_t>     unknownLabels)
  : m_Model(model)
  , m_Loads(loads)
  , m_Terms(std::move(terms))
  , m_UnknownLabels(std::move(unknownLabels))
{
  if (m_Terms.empty() || std::find(m_Terms.begin(), m_Terms.end(), nullptr) != m_Terms.end())
  {
    Fail("EstimationObjective", "no data term (or a null one): nothing to match");
  }
  if (m_Loads.GetNumberOfParameters() == 0 && m_UnknownLabels.empty())
  {
    Fail("EstimationObjective",
         "the scene has neither an unknown modulus (role unknown_material) nor a force surface: nothing to estimate");
  }
  m_Model.SetConstrainedNodes(m_Loads.GetConstrainedNodes());
  if (!m_Model.IsLinear())
  {
    m_Barrier = std::make_unique<CompressionBarrier>(m_Model.GetMesh());
  }
  FindObservedDofs();
}

/** The dofs an evaluation reads: of the state, the data terms' nodes and the unknown materials' (for
 * ModulusGradient()), unless a term may read any node; of the adjoint, the unknown materials' (and the pull-back's,
 * EvaluateAt()). None when the barrier reads every element. */
void
EstimationObjective::FindObservedDofs()
{
  if (m_Barrier)
  {
    return;
  }
  const TetrahedralMesh &   mesh = m_Model.GetMesh();
  std::vector<std::int32_t> materialNodes;
  for (std::size_t e = 0; e < mesh.labels.size(); ++e)
  {
    if (std::find(m_UnknownLabels.begin(), m_UnknownLabels.end(), mesh.labels[e]) != m_UnknownLabels.end())
    {
      materialNodes.insert(materialNodes.end(), &mesh.tetrahedra[4 * e], &mesh.tetrahedra[4 * e] + 4);
    }
  }
  const auto dofsOf = [](const std::vector<std::int32_t> & nodes) {
    std::vector<std::int32_t> dofs;
    for (const std::int32_t n : UniqueNodes(nodes))
    {
      dofs.insert(dofs.end(), { 3 * n, 3 * n + 1, 3 * n + 2 });
    }
    return dofs;
  };
  m_MaterialDofs = dofsOf(materialNodes);
  std::vector<std::int32_t> stateNodes = materialNodes;
  for (const DataTerm * term : m_Terms)
  {
    const std::optional<std::vector<std::int32_t>> nodes = term->GetObservedNodes();
    if (!nodes)
    {
      return;
    }
    stateNodes.insert(stateNodes.end(), nodes->begin(), nodes->end());
  }
  m_StateDofs = dofsOf(stateNodes);
}

/** The adjoint's observed dofs: the unknown materials' and those the pull-back reads for the load-controlled
 * constrained nodes (a held node's prescribed value does not depend on p, so its sensitivity is not needed). Kept
 * until the constrained nodes change (e.g. WallLoads::SetMotion()). */
const std::vector<std::int32_t> &
EstimationObjective::AdjointDofs()
{
  const std::vector<std::int32_t> & constrained = m_Loads.GetConstrainedNodes();
  if (constrained != m_AdjointDofsConstrained || m_AdjointDofs.empty())
  {
    m_AdjointDofsConstrained = constrained;
    const std::vector<std::int32_t> held = UniqueNodes(m_Loads.GetHeldNodes());
    std::vector<std::int32_t>       loaded;
    std::set_difference(constrained.begin(), constrained.end(), held.begin(), held.end(), std::back_inserter(loaded));
    std::vector<std::int32_t> dofs = m_Model.CoupledFreeDofs(loaded);
    dofs.insert(dofs.end(), m_MaterialDofs.begin(), m_MaterialDofs.end());
    m_AdjointDofs = UniqueNodes(std::move(dofs));
  }
  return m_AdjointDofs;
}

void
EstimationObjective::SetObservedSolves(bool observed)
{
  if (observed != m_ObservedSolves)
  {
    m_ObservedSolves = observed;
    m_Last.valid = false; // evaluated again, as asked
  }
}

EstimationObjective::~EstimationObjective() = default;

std::size_t
EstimationObjective::GetNumberOfParameters() const
{
  return m_Loads.GetNumberOfParameters();
}

const std::vector<std::int32_t> &
EstimationObjective::GetUnknownLabels() const
{
  return m_UnknownLabels;
}

void
EstimationObjective::SetYoungsModuli(const std::vector<double> & moduli)
{
  if (moduli.size() != m_UnknownLabels.size())
  {
    Fail("EstimationObjective::SetYoungsModuli", "expected one modulus per unknown material");
  }
  for (std::size_t m = 0; m < moduli.size(); ++m)
  {
    m_Model.SetYoungsModulus(m_UnknownLabels[m], moduli[m]);
  }
}

std::vector<double>
EstimationObjective::CurrentModuli() const
{
  std::vector<double> moduli;
  for (std::int32_t label : m_UnknownLabels)
  {
    moduli.push_back(m_Model.GetYoungsModulus(label));
  }
  return moduli;
}

bool
EstimationObjective::EvaluateAt(const std::vector<double> & p, bool adjoint)
{
  m_Last.valid = false;
  const BoundaryLoad load = m_Loads.Apply(p);
  const bool         observed = m_ObservedSolves && !m_StateDofs.empty();
  if (observed ? !m_Model.TrySolveObservedState(load.forces, load.prescribed, m_StateDofs, m_Last.u)
               : !m_Model.TrySolveState(load.forces, load.prescribed, m_Last.u))
  {
    return false;
  }
  const std::vector<double> & u = m_Last.u;
  m_Last.observed = observed;
  m_Last.inverted = observed ? 0 : CountInvertedElements(m_Model.GetMesh(), u);
  std::vector<double> g(adjoint ? u.size() : 0, 0.0);
  double              value = 0.0;
  for (const DataTerm * term : m_Terms)
  {
    value += term->Evaluate(u, adjoint ? &g : nullptr);
  }
  if (m_Barrier)
  {
    value += m_Barrier->Evaluate(u, adjoint ? &g : nullptr);
  }
  m_Last.value = value + m_Loads.EvaluatePrior(p);
  m_Last.lambda.clear();
  m_Last.gradientP.clear();
  if (adjoint)
  {
    // When p sets forces the pull-back reads the adjoint wherever they act (asked each time: a parameterization may
    // switch, e.g. WallLoads::SetMotion()).
    const bool observedAdjoint = m_ObservedSolves && !m_Barrier && !m_Loads.ReadsForceSensitivity();
    m_Last.lambda = observedAdjoint ? m_Model.SolveObservedAdjoint(g, AdjointDofs()) : m_Model.SolveAdjoint(g);
    m_Last.gradientP = PullBackThroughLoads(m_Model, m_Loads, p, g, m_Last.lambda);
  }
  m_Last.parameters = p;
  m_Last.moduli = CurrentModuli();
  m_Last.withAdjoint = adjoint;
  m_Last.valid = true;
  return true;
}

std::vector<double>
EstimationObjective::ModulusGradient(const std::vector<double> & u, const std::vector<double> & lambda) const
{
  std::vector<double> gradient(m_UnknownLabels.size(), 0.0);
  for (std::size_t m = 0; m < m_UnknownLabels.size(); ++m)
  {
    const std::vector<double> dfdE = m_Model.ModulusDerivative(m_UnknownLabels[m], u);
    double                    dot = 0.0;
    for (std::size_t i = 0; i < u.size(); ++i)
    {
      dot += lambda[i] * dfdE[i];
    }
    gradient[m] = -m_Model.GetYoungsModulus(m_UnknownLabels[m]) * dot;
  }
  return gradient;
}

double
EstimationObjective::Evaluate(const std::vector<double> & p,
                              std::vector<double> *       gradientP,
                              std::vector<double> *       gradientLogE)
{
  const bool wantGradient = gradientP != nullptr || gradientLogE != nullptr;
  const bool reuse =
    m_Last.valid && (m_Last.withAdjoint || !wantGradient) && m_Last.parameters == p && m_Last.moduli == CurrentModuli();
  if (!reuse && !EvaluateAt(p, wantGradient))
  {
    return InfeasibleValue(gradientP, gradientLogE);
  }
  m_Inverted = m_Last.inverted;
  m_InvertedKnown = !m_Last.observed;
  m_LastFeasibleValue = m_Last.value;
  if (gradientP != nullptr)
  {
    *gradientP = m_Last.gradientP;
  }
  if (gradientLogE != nullptr)
  {
    *gradientLogE = ModulusGradient(m_Last.u, m_Last.lambda);
  }
  return m_Last.value;
}

// A nonlinear model could not reach the loads of p: a value above the last feasible one (which fails any line
// search's sufficient decrease, so that the optimizer shortens its step) and a zero gradient.
double
EstimationObjective::InfeasibleValue(std::vector<double> * gradientP, std::vector<double> * gradientLogE)
{
  ++m_Infeasible;
  m_Inverted = m_Model.GetMesh().GetNumberOfTetrahedra();
  m_InvertedKnown = true;
  if (gradientP != nullptr)
  {
    gradientP->assign(GetNumberOfParameters(), 0.0);
  }
  if (gradientLogE != nullptr)
  {
    gradientLogE->assign(m_UnknownLabels.size(), 0.0);
  }
  return 2.0 * std::abs(m_LastFeasibleValue) + 1.0;
}

std::vector<double>
EstimationObjective::ComputeDisplacement(const std::vector<double> & p)
{
  const BoundaryLoad load = m_Loads.Apply(p);
  return m_Model.SolveState(load.forces, load.prescribed);
}

std::size_t
EstimationObjective::GetNumberOfInvertedElements()
{
  if (!m_InvertedKnown)
  {
    // The last state was solved at the observed dofs alone: the whole of it, once, at its moduli.
    const std::vector<double> moduli = CurrentModuli();
    SetYoungsModuli(m_Last.moduli);
    m_Inverted = CountInvertedElements(m_Model.GetMesh(), ComputeDisplacement(m_Last.parameters));
    m_InvertedKnown = true;
    SetYoungsModuli(moduli);
  }
  return m_Inverted;
}

std::vector<double>
EstimationObjective::ComputeBoundaryForces(const std::vector<double> & u) const
{
  return m_Loads.BoundaryForces(m_Model.InternalForces(u));
}

std::vector<ResidualStatistics>
EstimationObjective::ComputeStatistics(const std::vector<double> & u) const
{
  std::vector<ResidualStatistics> all;
  for (const DataTerm * term : m_Terms)
  {
    const std::vector<ResidualStatistics> s = term->ComputeStatistics(u);
    all.insert(all.end(), s.begin(), s.end());
  }
  return all;
}

std::vector<double>
EstimationObjective::EstimateInitialParameters() const
{
  return m_Loads.FitDisplacement(MatchDisplacement());
}

std::vector<double>
EstimationObjective::MatchDisplacement() const
{
  std::vector<char> held(m_Model.GetMesh().GetNumberOfPoints(), 0);
  for (std::int32_t n : m_Loads.GetHeldNodes())
  {
    held[n] = 1;
  }
  // The terms' displacements, summed: each term moves only its own nodes.
  std::vector<double> v(3 * held.size(), 0.0);
  for (const DataTerm * term : m_Terms)
  {
    const std::vector<double> vt = term->MatchDisplacement(held);
    for (std::size_t i = 0; i < v.size(); ++i)
    {
      v[i] += vt[i];
    }
  }
  return v;
}

namespace {
/** The residuals of every term, stacked, with their Jacobian rows. */
void
StackResiduals(const std::vector<const DataTerm *> & terms,
               const std::vector<double> &           u,
               std::vector<double> &                 r,
               ResidualJacobian *                    jacobian)
{
  r.clear();
  if (jacobian)
  {
    *jacobian = ResidualJacobian();
    jacobian->rowStart.push_back(0);
  }
  for (const DataTerm * term : terms)
  {
    std::vector<double> rt;
    ResidualJacobian    jt;
    term->EvaluateResiduals(u, rt, jacobian ? &jt : nullptr);
    r.insert(r.end(), rt.begin(), rt.end());
    if (jacobian)
    {
      const std::size_t offset = jacobian->dofs.size();
      jacobian->dofs.insert(jacobian->dofs.end(), jt.dofs.begin(), jt.dofs.end());
      jacobian->values.insert(jacobian->values.end(), jt.values.begin(), jt.values.end());
      for (std::size_t k = 1; k < jt.rowStart.size(); ++k)
      {
        jacobian->rowStart.push_back(offset + jt.rowStart[k]);
      }
    }
  }
}

/** The affine map u = u0 + A p restricted to the dofs the residuals read (rowOfDof: dof -> row of A). */
struct AffineState
{
  std::vector<double>       u0;
  Eigen::MatrixXd           A;
  std::vector<std::int32_t> rowOfDof;
};

std::vector<std::int32_t>
RowsOfDofs(const std::vector<std::int32_t> & dofs, std::size_t ndof)
{
  std::vector<std::int32_t> rowOfDof(ndof, -1);
  for (std::size_t i = 0; i < dofs.size(); ++i)
  {
    rowOfDof[dofs[i]] = static_cast<std::int32_t>(i);
  }
  return rowOfDof;
}

AffineState
LinearizeState(ForwardModel & model, const LoadParameterization & loads, const std::vector<std::int32_t> & dofs)
{
  // u = u0 + A p on the data dofs: A by columns (one solve per parameter) or, with fewer data dofs than
  // parameters, by rows through the adjoint (one solve per data dof; the same A, K being symmetric).
  AffineState        s;
  const BoundaryLoad zero = loads.Apply(std::vector<double>(loads.GetNumberOfParameters(), 0.0));
  s.u0 = model.SolveState(zero.forces, zero.prescribed);
  s.rowOfDof = RowsOfDofs(dofs, s.u0.size());
  const std::size_t np = loads.GetNumberOfParameters();
  s.A.resize(static_cast<Eigen::Index>(dofs.size()), static_cast<Eigen::Index>(np));
  if (dofs.size() < np)
  {
    // Fewer data dofs than parameters (markers): row i of A is du_i/dp, one adjoint solve per data dof.
    const std::vector<double> zero(np, 0.0);
    for (std::size_t i = 0; i < dofs.size(); ++i)
    {
      std::vector<double> g(s.u0.size(), 0.0);
      g[dofs[i]] = 1.0;
      const std::vector<double> row = PullBackThroughLoads(model, loads, zero, g, model.SolveAdjoint(g));
      for (std::size_t j = 0; j < np; ++j)
      {
        s.A(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)) = row[j];
      }
    }
    return s;
  }
  for (std::size_t j = 0; j < np; ++j)
  {
    const BoundaryLoad        direction = loads.Direction(j);
    const std::vector<double> uj = model.SolveState(direction.forces, direction.prescribed);
    for (std::size_t i = 0; i < dofs.size(); ++i)
    {
      s.A(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)) = uj[dofs[i]];
    }
  }
  return s;
}

/** du/dp on \a dofs at a nonlinear model's last equilibrium, for an affine parameterization: the tangent's
 * response to each direction's loads, \f$\Delta u = \Delta\bar u\f$ on the constrained dofs and
 * \f$K_{ff}^{-1}(\Delta f - K_T \Delta\bar u)_f\f$ on the free ones (one back-substitution per parameter on the
 * tangent's factorization, which the adjoint shares). */
Eigen::MatrixXd
TangentResponse(ForwardModel & model, const LoadParameterization & loads, const std::vector<std::int32_t> & dofs)
{
  const std::size_t ndof = 3 * model.GetMesh().GetNumberOfPoints();
  std::vector<char> constrained(ndof, 0);
  for (std::int32_t n : loads.GetConstrainedNodes())
  {
    constrained[3 * n] = constrained[3 * n + 1] = constrained[3 * n + 2] = 1;
  }
  const std::size_t np = loads.GetNumberOfParameters();
  Eigen::MatrixXd   A(static_cast<Eigen::Index>(dofs.size()), static_cast<Eigen::Index>(np));
  for (std::size_t j = 0; j < np; ++j)
  {
    const BoundaryLoad  direction = loads.Direction(j);
    std::vector<double> prescribed(ndof, 0.0), rhs(ndof, 0.0);
    for (std::size_t i = 0; i < ndof; ++i)
    {
      prescribed[i] = constrained[i] ? direction.prescribed[i] : 0.0;
    }
    const std::vector<double> Kprescribed = model.ApplyTangent(prescribed);
    for (std::size_t i = 0; i < ndof; ++i)
    {
      rhs[i] = constrained[i] ? 0.0 : (direction.forces.empty() ? 0.0 : direction.forces[i]) - Kprescribed[i];
    }
    const std::vector<double> du = model.SolveAdjoint(rhs); // K_T is symmetric
    for (std::size_t i = 0; i < dofs.size(); ++i)
    {
      A(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)) = du[dofs[i]] + prescribed[dofs[i]];
    }
  }
  return A;
}

/** The residuals SolveLoadsLevenbergMarquardt() minimizes, on the dofs they read (from their Jacobian's pattern at the
 * unloaded state), with the prior's weight. A linear model's state is affine in p: computed once. A nonlinear one
 * is solved at every p, and its derivative du/dp taken from the tangent at each point where the Jacobian is
 * needed. */
class LoadResiduals
{
public:
  LoadResiduals(ForwardModel &                        model,
                const LoadParameterization &          loads,
                const std::vector<const DataTerm *> & terms,
                const CompressionBarrier *            barrier,
                std::size_t &                         infeasible,
                std::size_t                           np)
    : m_Model(model)
    , m_Loads(loads)
    , m_Terms(terms)
    , m_Barrier(barrier)
    , m_Infeasible(infeasible)
    , m_NumberOfParameters(np)
  {
    std::vector<double> r;
    ResidualJacobian    pattern;
    StackResiduals(m_Terms, std::vector<double>(3 * m_Model.GetMesh().GetNumberOfPoints(), 0.0), r, &pattern);
    m_Dofs = UniqueNodes(pattern.dofs);
    m_Linear = m_Model.IsLinear();
    if (m_Linear)
    {
      m_State = LinearizeState(m_Model, m_Loads, m_Dofs);
    }
    else
    {
      m_State.rowOfDof = RowsOfDofs(m_Dofs, 3 * m_Model.GetMesh().GetNumberOfPoints());
    }
    // The prior's curvatures h_k from R(e_k) = h_k / 2 (exact in binary floating point): a prior without cross terms,
    // the ridge alpha/2 |p|^2 (every h_k = alpha) or a trained basis's w/2 sum p_k^2 / lambda_k.
    m_PriorCurvature.resize(static_cast<Eigen::Index>(np));
    for (std::size_t k = 0; k < np; ++k)
    {
      std::vector<double> unit(np, 0.0);
      unit[k] = 1.0;
      m_PriorCurvature[static_cast<Eigen::Index>(k)] = 2.0 * m_Loads.EvaluatePrior(unit);
    }
    m_Uniform = np == 0 || (m_PriorCurvature.array() == m_PriorCurvature[0]).all();
  }

  /** The prior's value, its gradient and its Hessian added to \a H; with equal curvatures by the ridge's formulas. */
  double
  Prior(const Eigen::VectorXd & p) const
  {
    return m_Uniform ? 0.5 * Alpha() * p.squaredNorm() : 0.5 * (m_PriorCurvature.array() * p.array().square()).sum();
  }
  Eigen::VectorXd
  PriorGradient(const Eigen::VectorXd & p) const
  {
    return m_Uniform ? Eigen::VectorXd(Alpha() * p) : Eigen::VectorXd(m_PriorCurvature.cwiseProduct(p));
  }
  void
  AddPriorHessian(Eigen::MatrixXd & H) const
  {
    if (m_Uniform)
    {
      H.diagonal().array() += Alpha();
    }
    else
    {
      H.diagonal() += m_PriorCurvature;
    }
  }

  /** Residuals r(p) and their Jacobian J = dr/du A; the prior is added to the value.
   * An infeasible p (no nonlinear state follows its loads) has an infinite value, which LM rejects. */
  double
  operator()(const Eigen::VectorXd & p, Eigen::VectorXd & rp, Eigen::MatrixXd * J)
  {
    std::vector<double> u;
    if (!StateAt(p, J != nullptr, u))
    {
      return std::numeric_limits<double>::infinity();
    }
    std::vector<double> rv;
    ResidualJacobian    jac;
    StackResiduals(m_Terms, u, rv, J ? &jac : nullptr);
    rp = Eigen::Map<const Eigen::VectorXd>(rv.data(), static_cast<Eigen::Index>(rv.size()));
    if (J)
    {
      ChainJacobian(jac, rv.size(), *J);
    }
    // The barrier (nonlinear models) enters the value that accepts or rejects a step, not the Jacobian (which
    // would need du/dp at every dof): a step that crushes elements is rejected like any rise of Phi.
    const double barrier = m_Barrier ? m_Barrier->Evaluate(u, nullptr) : 0.0;
    return 0.5 * rp.squaredNorm() + Prior(p) + barrier;
  }

private:
  /** The state \a u at \a p (and, with a nonlinear model and \a jacobian, A at it); false when p is infeasible. */
  bool
  StateAt(const Eigen::VectorXd & p, bool jacobian, std::vector<double> & u)
  {
    if (m_Linear)
    {
      const Eigen::VectorXd Ap = m_State.A * p;
      u = m_State.u0;
      for (std::size_t i = 0; i < m_Dofs.size(); ++i)
      {
        u[m_Dofs[i]] += Ap[static_cast<Eigen::Index>(i)];
      }
      return true;
    }
    const BoundaryLoad load = m_Loads.Apply(std::vector<double>(p.data(), p.data() + p.size()));
    if (!m_Model.TrySolveState(load.forces, load.prescribed, u))
    {
      ++m_Infeasible;
      return false;
    }
    if (jacobian)
    {
      m_State.A = TangentResponse(m_Model, m_Loads, m_Dofs);
    }
    return true;
  }

  /** J = dr/du A from the residuals' Jacobian \a jac (\a rows rows) and the state's A. */
  void
  ChainJacobian(const ResidualJacobian & jac, std::size_t rows, Eigen::MatrixXd & J) const
  {
    J.setZero(static_cast<Eigen::Index>(rows), static_cast<Eigen::Index>(m_NumberOfParameters));
    for (std::size_t k = 0; k < rows; ++k)
    {
      for (std::size_t e = jac.rowStart[k]; e < jac.rowStart[k + 1]; ++e)
      {
        J.row(static_cast<Eigen::Index>(k)) += jac.values[e] * m_State.A.row(m_State.rowOfDof[jac.dofs[e]]);
      }
    }
  }

  ForwardModel &                        m_Model;
  const LoadParameterization &          m_Loads;
  const std::vector<const DataTerm *> & m_Terms;
  const CompressionBarrier *            m_Barrier;
  std::size_t &                         m_Infeasible;
  std::size_t                           m_NumberOfParameters;
  std::vector<std::int32_t>             m_Dofs;
  bool                                  m_Linear{ false };
  AffineState                           m_State;
  Eigen::VectorXd                       m_PriorCurvature; ///< h_k of R(p) = 1/2 sum h_k p_k^2
  bool                                  m_Uniform{ true };

  double
  Alpha() const
  {
    return m_PriorCurvature.size() > 0 ? m_PriorCurvature[0] : 0.0;
  }
};

/** The Levenberg-Marquardt iterate: p with its residuals, Jacobian and value, and the damping mu. */
struct MarquardtIterate
{
  Eigen::VectorXd p, rp, rTry;
  Eigen::MatrixXd J;
  double          value{ 0.0 };
  double          mu{ 1e-3 };
  bool            converged{ false };
};

/** The iterate at \a start, or at zero loads when no equilibrium follows the start's. */
MarquardtIterate
StartIterate(LoadResiduals & residuals, const std::vector<double> & start)
{
  MarquardtIterate s;
  s.p = Eigen::Map<const Eigen::VectorXd>(start.data(), static_cast<Eigen::Index>(start.size()));
  s.value = residuals(s.p, s.rp, &s.J);
  if (!std::isfinite(s.value))
  {
    // No equilibrium follows the start's loads (a nonlinear model: a start carried over from another modulus or
    // scene): begin at zero loads, the unloaded state, which always is one. Without it r and J would be empty.
    s.p.setZero();
    s.value = residuals(s.p, s.rp, &s.J);
    if (!std::isfinite(s.value))
    {
      Fail("EstimationObjective::SolveLoadsLevenbergMarquardt",
           "no equilibrium at the start's loads nor at zero loads");
    }
  }
  return s;
}

/** One iteration's damped steps (H + mu diag) delta = -g, mu growing after each failure, until one decreases the
 * value (at most 30 attempts); false when none did. */
bool
TakeMarquardtStep(LoadResiduals &         residuals,
                  const Eigen::MatrixXd & H,
                  const Eigen::VectorXd & g,
                  MarquardtIterate &      s,
                  LoadSolution &          result)
{
  bool accepted = false;
  for (int attempt = 0; attempt < 30 && !accepted; ++attempt)
  {
    Eigen::MatrixXd M = H;
    // Marquardt scaling plus a floor of 1e-3 of the mean curvature: directions the objective hardly sees
    // (a wall sliding along itself) get short steps instead of huge rejected ones.
    M.diagonal().array() += s.mu * (H.diagonal().array() + 1e-3 * H.diagonal().mean());
    const Eigen::VectorXd pTry = s.p + M.ldlt().solve(-g);
    const double          valueTry = residuals(pTry, s.rTry, nullptr);
    if (valueTry < s.value)
    {
      const double decrease = s.value - valueTry;
      s.p = pTry;
      s.value = residuals(s.p, s.rp, &s.J);
      s.mu = std::max(s.mu / 3.0, 1e-9);
      accepted = true;
      if (decrease <= 1e-10 * s.value)
      {
        s.converged = true;
        result.stop = "no further decrease";
      }
    }
    else
    {
      s.mu *= 4.0;
    }
  }
  return accepted;
}
} // namespace

LoadSolution
EstimationObjective::SolveLoadsLevenbergMarquardt(const std::vector<double> & start,
                                                  unsigned int                maximumIterations,
                                                  double                      tolerance)
{
  const std::size_t np = GetNumberOfParameters();
  if (start.size() != np)
  {
    Fail("EstimationObjective::SolveLoadsLevenbergMarquardt",
         "the start holds " + std::to_string(start.size()) + " values, expected " + std::to_string(np));
  }
  if (!m_Loads.IsAffine())
  {
    Fail("EstimationObjective::SolveLoadsLevenbergMarquardt", "needs an affine load parameterization");
  }
  LoadResiduals residuals(m_Model, m_Loads, m_Terms, m_Barrier.get(), m_Infeasible, np);
  // Levenberg-Marquardt: (J^T J + mu diag(J^T J)) delta = -J^T r; mu shrinks after a success, grows after a failure.
  MarquardtIterate s = StartIterate(residuals, start);
  LoadSolution     result;
  result.stop = "maximum number of iterations";
  unsigned int it = 0;
  for (; it < maximumIterations && !s.converged; ++it)
  {
    const Eigen::VectorXd g = s.J.transpose() * s.rp + residuals.PriorGradient(s.p);
    if (g.norm() <= tolerance * std::max(1.0, s.p.norm()))
    {
      result.stop = "gradient below tolerance";
      break;
    }
    Eigen::MatrixXd H = s.J.transpose() * s.J;
    residuals.AddPriorHessian(H);
    if (!TakeMarquardtStep(residuals, H, g, s, result))
    {
      result.stop = "no descent";
      break;
    }
  }
  result.iterations = it;
  result.parameters.assign(s.p.data(), s.p.data() + np);
  result.value = Evaluate(result.parameters, &result.gradient, &result.logModulusGradient);
  return result;
}

} // namespace bmr
