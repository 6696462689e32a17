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
// LinearElasticModel's setup (materials, Dirichlet conditions, settings) and its outputs (forces, stresses).
// The system Eigen 3.4 and CHOLMOD are used only in src/fem; no ITK header that bundles ITK's own Eigen may be
// included here.
#include "bmrLinearElasticModelInternal.h"

#include "bmrStopwatch.h"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace bmr {
using Clock = SteadyClock;
using fem::ElementGradients;
using fem::LameParameters;


LinearElasticModel::LinearElasticModel(const TetrahedralMesh &                            mesh,
                                       const std::map<std::int32_t, MaterialParameters> & materials)
  : m_Impl(new Impl(mesh))
{
  for (const auto & kv : materials)
  {
    const MaterialParameters & m = kv.second;
    std::ostringstream         msg;
    msg << fem::MaterialProblem(kv.first, m.youngsModulus, m.poissonRatio);
    if (!msg.str().empty())
    {
      Fail("LinearElasticModel", msg.str());
    }
  }
  m_Impl->materials = materials;
  for (const auto & [label, material] : materials)
  {
    m_Impl->factorModuli[label] = material.youngsModulus; // what the first factorization's changes are learned from
  }
  const auto t0 = Clock::now();
  m_Impl->CheckElements();
  m_Impl->BuildPattern();
  m_Impl->constrained.assign(m_Impl->ndof, 0);
  m_Impl->prescribed.assign(m_Impl->ndof, 0.0);
  m_Impl->timings.assemble = SecondsSince(t0);
}

LinearElasticModel::~LinearElasticModel() = default;

void
LinearElasticModel::SetDirichletConditions(const std::vector<std::int32_t> & nodes, const std::vector<double> & values)
{
  Impl &            d = *m_Impl;
  const std::size_t N = d.mesh.GetNumberOfPoints();
  if (!values.empty() && values.size() != 3 * nodes.size())
  {
    Fail("LinearElasticModel::SetDirichletConditions", "expected 3 values per node or none");
  }
  d.constrained.assign(d.ndof, 0);
  d.prescribed.assign(d.ndof, 0.0);
  for (std::size_t k = 0; k < nodes.size(); ++k)
  {
    if (nodes[k] < 0 || static_cast<std::size_t>(nodes[k]) >= N)
    {
      std::ostringstream msg;
      msg << "Dirichlet node index " << nodes[k] << " is outside the mesh (" << N << " nodes)";
      Fail("LinearElasticModel::SetDirichletConditions", msg.str());
    }
    for (int c = 0; c < 3; ++c)
    {
      const double v = values.empty() ? 0.0 : values[3 * k + c];
      if (!std::isfinite(v))
      {
        std::ostringstream msg;
        msg << "prescribed displacement of node " << nodes[k] << " is not finite";
        Fail("LinearElasticModel::SetDirichletConditions", msg.str());
      }
      d.constrained[3 * nodes[k] + c] = 1;
      d.prescribed[3 * nodes[k] + c] = v;
    }
  }
  d.analyzed = false;
  d.factorized = false;
  d.hasFactor = false;
  d.couplingCurrent = false;
  d.freeBlockCurrent = false;
  d.freePatternCurrent = false;
}

void
LinearElasticModel::SetYoungsModulus(std::int32_t label, double youngsModulus)
{
  auto it = m_Impl->materials.find(label);
  if (it == m_Impl->materials.end())
  {
    Fail("LinearElasticModel::SetYoungsModulus", "label " + std::to_string(label) + " has no material");
  }
  if (!(std::isfinite(youngsModulus) && youngsModulus > 0.0))
  {
    std::ostringstream msg;
    msg << "label " << label << ": Young's modulus must be positive and finite, got " << youngsModulus << " kPa";
    Fail("LinearElasticModel::SetYoungsModulus", msg.str());
  }
  if (it->second.youngsModulus != youngsModulus)
  {
    it->second.youngsModulus = youngsModulus;
    m_Impl->valuesCurrent = false;
    m_Impl->freeBlockCurrent = false;
    m_Impl->factorized = false;
  }
}

void
LinearElasticModel::SetRefactorizationThreshold(double fraction)
{
  if (!(fraction >= 0.0 && fraction < 1.0))
  {
    std::ostringstream msg;
    msg << "the refactorization threshold must lie in [0, 1), got " << fraction;
    Fail("LinearElasticModel::SetRefactorizationThreshold", msg.str());
  }
  m_Impl->refactorizeAbove = fraction;
}

void
LinearElasticModel::SetNumberOfSolveThreads(unsigned threads)
{
  m_Impl->solveThreads = std::max(1U, threads);
}

bool
LinearElasticModel::UsesTreeCutFactorization() const
{
  return m_Impl->triangularReady && m_Impl->ownFactorization;
}

void
LinearElasticModel::SetReferenceFactorization(bool useCholmod)
{
  if (m_Impl->referenceOnly != useCholmod)
  {
    m_Impl->referenceOnly = useCholmod;
    m_Impl->triangularCut = false; // the next factorization cuts (or not) again
    m_Impl->factorized = false;
  }
}

