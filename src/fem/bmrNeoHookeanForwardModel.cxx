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
// NeoHookeanForwardModel's setup (materials, geometry, pattern) and interface (state solve, adjoint, stresses).
// The system Eigen 3.4 and CHOLMOD are used only in src/fem; no ITK header that bundles ITK's own Eigen may
// be included here.
#include "bmrNeoHookeanForwardModelInternal.h"

#include "bmrError.h"
#include "bmrStopwatch.h"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace bmr {
using neohookean::kWho;

// ---------------------------------------------------------------------------------------------- setup

NeoHookeanForwardModel::Impl::Impl(const TetrahedralMesh &                            m,
                                   const std::map<std::int32_t, MaterialParameters> & mats,
                                   const NewtonSettings &                             s)
  : mesh(m)
  , materials(mats)
  , settings(s)
  , ndof(3 * m.GetNumberOfPoints())
{
  ValidateMaterials();
  for (std::size_t e = 0; e < mesh.GetNumberOfTetrahedra(); ++e)
  {
    if (materials.find(mesh.labels[e]) == materials.end())
    {
      std::ostringstream msg;
      msg << "element " << e << " has label " << mesh.labels[e] << ", which has no material (E, nu) in the scene";
      Fail(kWho, msg.str());
    }
  }
  ValidateMesh(mesh);
  ComputeGeometry();
  UpdateLameParameters();
  BuildPatternAndEntries();
  constrained.assign(ndof, 0);
  passive.assign(mesh.GetNumberOfTetrahedra(), 0);
  // A tangent that is not positive definite is expected (and shifted) here: no CHOLMOD warning on stdout.
  solver.cholmod().print = 0;
}

void
NeoHookeanForwardModel::Impl::ValidateMaterials() const
{
  for (const auto & kv : materials)
  {
    const MaterialParameters & m = kv.second;
    std::ostringstream         msg;
    msg << fem::MaterialProblem(kv.first, m.youngsModulus, m.poissonRatio);
    if (msg.str().empty() && m.formulation != ElementFormulationEnum::Standard)
    {
      msg << "label " << kv.first << ": the neo-Hookean model has only the standard P1 formulation (got "
          << m.formulation << "); use the linear model for the nodal-averaged pressure";
    }
    if (!msg.str().empty())
    {
      Fail(kWho, msg.str());
    }
  }
  if (!(settings.residualTolerance > 0.0 && settings.energyTolerance >= 0.0 && settings.maximumIterations > 0 &&
        settings.initialIncrement > 0.0 && settings.initialIncrement <= 1.0 && settings.minimumIncrement > 0.0 &&
        settings.minimumIncrement <= settings.initialIncrement))
  {
    Fail(kWho, "Newton settings out of range (tolerances > 0, 0 < minimum increment <= initial increment <= 1)");
  }
}

void
NeoHookeanForwardModel::Impl::ComputeGeometry()
{
  const std::size_t M = mesh.GetNumberOfTetrahedra();
  gradients.resize(M);
  volumes.resize(M);
  for (std::size_t e = 0; e < M; ++e)
  {
    double g[4][3];
    volumes[e] = fem::ElementGradients(mesh, e, g);
    std::copy(&g[0][0], &g[0][0] + 12, gradients[e].begin());
  }
}

void
NeoHookeanForwardModel::Impl::UpdateLameParameters()
{
  const std::size_t M = mesh.GetNumberOfTetrahedra();
  mu.resize(M);
  lambda.resize(M);
  for (std::size_t e = 0; e < M; ++e)
  {
    const MaterialParameters & m = materials.at(mesh.labels[e]);
    fem::LameParameters(m.youngsModulus, m.poissonRatio, lambda[e], mu[e]);
  }
}

