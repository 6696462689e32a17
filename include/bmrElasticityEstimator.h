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
#ifndef bmrElasticityEstimator_h
#define bmrElasticityEstimator_h

#include "bmrSurfaceMatchingObjective.h"

#include <functional>
#include <map>
#include <optional>

namespace bmr {

/** A modulus to estimate: label, name, and the bounds of the search [kPa]. */
struct BiomechanicalRegistration_EXPORT UnknownModulus
{
  std::string  name;
  std::int32_t label{ 0 };
  double       initial{ 0.0 }; ///< kPa, used until the sweep has set it
  double       lowerBound{ 0.0 };
  double       upperBound{ 0.0 };
};

/** The unknown moduli of a scene (role unknown_material), in scene order. */
BiomechanicalRegistration_EXPORT std::vector<UnknownModulus>
                                 SceneUnknownModuli(const Scene & scene);

/** One inner solve: stage ("sweep", "fine", "curvature" or "outer"), E [kPa] of the unknown labels,
 * Phi* [mm^2], |dPhi/dp| at the inner optimum, dPhi* / dlogE [mm^2], inner iterations, wall time [s]. */
struct BiomechanicalRegistration_EXPORT IterationRecord
{
  std::string         stage;
  unsigned int        iteration{ 0 };
  std::vector<double> youngsModuli;
  double              value{ 0.0 };
  double              wallGradientNorm{ 0.0 };
  std::vector<double> logModulusGradient;
  unsigned int        innerIterations{ 0 };
  double              seconds{ 0.0 };
  SolverWork          work;           ///< the inner solve's model work (LoadSolution::work; nonlinear models count it)
  bool                loose{ false }; ///< solved to EstimatorSettings::looseInnerGradientTolerance only
};

/** Settings of ElasticityEstimator; the defaults are those of FEMElasticityOptimizer and biomechreg. */
struct BiomechanicalRegistration_EXPORT EstimatorSettings
{
  unsigned int numberOfSweepSamples{ 10 }; ///< per unknown modulus, >= 3
  unsigned int maximumInnerIterations{ 2000 };
  unsigned int maximumOuterIterations{ 20 }; ///< function evaluations of the outer search
  double       outerStepTolerance{ 1e-3 };   ///< one unknown: stop when the next step in log E is shorter
  double       innerGradientTolerance{ 1e-5 };
  /** L-BFGS inner solves: the tolerance of the sweep's samples and, with one unknown, of the fine evaluations the
   * secant search only passes through; each one it would stop on is solved on to innerGradientTolerance first
   * (bmr::SecantSearch's inexact points). Not above innerGradientTolerance: every solve to the full tolerance. */
  double looseInnerGradientTolerance{ 3e-4 };
  double outerGradientTolerance{ 1e-4 }; ///< relative to Phi* at the start of the fine stage
  double flatnessThreshold{ 0.01 };      ///< relative variation of Phi* over the bounds
  bool   estimateUncertainty{ true };
  double uncertaintyStep{ 0.05 };        ///< delta in log E of the curvature's central differences
  bool   limitElementInversion{ false }; ///< one parameter per wall node only

