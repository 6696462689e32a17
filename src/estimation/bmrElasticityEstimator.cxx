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
#include "bmrElasticityEstimator.h"

#include "bmrError.h"
#include "bmrStopwatch.h"
#include "bmrInnerSolve.h"
#include "bmrSecantSearch.h"

#include "itkLBFGSBOptimizerv4.h"

#include <Eigen/Dense>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <mutex>
#include <sstream>

namespace bmr {
void
EstimatorSettings::Validate() const
{
  const char * where = "EstimatorSettings";
  if (numberOfSweepSamples < 3)
  {
    FailInput(where, "numberOfSweepSamples must be at least 3, got " + std::to_string(numberOfSweepSamples));
  }
  if (!(innerGradientTolerance > 0.0) || !(outerGradientTolerance > 0.0) || !(looseInnerGradientTolerance > 0.0))
  {
    FailInput(where, "the gradient tolerances (inner, loose inner, outer) must be positive");
  }
  if (!(outerGradientTolerance < 1.0))
  {
    FailInput(where,
              "outerGradientTolerance must lie in (0, 1) (relative to Phi*), got " +
                std::to_string(outerGradientTolerance));
  }
  if (!(outerStepTolerance >= 0.0 && std::isfinite(outerStepTolerance)))
  {
    FailInput(where, "outerStepTolerance must be finite and not negative, got " + std::to_string(outerStepTolerance));
  }
  if (!(uncertaintyStep >= 1e-4 && uncertaintyStep <= 1.0))
  {
    FailInput(where, "uncertaintyStep must lie in [1e-4, 1] (log E), got " + std::to_string(uncertaintyStep));
  }
}

namespace {
/** vnl's L-BFGS-B (under itk::LBFGSBOptimizerv4) keeps its iteration state in function-local static variables
 * (ITK issue #230): two outer searches running at once in one process corrupt each other. The outer search is
 * therefore serialized; everything else of an estimation (sweep, inner solves outside it) runs concurrently. */
std::mutex &
OuterSearchMutex()
{
  static std::mutex m;
  return m;
}
using Clock = SteadyClock;

double
Norm(const std::vector<double> & v)
{
  double s = 0.0;
  for (double x : v)
  {
    s += x * x;
  }
  return std::sqrt(s);
}

IterationRecord
MakeRecord(const char *                stage,
           unsigned int                iteration,
           const std::vector<double> & moduli,
           const LoadSolution &        s,
           double                      seconds)
{
  IterationRecord r;
  r.stage = stage;
  r.iteration = iteration;
  r.youngsModuli = moduli;
  r.value = s.value;
  r.wallGradientNorm = Norm(s.gradient);
  r.logModulusGradient = s.logModulusGradient;
  r.innerIterations = s.iterations;
  r.seconds = seconds;
  r.work = s.work;
  return r;
}

SolverWork
WorkSince(const SolverWork & now, const SolverWork & before)
{
  SolverWork w;
  w.stateSolves = now.stateSolves - before.stateSolves;
  w.newtonIterations = now.newtonIterations - before.newtonIterations;
  w.factorizations = now.factorizations - before.factorizations;
  w.conjugateGradientIterations = now.conjugateGradientIterations - before.conjugateGradientIterations;
  w.rejectedIncrements = now.rejectedIncrements - before.rejectedIncrements;
  w.coldStarts = now.coldStarts - before.coldStarts;
  return w;
}

bool
OnBound(double E, const UnknownModulus & unknown)
{
  return E <= unknown.lowerBound * 1.0001 || E >= unknown.upperBound * 0.9999;
}

/** The first bracket of the sweep's minimum: the first sign change of dPhi* / dlogE_k from - to + among the
 * samples so far, its zero interpolated linearly in log E_k. A later sample cannot change it. False: none yet. */
bool
FirstBracket(const std::vector<IterationRecord> & sweep, std::size_t k, double & logE, double & curvature)
{
  for (std::size_t i = 0; i + 1 < sweep.size(); ++i)
  {
    const double g0 = sweep[i].logModulusGradient[k], g1 = sweep[i + 1].logModulusGradient[k];
    if (g0 < 0.0 && g1 >= 0.0)
    {
      const double l0 = std::log(sweep[i].youngsModuli[k]), l1 = std::log(sweep[i + 1].youngsModuli[k]);
      logE = l0 + (l1 - l0) * g0 / (g0 - g1);
      // Phi* grows with the number of objective nodes and so does its curvature: relative to Phi*, the
      // coarse sweep's curvature predicts the fine mesh's.
      curvature = (g1 - g0) / (l1 - l0) / std::max(0.5 * (sweep[i].value + sweep[i + 1].value), 1e-300);
      return true;
    }
  }
  return false;
}

/** The sweep \a sweep of unknown \a k: the minimum is bracketed by the first sign change of the envelope
 * gradient dPhi* / dlogE_k from - to + (more robust than the sampled values, which carry the inner
 * solver's tolerance); the zero is interpolated linearly in log E_k. Without a sign change the minimum
 * lies on a bound; when Phi* varies by less than \a flatness (relative) the modulus is not identifiable. */
SweepAnalysis
Analyzesweep(const std::vector<IterationRecord> & sweep, std::size_t k, const UnknownModulus & unknown, double flatness)
{
  double vmin = sweep[0].value, vmax = sweep[0].value;
  for (const auto & r : sweep)
  {
    vmin = std::min(vmin, r.value);
    vmax = std::max(vmax, r.value);
  }
  std::size_t        best = sweep.back().logModulusGradient[k] < 0.0 ? sweep.size() - 1 : 0;
  double             logE = std::log(sweep[best].youngsModuli[k]);
  double             curvature = 0.0;
  const bool         bracketed = FirstBracket(sweep, k, logE, curvature);
  SweepAnalysis      a;
  std::ostringstream msg;
  a.modulus = std::exp(logE);
  a.relativeCurvature = curvature;
  const double variation = (vmax - vmin) / std::max(vmin, 1e-300);
  if (variation < flatness)
  {
    a.identifiable = false;
    msg << "Phi*(E) of \"" << unknown.name << "\" varies by only " << 100.0 * variation << " % over ["
        << unknown.lowerBound << ", " << unknown.upperBound << "] kPa (threshold " << 100.0 * flatness
        << " %): the modulus is not identifiable from these surfaces";
  }
  else if (!bracketed)
  {
    a.identifiable = false;
    a.onBound = true;
    msg << "the minimum of Phi*(E) of \"" << unknown.name << "\" lies on the bound " << sweep[best].youngsModuli[k]
        << " kPa: the true modulus may lie outside [" << unknown.lowerBound << ", " << unknown.upperBound << "] kPa";
  }
  else
  {
    msg << "Phi*(E) varies by " << 100.0 * variation << " % over the bounds, minimum inside";
  }
  a.message = msg.str();
  return a;
}

/** Residual noise of the data at the estimate: the weighted mean square
 * s^2 = sum_s w_s n_s rms_s^2 / sum_s w_s n_s [mm^2], and the effective weight
 * w_eff = sum_s w_s^2 n_s / sum_s w_s n_s, with which Cov(log E) = s^2 w_eff H^-1 holds
 * exactly for equal weights (H grows with the weights, the noise of a residual does not). */
struct ResidualNoise
{
  double variance{ 0.0 };
  double weight{ 1.0 };
};

ResidualNoise
EstimateResidualNoise(const std::vector<ResidualStatistics> & residuals)
{
  double squares = 0.0, weightedCount = 0.0, squaredWeights = 0.0;
  for (const auto & s : residuals)
  {
    squares += s.weight * double(s.count) * s.rms * s.rms;
    weightedCount += s.weight * double(s.count);
    squaredWeights += s.weight * s.weight * double(s.count);
  }
  ResidualNoise noise;
  if (weightedCount > 0.0)
  {
    noise.variance = squares / weightedCount;
    noise.weight = squaredWeights / weightedCount;
  }
  return noise;
}

/** Standard deviations of log E, sqrt(diag(v H^-1)) with v = s^2 w_eff [mm^2], from the symmetrized
 * Hessian [mm^2]; infinite when it is not positive definite (no curvature to determine E). */
std::vector<double>
LogModulusStandardDeviations(const Eigen::MatrixXd & hessian, double residualVariance)
{
  const Eigen::MatrixXd             H = 0.5 * (hessian + hessian.transpose());
  const Eigen::LLT<Eigen::MatrixXd> llt(H);
  std::vector<double>               sigma(H.rows(), std::numeric_limits<double>::infinity());
  if (llt.info() != Eigen::Success)
  {
    return sigma;
  }
  const Eigen::MatrixXd covariance = residualVariance * llt.solve(Eigen::MatrixXd::Identity(H.rows(), H.cols()));
  for (Eigen::Index k = 0; k < H.rows(); ++k)
  {
    sigma[k] = std::sqrt(std::max(0.0, covariance(k, k)));
  }
  return sigma;
}
} // namespace

std::vector<UnknownModulus>
SceneUnknownModuli(const Scene & scene)
{
  std::vector<UnknownModulus> unknowns;
  for (const SceneLabel * l : scene.UnknownLabels())
  {
    unknowns.push_back({ l->name, l->value, l->youngsModulus, l->lowerBound, l->upperBound });
  }
  return unknowns;
}

/** The stages of one Run(), sharing the moduli, the warm-start loads and the result. */
struct ElasticityEstimator::Stages
{
  ElasticityEstimator &      estimator;
  const EstimatorSettings &  settings;
  EstimationResult           result;
  std::vector<double>        moduli;
  std::vector<double>        loads;  // warm start of the next inner solve
  std::vector<SweepAnalysis> status; // per unknown
  double                     progress{ 0.0 };
  // The inner solver follows the loads (LoadParameterization::IsReducedBasis()), the same for the coarse objective.
  const bool levenbergMarquardt;

