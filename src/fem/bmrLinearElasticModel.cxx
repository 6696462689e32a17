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
// The system Eigen 3.4 and CHOLMOD are used only in this translation unit; no
// ITK header that bundles ITK's own Eigen may be included here.
#include "bmrLinearElasticModel.h"

#include "bmrError.h"
#include "bmrFemAssembly.h"
#include "bmrStopwatch.h"
#include "bmrSupernodalFactorize.h"
#include "bmrSupernodalSolve.h"

#include <Eigen/CholmodSupport>
#include <Eigen/SparseCore>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <future>
#include <numeric>
#include <set>
#include <sstream>
#include <utility>

namespace bmr {
using Clock = SteadyClock;
using fem::ElementGradients;
using fem::LameParameters;

namespace {
/** CHOLMOD's supernodal LL^T through Eigen, with its factor readable (for fem::SupernodalSolver). */
class SupernodalLLT : public Eigen::CholmodSupernodalLLT<Eigen::SparseMatrix<double>, Eigen::Lower>
{
public:
  cholmod_factor *
  Factor()
  {
    return this->m_cholmodFactor;
  }
};
} // namespace

struct LinearElasticModel::Impl
{
  const TetrahedralMesh &                     mesh;
  std::map<std::int32_t, MaterialParameters>  materials;
  std::size_t                                 ndof{ 0 };
  fem::LowerPattern                           pattern;              // of the full 3N x 3N stiffness
  std::map<std::int32_t, std::vector<double>> unitValues;           // Khat_m per label, on the shared pattern
  bool                                        accumulated{ false }; // unitValues and values allocated and summed
  std::vector<double>                         values;               // sum_m E_m Khat_m
  bool                                        valuesCurrent{ false };
  std::vector<char>                           constrained;
  std::vector<double>                         prescribed; // 3N
  std::vector<std::int32_t>                   freeIndex;  // dof -> free index or -1
  fem::CouplingRows                           coupling;   // the free-constrained block, by row
  bool                                        couplingCurrent{ false };
  bool                                        freeBlockCurrent{ false };   // Kff holds the current values
  bool                                        freePatternCurrent{ false }; // Kff and freePositions: this analysis
  std::vector<std::int64_t>                   freePositions; // of each pattern entry in Kff's values, or -1
  std::size_t                                 nfree{ 0 };
  Eigen::SparseMatrix<double>                 Kff;
  SupernodalLLT                               solver;
  fem::SupernodalSolver                       triangular;                // solves with solver's factor
  fem::SupernodalFactorizer                   factorizer;                // computes solver's factor
  bool                                        triangularCut{ false };    // its tree cut for the current analysis
  bool                                        ownFactorization{ false }; // factorizer set for the current analysis
  bool                                        triangularReady{ false };  // and the factor computed
  bool                                        referenceOnly{ false };    // CHOLMOD's factorization and solves
  unsigned                                    solveThreads{ 1 };
  bool                                        analyzed{ false };
  bool                                        factorized{ false };
  SolverTimings                               timings;
  // The factorization of K_ff at factorModuli, kept when the moduli change by less than refactorizeAbove:
  // Solve() then iterates with it as the preconditioner (PreconditionedSolve) instead of refactorizing. Before the
  // first factorization factorModuli holds the moduli the model was built with.
  bool                           hasFactor{ false };
  std::map<std::int32_t, double> factorModuli;
  double                         refactorizeAbove{ 0.003 };
  // The labels whose moduli the factorizer's kept fixed part leaves out (fem::SupernodalFactorizer::
  // FactorizeVarying), the other labels' moduli it was computed with, and the two parts' values on K_ff.
  std::set<std::int32_t>         varyingLabels;
  std::map<std::int32_t, double> fixedPartModuli;
  std::vector<double>            fixedFree, varyingFree;
  double                         refactorizedShare{ 0.0 }; // of the last factorization's work

  explicit Impl(const TetrahedralMesh & m)
    : mesh(m)
  {}

