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
#ifndef bmrLinearElasticModel_h
#define bmrLinearElasticModel_h

#include "bmrTetrahedralMesh.h"

#include <iosfwd>
#include <map>
#include <memory>

namespace bmr {

/** The element formulation of a material (LinearElasticModel). */
enum class ElementFormulationEnum : std::uint8_t
{
  /** Plain P1 tetrahedra: volumetric locking as nu -> 0.5. */
  Standard,
  /** Nodal-averaged pressure (Bonet & Burton 1998): locking-free to nu = 0.499. */
  NodalAveragedPressure
};
BiomechanicalRegistration_EXPORT std::ostream &
                                 operator<<(std::ostream & os, ElementFormulationEnum value);

/** Isotropic linear-elastic material: Young's modulus E [kPa], Poisson's ratio nu and the element formulation. */
struct BiomechanicalRegistration_EXPORT MaterialParameters
{
  double                 youngsModulus{ 10.0 };
  double                 poissonRatio{ 0.35 };
  ElementFormulationEnum formulation{ ElementFormulationEnum::Standard };
};

/** Wall times [s] of the stages of the last Factorize()/Solve(). */
struct BiomechanicalRegistration_EXPORT SolverTimings
{
  double assemble{ 0.0 };
  double analyze{ 0.0 };
  double factorize{ 0.0 };
  double solve{ 0.0 };
};

/** \brief Linear-elastic finite element model on P1 tetrahedra.
 *
 * Solves K(E) u = f with K(E) = sum_m E_m Khat_m, where Khat_m is the stiffness
 * of the elements of material m with unit modulus:
 * \f[ K^e_{ai,bj} = V_e \left( \lambda\, g_{a,i} g_{b,j} + \mu\, g_{a,j} g_{b,i}
 *     + \mu\, \delta_{ij}\, g_a \cdot g_b \right), \f]
 * g_a the gradient of the barycentric coordinate of node a, V_e the element
 * volume, lambda = E nu / ((1+nu)(1-2nu)) and mu = E / (2(1+nu)).
 * Units: u in mm, E in kPa, forces in mN (kPa mm^2).
 *
 * Near incompressibility (nu -> 0.5) locks P1 tetrahedra: the bulk modulus kappa = lambda + 2 mu / 3
 * penalizes the piecewise-constant volumetric strain of every element, which has too few degrees of
 * freedom to vanish. A material with ElementFormulationEnum::NodalAveragedPressure uses the nodal-averaged pressure
 * formulation instead (Bonet & Burton 1998): the element keeps only its deviatoric part
 * (lambda replaced by -2 mu / 3), and the volumetric energy is taken at the nodes,
 * \f[ \tfrac12 \sum_p \kappa V_p \theta_p^2, \quad \theta_p = \bar g_p^T u, \quad
 *     \bar g_p = \frac{1}{V_p} \sum_{e \in p} \frac{V_e}{4} b_e, \quad V_p = \sum_{e \in p} \frac{V_e}{4}, \f]
 * over the patches p = (node, material) of the elements of that material around each node, b_e the
 * element's divergence operator (b_e^T u = tr eps_e). With one volumetric constraint per node instead of
 * per element (about 5 elements per node) the mesh can represent isochoric motion, and the solution stays
 * accurate to nu = 0.499 (see bmrTwoLayerSphereTest). K becomes wider (each node couples to its patch
 * neighbors' neighbors), so assembly and factorization cost more; the stress deviator, and so the von
 * Mises stress, is unchanged.
 *
 * Dirichlet conditions u_p = g are eliminated: K_ff u_f = f_f - K_fp g. The
 * sparse Cholesky factorization of K_ff (CHOLMOD supernodal) is computed once
 * by Factorize() and reused by every Solve(); changing a modulus (by more
 * than SetRefactorizationThreshold(), below which it preconditions) or the
 * Dirichlet set invalidates it (the symbolic analysis is kept when only a
 * modulus changes). Reaction forces are r = K u - f at the constrained nodes.
 *
 * The model keeps a reference to the mesh, which must outlive it.
 *
 * Errors (itk::ExceptionObject): an element label without material, E <= 0 or
 * not finite, nu outside (-1, 0.5), a degenerate or inverted element (named),
 * a connected component of the mesh that no Dirichlet condition holds against
 * rigid-body motion (named by its labels), and a factorization that fails.
 * \ingroup BiomechanicalRegistration BiomechanicalRegistrationFEM
 */
class BiomechanicalRegistration_EXPORT LinearElasticModel
{
public:
  LinearElasticModel(const TetrahedralMesh & mesh, const std::map<std::int32_t, MaterialParameters> & materials);
  ~LinearElasticModel();
  LinearElasticModel(const LinearElasticModel &) = delete;
  LinearElasticModel &
  operator=(const LinearElasticModel &) = delete;