void
NeoHookeanForwardModel::Impl::BuildPatternAndEntries()
{
  fem::NodeAdjacency upper = fem::ElementNodeAdjacency(mesh);
  fem::SortAdjacencyAndCheckNodesUsed(upper, kWho);
  pattern = fem::BuildColumnPattern(upper);
  const std::size_t M = mesh.GetNumberOfTetrahedra();
  elementEntries.assign(144 * M, -1);
  for (std::size_t e = 0; e < M; ++e)
  {
    const std::int32_t * t = &mesh.tetrahedra[4 * e];
    for (int a = 0; a < 4; ++a)
    {
      for (int b = 0; b < 4; ++b)
      {
        for (int i = 0; i < 3; ++i)
        {
          for (int k = 0; k < 3; ++k)
          {
            const std::size_t row = 3 * static_cast<std::size_t>(t[a]) + i;
            const std::size_t col = 3 * static_cast<std::size_t>(t[b]) + k;
            if (row >= col)
            {
              elementEntries[144 * e + 12 * (3 * a + i) + 3 * b + k] =
                static_cast<std::int64_t>(pattern.EntryIndex(row, col));
            }
          }
        }
      }
    }
  }
  tangent.assign(pattern.Size(), 0.0);
}

// ------------------------------------------------------------------------------------------- interface

NeoHookeanForwardModel::NeoHookeanForwardModel(const TetrahedralMesh &                            mesh,
                                               const std::map<std::int32_t, MaterialParameters> & materials,
                                               const NewtonSettings &                             settings)
  : m_Impl(new Impl(mesh, materials, settings))
{
  m_Impl->AssembleTangent(std::vector<double>(m_Impl->ndof, 0.0));
}

NeoHookeanForwardModel::~NeoHookeanForwardModel() = default;

const TetrahedralMesh &
NeoHookeanForwardModel::GetMesh() const
{
  return m_Impl->mesh;
}

void
NeoHookeanForwardModel::SetConstrainedNodes(const std::vector<std::int32_t> & nodes)
{
  Impl &            d = *m_Impl;
  const std::size_t N = d.mesh.GetNumberOfPoints();
  d.constrained.assign(d.ndof, 0);
  for (std::int32_t n : nodes)
  {
    if (n < 0 || static_cast<std::size_t>(n) >= N)
    {
      Fail(kWho,
           "constrained node index " + std::to_string(n) + " is outside the mesh (" + std::to_string(N) + " nodes)");
    }
    d.constrained[3 * n] = d.constrained[3 * n + 1] = d.constrained[3 * n + 2] = 1;
  }
  fem::CheckRigidBodyModes(d.mesh, d.constrained, kWho);
  for (std::size_t e = 0; e < d.passive.size(); ++e)
  {
    const std::int32_t * t = &d.mesh.tetrahedra[4 * e];
    d.passive[e] =
      d.constrained[3 * t[0]] && d.constrained[3 * t[1]] && d.constrained[3 * t[2]] && d.constrained[3 * t[3]];
  }
  d.nfree = fem::NumberFreeDofs(d.constrained, d.freeIndex);
  d.Kff = fem::FreeBlock(d.pattern, d.tangent, d.freeIndex, d.nfree, &d.freePositions);
  d.freeDiagonal.clear();
  for (std::size_t i = 0; i < d.ndof; ++i)
  {
    if (d.freeIndex[i] >= 0)
    {
      d.freeDiagonal.push_back(d.freePositions[d.pattern.EntryIndex(i, i)]);
    }
  }
  d.analyzed = false;
  d.haveFactorization = d.factorizationExact = d.refactorNext = false;
  d.hasState = false;
}

void
NeoHookeanForwardModel::SetYoungsModulus(std::int32_t label, double youngsModulus)
{
  auto it = m_Impl->materials.find(label);
  if (it == m_Impl->materials.end())
  {
    Fail(kWho, "label " + std::to_string(label) + " has no material");
  }
  if (!(std::isfinite(youngsModulus) && youngsModulus > 0.0))
  {
    std::ostringstream msg;
    msg << "label " << label << ": Young's modulus must be positive and finite, got " << youngsModulus << " kPa";
    Fail(kWho, msg.str());
  }
  if (it->second.youngsModulus != youngsModulus)
  {
    it->second.youngsModulus = youngsModulus;
    m_Impl->UpdateLameParameters();
    m_Impl->AssembleTangent(m_Impl->hasState ? m_Impl->state : std::vector<double>(m_Impl->ndof, 0.0));
  }
}

double
NeoHookeanForwardModel::GetYoungsModulus(std::int32_t label) const
{
  auto it = m_Impl->materials.find(label);
  if (it == m_Impl->materials.end())
  {
    Fail(kWho, "label " + std::to_string(label) + " has no material");
  }
  return it->second.youngsModulus;
}

