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
#include "bmrTrainedWallLoads.h"

#include "bmrError.h"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <map>
#include <set>

namespace bmr {

struct TrainedWallLoads::Impl
{
  std::vector<std::int32_t> heldNodes, controlNodes, constrainedNodes;
  std::vector<double>       basePrescribed; // 3N: the held values, 0 elsewhere
  std::vector<double>       forces;
  TransferredWallBasis      basis; // at the control nodes, 3 values per node
  double                    priorWeight{ 0.25 };

  std::size_t
  Modes() const
  {
    return basis.modes.size();
  }
  /** \a prescribed with the control nodes set to mean + sum_k p_k psi_k (when \a withMean, else without the mean). */
  void
  SetWalls(std::vector<double> & prescribed, const std::vector<double> & p, bool withMean) const
  {
    for (std::size_t i = 0; i < controlNodes.size(); ++i)
    {
      for (int c = 0; c < 3; ++c)
      {
        const std::size_t local = 3 * i + c;
        double            d = withMean ? basis.mean[local] : 0.0;
        for (std::size_t k = 0; k < p.size(); ++k)
        {
          d += p[k] * basis.modes[k][local];
        }
        prescribed[3 * static_cast<std::size_t>(controlNodes[i]) + c] = d;
      }
    }
  }
};

namespace {
/** The walls' nodes that are not held, sorted, and the index of each one's wall in \a basis. */
void
ControlNodesOnBasis(const std::vector<LoadedWall> & walls,
                    const std::vector<char> &       held,
                    const WallMotionBasis &         basis,
                    std::vector<std::int32_t> &     nodes,
                    std::vector<std::int32_t> &     basisWalls)
{
  std::map<std::int32_t, std::int32_t> wallOfNode; // a node on two walls belongs to the first, as in WallAtlas()
  for (const LoadedWall & wall : walls)
  {
    const auto it = std::find(basis.walls.begin(), basis.walls.end(), wall.name);
    if (it == basis.walls.end())
    {
      FailInput("TrainedWallLoads", "the wall motion basis has no wall \"" + wall.name + "\"");
    }
    for (std::int32_t n : wall.nodes)
    {
      if (!held[n])
      {
        wallOfNode.emplace(n, static_cast<std::int32_t>(it - basis.walls.begin()));
      }
    }
  }
  for (const auto & kv : wallOfNode)
  {
    nodes.push_back(kv.first);
    basisWalls.push_back(kv.second);
  }
}
/** \a walls in the order of \a basis's walls (each found by name; ControlNodesOnBasis() refuses a missing one). */
std::vector<LoadedWall>
InBasisOrder(const std::vector<LoadedWall> & walls, const WallMotionBasis & basis)
{
  std::vector<LoadedWall> ordered;
  for (const std::string & name : basis.walls)
  {
    const auto it = std::find_if(walls.begin(), walls.end(), [&](const LoadedWall & w) { return w.name == name; });
    if (it == walls.end())
    {
      FailInput("TrainedWallLoads", "the scene has no loaded wall \"" + name + "\" of the wall motion basis");
    }
    ordered.push_back(*it);
  }
  return ordered;
}
} // namespace

TrainedWallLoads::TrainedWallLoads(const TetrahedralMesh &           mesh,
                                   const std::vector<std::int32_t> & heldNodes,
                                   const std::vector<double> &       heldValues,
                                   std::vector<double>               forces,
                                   const std::vector<LoadedWall> &   walls,
                                   const WallMotionBasis &           basis,
                                   std::size_t                       modes,
                                   double                            priorWeight)
  : m_Impl(new Impl)
{
  Impl &            d = *m_Impl;
  const std::size_t N = mesh.GetNumberOfPoints();
  if (heldValues.size() != 3 * heldNodes.size() || !(forces.empty() || forces.size() == 3 * N))
  {
    FailInput("TrainedWallLoads", "expected 3 held values per held node and 3 forces per mesh node");
  }
  if (!(priorWeight > 0.0 && std::isfinite(priorWeight)))
  {
    FailInput("TrainedWallLoads", "the prior weight must be positive and finite [mm^2]");
  }
  basis.Validate();
  d.heldNodes = heldNodes;
  d.forces = std::move(forces);
  d.priorWeight = priorWeight;
  d.basePrescribed.assign(3 * N, 0.0);
  std::vector<char> held(N, 0);
  for (std::size_t k = 0; k < heldNodes.size(); ++k)
  {
    held[heldNodes[k]] = 1;
    std::copy_n(&heldValues[3 * k], 3, &d.basePrescribed[3 * static_cast<std::size_t>(heldNodes[k])]);
  }
  std::vector<std::int32_t> basisWalls;
  ControlNodesOnBasis(walls, held, basis, d.controlNodes, basisWalls);
  if (d.controlNodes.empty())
  {
    FailInput("TrainedWallLoads", "the loaded walls have no node that is not held");
  }
  std::vector<double> points;
  for (std::int32_t n : d.controlNodes)
  {
    points.insert(points.end(), &mesh.points[3 * static_cast<std::size_t>(n)], &mesh.points[3 * n + 3]);
  }
  // The atlas fitted to this mesh's walls gives the correspondence (on the atlas's own mesh it stays put).
  const std::vector<double> fitted = FitAtlasToWalls(basis, WallAtlas(mesh, InBasisOrder(walls, basis)));
  d.basis = TransferWallMotionBasis(basis, modes == 0 ? basis.GetNumberOfModes() : modes, points, basisWalls, &fitted);
  std::set<std::int32_t> constrained(heldNodes.begin(), heldNodes.end());
  constrained.insert(d.controlNodes.begin(), d.controlNodes.end());
  d.constrainedNodes.assign(constrained.begin(), constrained.end());
}

TrainedWallLoads::~TrainedWallLoads() = default;

std::size_t
TrainedWallLoads::GetNumberOfParameters() const
{
  return m_Impl->Modes();
}

const std::vector<std::int32_t> &
TrainedWallLoads::GetConstrainedNodes() const
{
  return m_Impl->constrainedNodes;
}

const std::vector<std::int32_t> &
TrainedWallLoads::GetHeldNodes() const
{
  return m_Impl->heldNodes;
}

BoundaryLoad
TrainedWallLoads::Apply(const std::vector<double> & p) const
{
  if (p.size() != GetNumberOfParameters())
  {
    Fail("TrainedWallLoads::Apply", "expected one parameter per mode");
  }
  BoundaryLoad load{ m_Impl->forces, m_Impl->basePrescribed };
  m_Impl->SetWalls(load.prescribed, p, true);
  return load;
}

BoundaryLoad
TrainedWallLoads::Direction(std::size_t j) const
{
  std::vector<double> unit(GetNumberOfParameters(), 0.0);
  unit.at(j) = 1.0;
  BoundaryLoad direction{ {}, std::vector<double>(m_Impl->basePrescribed.size(), 0.0) };
  m_Impl->SetWalls(direction.prescribed, unit, false);
  return direction;
}

std::vector<double>
TrainedWallLoads::PullBackGradient(const std::vector<double> & p,
                                   const std::vector<double> & prescribedSensitivity,
                                   const std::vector<double> &) const
{
  const Impl &        d = *m_Impl;
  std::vector<double> gradient(d.Modes(), 0.0);
  for (std::size_t k = 0; k < d.Modes(); ++k)
  {
    for (std::size_t i = 0; i < d.controlNodes.size(); ++i)
    {
      for (int c = 0; c < 3; ++c)
      {
        gradient[k] +=
          d.basis.modes[k][3 * i + c] * prescribedSensitivity[3 * static_cast<std::size_t>(d.controlNodes[i]) + c];
      }
    }
    gradient[k] += d.priorWeight * p[k] / d.basis.variances[k];
  }
  return gradient;
}

double
TrainedWallLoads::EvaluatePrior(const std::vector<double> & p) const
{
  double sum = 0.0;
  for (std::size_t k = 0; k < p.size(); ++k)
  {
    sum += p[k] * p[k] / m_Impl->basis.variances[k];
  }
  return 0.5 * m_Impl->priorWeight * sum;
}

std::vector<double>
TrainedWallLoads::FitDisplacement(const std::vector<double> & u) const
{
  const Impl &      d = *m_Impl;
  const auto        K = static_cast<Eigen::Index>(d.Modes());
  const std::size_t n3 = 3 * d.controlNodes.size();
  Eigen::MatrixXd   Psi(n3, K);
  Eigen::VectorXd   residual(n3);
  for (std::size_t i = 0; i < d.controlNodes.size(); ++i)
  {
    for (int c = 0; c < 3; ++c)
    {
      residual[3 * i + c] = u[3 * static_cast<std::size_t>(d.controlNodes[i]) + c] - d.basis.mean[3 * i + c];
    }
  }
  for (Eigen::Index k = 0; k < K; ++k)
  {
    Psi.col(k) = Eigen::Map<const Eigen::VectorXd>(d.basis.modes[k].data(), n3);
  }
  // The normal equations of the least squares with the prior: (Psi^T Psi + w diag(1/lambda)) p = Psi^T (u - mean).
  Eigen::MatrixXd normal = Psi.transpose() * Psi;
  for (Eigen::Index k = 0; k < K; ++k)
  {
    normal(k, k) += d.priorWeight / d.basis.variances[k];
  }
  const Eigen::VectorXd p = normal.ldlt().solve(Psi.transpose() * residual);
  return { p.data(), p.data() + K };
}

std::vector<double>
TrainedWallLoads::BoundaryForces(const std::vector<double> & internal) const
{
  return ReactionForcesAt(m_Impl->controlNodes, internal, m_Impl->forces);
}

const std::vector<std::int32_t> &
TrainedWallLoads::GetControlNodes() const
{
  return m_Impl->controlNodes;
}

const std::vector<double> &
TrainedWallLoads::GetTransferDistances() const
{
  return m_Impl->basis.distances;
}

} // namespace bmr