  explicit Stages(ElasticityEstimator & e)
    : estimator(e)
    , settings(e.m_Settings)
    , levenbergMarquardt(e.m_Fine.GetLoads().IsReducedBasis())
  {
    for (const UnknownModulus & u : e.m_Unknowns)
    {
      moduli.push_back(u.initial);
    }
    status.resize(moduli.size());
  }
  const std::vector<UnknownModulus> &
  Unknowns() const
  {
    return estimator.m_Unknowns;
  }
  LoadSolution
  Solve(EstimationObjective &       objective,
        const std::vector<double> & E,
        const std::vector<double> & start,
        double                      tolerance)
  {
    InnerSettings inner;
    inner.maximumIterations = settings.maximumInnerIterations;
    inner.tolerance = tolerance;
    inner.levenbergMarquardt = levenbergMarquardt;
    inner.limitInversion = settings.limitElementInversion;
    const SolverWork before = objective.GetForwardModel().GetSolverWork();
    LoadSolution     s = SolveInner(objective, E, start, inner, result.rejectedSteps);
    s.work = WorkSince(objective.GetForwardModel().GetSolverWork(), before);
    return s;
  }
  LoadSolution
  Solve(EstimationObjective & objective, const std::vector<double> & E, const std::vector<double> & start)
  {
    return Solve(objective, E, start, settings.innerGradientTolerance);
  }
  void
  Record(const IterationRecord & record, std::vector<IterationRecord> & list, double newProgress)
  {
    list.push_back(record);
    progress = newProgress;
    if (estimator.m_Observer)
    {
      estimator.m_Observer(record, progress);
    }
  }
  /** L-BFGS inner solves and a looser tolerance set: the sweep's samples are loose. They locate the fine stage's
   * start and judge flatness, for which a loose Phi* (above the optimum by about 3e-5 relative on the demo pair)
   * and its log-E derivative do. */
  bool
  LooseSweep() const
  {
    return !levenbergMarquardt && settings.looseInnerGradientTolerance > settings.innerGradientTolerance;
  }
  /** One unknown besides: the outer search's evaluations are loose first. */
  bool
  LooseOuterEvaluations() const
  {
    return moduli.size() == 1 && LooseSweep();
  }
  void
  Sweep();
  struct FineEvaluations;
  void
  Fine();
  void
  OuterSecant(FineEvaluations & fine);
  void
  OuterLBFGSB(FineEvaluations & fine);
  void
  JudgeIdentifiability(const std::vector<double> & estimate);
  void
  Outputs(const std::vector<double> & estimate, const std::vector<double> & estimateLoads);
  void
  Uncertainty(const std::vector<double> & estimate, const std::vector<double> & estimateLoads);
};

void
ElasticityEstimator::Stages::Sweep()
{
  EstimationObjective & objective = estimator.m_Coarse ? *estimator.m_Coarse : estimator.m_Fine;
  std::vector<double>   start = objective.EstimateInitialParameters();
  const unsigned int    n = settings.numberOfSweepSamples;
  const double          total = double(n) * double(moduli.size());
  const double tolerance = LooseSweep() ? settings.looseInnerGradientTolerance : settings.innerGradientTolerance;
  for (std::size_t k = 0; k < moduli.size(); ++k)
  {
    const UnknownModulus &       unknown = Unknowns()[k];
    std::vector<IterationRecord> samples;
    for (unsigned int i = 0; i < n; ++i)
    {
      const auto          ts = Clock::now();
      std::vector<double> E = moduli;
      E[k] = unknown.lowerBound * std::pow(unknown.upperBound / unknown.lowerBound, double(i) / double(n - 1));
      // Continuation: each sample starts from the previous optimum, so that the sweep follows one branch of
      // minima of the (non-convex) distance objective and Phi*(E) is smooth.
      const LoadSolution s = Solve(objective, E, start, tolerance);
      start = s.parameters;
      const unsigned int index = static_cast<unsigned int>(k * n + i);
      samples.push_back(MakeRecord("sweep", index, E, s, SecondsSince(ts)));
      samples.back().loose = LooseSweep();
      Record(samples.back(), result.sweep, 0.5 * double(index + 1) / total);
    }
    status[k] = Analyzesweep(samples, k, unknown, settings.flatnessThreshold);
    moduli[k] = status[k].modulus;
  }
}

/** The fine stage's inner solves: each warm-started from the previous optimum, recorded, and the best
 * visited kept (an outer search may end on a trial point). A loose solve (to looseInnerGradientTolerance, a point
 * the outer search passes through) is never the best: the result always comes from a full solve. */
struct ElasticityEstimator::Stages::FineEvaluations
{
  Stages &            stages;
  LoadSolution        last;
  bool                lastLoose{ false };
  unsigned int        evaluation{ 0 };
  std::vector<double> bestModuli, bestLoads;
  double              bestValue{ std::numeric_limits<double>::infinity() };