std::vector<double>
NeoHookeanForwardModel::SolveState(const std::vector<double> & forces, const std::vector<double> & prescribed)
{
  std::vector<double> u;
  if (!TrySolveState(forces, prescribed, u))
  {
    Fail(kWho, m_Impl->lastFailure);
  }
  return u;
}

bool
NeoHookeanForwardModel::TrySolveState(const std::vector<double> & forces,
                                      const std::vector<double> & prescribed,
                                      std::vector<double> &       u)
{
  Impl & d = *m_Impl;
  if ((!forces.empty() && forces.size() != d.ndof) || prescribed.size() != d.ndof)
  {
    Fail(kWho, "the force and prescribed displacement vectors must hold 3 values per node");
  }
  const auto          start = SteadyClock::now();
  std::vector<double> f1(d.ndof, 0.0), g1(d.ndof, 0.0);
  for (std::size_t i = 0; i < d.ndof; ++i)
  {
    const double value = d.constrained[i] ? prescribed[i] : (forces.empty() ? 0.0 : forces[i]);
    if (!std::isfinite(value))
    {
      Fail(kWho, "load at degree of freedom " + std::to_string(i) + " is not finite");
    }
    (d.constrained[i] ? g1 : f1)[i] = value;
  }
  d.earlierWork = d.Work();
  ++d.earlierWork.stateSolves;
  d.statistics = NewtonStatistics();
  Impl::IncrementFailure failure;
  double                 reached = 0.0;
  bool                   ok = false;
  if (d.hasState)
  {
    u = d.state;
    d.statistics.warmStart = true;
    ok = d.FollowPath(u, d.stateForces, d.statePrescribed, f1, g1, reached, failure);
  }
  if (!ok && (!d.hasState || d.settings.restartFromRest))
  {
    d.earlierWork.coldStarts += d.hasState; // a warm start was tried and failed
    d.statistics.warmStart = false;
    u.assign(d.ndof, 0.0);
    const std::vector<double> zero(d.ndof, 0.0);
    ok = d.FollowPath(u, zero, zero, f1, g1, reached, failure);
  }
  d.statistics.seconds = SecondsSince(start);
  if (!ok)
  {
    std::ostringstream msg;
    msg << "the loads could not be applied: equilibrium reached up to load fraction " << reached << " of 1, then "
        << failure.reason << " (smallest J " << failure.worstJ << " in element " << failure.worstElement;
    if (failure.worstElement >= 0)
    {
      // Which element, and whether its free nodes could have saved it: what a user needs to change the loads.
      const std::int32_t * t = &d.mesh.tetrahedra[4 * failure.worstElement];
      int                  prescribedNodes = 0;
      for (int a = 0; a < 4; ++a)
      {
        prescribedNodes += d.constrained[3 * t[a]];
      }
      msg << ", label " << d.mesh.labels[failure.worstElement] << ", " << prescribedNodes
          << " of its 4 nodes prescribed";
    }
    msg << ") with increments down to " << d.settings.minimumIncrement;
    d.lastFailure = msg.str();
    if (d.hasState)
    {
      d.AssembleTangent(d.state); // the tangent belongs to the last equilibrium again
    }
    return false;
  }
  d.state = u;
  d.stateForces = f1;
  d.statePrescribed = g1;
  d.hasState = true;
  d.AssembleTangent(u);
  return true;
}

std::vector<double>
NeoHookeanForwardModel::SolveAdjoint(const std::vector<double> & g)
{
  Impl & d = *m_Impl;
  if (g.size() != d.ndof)
  {
    Fail(kWho, "the adjoint right-hand side must hold 3 values per node");
  }
  if (!d.hasState)
  {
    Fail(kWho, "SolveAdjoint() needs an equilibrium: call SolveState() first");
  }
  if (d.nfree == 0)
  {
    return std::vector<double>(d.ndof, 0.0);
  }
  std::vector<double> lambda;
  d.SolveTangent(g, lambda, true);
  return lambda;
}

std::vector<double>
NeoHookeanForwardModel::ApplyTangent(const std::vector<double> & v) const
{
  if (v.size() != m_Impl->ndof)
  {
    Fail(kWho, "the vector must hold 3 values per node");
  }
  std::vector<double> y;
  fem::SymmetricProduct(m_Impl->pattern, m_Impl->tangent, v, y);
  return y;
}

