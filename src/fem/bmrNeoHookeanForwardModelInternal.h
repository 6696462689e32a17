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
// Internal to src/fem: NeoHookeanForwardModel's state (its Impl), shared by the model's setup, assembly and solve.
#ifndef bmrNeoHookeanForwardModelInternal_h
#define bmrNeoHookeanForwardModelInternal_h

// The system Eigen 3.4 and CHOLMOD are used only in src/fem; no ITK header that bundles ITK's own Eigen may
// be included here.
#include "bmrNeoHookeanForwardModel.h"

#include "bmrFemAssembly.h"
#include "bmrNeoHookeanElement.h"

#include <Eigen/CholmodSupport>

#include <array>
#include <cstddef>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace bmr {

namespace neohookean {
/** Who the neo-Hookean model's errors come from. */
inline constexpr const char * kWho = "NeoHookeanForwardModel";
} // namespace neohookean

struct NeoHookeanForwardModel::Impl
{
  /** One trial of a load increment that did not work, and why (for the error message). */
  struct IncrementFailure
  {
    std::string  reason;
    std::int64_t worstElement{ -1 };
    double       worstJ{ 0.0 };
  };

  const TetrahedralMesh &                    mesh;
  std::map<std::int32_t, MaterialParameters> materials;
  NewtonSettings                             settings;
  std::size_t                                ndof{ 0 };
  // Reference geometry, per element.
  std::vector<std::array<double, 12>> gradients; // g[a][i] at 3a+i
  std::vector<double>                 volumes;
  std::vector<double>                 mu, lambda; // per element [kPa], from its material
  // Elements whose four nodes are all constrained: they cannot move, so they take no part in the free
  // equilibrium (no residual, no tangent on free dofs) and in the line search; one that the prescribed motion
  // alone inverts (a boundary sliver) would otherwise make every state infeasible.
  std::vector<char> passive;
  // The tangent on the full lower pattern, and where each element's 4x4 node blocks go in it.
  fem::LowerPattern         pattern;
  std::vector<std::int64_t> elementEntries; // 144 per element: position of K[3a+i][3b+k] or -1 (upper part)
  std::vector<double>       tangent;
  // The free block and its factorization.
  std::vector<char>                                                      constrained;
  std::vector<std::int32_t>                                              freeIndex;
  std::size_t                                                            nfree{ 0 };
  Eigen::SparseMatrix<double>                                            Kff;
  std::vector<std::int64_t>                                              freePositions;
  std::vector<std::int64_t>                                              freeDiagonal; // positions in Kff
  Eigen::CholmodSupernodalLLT<Eigen::SparseMatrix<double>, Eigen::Lower> solver;
  bool                                                                   analyzed{ false };
  bool haveFactorization{ false };  // the solver holds a factorization of a recent tangent (this constrained set)
  bool factorizationExact{ false }; // ... of the current tangent, unshifted: solves are direct
  bool refactorNext{ false };       // the last preconditioned solve was slow: factorize before the next one
  unsigned int iterationsAtThisTangent{ 0 }; // CG iterations spent on the current tangent (repeated solves)
  // The last equilibrium and its loads (the warm start), and the tangent's state.
  bool                hasState{ false };
  std::vector<double> state, stateForces, statePrescribed;
  NewtonStatistics    statistics;
  SolverWork          earlierWork; // of the solves before the one \a statistics describes
  std::string         lastFailure;

  Impl(const TetrahedralMesh & m, const std::map<std::int32_t, MaterialParameters> & mats, const NewtonSettings & s);

  /** The work of every solve so far: the earlier ones and the current statistics (its adjoints included). */
  SolverWork
  Work() const
  {
    SolverWork w = earlierWork;
    w.newtonIterations += statistics.iterations;
    w.factorizations += statistics.factorizations;
    w.conjugateGradientIterations += statistics.conjugateGradientIterations;
    w.rejectedIncrements += statistics.rejectedIncrements;
    return w;
  }

  // Setup.
  void
  ValidateMaterials() const;
  void
  ComputeGeometry();
  void
  UpdateLameParameters();
  void
  BuildPatternAndEntries();
  // Assembly.
  bool
  Deform(std::size_t e, const std::vector<double> & u, fem::ElementDeformation & d) const;
  double
  Energy(const std::vector<double> & u, std::int64_t * worst = nullptr, double * worstJ = nullptr) const;
  std::vector<double>
  Forces(const std::vector<double> & u, std::int32_t onlyLabel = -1) const;
  void
  AssembleTangent(const std::vector<double> & u);
  // Solve.
  void
  CopyTangentToFreeBlock();
  bool
  Factorize(bool allowShift);
  bool
  PreconditionedCG(const Eigen::VectorXd & b, Eigen::VectorXd & x, unsigned int & iterations, double tolerance) const;
  bool
  SolveTangent(const std::vector<double> & rhs, std::vector<double> & out, bool exact, double tolerance = 1e-12);
  bool
  NewtonStep(const std::vector<double> & u,
             const std::vector<double> & r,
             const std::vector<double> & step,
             double                      forcing,
             std::vector<double> &       du);
  bool
  LineSearch(std::vector<double> &       u,
             const std::vector<double> & du,
             const std::vector<double> & f,
             double                      decrement,
             bool                        jump,
             IncrementFailure &          failure) const;
  bool
  NewtonIncrement(std::vector<double> &       u,
                  const std::vector<double> & f,
                  const std::vector<double> & prescribed,
                  IncrementFailure &          failure);
  bool
  FollowPath(std::vector<double> &       u,
             const std::vector<double> & f0,
             const std::vector<double> & g0,
             const std::vector<double> & f1,
             const std::vector<double> & g1,
             double &                    reached,
             IncrementFailure &          failure);
};

} // namespace bmr

#endif