  /** Prescribes u at \a nodes; \a values holds 3 per node [mm] or is empty for u = 0. */
  void
  SetDirichletConditions(const std::vector<std::int32_t> & nodes, const std::vector<double> & values);

  /** Changes the modulus of every element of \a label [kPa]. */
  void
  SetYoungsModulus(std::int32_t label, double youngsModulus);
  double
  GetYoungsModulus(std::int32_t label) const;

  /** Checks the model and computes the symbolic analysis of K_ff (its fill-reducing ordering), which depends only
   * on the mesh and the constrained dofs; Factorize() does it when it has not been done. Done ahead, e.g. on
   * another thread, it leaves the factorizations and every result as they are. The element stiffnesses, which the
   * construction leaves for their first use, are summed here too: on a second thread alongside the ordering when
   * SetNumberOfSolveThreads() allows two (the same sums either way). */
  void
  Analyze();

  /** After the moduli change by at most \a fraction each (relative, since the last factorization), Solve() does not
   * refactorize: it runs conjugate gradients on K_ff(E) preconditioned with that factorization, which converge to
   * the direct solve's accuracy (1e-13 of |u|) in about four iterations, each a pair of triangular solves and a
   * product with K_ff: cheaper than a factorization for the few solves an estimator's last, small steps in E need.
   * Above 0.3 % each solve needs about five iterations or more, and a refactorization becomes the cheaper
   * (measurements: docs/estimation.md). It refactorizes when 8 iterations do not converge. 0 refactorizes on every
   * change. Default 0.003. */
  void
  SetRefactorizationThreshold(double fraction);

  /** The factorizations and triangular solves of every Solve() on up to \a threads threads (default 1; 0 is taken
   * as 1): the factor's elimination tree is cut into a fixed number of bins of subtrees, factorized and solved side
   * by side, and their ancestors, each factorized in tiles shared by the threads. The displacements are the same
   * bit for bit whatever the number (the cut does not depend on it, and each value is computed by the same
   * operations in the same order); only the time changes. The threads come from TBB's pool, shared with the
   * host. */
  void
  SetNumberOfSolveThreads(unsigned threads);
  /** The fraction of the current factor's entries in the bins that the solve threads take side by side (the rest,
   * their ancestors, is solved by one thread); 0 before the first factorization. */
  double
  GetParallelSolveShare() const;
  /** Whether the current analysis is factorized by the project's tree-cut supernodal factorization (the default
   * for every factor CHOLMOD lays out as supernodal LL^T) rather than by CHOLMOD's own (one thread); false before
   * the first factorization. */
  bool
  UsesTreeCutFactorization() const;
  /** CHOLMOD's own factorization and solves (one thread) instead of the tree-cut ones, for every later
   * factorization: the reference the tree-cut factorization is tested against. Default false. */
  void
  SetReferenceFactorization(bool useCholmod);

  /** Assembles K_ff and factorizes it; checks the model first.
   *
   * A refactorization after only some labels' moduli changed (an estimator's unknown moduli) recomputes only the
   * part of the factor they reach: the supernodes holding entries of their elements and the ancestors of those in
   * the elimination tree. The rest, which depends on the other labels alone, is kept from the factorization that
   * first saw those labels change (or, for the first factorization, change since the model was built), as are its
   * updates of the recomputed part. On the default pelvis mesh a change of the prostate's modulus recomputes
   * about half of the multiply-adds. The factor holds the same sums as a whole factorization in another order; it
   * is the same bit for bit on any number of threads and for the same moduli whichever factorizations came
   * before, once the changing labels are known. */
  void
  Factorize();
  /** The fraction of a whole factorization's multiply-adds that the last Factorize() computed: 1 for a whole one,
   * less for a refactorization of the part a change of some labels' moduli reaches; 0 before the first. */
  double
  GetRefactorizedShare() const;
  bool
  IsFactorized() const;