std::vector<double>
NeoHookeanForwardModel::InternalForces(const std::vector<double> & u) const
{
  if (u.size() != m_Impl->ndof)
  {
    Fail(kWho, "the displacement vector must hold 3 values per node");
  }
  return m_Impl->Forces(u);
}

std::vector<double>
NeoHookeanForwardModel::ModulusDerivative(std::int32_t label, const std::vector<double> & u) const
{
  if (u.size() != m_Impl->ndof)
  {
    Fail(kWho, "the displacement vector must hold 3 values per node");
  }
  std::vector<double> f = m_Impl->Forces(u, label);
  const double        E = GetYoungsModulus(label);
  for (double & x : f)
  {
    x /= E;
  }
  return f;
}

double
NeoHookeanForwardModel::StoredEnergy(const std::vector<double> & u) const
{
  if (u.size() != m_Impl->ndof)
  {
    Fail(kWho, "the displacement vector must hold 3 values per node");
  }
  return m_Impl->Energy(u);
}

std::vector<double>
NeoHookeanForwardModel::FirstPiolaKirchhoffStress(const std::vector<double> & u) const
{
  const Impl & d = *m_Impl;
  if (u.size() != d.ndof)
  {
    Fail(kWho, "the displacement vector must hold 3 values per node");
  }
  std::vector<double> stress(9 * d.volumes.size());
  for (std::size_t e = 0; e < d.volumes.size(); ++e)
  {
    fem::ElementDeformation def;
    if (!d.Deform(e, u, def))
    {
      Fail(kWho, "element " + std::to_string(e) + " is inverted: no stress");
    }
    fem::FirstPiolaStress(def, d.mu[e], d.lambda[e], reinterpret_cast<double(*)[3]>(&stress[9 * e]));
  }
  return stress;
}

std::vector<double>
NeoHookeanForwardModel::VonMisesStress(const std::vector<double> & u) const
{
  return NeoHookeanVonMisesStress(m_Impl->mesh, m_Impl->materials, u);
}

std::vector<double>
NeoHookeanVonMisesStress(const TetrahedralMesh &                            mesh,
                         const std::map<std::int32_t, MaterialParameters> & materials,
                         const std::vector<double> &                        u)
{
  if (u.size() != 3 * mesh.GetNumberOfPoints())
  {
    Fail(kWho, "the displacement vector must hold 3 values per node");
  }
  std::vector<double> vonMises(mesh.GetNumberOfTetrahedra(), 0.0);
  for (std::size_t e = 0; e < vonMises.size(); ++e)
  {
    double                  g[4][3], mu, lambda, P[3][3], sigma[3][3];
    const std::int32_t *    t = &mesh.tetrahedra[4 * e];
    const double * const    ua[4] = { &u[3 * t[0]], &u[3 * t[1]], &u[3 * t[2]], &u[3 * t[3]] };
    fem::ElementDeformation def;
    fem::ElementGradients(mesh, e, g);
    if (!fem::DeformElement(g, ua, def))
    {
      continue; // 0: an element inverted by prescribed motion alone (see the class documentation)
    }
    const MaterialParameters & m = materials.at(mesh.labels[e]);
    fem::LameParameters(m.youngsModulus, m.poissonRatio, lambda, mu);
    fem::FirstPiolaStress(def, mu, lambda, P);
    for (int i = 0; i < 3; ++i)
    {
      for (int j = 0; j < 3; ++j)
      {
        sigma[i][j] = (P[i][0] * def.F[j][0] + P[i][1] * def.F[j][1] + P[i][2] * def.F[j][2]) / def.J;
      }
    }
    vonMises[e] = fem::VonMises(sigma);
  }
  return vonMises;
}

void
NeoHookeanForwardModel::ForgetState()
{
  // The factorization too: it preconditions the next solves, whose last bits would depend on it.
  m_Impl->hasState = false;
  m_Impl->haveFactorization = m_Impl->factorizationExact = m_Impl->refactorNext = false;
}

const std::string &
NeoHookeanForwardModel::GetLastFailure() const
{
  return m_Impl->lastFailure;
}

const NewtonStatistics &
NeoHookeanForwardModel::GetStatistics() const
{
  return m_Impl->statistics;
}

SolverWork
NeoHookeanForwardModel::GetSolverWork() const
{
  return m_Impl->Work();
}

} // namespace bmr