  /** Throws itk::InvalidArgumentError (bmr::FailInput) naming the first setting out of range: fewer than 3 sweep
   * samples, a gradient tolerance not positive, a step tolerance negative or not finite, an uncertainty step
   * outside [1e-4, 1]. */
  void
  Validate() const;
};

/** What ElasticityEstimator::Run() found. Vectors over the unknowns are in the order they were given. */
struct BiomechanicalRegistration_EXPORT EstimationResult
{
  std::vector<double>          youngsModuli;   ///< kPa
  std::vector<double>          loadParameters; ///< at the estimate
  std::vector<double>          displacement;   ///< mm, 3N on the fine mesh
  std::vector<double>          boundaryForces; ///< mN, 3N
  double                       value{ 0.0 };   ///< Phi* [mm^2]
  std::vector<IterationRecord> sweep, history, outerIterations;
  std::string                  outerStopCondition;
  bool                         identifiable{ true };
  std::string                  identifiabilityMessage;
  std::vector<double>          logModulusSigma; ///< standard deviations of log E; empty when not computed
  std::vector<double>          curvature;       ///< d2 Phi* / dlogE_i dlogE_j [mm^2], row-major, or empty
  double relativeCurvature{ 0.0 };         ///< one unknown: the outer search's last secant of d2 Phi*/dlogE2, / Phi*
  double residualStandardDeviation{ 0.0 }; ///< mm
  std::vector<ResidualStatistics> residuals;
  std::size_t                     rejectedSteps{ 0 };
  std::size_t                     invertedElements{ 0 };
  std::map<std::string, double>   timings; ///< s: "sweep", "initial loads", "fine", "uncertainty"
};

/** Per unknown, what its sweep found (ElasticityEstimator::Sweep()). */
struct BiomechanicalRegistration_EXPORT SweepAnalysis
{
  double      modulus{ 0.0 }; ///< kPa: where the fine stage starts
  bool        identifiable{ true };
  bool        onBound{ false };         ///< not flat, but no sign change of dPhi*/dlogE: the minimum is on a bound
  double      relativeCurvature{ 0.0 }; ///< (d2Phi*/dlogE2) / Phi* across the bracket; 0 without one
  std::string message;
};

/** A sweep's outcome (ElasticityEstimator::Sweep()), from which the fine stage starts (SetSweep()). */
struct BiomechanicalRegistration_EXPORT ModulusSweep
{
  std::vector<SweepAnalysis>   unknowns; ///< the unknowns' order
  std::vector<IterationRecord> samples;
  std::size_t                  rejectedSteps{ 0 };
  double                       seconds{ 0.0 };
};

/** \brief Joint estimation of the loads and the unknown moduli over any EstimationObjective
 * (dissertation chapter 3): sweep, outer bounded optimization, uncertainty, identifiability.
 *
 * - inner: \f$\Phi^*(E) = \min_p \Phi(E, p)\f$ by L-BFGS (itk::LBFGS2Optimizerv4, More-Thuente line
 *   search) with the adjoint gradient, or Levenberg-Marquardt (EstimationObjective::SolveLoadsLevenbergMarquardt)
 *   when the objective's loads are a reduced basis (LoadParameterization::IsReducedBasis()); each warm-started from the
 * previous optimum;
 * - sweep (coarse objective, or the fine one): a coordinate sweep. For each unknown in turn, with the
 *   others at their current values, Phi* is sampled at numberOfSweepSamples log-spaced moduli over its
 *   bounds (each sample warm-started from the previous one, so that the sweep follows one branch of
 *   minima); the minimum is bracketed by the first sign change of \f$d\Phi^{*}/d\log E_k\f$ from - to + and
 *   interpolated linearly in log E_k. One unknown gives one sweep (dissertation), two or more give one
 *   pass of coordinate descent, which only starts the joint outer search;
 * - outer: \f$\min_{\log E} \Phi^*(E)\f$ within the bounds with the envelope gradient
 *   \f$ d\Phi^{*}/d\log E_m = \partial\Phi/\partial\log E_m \f$ at the inner optimum. One unknown: SecantSearch
 *   on \f$ d\Phi^{*}/d\log E = 0 \f$, its first step from the sweep's curvature relative to \f$\Phi^*\f$ (the
 *   fine mesh's \f$\Phi^*\f$ differs from the coarse one's by the number of nodes, and so does its
 *   curvature), stopping when the next step in log E is below outerStepTolerance (0.1 % of E) or the gradient
 *   below outerGradientTolerance. Its evaluations are inner solves to looseInnerGradientTolerance, each
 *   continued to innerGradientTolerance before the search stops on it; two or more: itk::LBFGSBOptimizerv4,
 *   every evaluation to innerGradientTolerance. The result is the best point visited and solved in full;
 * - identifiability, per unknown: flat (relative variation of Phi* over its bounds below
 *   flatnessThreshold), or the sweep's minimum on a bound, or the estimate on a bound;
 * - uncertainty: \f$ H = \partial^2\Phi^{*}/\partial\log E^2 \f$ by central differences of the envelope
 *   gradient at \f$\pm\delta\f$ (two inner solves per unknown), residual variance
 *   \f$ s^2 = \sum_s w_s n_s \mathrm{rms}_s^2 / \sum_s w_s n_s \f$, effective weight
 *   \f$ w_{\mathrm{eff}} = \sum_s w_s^2 n_s / \sum_s w_s n_s \f$ and
 *   \f$ \mathrm{Cov}(\log E) = s^2 w_{\mathrm{eff}} H^{-1} \f$; not computed when an estimate lies on a
 *   bound, infinite when H is not positive definite.
 * Deterministic: sequential, no random numbers.
 * \ingroup BiomechanicalRegistration BiomechanicalRegistrationEstimation
 */
class BiomechanicalRegistration_EXPORT ElasticityEstimator
{
public:
  /** Called after every inner solve with its record and the fraction of the work done. */
  using Observer = std::function<void(const IterationRecord &, double progress)>;

  /** \a fine must outlive the estimator; \a coarse (optional) is the same anatomy on a coarser mesh, used
   * for the sweep only. The unknowns must be those of the objectives (same order). Throws on an invalid
   * setting or unknown. */
  ElasticityEstimator(EstimationObjective &       fine,
                      EstimationObjective *       coarse,
                      std::vector<UnknownModulus> unknowns,
                      EstimatorSettings           settings);

  void
  SetObserver(Observer observer)
  {
    m_Observer = std::move(observer);
  }

  /** Runs the sweep now (on the coarse objective, or the fine one) and returns it; Run() does not sweep again. A
   * caller that has a coarse objective before the fine one constructs an estimator with the coarse objective as its
   * fine one, sweeps, and hands the sweep to the estimator of the fine objective (SetSweep()), making the fine one
   * meanwhile: the same result as one estimator with both objectives. */
  ModulusSweep
  Sweep();
  /** The fine stage starts from \a sweep (made by Sweep() of an estimator with the same unknowns and settings)
   * instead of sweeping. Throws unless it has one analysis per unknown. */
  void
  SetSweep(ModulusSweep sweep);

  /** The fine stage's start loads instead of the fine objective's EstimateInitialParameters(). Throws unless it has
   * one value per parameter of the fine objective. */
  void
  SetStartLoads(std::vector<double> loads);

  /** Warm start [kPa, the unknowns' order]: no sweep (and no coarse objective needed), the outer search starts at
   * \a moduli, its first step from \a relativeCurvature (EstimationResult's, of an earlier estimate of nearly the
   * same data). Used by the resamples of the stated interval. Throws unless it gives one modulus per unknown, each
   * within its bounds. */
  void
  SetWarmStart(std::vector<double> moduli, double relativeCurvature);

  EstimationResult
  Run();

private:
  struct Stages;
  EstimationObjective &       m_Fine;
  EstimationObjective *       m_Coarse;
  std::vector<UnknownModulus> m_Unknowns;
  EstimatorSettings           m_Settings;
  std::vector<double>         m_StartModuli; ///< kPa, empty: no warm start
  double                      m_StartRelativeCurvature{ 0.0 };
  std::optional<ModulusSweep> m_Sweep;
  std::vector<double>         m_StartLoads; ///< empty: the fine objective's own start
  Observer                    m_Observer;
};

} // namespace bmr

#endif
