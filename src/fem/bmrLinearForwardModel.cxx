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
#include "bmrForwardModel.h"

#include <ostream>

namespace bmr {

std::ostream &
operator<<(std::ostream & os, ElementFormulationEnum value)
{
  switch (value)
  {
    case ElementFormulationEnum::Standard:
      return os << "bmr::ElementFormulationEnum::Standard";
    case ElementFormulationEnum::NodalAveragedPressure:
      return os << "bmr::ElementFormulationEnum::NodalAveragedPressure";
  }
  return os << "INVALID VALUE FOR bmr::ElementFormulationEnum";
}

LinearForwardModel::LinearForwardModel(const TetrahedralMesh &                            mesh,
                                       const std::map<std::int32_t, MaterialParameters> & materials)
  : m_Mesh(mesh)
  , m_Model(new LinearElasticModel(mesh, materials))
{}

LinearForwardModel::~LinearForwardModel() = default;

void
LinearForwardModel::SetConstrainedNodes(const std::vector<std::int32_t> & nodes)
{
  m_Model->SetDirichletConditions(nodes, {});
}

void
LinearForwardModel::SetYoungsModulus(std::int32_t label, double youngsModulus)
{
  m_Model->SetYoungsModulus(label, youngsModulus);
}

void
LinearForwardModel::Prepare()
{
  m_Model->Analyze();
}

void
LinearForwardModel::PrepareSolves()
{
  m_Model->Factorize();
}

void
LinearForwardModel::SetNumberOfSolveThreads(unsigned threads)
{
  m_Model->SetNumberOfSolveThreads(threads);
}

double
LinearForwardModel::GetYoungsModulus(std::int32_t label) const
{
  return m_Model->GetYoungsModulus(label);
}

std::vector<double>
LinearForwardModel::SolveState(const std::vector<double> & forces, const std::vector<double> & prescribed)
{
  ++m_Work.stateSolves;
  return m_Model->Solve(forces, prescribed);
}

std::vector<double>
LinearForwardModel::SolveAdjoint(const std::vector<double> & g)
{
  // K is symmetric: the adjoint system is the state system with zero prescribed values.
  return m_Model->Solve(g, std::vector<double>(g.size(), 0.0));
}

bool
LinearForwardModel::TrySolveObservedState(const std::vector<double> &       forces,
                                          const std::vector<double> &       prescribed,
                                          const std::vector<std::int32_t> & observedDofs,
                                          std::vector<double> &             u)
{
  ++m_Work.stateSolves;
  u = m_Model->Solve(forces, prescribed, observedDofs);
  return true;
}

std::vector<double>
LinearForwardModel::SolveObservedAdjoint(const std::vector<double> & g, const std::vector<std::int32_t> & observedDofs)
{
  return m_Model->Solve(g, std::vector<double>(g.size(), 0.0), observedDofs);
}

std::vector<std::int32_t>
LinearForwardModel::CoupledFreeDofs(const std::vector<std::int32_t> & nodes) const
{
  return m_Model->GetCoupledFreeDegreesOfFreedom(nodes);
}

std::vector<double>
LinearForwardModel::ApplyTangent(const std::vector<double> & v) const
{
  return m_Model->ComputeInternalForces(v);
}

std::vector<double>
LinearForwardModel::ApplyTangentAtConstrained(const std::vector<double> & v) const
{
  return m_Model->ComputeCouplingForces(v);
}

std::vector<double>
LinearForwardModel::InternalForces(const std::vector<double> & u) const
{
  return m_Model->ComputeInternalForces(u);
}

std::vector<double>
LinearForwardModel::ModulusDerivative(std::int32_t label, const std::vector<double> & u) const
{
  return m_Model->ComputeMaterialStiffnessProduct(label, u);
}

} // namespace bmr