  /** The elements of one material around one node, and their nodes (sorted): the support of the node's
   * averaged volumetric strain in the nodal-averaged pressure formulation. */
  struct AveragingPatch
  {
    std::int32_t              label{ 0 };
    std::vector<std::int32_t> elements;
    std::vector<std::int32_t> nodes;
  };
  std::vector<AveragingPatch> patches; // of the averaged materials, until their bulk stiffness is accumulated

  std::vector<AveragingPatch>
  BuildAveragingPatches() const;
  void
  BuildPattern();
  /** The element stiffnesses on the pattern (unitValues), once: deferred from the construction to the first use,
   * so that Analyze() can compute them alongside the fill-reducing order. */
  void
  AccumulateStiffnesses();
  // Pieces of BuildPattern.
  using NodeAdjacency = fem::NodeAdjacency;
  static void
  AddPatchNodeCouplings(const std::vector<AveragingPatch> & patches, NodeAdjacency & upper);
  void
  AccumulateUnitElementStiffnesses();
  void
  AccumulateAveragedBulkStiffnesses(const std::vector<AveragingPatch> & patches);
  void
  CheckElements() const;
  void
  UpdateValues();
  /** unitValues of \a label, accumulated first if they are not yet. */
  const std::vector<double> &
  UnitValues(std::int32_t label);
  void
  SymmetricProduct(const std::vector<double> & x, std::vector<double> & y) const
  {
    fem::SymmetricProduct(pattern, values, x, y);
  }
  /** K_ff with the current moduli, rebuilt only when they or the constrained set changed. */
  void
  UpdateFreeBlock()
  {
    UpdateValues();
    if (freeBlockCurrent)
    {
      return;
    }
    if (freePatternCurrent)
    {
      double * entries = Kff.valuePtr();
      for (std::size_t k = 0; k < values.size(); ++k)
      {
        if (freePositions[k] >= 0)
        {
          entries[freePositions[k]] = values[k];
        }
      }
    }
    else
    {
      Kff = fem::FreeBlock(pattern, values, freeIndex, nfree, &freePositions);
      freePatternCurrent = true;
    }
    freeBlockCurrent = true;
  }
  int
  FactorizeOwn();
  void
  SplitFreeValues(bool varyingOnly);
  std::vector<char>
  VaryingEntries() const;
  /** Whether every modulus lies within refactorizeAbove (relative) of the kept factorization's. */
  bool
  FactorStillPreconditions() const
  {
    if (!hasFactor || refactorizeAbove <= 0.0)
    {
      return false;
    }
    for (const auto & [label, material] : materials)
    {
      if (!(std::abs(std::log(material.youngsModulus / factorModuli.at(label))) <= std::log1p(refactorizeAbove)))
      {
        return false;
      }
    }
    return true;
  }
  /** After an analysis: the factor's values allocated, its elimination tree cut (fem::SupernodalSolver) and
   * K_ff's entries placed in it (fem::SupernodalFactorizer); CHOLMOD's own factorization and solves stay for a
   * factor these do not take. */
  void
  CutTree()
  {
    cholmod_factor * factor = solver.Factor();
    if (factor != nullptr && factor->is_super && factor->xtype == CHOLMOD_PATTERN)
    {
      cholmod_change_factor(CHOLMOD_REAL, true, true, true, true, factor, &solver.cholmod());
    }
    triangularCut = !referenceOnly && triangular.SetFactor(factor);
    Kff.makeCompressed();
    ownFactorization = triangularCut && factorizer.SetStructure(factor,
                                                                solver.cholmod(),
                                                                static_cast<int>(nfree),
                                                                Kff.outerIndexPtr(),
                                                                Kff.innerIndexPtr(),
                                                                triangular.GetBins());
  }
  bool
  PreconditionedSolve(const Eigen::VectorXd & b, Eigen::VectorXd & x);
  /** K_ff^-1 b with the current factorization: fem::SupernodalSolver on solveThreads threads (the same result on
   * any number), or CHOLMOD's own solve for a factor it does not take. */
  Eigen::VectorXd
  TriangularSolve(const Eigen::VectorXd & b, const std::vector<std::int32_t> * observedFree = nullptr)
  {
    if (!triangularReady)
    {
      return solver.solve(b);
    }
    Eigen::VectorXd x(b.size());
    if (observedFree != nullptr)
    {
      triangular.Solve(b.data(), x.data(), solveThreads, *observedFree);
    }
    else
    {
      triangular.Solve(b.data(), x.data(), solveThreads);
    }
    return x;
  }
  /** The free indices of the free dofs among \a dofs (3N indices; throws on one out of range). */
  std::vector<std::int32_t>
  FreeIndices(const std::vector<std::int32_t> & dofs) const
  {
    std::vector<std::int32_t> free;
    free.reserve(dofs.size());
    for (const std::int32_t dof : dofs)
    {
      if (dof < 0 || static_cast<std::size_t>(dof) >= ndof)
      {
        Fail("LinearElasticModel::Solve", "observed degree of freedom " + std::to_string(dof) + " is out of range");
      }
      if (freeIndex[dof] >= 0)
      {
        free.push_back(freeIndex[dof]);
      }
    }
    return free;
  }

