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
// LinearElasticModel's assembly: the stiffness pattern and the per-label unit stiffnesses on it.
#include "bmrLinearElasticModelInternal.h"

#include "bmrStopwatch.h"

#include <algorithm>
#include <set>
#include <sstream>
#include <utility>

namespace bmr {
using Clock = SteadyClock;
using fem::ElementGradients;
using fem::LameParameters;

void
LinearElasticModel::Impl::CheckElements() const
{
  const std::size_t M = mesh.GetNumberOfTetrahedra();
  for (std::size_t e = 0; e < M; ++e)
  {
    const std::int32_t label = mesh.labels[e];
    if (materials.find(label) == materials.end())
    {
      std::ostringstream msg;
      msg << "element " << e << " has label " << label << ", which has no material (E, nu) in the scene";
      Fail("LinearElasticModel", msg.str());
    }
  }
  ValidateMesh(mesh);
}

auto
LinearElasticModel::Impl::BuildAveragingPatches() const -> std::vector<AveragingPatch>
{
  std::vector<AveragingPatch> patches;
  const std::size_t           M = mesh.GetNumberOfTetrahedra();
  // Elements of averaged materials around every node, in element order (deterministic).
  std::vector<std::vector<std::int32_t>> around(mesh.GetNumberOfPoints());
  for (std::size_t e = 0; e < M; ++e)
  {
    if (materials.at(mesh.labels[e]).formulation == ElementFormulationEnum::NodalAveragedPressure)
    {
      for (int a = 0; a < 4; ++a)
      {
        around[mesh.tetrahedra[4 * e + a]].push_back(static_cast<std::int32_t>(e));
      }
    }
  }
  for (const auto & elements : around)
  {
    // One patch per material present around the node (interfaces keep the materials apart).
    std::set<std::int32_t> labels;
    for (std::int32_t e : elements)
    {
      labels.insert(mesh.labels[e]);
    }
    for (std::int32_t label : labels)
    {
      AveragingPatch patch;
      patch.label = label;
      for (std::int32_t e : elements)
      {
        if (mesh.labels[e] == label)
        {
          patch.elements.push_back(e);
          patch.nodes.insert(patch.nodes.end(), &mesh.tetrahedra[4 * e], &mesh.tetrahedra[4 * e] + 4);
        }
      }
      std::sort(patch.nodes.begin(), patch.nodes.end());
      patch.nodes.erase(std::unique(patch.nodes.begin(), patch.nodes.end()), patch.nodes.end());
      patches.push_back(std::move(patch));
    }
  }
  return patches;
}

// Nodal-averaged pressure: the volumetric strain of a (node, material) pair averages the elements of that
// material around the node, which couples every pair of nodes of that patch.
void
LinearElasticModel::Impl::AddPatchNodeCouplings(const std::vector<AveragingPatch> & patches, NodeAdjacency & upper)
{
  for (const AveragingPatch & patch : patches)
  {
    for (std::int32_t a : patch.nodes)
    {
      for (std::int32_t b : patch.nodes)
      {
        if (b >= a)
        {
          upper[a].push_back(b);
        }
      }
    }
  }
}

// Unit-modulus element stiffnesses accumulated per label on the shared pattern.
void
LinearElasticModel::Impl::AccumulateUnitElementStiffnesses()
{
  const std::size_t M = mesh.GetNumberOfTetrahedra();
  for (const auto & kv : materials)
  {
    unitValues[kv.first].assign(pattern.Size(), 0.0);
  }
  for (std::size_t e = 0; e < M; ++e)
  {
    double                     g[4][3];
    const double               V = ElementGradients(mesh, e, g);
    double                     lambda, mu;
    const MaterialParameters & material = materials.at(mesh.labels[e]);
    LameParameters(1.0, material.poissonRatio, lambda, mu);
    if (material.formulation == ElementFormulationEnum::NodalAveragedPressure)
    {
      // Deviatoric part only (lambda -> -2 mu / 3); the bulk part kappa comes from the nodal patches below.
      lambda = -2.0 * mu / 3.0;
    }
    std::vector<double> & vals = unitValues[mesh.labels[e]];
    const std::int32_t *  t = &mesh.tetrahedra[4 * e];
    for (int a = 0; a < 4; ++a)
    {
      for (int b = 0; b < 4; ++b)
      {
        // Only the lower triangle is stored: node blocks with t[a] >= t[b], and i >= j on the diagonal block.
        const auto m = static_cast<std::size_t>(t[a]), n = static_cast<std::size_t>(t[b]);
        if (m < n)
        {
          continue;
        }
        const std::size_t offset = pattern.NodeBlockOffset(m, n);
        const double      gab = g[a][0] * g[b][0] + g[a][1] * g[b][1] + g[a][2] * g[b][2];
        for (int i = 0; i < 3; ++i)
        {
          for (int j = 0; j < 3; ++j)
          {
            if (m == n && i < j)
            {
              continue;
            }
            const double kij = V * (lambda * g[a][i] * g[b][j] + mu * g[a][j] * g[b][i] + (i == j ? mu * gab : 0.0));
            vals[pattern.NodeBlockEntry(offset, n, i, j)] += kij;
          }
        }
      }
    }
  }
}

// Bulk part of the averaged materials: kappa V_p gbar gbar^T per patch p, with the averaged divergence
// operator gbar = sum_e (V_e / 4) g_e / V_p and V_p = sum_e V_e / 4 over the patch's elements.
void
LinearElasticModel::Impl::AccumulateAveragedBulkStiffnesses(const std::vector<AveragingPatch> & patches)
{
  for (const AveragingPatch & patch : patches)
  {
    const double        kappa = 1.0 / (3.0 * (1.0 - 2.0 * materials.at(patch.label).poissonRatio)); // unit E
    std::vector<double> gbar(3 * patch.nodes.size(), 0.0);
    double              volume = 0.0;
    for (std::int32_t e : patch.elements)
    {
      double       g[4][3];
      const double V = ElementGradients(mesh, static_cast<std::size_t>(e), g);
      volume += 0.25 * V;
      for (int a = 0; a < 4; ++a)
      {
        const auto k = static_cast<std::size_t>(
          std::lower_bound(patch.nodes.begin(), patch.nodes.end(), mesh.tetrahedra[4 * e + a]) - patch.nodes.begin());
        for (int i = 0; i < 3; ++i)
        {
          gbar[3 * k + i] += 0.25 * V * g[a][i];
        }
      }
    }
    for (double & x : gbar)
    {
      x /= volume;
    }
    std::vector<double> & vals = unitValues[patch.label];
    for (std::size_t ka = 0; ka < patch.nodes.size(); ++ka)
    {
      for (std::size_t kb = 0; kb < patch.nodes.size(); ++kb)
      {
        for (int i = 0; i < 3; ++i)
        {
          for (int j = 0; j < 3; ++j)
          {
            const std::size_t row = 3 * static_cast<std::size_t>(patch.nodes[ka]) + i;
            const std::size_t col = 3 * static_cast<std::size_t>(patch.nodes[kb]) + j;
            if (row >= col)
            {
              vals[pattern.EntryIndex(row, col)] += kappa * volume * gbar[3 * ka + i] * gbar[3 * kb + j];
            }
          }
        }
      }
    }
  }
}

void
LinearElasticModel::Impl::BuildPattern()
{
  const std::size_t N = mesh.GetNumberOfPoints();
  ndof = 3 * N;
  NodeAdjacency upper = fem::ElementNodeAdjacency(mesh);
  patches = BuildAveragingPatches();
  AddPatchNodeCouplings(patches, upper);
  fem::SortAdjacencyAndCheckNodesUsed(upper, "LinearElasticModel");
  pattern = fem::BuildColumnPattern(upper);
  valuesCurrent = false;
}

void
LinearElasticModel::Impl::AccumulateStiffnesses()
{
  if (accumulated)
  {
    return;
  }
  const auto t0 = Clock::now();
  AccumulateUnitElementStiffnesses();
  AccumulateAveragedBulkStiffnesses(patches);
  std::vector<AveragingPatch>().swap(patches);
  values.assign(pattern.Size(), 0.0);
  valuesCurrent = false;
  accumulated = true;
  timings.assemble += SecondsSince(t0);
}

const std::vector<double> &
LinearElasticModel::Impl::UnitValues(std::int32_t label)
{
  AccumulateStiffnesses();
  const auto found = unitValues.find(label);
  if (found == unitValues.end())
  {
    Fail("LinearElasticModel", "label " + std::to_string(label) + " has no material");
  }
  return found->second;
}

void
LinearElasticModel::Impl::UpdateValues()
{
  AccumulateStiffnesses();
  if (valuesCurrent)
  {
    return;
  }
  std::fill(values.begin(), values.end(), 0.0);
  for (const auto & kv : unitValues)
  {
    const double E = materials.at(kv.first).youngsModulus;
    const auto & u = kv.second;
    for (std::size_t k = 0; k < values.size(); ++k)
    {
      values[k] += E * u[k];
    }
  }
  valuesCurrent = true;
}

} // namespace bmr