double
LinearElasticModel::GetParallelSolveShare() const
{
  return m_Impl->triangularReady ? m_Impl->triangular.GetParallelShare() : 0.0;
}

double
LinearElasticModel::GetYoungsModulus(std::int32_t label) const
{
  auto it = m_Impl->materials.find(label);
  if (it == m_Impl->materials.end())
  {
    Fail("LinearElasticModel::GetYoungsModulus", "label " + std::to_string(label) + " has no material");
  }
  return it->second.youngsModulus;
}


std::vector<double>
LinearElasticModel::ComputeInternalForces(const std::vector<double> & u) const
{
  if (u.size() != m_Impl->ndof)
  {
    Fail("LinearElasticModel::ComputeInternalForces", "the displacement vector must hold 3 values per node");
  }
  m_Impl->UpdateValues();
  std::vector<double> y;
  m_Impl->SymmetricProduct(u, y);
  return y;
}

std::vector<double>
LinearElasticModel::ComputeCouplingForces(const std::vector<double> & v) const
{
  if (v.size() != m_Impl->ndof)
  {
    Fail("LinearElasticModel::ComputeCouplingForces", "the displacement vector must hold 3 values per node");
  }
  std::vector<double> y;
  m_Impl->CouplingProduct(v, true, y);
  return y;
}

std::vector<double>
LinearElasticModel::ComputeMaterialStiffnessProduct(std::int32_t label, const std::vector<double> & u) const
{
  if (u.size() != m_Impl->ndof)
  {
    Fail("LinearElasticModel::ComputeMaterialStiffnessProduct", "the displacement vector must hold 3 values per node");
  }
  if (m_Impl->materials.count(label) == 0)
  {
    Fail("LinearElasticModel::ComputeMaterialStiffnessProduct", "label " + std::to_string(label) + " has no material");
  }
  std::vector<double> y;
  fem::SymmetricProduct(m_Impl->pattern, m_Impl->UnitValues(label), u, y);
  return y;
}

std::vector<double>
LinearElasticModel::ComputeReactionForces(const std::vector<double> & u, const std::vector<double> & forces) const
{
  std::vector<double> r = ComputeInternalForces(u);
  for (std::size_t i = 0; i < r.size(); ++i)
  {
    r[i] = m_Impl->constrained[i] ? r[i] - (forces.empty() ? 0.0 : forces[i]) : 0.0;
  }
  return r;
}

std::vector<double>
LinearElasticModel::ComputeVonMisesStress(const std::vector<double> & u) const
{
  const TetrahedralMesh & mesh = m_Impl->mesh;
  const std::size_t       M = mesh.GetNumberOfTetrahedra();
  std::vector<double>     vm(M);
  for (std::size_t e = 0; e < M; ++e)
  {
    double g[4][3];
    ElementGradients(mesh, e, g);
    double grad[3][3] = {}; // du_i/dx_j
    for (int a = 0; a < 4; ++a)
    {
      const double * ua = &u[3 * mesh.tetrahedra[4 * e + a]];
      for (int i = 0; i < 3; ++i)
      {
        for (int j = 0; j < 3; ++j)
        {
          grad[i][j] += ua[i] * g[a][j];
        }
      }
    }
    const MaterialParameters & m = m_Impl->materials.at(mesh.labels[e]);
    double                     lambda, mu;
    LameParameters(m.youngsModulus, m.poissonRatio, lambda, mu);
    const double tr = grad[0][0] + grad[1][1] + grad[2][2];
    double       s[3][3];
    for (int i = 0; i < 3; ++i)
    {
      for (int j = 0; j < 3; ++j)
      {
        s[i][j] = mu * (grad[i][j] + grad[j][i]) + (i == j ? lambda * tr : 0.0);
      }
    }
    vm[e] = fem::VonMises(s);
  }
  return vm;
}

std::vector<double>
LinearElasticModel::GetElementYoungsModuli() const
{
  std::vector<double> E(m_Impl->mesh.GetNumberOfTetrahedra());
  for (std::size_t e = 0; e < E.size(); ++e)
  {
    E[e] = m_Impl->materials.at(m_Impl->mesh.labels[e]).youngsModulus;
  }
  return E;
}

std::vector<double>
LinearElasticModel::GetElementPoissonRatios() const
{
  std::vector<double> nu(m_Impl->mesh.GetNumberOfTetrahedra());
  for (std::size_t e = 0; e < nu.size(); ++e)
  {
    nu[e] = m_Impl->materials.at(m_Impl->mesh.labels[e]).poissonRatio;
  }
  return nu;
}

std::size_t
LinearElasticModel::GetNumberOfFreeDegreesOfFreedom() const
{
  return m_Impl->nfree;
}

const std::vector<char> &
LinearElasticModel::GetConstrainedDegreesOfFreedom() const
{
  return m_Impl->constrained;
}

const SolverTimings &
LinearElasticModel::GetTimings() const
{
  return m_Impl->timings;
}

} // namespace bmr