  /** The free-constrained block's pattern, built once per constrained set. */
  const fem::CouplingRows &
  Coupling()
  {
    if (!couplingCurrent)
    {
      coupling = fem::BuildCouplingRows(pattern, constrained);
      couplingCurrent = true;
    }
    return coupling;
  }
  /** K_fc x_c at the free dofs (\a constrainedRows false) or K_cf x_f at the constrained ones (true). */
  void
  CouplingProduct(const std::vector<double> & x, bool constrainedRows, std::vector<double> & y)
  {
    Coupling();
    UpdateValues();
    fem::CouplingProduct(coupling, values, constrained, constrainedRows, x, y);
  }
};

/** Conjugate gradients on K_ff x = b preconditioned with the kept factorization of K_ff(E_f). With every modulus
 * within a factor 1 + t of E_f, K(E) = sum_m E_m Khat_m gives x^T K(E) x / x^T K(E_f) x in [1/(1+t), 1+t], so the
 * preconditioned matrix has condition number at most (1 + t)^2 and the error falls by at least
 * (sqrt(kappa) - 1) / (sqrt(kappa) + 1) = t / (2 + t) per iteration: for t = 1 %, from 1 % after the first solve to
 * the tolerance, 1e-13 of |x|, in at most about 5 iterations (3 for the demo's last step of 0.2 % in E), each a pair
 * of triangular solves and a product with K_ff. The stopping test is the preconditioned residual |M^-1 r|, which is
 * the error to within that same factor: the direct solve's accuracy, not the residual's. Sequential and in a fixed
 * order: deterministic. False (x then undefined) when 8 iterations do not reach the tolerance. */
bool
LinearElasticModel::Impl::PreconditionedSolve(const Eigen::VectorXd & b, Eigen::VectorXd & x)
{
  UpdateFreeBlock();
  const auto       K = Kff.selfadjointView<Eigen::Lower>();
  constexpr int    maximumIterations = 8;
  constexpr double tolerance = 1e-13;
  x = TriangularSolve(b);
  Eigen::VectorXd r = b - K * x;
  Eigen::VectorXd z = TriangularSolve(r);
  Eigen::VectorXd p = z;
  double          rz = r.dot(z);
  for (int k = 0; k < maximumIterations; ++k)
  {
    if (!(z.norm() > tolerance * x.norm()))
    {
      return x.allFinite();
    }
    const Eigen::VectorXd q = K * p;
    const double          alpha = rz / p.dot(q);
    x += alpha * p;
    r -= alpha * q;
    z = TriangularSolve(r);
    const double next = r.dot(z);
    p = z + (next / rz) * p;
    rz = next;
  }
  return !(z.norm() > tolerance * x.norm()) && x.allFinite();
}

/** K_ff = L L^T by fem::SupernodalFactorizer. When only the moduli of varyingLabels changed since its kept fixed part
 * was computed, only the supernodes they reach are refactorized (on the 140k pelvis, 49.5 % of the work for the
 * prostate). Otherwise the labels whose moduli changed since the last factorization (before the first: since the
 * model was built, as an estimator sets its start moduli) become varyingLabels, as an estimator changes the same
 * unknown moduli again and again, and the whole factor is computed, keeping the new fixed part; with no change to
 * learn from, it is the plain factorization. */
int
LinearElasticModel::Impl::FactorizeOwn()
{
  bool fixedPartHolds = factorizer.HasFixedPart() && !varyingLabels.empty();
  for (const auto & [label, material] : materials)
  {
    const auto kept = fixedPartModuli.find(label);
    fixedPartHolds = fixedPartHolds && (varyingLabels.count(label) > 0 ||
                                        (kept != fixedPartModuli.end() && kept->second == material.youngsModulus));
  }
  if (fixedPartHolds)
  {
    SplitFreeValues(true);
    refactorizedShare = factorizer.GetVaryingShare();
    return factorizer.FactorizeVarying(varyingFree.data(), solveThreads);
  }
  refactorizedShare = 1.0;
  varyingLabels.clear();
  for (const auto & [label, material] : materials)
  {
    const auto factored = factorModuli.find(label);
    if (factored != factorModuli.end() && factored->second != material.youngsModulus)
    {
      varyingLabels.insert(label);
    }
    fixedPartModuli[label] = material.youngsModulus;
  }
  factorizer.SetVaryingEntries(VaryingEntries());
  if (varyingLabels.empty())
  {
    return factorizer.Factorize(Kff.valuePtr(), solveThreads);
  }
  SplitFreeValues(false);
  const int factorized = factorizer.Factorize(fixedFree.data(), varyingFree.data(), solveThreads);
  std::vector<double>().swap(fixedFree); // kept by the factorizer where it is needed again
  return factorized;
}

/** K_ff's values split into varyingLabels' sum_m E_m Khat_m (varyingFree) and, unless \a varyingOnly, the other
 * labels' (fixedFree), each summed in label order like Impl::values. */
void
LinearElasticModel::Impl::SplitFreeValues(bool varyingOnly)
{
  const auto entries = static_cast<std::size_t>(Kff.nonZeros());
  varyingFree.assign(entries, 0.0);
  if (!varyingOnly)
  {
    fixedFree.assign(entries, 0.0);
  }
  for (const auto & [label, unit] : unitValues)
  {
    const bool varies = varyingLabels.count(label) > 0;
    if (varyingOnly && !varies)
    {
      continue;
    }
    std::vector<double> & target = varies ? varyingFree : fixedFree;
    const double          E = materials.at(label).youngsModulus;
    for (std::size_t k = 0; k < unit.size(); ++k)
    {
      if (freePositions[k] >= 0)
      {
        target[freePositions[k]] += E * unit[k];
      }
    }
  }
}

/** Which entries of K_ff a modulus of varyingLabels enters (a nonzero unit stiffness there). */
std::vector<char>
LinearElasticModel::Impl::VaryingEntries() const
{
  std::vector<char> varies;
  if (varyingLabels.empty())
  {
    return varies;
  }
  varies.assign(static_cast<std::size_t>(Kff.nonZeros()), 0);
  for (const std::int32_t label : varyingLabels)
  {
    const auto found = unitValues.find(label);
    if (found == unitValues.end())
    {
      continue;
    }
    const std::vector<double> & unit = found->second;
    for (std::size_t k = 0; k < unit.size(); ++k)
    {
      if (unit[k] != 0.0 && freePositions[k] >= 0)
      {
        varies[freePositions[k]] = 1;
      }
    }
  }
  return varies;
}

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

void
LinearElasticModel::Analyze()
{
  Impl & d = *m_Impl;
  if (d.analyzed)
  {
    return;
  }
  const fem::SingleThreadedCholmod serial;
  auto                             t0 = Clock::now();
  fem::CheckRigidBodyModes(d.mesh, d.constrained, "LinearElasticModel");
  d.timings.assemble += SecondsSince(t0);
  t0 = Clock::now();
  {
    // The element stiffnesses are summed on a second thread, when there is one, while this one computes the
    // fill-reducing order from the node graph (nine times fewer edges than CHOLMOD's dof graph), given to CHOLMOD as
    // the free dofs' numbering: neither reads what the other writes.
    std::future<void> accumulated;
    if (!d.accumulated && d.solveThreads > 1)
    {
      accumulated = std::async(std::launch::async, [&d]() { d.AccumulateStiffnesses(); });
    }
    {
      const auto serialized = fem::LockOrdering();
      d.nfree = fem::NumberFreeDofsByNestedDissection(d.pattern, d.constrained, d.freeIndex);
    }
    if (accumulated.valid())
    {
      accumulated.get();
    }
  }
  d.freePatternCurrent = false; // K_ff in the new numbering
  d.freeBlockCurrent = false;
  if (d.nfree == 0)
  {
    d.analyzed = true;
    d.timings.analyze = SecondsSince(t0);
    return;
  }
  const double ordering = SecondsSince(t0);
  t0 = Clock::now();
  d.UpdateFreeBlock();
  d.timings.assemble += SecondsSince(t0);
  t0 = Clock::now();
  fem::OrderAsNumbered(d.solver.cholmod());
  d.solver.analyzePattern(d.Kff);
  d.triangularCut = false;
  d.ownFactorization = false;
  d.analyzed = true;
  d.timings.analyze = ordering + SecondsSince(t0);
}

void
LinearElasticModel::Factorize()
{
  Impl & d = *m_Impl;
  if (d.factorized)
  {
    return;
  }
  Analyze();
  if (d.nfree == 0)
  {
    d.factorized = true;
    return;
  }
  const fem::SingleThreadedCholmod serial;
  auto                             t0 = Clock::now();
  d.UpdateFreeBlock();
  d.timings.assemble += SecondsSince(t0);
  t0 = Clock::now();
  d.hasFactor = false;
  d.triangularReady = false;
  // The tree is cut once per analysis: a refactorization keeps the factor's structure.
  if (!d.triangularCut || (d.ownFactorization && d.factorizer.GetNumberOfEntries() != d.Kff.nonZeros()))
  {
    d.CutTree();
  }
  bool positiveDefinite = true;
  if (d.ownFactorization)
  {
    positiveDefinite = d.FactorizeOwn() == static_cast<int>(d.nfree);
  }
  else
  {
    d.refactorizedShare = 1.0;
    d.solver.factorize(d.Kff);
    positiveDefinite = d.solver.info() == Eigen::Success;
  }
  d.timings.factorize = SecondsSince(t0);
  if (!positiveDefinite)
  {
    Fail("LinearElasticModel::Factorize",
         "the stiffness matrix is not positive definite (the Cholesky factorization failed): the model is singular "
         "or ill-conditioned; check the fixed labels and the element quality");
  }
  d.factorized = true;
  d.hasFactor = true;
  d.triangularReady = d.triangularCut;
  for (const auto & [label, material] : d.materials)
  {
    d.factorModuli[label] = material.youngsModulus;
  }
}

double
LinearElasticModel::GetRefactorizedShare() const
{
  return m_Impl->refactorizedShare;
}

bool
LinearElasticModel::IsFactorized() const
{
  return m_Impl->factorized;
}

std::vector<double>
LinearElasticModel::Solve(const std::vector<double> & forces)
{
  return Solve(forces, m_Impl->prescribed);
}

std::vector<double>
LinearElasticModel::Solve(const std::vector<double> & forces, const std::vector<double> & prescribedAll)
{
  return SolveObserving(forces, prescribedAll, nullptr);
}

std::vector<double>
LinearElasticModel::Solve(const std::vector<double> &       forces,
                          const std::vector<double> &       prescribedAll,
                          const std::vector<std::int32_t> & observedDofs)
{
  return SolveObserving(forces, prescribedAll, &observedDofs);
}

std::vector<std::int32_t>
LinearElasticModel::GetCoupledFreeDegreesOfFreedom(const std::vector<std::int32_t> & nodes) const
{
  Impl &                    d = *m_Impl;
  const fem::CouplingRows & coupling = d.Coupling();
  std::vector<std::int32_t> coupled;
  for (const std::int32_t node : nodes)
  {
    for (std::size_t i = 3 * static_cast<std::size_t>(node); i < 3 * static_cast<std::size_t>(node) + 3; ++i)
    {
      if (i < d.ndof && d.constrained[i])
      {
        coupled.insert(coupled.end(),
                       coupling.column.begin() + coupling.rowStart[i],
                       coupling.column.begin() + coupling.rowStart[i + 1]);
      }
    }
  }
  return UniqueNodes(std::move(coupled));
}

std::vector<double>
LinearElasticModel::SolveObserving(const std::vector<double> &       forces,
                                   const std::vector<double> &       prescribedAll,
                                   const std::vector<std::int32_t> * observedDofs)
{
  Impl &                           d = *m_Impl;
  const fem::SingleThreadedCholmod serial;
  if (!forces.empty() && forces.size() != d.ndof)
  {
    Fail("LinearElasticModel::Solve", "the force vector must hold 3 values per node");
  }
  if (prescribedAll.size() != d.ndof)
  {
    Fail("LinearElasticModel::Solve", "the prescribed displacement vector must hold 3 values per node");
  }
  std::vector<double> prescribed(d.ndof, 0.0);
  for (std::size_t i = 0; i < d.ndof; ++i)
  {
    if (d.constrained[i])
    {
      if (!std::isfinite(prescribedAll[i]))
      {
        Fail("LinearElasticModel::Solve",
             "prescribed displacement at degree of freedom " + std::to_string(i) + " is not finite");
      }
      prescribed[i] = prescribedAll[i];
    }
  }
  // A small change of the moduli since the last factorization is solved with it as the preconditioner.
  const bool iterate = !d.factorized && d.nfree > 0 && d.analyzed && d.FactorStillPreconditions();
  if (!iterate)
  {
    Factorize();
  }
  const std::vector<std::int32_t> observedFree =
    observedDofs ? d.FreeIndices(*observedDofs) : std::vector<std::int32_t>{};
  const auto t0 = Clock::now();
  // Only the free rows of K g are read and g vanishes on the free dofs: the coupling block K_fc g_c gives them
  // bit for bit (fem::CouplingProduct), and nothing when g = 0 (an adjoint).
  std::vector<double> Kg(d.ndof, 0.0);
  if (std::any_of(prescribed.begin(), prescribed.end(), [](double v) { return v != 0.0; }))
  {
    d.CouplingProduct(prescribed, false, Kg);
  }
  Eigen::VectorXd b(static_cast<Eigen::Index>(d.nfree));
  for (std::size_t i = 0; i < d.ndof; ++i)
  {
    const std::int32_t f = d.freeIndex[i];
    if (f >= 0)
    {
      const double fi = forces.empty() ? 0.0 : forces[i];
      if (!std::isfinite(fi))
      {
        Fail("LinearElasticModel::Solve", "force at degree of freedom " + std::to_string(i) + " is not finite");
      }
      b[f] = fi - Kg[i];
    }
  }
  std::vector<double> u(std::move(prescribed));
  if (d.nfree > 0)
  {
    Eigen::VectorXd x;
    // Conjugate gradients need every dof of each iterate; a direct solve only the observed ones (and their
    // ancestors in the elimination tree).
    if (!iterate || !d.PreconditionedSolve(b, x))
    {
      Factorize();
      x = d.TriangularSolve(b, observedDofs ? &observedFree : nullptr);
    }
    if (d.solver.info() != Eigen::Success || !x.allFinite())
    {
      Fail("LinearElasticModel::Solve", "the triangular solves failed or produced non-finite displacements");
    }
    for (std::size_t i = 0; i < d.ndof; ++i)
    {
      if (d.freeIndex[i] >= 0)
      {
        u[i] = x[d.freeIndex[i]];
      }
    }
  }
  d.timings.solve = SecondsSince(t0);
  return u;
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