  /** The inner solve at \a E, loose or to the full tolerance; asked for again, the last one (an outer search
   * starts by evaluating the point it was given), unless that was loose and a full one is asked for: then the
   * loose solve is continued to the full tolerance. */
  const LoadSolution &
  At(const std::vector<double> & E, bool loose = false)
  {
    if (evaluation > 0 && stages.result.history.back().youngsModuli == E && (loose || !lastLoose))
    {
      return last;
    }
    const auto ts = Clock::now();
    last = stages.Solve(stages.estimator.m_Fine,
                        E,
                        stages.loads,
                        loose ? stages.settings.looseInnerGradientTolerance : stages.settings.innerGradientTolerance);
    lastLoose = loose;
    stages.loads = last.parameters;
    IterationRecord record = MakeRecord("fine", evaluation, E, last, SecondsSince(ts));
    record.loose = loose;
    stages.Record(record, stages.result.history, std::min(0.99, 0.5 + 0.02 * double(evaluation + 1)));
    ++evaluation;
    if (!loose && last.value < bestValue)
    {
      bestValue = last.value;
      bestModuli = E;
      bestLoads = stages.loads;
    }
    return last;
  }
};

void
ElasticityEstimator::Stages::Fine()
{
  FineEvaluations fine{ *this };
  fine.At(moduli, LooseOuterEvaluations());
  if (moduli.size() == 1)
  {
    OuterSecant(fine);
  }
  else if (!moduli.empty())
  {
    OuterLBFGSB(fine);
  }
  result.value = fine.bestValue;
  moduli = fine.bestModuli;
  loads = fine.bestLoads;
}

void
ElasticityEstimator::Stages::OuterSecant(FineEvaluations & fine)
{
  const UnknownModulus & unknown = Unknowns()[0];
  SecantSearchSettings   search;
  const double           startValue = fine.last.value; // Phi* at the start, from above when loose
  search.lowerBound = std::log(unknown.lowerBound);
  search.upperBound = std::log(unknown.upperBound);
  search.curvatureGuess = status[0].relativeCurvature * startValue;
  search.stepTolerance = settings.outerStepTolerance;
  search.derivativeTolerance = settings.outerGradientTolerance * std::max(startValue, 1e-12);
  search.maximumEvaluations = settings.maximumOuterIterations;
  const bool loose = LooseOuterEvaluations();
  const auto point = [&](double logE, const LoadSolution & s) {
    IterationRecord r = result.history.back();
    r.stage = "outer";
    r.iteration = static_cast<unsigned int>(result.outerIterations.size());
    result.outerIterations.push_back(r);
    return SecantPoint{ logE, s.value, s.logModulusGradient[0], !fine.lastLoose };
  };
  const auto evaluate = [&](double logE) { return point(logE, fine.At({ std::exp(logE) }, loose)); };
  const auto refine = [&](double logE) {
    result.outerIterations.pop_back(); // the same outer iteration, now solved in full
    return point(logE, fine.At({ std::exp(logE) }, false));
  };
  const SecantSearchResult found = SecantSearch(evaluate, std::log(moduli[0]), search, refine);
  result.outerStopCondition = "secant search: " + found.stopCondition;
  result.relativeCurvature = found.curvature / std::max(fine.bestValue, 1e-300);
}

void
ElasticityEstimator::Stages::OuterLBFGSB(FineEvaluations & fine)
{
  // Bounded L-BFGS over log E (vnl's L-BFGS-B through ITK).
  auto metric = FunctionMetric::New();
  metric->m_Function = [&](const std::vector<double> & logE, std::vector<double> * g) {
    std::vector<double> E(logE.size());
    for (std::size_t m = 0; m < E.size(); ++m)
    {
      E[m] = std::exp(logE[m]);
    }
    const LoadSolution & s = fine.At(E);
    if (g)
    {
      *g = s.logModulusGradient;
    }
    return s.value;
  };
  const unsigned int                         m = static_cast<unsigned int>(moduli.size());
  FunctionMetric::ParametersType             p(m);
  itk::LBFGSBOptimizerv4::BoundValueType     lo(m), hi(m);
  itk::LBFGSBOptimizerv4::BoundSelectionType select(m);
  for (unsigned int k = 0; k < m; ++k)
  {
    p[k] = std::log(moduli[k]);
    lo[k] = std::log(Unknowns()[k].lowerBound);
    hi[k] = std::log(Unknowns()[k].upperBound);
    select[k] = 2; // both bounds
  }
  metric->SetParameters(p);
  auto optimizer = itk::LBFGSBOptimizerv4::New();
  optimizer->SetMetric(metric);
  optimizer->SetLowerBound(lo);
  optimizer->SetUpperBound(hi);
  optimizer->SetBoundSelection(select);
  optimizer->SetNumberOfIterations(settings.maximumOuterIterations);
  optimizer->SetMaximumNumberOfFunctionEvaluations(settings.maximumOuterIterations);
  optimizer->SetGradientConvergenceTolerance(settings.outerGradientTolerance * std::max(fine.bestValue, 1e-12));
  optimizer->SetCostFunctionConvergenceFactor(1e7);
  // The accepted iterates of L-BFGS-B (its line searches' trial points are in the history only).
  optimizer->AddObserver(itk::IterationEvent(), [&](const itk::EventObject &) {
    IterationRecord r = result.history.back();
    r.stage = "outer";
    r.iteration = static_cast<unsigned int>(optimizer->GetCurrentIteration());
    if (!result.outerIterations.empty() && result.outerIterations.back().iteration == r.iteration)
    {
      result.outerIterations.pop_back(); // the event comes more than once per iteration
    }
    r.value = optimizer->GetCurrentMetricValue();
    const auto & position = optimizer->GetCurrentPosition();
    for (unsigned int k = 0; k < position.GetSize(); ++k)
    {
      r.youngsModuli[k] = std::exp(position[k]);
    }
    result.outerIterations.push_back(r);
  });
  {
    const std::lock_guard<std::mutex> serialized(OuterSearchMutex());
    optimizer->StartOptimization();
  }
  result.outerStopCondition = optimizer->GetStopConditionDescription();
}

void
ElasticityEstimator::Stages::JudgeIdentifiability(const std::vector<double> & estimate)
{
  result.identifiable = true;
  result.identifiabilityMessage.clear();
  for (std::size_t k = 0; k < estimate.size(); ++k)
  {
    SweepAnalysis & s = status[k];
    if (OnBound(estimate[k], Unknowns()[k]))
    {
      s.identifiable = false;
      s.message += "; the estimate lies on a bound";
    }
    else if (s.onBound)
    {
      // The coarse mesh only starts the search; what counts is where the fine-mesh minimum lies.
      std::ostringstream msg;
      msg << "the coarse-mesh sweep's minimum lay on a bound, the fine-mesh minimum lies inside the bounds at "
          << estimate[k] << " kPa (" << s.message << ")";
      s.identifiable = true;
      s.message = msg.str();
    }
    result.identifiable = result.identifiable && s.identifiable;
    // One unknown: its message; several: each named, in order.
    const std::string named = estimate.size() > 1 ? Unknowns()[k].name + ": " + s.message : s.message;
    result.identifiabilityMessage += (k ? "; " : "") + named;
  }
}

void
ElasticityEstimator::Stages::Outputs(const std::vector<double> & estimate, const std::vector<double> & estimateLoads)
{
  EstimationObjective & fine = estimator.m_Fine;
  result.youngsModuli = estimate;
  result.loadParameters = estimateLoads;
  fine.SetYoungsModuli(estimate);
  result.displacement = fine.ComputeDisplacement(estimateLoads);
  result.boundaryForces = fine.ComputeBoundaryForces(result.displacement);
  result.invertedElements = CountInvertedElements(fine.GetForwardModel().GetMesh(), result.displacement);
  result.residuals = fine.ComputeStatistics(result.displacement);
  result.residualStandardDeviation = std::sqrt(EstimateResidualNoise(result.residuals).variance);
}

void
ElasticityEstimator::Stages::Uncertainty(const std::vector<double> & estimate,
                                         const std::vector<double> & estimateLoads)
{
  // Curvature of Phi* by central differences of the envelope gradient, each inner solve warm-started from
  // the estimate's loads. Meaningless on a bound, where Phi* is not stationary.
  const Eigen::Index m = static_cast<Eigen::Index>(estimate.size());
  Eigen::MatrixXd    hessian(m, m);
  const double       delta = settings.uncertaintyStep;
  for (Eigen::Index k = 0; k < m; ++k)
  {
    std::vector<double> gradient[2];
    for (int side = 0; side < 2; ++side)
    {
      const auto          ts = Clock::now();
      std::vector<double> E = estimate;
      E[k] *= std::exp(side == 0 ? delta : -delta);
      const LoadSolution s = Solve(estimator.m_Fine, E, estimateLoads);
      gradient[side] = s.logModulusGradient;
      Record(MakeRecord("curvature", unsigned(2 * k + side), E, s, SecondsSince(ts)), result.history, progress);
    }
    for (Eigen::Index i = 0; i < m; ++i)
    {
      hessian(i, k) = (gradient[0][i] - gradient[1][i]) / (2.0 * delta);
    }
  }
  result.curvature.assign(hessian.data(), hessian.data() + hessian.size());
  const ResidualNoise noise = EstimateResidualNoise(result.residuals);
  result.logModulusSigma = LogModulusStandardDeviations(hessian, noise.variance * noise.weight);
}

ElasticityEstimator::ElasticityEstimator(EstimationObjective &       fine,
                                         EstimationObjective *       coarse,
                                         std::vector<UnknownModulus> unknowns,
                                         EstimatorSettings           settings)
  : m_Fine(fine)
  , m_Coarse(coarse)
  , m_Unknowns(std::move(unknowns))
  , m_Settings(settings)
{
  if (m_Unknowns.size() != fine.GetUnknownLabels().size())
  {
    Fail("ElasticityEstimator", "the unknown moduli differ from the objective's unknown labels");
  }
  if (coarse && m_Unknowns.size() != coarse->GetUnknownLabels().size())
  {
    Fail("ElasticityEstimator", "the unknown moduli differ from the objective's unknown labels");
  }
  for (const UnknownModulus & u : m_Unknowns)
  {
    if (!(u.lowerBound > 0.0 && u.upperBound > u.lowerBound && std::isfinite(u.upperBound)))
    {
      Fail("ElasticityEstimator", "the bounds of \"" + u.name + "\" must satisfy 0 < lower < upper < inf [kPa]");
    }
  }
  m_Settings.Validate();
}

void
ElasticityEstimator::SetWarmStart(std::vector<double> moduli, double relativeCurvature)
{
  if (moduli.size() != m_Unknowns.size())
  {
    FailInput("ElasticityEstimator", "the warm start must give one modulus per unknown");
  }
  for (std::size_t k = 0; k < moduli.size(); ++k)
  {
    if (!(moduli[k] >= m_Unknowns[k].lowerBound && moduli[k] <= m_Unknowns[k].upperBound))
    {
      FailInput("ElasticityEstimator", "the warm start of \"" + m_Unknowns[k].name + "\" lies outside its bounds");
    }
  }
  m_StartModuli = std::move(moduli);
  m_StartRelativeCurvature = relativeCurvature;
}

ModulusSweep
ElasticityEstimator::Sweep()
{
  if (m_Unknowns.empty())
  {
    Fail("ElasticityEstimator", "there is no unknown modulus to sweep");
  }
  Stages     run(*this);
  const auto t0 = Clock::now();
  run.Sweep();
  ModulusSweep sweep{ run.status, run.result.sweep, run.result.rejectedSteps, SecondsSince(t0) };
  m_Sweep = sweep;
  return sweep;
}

void
ElasticityEstimator::SetSweep(ModulusSweep sweep)
{
  if (sweep.unknowns.size() != m_Unknowns.size())
  {
    FailInput("ElasticityEstimator", "the sweep must give one analysis per unknown");
  }
  m_Sweep = std::move(sweep);
}

void
ElasticityEstimator::SetStartLoads(std::vector<double> loads)
{
  if (loads.size() != m_Fine.GetNumberOfParameters())
  {
    FailInput("ElasticityEstimator", "the start loads must give one value per parameter of the fine objective");
  }
  m_StartLoads = std::move(loads);
}

EstimationResult
ElasticityEstimator::Run()
{
  Stages run(*this);
  auto   t0 = Clock::now();
  if (!m_StartModuli.empty())
  {
    run.moduli = m_StartModuli;
    run.status[0].relativeCurvature = m_StartRelativeCurvature;
  }
  else if (!m_Unknowns.empty())
  {
    if (!m_Sweep)
    {
      run.Sweep();
    }
    else
    {
      run.status = m_Sweep->unknowns;
      run.result.sweep = m_Sweep->samples;
      run.result.rejectedSteps = m_Sweep->rejectedSteps;
      run.progress = 0.5;
      for (std::size_t k = 0; k < m_Unknowns.size(); ++k)
      {
        run.moduli[k] = run.status[k].modulus;
      }
    }
  }
  run.result.timings["sweep"] = m_Sweep ? m_Sweep->seconds : SecondsSince(t0);

  t0 = Clock::now();
  run.loads = m_StartLoads.empty() ? m_Fine.EstimateInitialParameters() : m_StartLoads;
  run.result.timings["initial loads"] = SecondsSince(t0);

  t0 = Clock::now();
  run.Fine();
  run.JudgeIdentifiability(run.moduli);
  run.result.timings["fine"] = SecondsSince(t0);

  const std::vector<double> estimate = run.moduli, estimateLoads = run.loads;
  run.Outputs(estimate, estimateLoads);
  bool onBound = false;
  for (std::size_t k = 0; k < m_Unknowns.size(); ++k)
  {
    onBound = onBound || OnBound(estimate[k], m_Unknowns[k]);
  }
  if (m_Settings.estimateUncertainty && !m_Unknowns.empty() && !onBound)
  {
    t0 = Clock::now();
    run.Uncertainty(estimate, estimateLoads);
    run.result.timings["uncertainty"] = SecondsSince(t0);
  }
  return run.result;
}

} // namespace bmr