  /** Displacements [mm] of all nodes (3N) for nodal forces \a forces [mN] (3N or
   * empty); forces on constrained dofs are ignored (they become reactions). */
  std::vector<double>
  Solve(const std::vector<double> & forces);

  /** As Solve(), but with the prescribed displacements taken from \a prescribed
   * (3N [mm]; read at the constrained dofs only) instead of those given to
   * SetDirichletConditions(). The constrained set, and so the factorization, is
   * unchanged: this is the cheap path for many boundary displacements on one
   * model (u_f = K_ff^{-1} (f_f - K_fp g)). */
  std::vector<double>
  Solve(const std::vector<double> & forces, const std::vector<double> & prescribed);

  /** As Solve(forces, prescribed), but exact only at the dofs \a observedDofs (3N indices, any order) and the
   * constrained ones; the other free dofs are 0. The backward triangular solve then computes only the factor's
   * supernodes that hold an observed dof and their ancestors in the elimination tree, each value by the same
   * operations as Solve(), so the observed displacements are Solve()'s bit for bit. (Both solves skip the supernodes
   * that no nonzero of the right-hand side reaches, whose values are exact zeros.) When the solve iterates with a
   * kept factorization (SetRefactorizationThreshold()), every dof is computed. */
  std::vector<double>
  Solve(const std::vector<double> &       forces,
        const std::vector<double> &       prescribed,
        const std::vector<std::int32_t> & observedDofs);

  /** The free dofs (3N indices, ascending) that ComputeCouplingForces() reads for its values at the constrained dofs
   * of \a nodes: those coupled to one of them in K. */
  std::vector<std::int32_t>
  GetCoupledFreeDegreesOfFreedom(const std::vector<std::int32_t> & nodes) const;

  /** Khat_m u at every dof [mN per kPa]: the derivative of K(E) u with respect to
   * the modulus of material \a label, dK/dE_m u. */
  std::vector<double>
  ComputeMaterialStiffnessProduct(std::int32_t label, const std::vector<double> & u) const;

  /** K u at every dof [mN]: with Solve()'s u this is f on free dofs and f + reaction on constrained ones. */
  std::vector<double>
  ComputeInternalForces(const std::vector<double> & u) const;

  /** K_cf v_f [mN]: the forces on the constrained dofs from the free dofs' displacement \a v [mm] (3N; its
   * constrained values are not read), zero on the free dofs. For a v that vanishes on the constrained dofs (an
   * adjoint state) this is K v there, from the small free-constrained block instead of the whole matrix. */
  std::vector<double>
  ComputeCouplingForces(const std::vector<double> & v) const;

  /** Reaction forces [mN] (3N, zero on free dofs): K u - f on constrained dofs. */
  std::vector<double>
  ComputeReactionForces(const std::vector<double> & u, const std::vector<double> & forces) const;

  /** Von Mises stress of every element [kPa]. */
  std::vector<double>
  ComputeVonMisesStress(const std::vector<double> & u) const;

  /** Per-element modulus [kPa] and Poisson's ratio. */
  std::vector<double>
  GetElementYoungsModuli() const;
  std::vector<double>
  GetElementPoissonRatios() const;

  std::size_t
  GetNumberOfFreeDegreesOfFreedom() const;
  const std::vector<char> &
  GetConstrainedDegreesOfFreedom() const;
  const SolverTimings &
  GetTimings() const;

private:
  std::vector<double>
  SolveObserving(const std::vector<double> &       forces,
                 const std::vector<double> &       prescribed,
                 const std::vector<std::int32_t> * observedDofs);

  struct Impl;
  std::unique_ptr<Impl> m_Impl;
};

} // namespace bmr

#endif
