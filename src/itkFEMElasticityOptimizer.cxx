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
#include "itkFEMElasticityOptimizer.h"

#include "bmrError.h"
#include "bmrSurfaceMatchingObjective.h"
#include "itkGridGeometryConversion.h"
#include "itkLBFGS2Optimizerv4.h"
#include "itkLBFGSBOptimizerv4.h"
#include "itkObjectToObjectMetricBase.h"

#include <Eigen/Dense>

#include <algorithm>
#include <chrono>
#include <limits>
#include <functional>
#include <memory>
#include <cmath>
#include <sstream>

namespace itk {
namespace {
using Clock = std::chrono::steady_clock;
double
Seconds(Clock::time_point start)
{
  return std::chrono::duration<double>(Clock::now() - start).count();
}

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

/** Adapts a function with gradient to ITK's v4 metric interface, which v4
 * optimizers minimise; by ITK's convention the "derivative" handed to the
 * optimizer is the negative gradient. */
class FunctionMetric : public ObjectToObjectMetricBaseTemplate<double>
{
public:
  ITK_DISALLOW_COPY_AND_MOVE(FunctionMetric);
  using Self = FunctionMetric;
  using Superclass = ObjectToObjectMetricBaseTemplate<double>;
  using Pointer = SmartPointer<Self>;
  itkNewMacro(Self);
  itkTypeMacro(FunctionMetric, ObjectToObjectMetricBaseTemplate);

  /** value(x, gradient or null) */
  using FunctionType = std::function<double(const std::vector<double> &, std::vector<double> *)>;
  FunctionType m_Function;

  void
  Initialize() override
  {}
  MeasureType
  GetValue() const override
  {
    this->m_Value = m_Function(AsVector(), nullptr);
    return this->m_Value;
  }
  void
  GetDerivative(DerivativeType & derivative) const override
  {
    MeasureType value;
    GetValueAndDerivative(value, derivative);
  }
  void
  GetValueAndDerivative(MeasureType & value, DerivativeType & derivative) const override
  {
    std::vector<double> gradient;
    value = m_Function(AsVector(), &gradient);
    this->m_Value = value;
    if (derivative.GetSize() != gradient.size())
    {
      derivative.SetSize(static_cast<unsigned int>(gradient.size()));
    }
    for (std::size_t i = 0; i < gradient.size(); ++i)
    {
      derivative[static_cast<unsigned int>(i)] = -gradient[i];
    }
  }
  NumberOfParametersType
  GetNumberOfParameters() const override
  {
    return m_Parameters.GetSize();
  }
  NumberOfParametersType
  GetNumberOfLocalParameters() const override
  {
    return m_Parameters.GetSize();
  }
  void
  SetParameters(ParametersType & parameters) override
  {
    m_Parameters = parameters;
  }
  const ParametersType &
  GetParameters() const override
  {
    return m_Parameters;
  }
  bool
  HasLocalSupport() const override
  {
    return false;
  }
  void
  UpdateTransformParameters(const DerivativeType & update, ParametersValueType factor) override
  {
    for (unsigned int i = 0; i < m_Parameters.GetSize(); ++i)
    {
      m_Parameters[i] += factor * update[i];
    }
  }
  std::vector<double>
  AsVector() const
  {
    return std::vector<double>(m_Parameters.begin(), m_Parameters.end());
  }

protected:
  FunctionMetric() = default;
  ~FunctionMetric() override = default;

private:
  ParametersType m_Parameters;
};

/** Result of an inner solve at fixed E. */
struct InnerSolution
{
  double              value{ 0.0 };
  std::vector<double> wall;
  std::vector<double> logModulusGradient;
  double              wallGradientNorm{ 0.0 };
  unsigned int        iterations{ 0 };
  std::string         stop;
};

/** \a start, or when it inverts more elements than the unloaded walls (p = 0) do, the largest
 * fraction t start (bisection to 1/1024) that does not: the step limit's feasible start, e.g. after
 * surface matching pulled the walls through thin tissue. */
std::vector<double>
WithoutNewInversions(bmr::SurfaceMatchingObjective & objective, const std::vector<double> & start)
{
  objective.Evaluate(start, nullptr, nullptr);
  const std::size_t atStart = objective.GetNumberOfInvertedElements();
  if (atStart == 0)
  {
    return start;
  }
  const std::vector<double> zero(start.size(), 0.0);
  objective.Evaluate(zero, nullptr, nullptr);
  const std::size_t unloaded = objective.GetNumberOfInvertedElements();
  if (atStart <= unloaded)
  {
    return start;
  }
  const auto scaled = [&start](double t) {
    std::vector<double> s(start);
    for (double & x : s)
    {
      x *= t;
    }
    return s;
  };
  double feasible = 0.0, infeasible = 1.0;
  for (int k = 0; k < 10; ++k)
  {
    const double middle = 0.5 * (feasible + infeasible);
    objective.Evaluate(scaled(middle), nullptr, nullptr);
    (objective.GetNumberOfInvertedElements() > unloaded ? infeasible : feasible) = middle;
  }
  return scaled(feasible);
}

/** min_p Phi(E, p) from \a start: Levenberg-Marquardt in the reduced wall basis, or L-BFGS
 * (libLBFGS through ITK) with one parameter per wall node; then the gradients at the optimum.
 * With \a limitInversion (L-BFGS only) a trial point that inverts more elements than \a start is
 * answered with a value above Phi(start), so that the line search shortens the step; the
 * number of such rejections is added to \a rejected. */
InnerSolution
SolveInner(bmr::SurfaceMatchingObjective & objective,
           const std::vector<double> &     moduli,
           const std::vector<double> &     start,
           unsigned int                    maximumIterations,
           double                          tolerance,
           bool                            gaussNewton,
           bool                            limitInversion = false,
           std::size_t *                   rejected = nullptr)
{
  objective.SetYoungsModuli(moduli);
  InnerSolution result;
  result.wall = start;
  if (gaussNewton && objective.GetNumberOfParameters() > 0)
  {
    const bmr::WallSolution w = objective.SolveWalls(start, maximumIterations, tolerance);
    result.wall = w.parameters;
    result.value = w.value;
    result.logModulusGradient = w.logModulusGradient;
    result.wallGradientNorm = Norm(w.gradient);
    result.iterations = w.iterations;
    result.stop = w.stop;
    return result;
  }
  if (objective.GetNumberOfParameters() > 0)
  {
    std::size_t         allowed = 0;
    double              ceiling = 0.0;
    double              bestFeasibleValue = 0.0;
    std::vector<double> bestFeasible = start;
    if (limitInversion)
    {
      bestFeasible = WithoutNewInversions(objective, start);
      bestFeasibleValue = objective.Evaluate(bestFeasible, nullptr, nullptr);
      allowed = objective.GetNumberOfInvertedElements();
      ceiling = 2.0 * bestFeasibleValue + 1.0; // above Phi(start): fails the line search's sufficient decrease
    }
    auto metric = FunctionMetric::New();
    metric->m_Function = [&](const std::vector<double> & d, std::vector<double> * g) {
      const double value = objective.Evaluate(d, g, nullptr);
      if (!limitInversion)
      {
        return value;
      }
      if (objective.GetNumberOfInvertedElements() > allowed)
      {
        if (rejected)
        {
          ++*rejected;
        }
        return std::max(value, ceiling);
      }
      if (value < bestFeasibleValue)
      {
        bestFeasibleValue = value;
        bestFeasible = d;
      }
      return value;
    };
    FunctionMetric::ParametersType p(static_cast<unsigned int>(start.size()));
    std::copy(bestFeasible.begin(), bestFeasible.end(), p.begin());
    metric->SetParameters(p);
    auto optimizer = LBFGS2Optimizerv4::New();
    optimizer->SetMetric(metric);
    optimizer->SetSolutionAccuracy(tolerance);
    optimizer->SetMaximumIterations(static_cast<int>(maximumIterations));
    optimizer->SetHessianApproximationAccuracy(10);
    // Stop also when Phi has decreased by less than 1e-10 relative over 10 iterations (a flat valley).
    optimizer->SetDeltaConvergenceDistance(10);
    optimizer->SetDeltaConvergenceTolerance(1e-10);
    optimizer->StartOptimization();
    // libLBFGS returns its last accepted point, which never inverts; the best feasible point visited is
    // kept in case an implementation does otherwise.
    result.wall = limitInversion ? bestFeasible : metric->AsVector();
    result.iterations = static_cast<unsigned int>(optimizer->GetCurrentIteration() + 1);
    result.stop = optimizer->GetStopConditionDescription();
  }
  std::vector<double> gradientD;
  result.value = objective.Evaluate(result.wall, &gradientD, &result.logModulusGradient);
  result.wallGradientNorm = Norm(gradientD);
  return result;
}

FEMElasticityOptimizer::IterationRecord
MakeRecord(const char *                stage,
           unsigned int                iteration,
           const std::vector<double> & moduli,
           const InnerSolution &       s,
           double                      seconds)
{
  FEMElasticityOptimizer::IterationRecord r;
  r.stage = stage;
  r.iteration = iteration;
  r.youngsModuli = moduli;
  r.value = s.value;
  r.wallGradientNorm = s.wallGradientNorm;
  r.logModulusGradient = s.logModulusGradient;
  r.innerIterations = s.iterations;
  r.seconds = seconds;
  return r;
}

/** Residual noise of the objective nodes at the estimate: the weighted mean square
 * s^2 = sum_s w_s n_s rms_s^2 / sum_s w_s n_s [mm^2], and the effective weight
 * w_eff = sum_s w_s^2 n_s / sum_s w_s n_s, with which Cov(log E) = s^2 w_eff H^-1 holds
 * exactly for equal weights (H grows with the weights, the noise of a residual does not). */
struct ResidualNoise
{
  double variance{ 0.0 };
  double weight{ 1.0 };
};

ResidualNoise
EstimateResidualNoise(const bmr::Scene & scene, const std::vector<bmr::SurfaceDistanceStatistics> & surfaces)
{
  double squares = 0.0, weightedCount = 0.0, squaredWeights = 0.0;
  for (const auto & s : surfaces)
  {
    double weight = 1.0;
    for (const auto & term : scene.objective)
    {
      if (term.label == s.name)
      {
        weight = term.weight;
      }
    }
    squares += weight * double(s.nodes) * s.rms * s.rms;
    weightedCount += weight * double(s.nodes);
    squaredWeights += weight * weight * double(s.nodes);
  }
  ResidualNoise noise;
  if (weightedCount > 0.0)
  {
    noise.variance = squares / weightedCount;
    noise.weight = squaredWeights / weightedCount;
  }
  return noise;
}

/** Standard deviations of log E, sqrt(diag(v H^-1)) with v = s^2 w_eff [mm^2], from the symmetrised
 * Hessian \a hessian [mm^2]; infinite when it is not positive definite (no curvature to determine E). */
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

/** Initial modulus and identifiability from the sweep of Phi*(E). */
struct SweepAnalysis
{
  double      modulus{ 0.0 };
  bool        identifiable{ true };
  bool        onBound{ false }; ///< not flat, but no sign change of dPhi*/dlogE: the coarse minimum is on a bound
  std::string message;
};

/** The minimum is bracketed by the first sign change of the envelope gradient dPhi* / dlogE from - to +
 * (more robust than the sampled values, which carry the inner solver's tolerance); the zero is
 * interpolated linearly in log E. Without a sign change the minimum lies on a bound; when Phi* varies by
 * less than \a flatness (relative) over the bounds the modulus is not identifiable. */
SweepAnalysis
AnalyseSweep(const std::vector<FEMElasticityOptimizer::IterationRecord> & sweep,
             const std::string &                                          name,
             double                                                       lower,
             double                                                       upper,
             double                                                       flatness)
{
  double vmin = sweep[0].value, vmax = sweep[0].value;
  for (const auto & r : sweep)
  {
    vmin = std::min(vmin, r.value);
    vmax = std::max(vmax, r.value);
  }
  std::size_t best = sweep.back().logModulusGradient[0] < 0.0 ? sweep.size() - 1 : 0;
  double      logE = std::log(sweep[best].youngsModuli[0]);
  bool        bracketed = false;
  for (std::size_t k = 0; k + 1 < sweep.size() && !bracketed; ++k)
  {
    const double g0 = sweep[k].logModulusGradient[0], g1 = sweep[k + 1].logModulusGradient[0];
    if (g0 < 0.0 && g1 >= 0.0)
    {
      const double l0 = std::log(sweep[k].youngsModuli[0]), l1 = std::log(sweep[k + 1].youngsModuli[0]);
      logE = l0 + (l1 - l0) * g0 / (g0 - g1);
      bracketed = true;
    }
  }
  SweepAnalysis      a;
  std::ostringstream msg;
  a.modulus = std::exp(logE);
  const double variation = (vmax - vmin) / std::max(vmin, 1e-300);
  if (variation < flatness)
  {
    a.identifiable = false;
    msg << "Phi*(E) of \"" << name << "\" varies by only " << 100.0 * variation << " % over [" << lower << ", " << upper
        << "] kPa (threshold " << 100.0 * flatness << " %): the modulus is not identifiable from these surfaces";
  }
  else if (!bracketed)
  {
    a.identifiable = false;
    a.onBound = true;
    msg << "the minimum of Phi*(E) of \"" << name << "\" lies on the bound " << sweep[best].youngsModuli[0]
        << " kPa: the true modulus may lie outside [" << lower << ", " << upper << "] kPa";
  }
  else
  {
    msg << "Phi*(E) varies by " << 100.0 * variation << " % over the bounds, minimum inside";
  }
  a.message = msg.str();
  return a;
}

std::shared_ptr<const bmr::SignedDistanceSampler>
ToSampler(const FEMElasticityOptimizer::DistanceMapType * map, const std::string & name)
{
  const auto region = map->GetBufferedRegion();
  if (region != map->GetLargestPossibleRegion() || region.GetNumberOfPixels() == 0)
  {
    itkGenericExceptionMacro(<< "FEMElasticityOptimizer: the distance map of \"" << name
                             << "\" is empty or not fully buffered");
  }
  const float *      p = map->GetBufferPointer();
  std::vector<float> values(p, p + region.GetNumberOfPixels());
  const std::string  what = "distance map of \"" + name + "\"";
  return std::make_shared<bmr::SignedDistanceSampler>(GridGeometryOf(map), std::move(values), what.c_str());
}
} // namespace

FEMElasticityOptimizer::FEMElasticityOptimizer()
{
  this->SetNumberOfRequiredInputs(1);
  this->SetNumberOfRequiredOutputs(1);
  this->SetNthOutput(0, this->MakeOutput(0));
  this->ProcessObject::SetNthOutput(0, MeshObjectType::New().GetPointer());
}

void
FEMElasticityOptimizer::SetMesh(const MeshObjectType * mesh)
{
  this->SetNthInput(0, const_cast<MeshObjectType *>(mesh));
}

const FEMElasticityOptimizer::MeshObjectType *
FEMElasticityOptimizer::GetMesh() const
{
  return itkDynamicCastInDebugMode<const MeshObjectType *>(this->GetInput(0));
}

void
FEMElasticityOptimizer::SetCoarseMesh(const MeshObjectType * mesh)
{
  this->SetInput("CoarseMesh", const_cast<MeshObjectType *>(mesh));
}

const FEMElasticityOptimizer::MeshObjectType *
FEMElasticityOptimizer::GetCoarseMesh() const
{
  return dynamic_cast<const MeshObjectType *>(this->GetInput("CoarseMesh"));
}

void
FEMElasticityOptimizer::SetDistanceMap(const std::string & labelName, const DistanceMapType * map)
{
  if (std::find(m_DistanceMapNames.begin(), m_DistanceMapNames.end(), labelName) == m_DistanceMapNames.end())
  {
    m_DistanceMapNames.push_back(labelName);
  }
  this->SetInput("DistanceMap:" + labelName, const_cast<DistanceMapType *>(map));
}

const FEMElasticityOptimizer::DistanceMapType *
FEMElasticityOptimizer::GetDistanceMap(const std::string & labelName) const
{
  return dynamic_cast<const DistanceMapType *>(this->GetInput("DistanceMap:" + labelName));
}

void
FEMElasticityOptimizer::SetScene(const bmr::Scene & scene)
{
  scene.Validate();
  m_Scene = scene;
  this->Modified();
}

FEMElasticityOptimizer::MeshObjectType *
FEMElasticityOptimizer::GetOutput()
{
  return itkDynamicCastInDebugMode<MeshObjectType *>(this->ProcessObject::GetOutput(0));
}

void
FEMElasticityOptimizer::VerifyPreconditions() ITKv5_CONST
{
  Superclass::VerifyPreconditions();
  if (m_Scene.labels.empty())
  {
    itkExceptionMacro(<< "no scene was set (SetScene)");
  }
  if (m_Scene.objective.empty())
  {
    itkExceptionMacro(<< "the scene has no objective surface");
  }
  for (const auto & term : m_Scene.objective)
  {
    if (this->GetDistanceMap(term.label) == nullptr)
    {
      itkExceptionMacro(<< "no distance map for objective label \"" << term.label << "\" (SetDistanceMap)");
    }
  }
  if (m_NumberOfSweepSamples < 3)
  {
    itkExceptionMacro(<< "NumberOfSweepSamples must be at least 3, got " << m_NumberOfSweepSamples);
  }
  if (!(m_InnerGradientTolerance > 0.0) || !(m_OuterGradientTolerance > 0.0))
  {
    itkExceptionMacro(<< "the gradient tolerances must be positive");
  }
  if (m_LimitElementInversion && m_WallControlSpacing > 0.0)
  {
    itkExceptionMacro(<< "LimitElementInversion needs one parameter per wall node (WallControlSpacing 0, got "
                      << m_WallControlSpacing << " mm): the reduced-basis solver sees only the objective nodes");
  }
}

void
FEMElasticityOptimizer::Record(const IterationRecord & record, std::vector<IterationRecord> & list)
{
  m_CurrentRecord = record;
  list.push_back(record);
  this->InvokeEvent(IterationEvent());
}

void
FEMElasticityOptimizer::GenerateData()
{
  m_Sweep.clear();
  m_History.clear();
  m_OuterIterations.clear();
  m_OuterStopCondition.clear();
  m_SurfaceDistances.clear();
  m_EstimatedYoungsModuli.clear();
  m_Timings.clear();
  m_Identifiable = true;
  m_IdentifiabilityMessage.clear();
  m_ModulusUncertainty.clear();
  m_NumberOfRejectedSteps = 0;
  m_NumberOfInvertedElements = 0;
  m_ResidualStandardDeviation = 0.0;
  m_ModulusCurvature = 0.0;

  // Distance maps are shared by the coarse and the fine objective.
  std::map<std::int32_t, std::shared_ptr<const bmr::SignedDistanceSampler>> samplers;
  for (const auto & term : m_Scene.objective)
  {
    samplers[m_Scene.FindLabel(term.label)->value] = ToSampler(this->GetDistanceMap(term.label), term.label);
  }
  const bmr::SceneLabel * gauge = m_Scene.gauge.empty() ? nullptr : m_Scene.FindLabel(m_Scene.gauge);
  if (gauge == nullptr)
  {
    for (const auto & l : m_Scene.labels)
    {
      if (l.role == bmr::LabelRole::Material)
      {
        gauge = &l;
        break;
      }
    }
  }
  m_GaugeLabel = gauge ? gauge->name : std::string();

  std::vector<const bmr::SceneLabel *> unknown;
  std::vector<double>                  moduli, lower, upper;
  for (const auto & l : m_Scene.labels)
  {
    if (l.role == bmr::LabelRole::UnknownMaterial)
    {
      unknown.push_back(&l);
      moduli.push_back(l.youngsModulus);
      lower.push_back(l.lowerBound);
      upper.push_back(l.upperBound);
    }
  }

  const bmr::TetrahedralMesh &  fine = this->GetMesh()->Get();
  bmr::SurfaceMatchingObjective fineObjective(fine, m_Scene, bmr::SceneObjectiveSurfaces(m_Scene, fine, samplers));
  fineObjective.SetWallControlSpacing(m_WallControlSpacing);
  fineObjective.SetWallRegularization(m_WallRegularization);
  fineObjective.SetWallMotionAlongNormals(m_WallMotionAlongNormals);

  // Levenberg-Marquardt needs one solve per parameter: only with the reduced wall basis.
  const bool gaussNewton = m_WallControlSpacing > 0.0;

  // Every inner solve, with the same stopping rules and step limit.
  const auto solve =
    [&](bmr::SurfaceMatchingObjective & objective, const std::vector<double> & E, const std::vector<double> & start) {
      return SolveInner(objective,
                        E,
                        start,
                        m_MaximumNumberOfInnerIterations,
                        m_InnerGradientTolerance,
                        gaussNewton,
                        m_LimitElementInversion,
                        &m_NumberOfRejectedSteps);
    };

  // 1. Sweep of Phi*(E) over the bounds of the first unknown modulus, on the coarse mesh.
  bool sweepOnBound = false;
  auto t0 = Clock::now();
  if (!unknown.empty())
  {
    const MeshObjectType *                         coarseObject = this->GetCoarseMesh();
    const bmr::TetrahedralMesh &                   coarse = coarseObject ? coarseObject->Get() : fine;
    std::unique_ptr<bmr::SurfaceMatchingObjective> coarseOwned;
    bmr::SurfaceMatchingObjective *                sweepObjective = &fineObjective;
    if (coarseObject)
    {
      coarseOwned.reset(
        new bmr::SurfaceMatchingObjective(coarse, m_Scene, bmr::SceneObjectiveSurfaces(m_Scene, coarse, samplers)));
      sweepObjective = coarseOwned.get();
      sweepObjective->SetWallControlSpacing(m_WallControlSpacing);
      sweepObjective->SetWallRegularization(m_WallRegularization);
      sweepObjective->SetWallMotionAlongNormals(m_WallMotionAlongNormals);
    }
    std::vector<double> wall = sweepObjective->MatchSurfaces();
    const unsigned int  n = m_NumberOfSweepSamples;
    for (unsigned int k = 0; k < n; ++k)
    {
      const auto          ts = Clock::now();
      std::vector<double> E = moduli;
      E[0] = lower[0] * std::pow(upper[0] / lower[0], double(k) / double(n - 1));
      // Continuation: each sample starts from the previous optimum, so that the sweep follows one branch of
      // minima of the (non-convex) distance objective and Phi*(E) is smooth.
      const InnerSolution s = solve(*sweepObjective, E, wall);
      wall = s.wall;
      this->Record(MakeRecord("sweep", k, E, s, Seconds(ts)), m_Sweep);
      this->UpdateProgress(0.5f * float(k + 1) / float(n));
    }
    const SweepAnalysis analysis = AnalyseSweep(m_Sweep, unknown[0]->name, lower[0], upper[0], m_FlatnessThreshold);
    moduli[0] = analysis.modulus;
    m_Identifiable = analysis.identifiable;
    m_IdentifiabilityMessage = analysis.message;
    sweepOnBound = analysis.onBound;
  }
  m_Timings["sweep"] = Seconds(t0);

  // 2. Initial loads on the fine mesh by surface matching.
  t0 = Clock::now();
  std::vector<double> wall = fineObjective.MatchSurfaces();
  m_Timings["initial loads"] = Seconds(t0);

  // 3. Fine mesh: nested optimisation, warm-started from the last inner optimum.
  t0 = Clock::now();
  InnerSolution last;
  unsigned int  outerIteration = 0;
  const auto    innerAt = [&](const std::vector<double> & E) {
    if (!m_History.empty() && m_History.back().youngsModuli == E)
    {
      return last.value; // L-BFGS-B starts by evaluating the point it was given
    }
    const auto ts = Clock::now();
    last = solve(fineObjective, E, wall);
    wall = last.wall;
    this->Record(MakeRecord("fine", outerIteration++, E, last, Seconds(ts)), m_History);
    this->UpdateProgress(std::min(0.99f, 0.5f + 0.02f * float(outerIteration)));
    return last.value;
  };
  std::vector<double> bestModuli = moduli;
  double              bestValue = innerAt(moduli);
  std::vector<double> bestWall = wall;
  if (!unknown.empty())
  {
    // Outer: bounded L-BFGS over log E (vnl's L-BFGS-B through ITK).
    auto metric = FunctionMetric::New();
    metric->m_Function = [&](const std::vector<double> & logE, std::vector<double> * g) {
      std::vector<double> E(logE.size());
      for (std::size_t m = 0; m < E.size(); ++m)
      {
        E[m] = std::exp(logE[m]);
      }
      const double value = innerAt(E);
      if (value < bestValue)
      {
        bestValue = value;
        bestModuli = E;
        bestWall = wall;
      }
      if (g)
      {
        *g = last.logModulusGradient;
      }
      return value;
    };
    const unsigned int                    m = static_cast<unsigned int>(unknown.size());
    FunctionMetric::ParametersType        p(m);
    LBFGSBOptimizerv4::BoundValueType     lo(m), hi(m);
    LBFGSBOptimizerv4::BoundSelectionType select(m);
    for (unsigned int k = 0; k < m; ++k)
    {
      p[k] = std::log(moduli[k]);
      lo[k] = std::log(lower[k]);
      hi[k] = std::log(upper[k]);
      select[k] = 2; // both bounds
    }
    metric->SetParameters(p);
    auto optimizer = LBFGSBOptimizerv4::New();
    optimizer->SetMetric(metric);
    optimizer->SetLowerBound(lo);
    optimizer->SetUpperBound(hi);
    optimizer->SetBoundSelection(select);
    optimizer->SetNumberOfIterations(m_MaximumNumberOfOuterIterations);
    optimizer->SetMaximumNumberOfFunctionEvaluations(m_MaximumNumberOfOuterIterations);
    optimizer->SetGradientConvergenceTolerance(m_OuterGradientTolerance * std::max(bestValue, 1e-12));
    optimizer->SetCostFunctionConvergenceFactor(1e7);
    // The accepted iterates of L-BFGS-B (its line searches' trial points are in the history only).
    optimizer->AddObserver(IterationEvent(), [&](const EventObject &) {
      IterationRecord r = m_History.back();
      r.stage = "outer";
      r.iteration = static_cast<unsigned int>(optimizer->GetCurrentIteration());
      if (!m_OuterIterations.empty() && m_OuterIterations.back().iteration == r.iteration)
      {
        m_OuterIterations.pop_back(); // the event comes more than once per iteration
      }
      r.value = optimizer->GetCurrentMetricValue();
      const auto & position = optimizer->GetCurrentPosition();
      for (unsigned int k = 0; k < position.GetSize(); ++k)
      {
        r.youngsModuli[k] = std::exp(position[k]);
      }
      m_OuterIterations.push_back(r);
    });
    optimizer->StartOptimization();
    m_OuterStopCondition = optimizer->GetStopConditionDescription();
    const bool estimateOnBound =
      moduli.size() == 1 && (bestModuli[0] <= lower[0] * 1.0001 || bestModuli[0] >= upper[0] * 0.9999);
    if (estimateOnBound)
    {
      m_Identifiable = false;
      m_IdentifiabilityMessage += "; the estimate lies on a bound";
    }
    else if (moduli.size() == 1 && sweepOnBound)
    {
      // The coarse mesh only starts the search; what counts is where the fine-mesh minimum lies.
      std::ostringstream msg;
      msg << "the coarse-mesh sweep's minimum lay on a bound, the fine-mesh minimum lies inside the bounds at "
          << bestModuli[0] << " kPa (" << m_IdentifiabilityMessage << ")";
      m_Identifiable = true;
      m_IdentifiabilityMessage = msg.str();
    }
  }
  m_Timings["fine"] = Seconds(t0);

  // 4. Outputs: the best point visited (L-BFGS-B may end on a trial point).
  m_FinalValue = bestValue;
  for (std::size_t k = 0; k < unknown.size(); ++k)
  {
    m_EstimatedYoungsModuli[unknown[k]->name] = bestModuli[k];
  }
  fineObjective.SetYoungsModuli(bestModuli);
  bmr::TetrahedralMesh out = fine;
  out.displacement = fineObjective.ComputeDisplacement(bestWall);
  out.force = fineObjective.ComputeBoundaryForces(out.displacement);
  m_NumberOfInvertedElements = bmr::CountInvertedElements(out, out.displacement);
  const std::vector<bmr::SurfaceDistanceStatistics> residuals = fineObjective.ComputeSurfaceDistances(out.displacement);
  for (const auto & s : residuals)
  {
    m_SurfaceDistances.push_back({ s.name, s.rms, s.maximum, s.mean });
  }
  const ResidualNoise noise = EstimateResidualNoise(m_Scene, residuals);
  m_ResidualStandardDeviation = std::sqrt(noise.variance);

  // 5. Uncertainty of log E: curvature of Phi* by central differences of the envelope gradient, each
  // inner solve warm-started from the optimum's walls. Meaningless on a bound, where Phi* is not stationary.
  bool onBound = false;
  for (std::size_t k = 0; k < unknown.size(); ++k)
  {
    onBound = onBound || bestModuli[k] <= lower[k] * 1.0001 || bestModuli[k] >= upper[k] * 0.9999;
  }
  if (m_EstimateUncertainty && !unknown.empty() && !onBound)
  {
    t0 = Clock::now();
    const Eigen::Index m = static_cast<Eigen::Index>(unknown.size());
    Eigen::MatrixXd    hessian(m, m);
    for (Eigen::Index k = 0; k < m; ++k)
    {
      std::vector<double> gradient[2];
      for (int side = 0; side < 2; ++side)
      {
        const auto          ts = Clock::now();
        std::vector<double> E = bestModuli;
        E[k] *= std::exp(side == 0 ? m_UncertaintyStep : -m_UncertaintyStep);
        const InnerSolution s = solve(fineObjective, E, bestWall);
        gradient[side] = s.logModulusGradient;
        this->Record(MakeRecord("curvature", unsigned(2 * k + side), E, s, Seconds(ts)), m_History);
      }
      for (Eigen::Index i = 0; i < m; ++i)
      {
        hessian(i, k) = (gradient[0][i] - gradient[1][i]) / (2.0 * m_UncertaintyStep);
      }
    }
    m_ModulusCurvature = hessian(0, 0);
    const std::vector<double> sigma = LogModulusStandardDeviations(hessian, noise.variance * noise.weight);
    for (std::size_t k = 0; k < unknown.size(); ++k)
    {
      m_ModulusUncertainty[unknown[k]->name] = sigma[k];
    }
    m_Timings["uncertainty"] = Seconds(t0);
  }
  this->GetOutput()->Set(out);
  this->UpdateProgress(1.0f);
}

void
FEMElasticityOptimizer::PrintSelf(std::ostream & os, Indent indent) const
{
  Superclass::PrintSelf(os, indent);
  os << indent << "Scene: " << m_Scene.name << " (" << m_Scene.labels.size() << " labels)" << std::endl;
  os << indent << "NumberOfSweepSamples: " << m_NumberOfSweepSamples << std::endl;
  os << indent << "MaximumNumberOfInnerIterations: " << m_MaximumNumberOfInnerIterations << std::endl;
  os << indent << "MaximumNumberOfOuterIterations: " << m_MaximumNumberOfOuterIterations << std::endl;
  os << indent << "InnerGradientTolerance: " << m_InnerGradientTolerance << std::endl;
  os << indent << "OuterGradientTolerance: " << m_OuterGradientTolerance << std::endl;
  os << indent << "FlatnessThreshold: " << m_FlatnessThreshold << std::endl;
  os << indent << "EstimateUncertainty: " << (m_EstimateUncertainty ? "On" : "Off") << std::endl;
  os << indent << "UncertaintyStep: " << m_UncertaintyStep << std::endl;
  os << indent << "LimitElementInversion: " << (m_LimitElementInversion ? "On" : "Off") << std::endl;
  os << indent << "NumberOfRejectedSteps: " << m_NumberOfRejectedSteps << std::endl;
  os << indent << "NumberOfInvertedElements: " << m_NumberOfInvertedElements << std::endl;
  os << indent << "WallControlSpacing: " << m_WallControlSpacing << " mm" << std::endl;
  os << indent << "WallRegularization: " << m_WallRegularization << std::endl;
  os << indent << "WallMotionAlongNormals: " << (m_WallMotionAlongNormals ? "On" : "Off") << std::endl;
  os << indent << "GaugeLabel: " << m_GaugeLabel << std::endl;
  for (const auto & kv : m_EstimatedYoungsModuli)
  {
    os << indent << "EstimatedYoungsModulus[" << kv.first << "]: " << kv.second << " kPa" << std::endl;
  }
  os << indent << "FinalValue: " << m_FinalValue << " mm^2" << std::endl;
  for (const auto & kv : m_ModulusUncertainty)
  {
    os << indent << "ModulusUncertainty[" << kv.first << "]: " << kv.second << " (standard deviation of log E)"
       << std::endl;
  }
  os << indent << "ResidualStandardDeviation: " << m_ResidualStandardDeviation << " mm" << std::endl;
  os << indent << "ModulusCurvature: " << m_ModulusCurvature << " mm^2" << std::endl;
  os << indent << "Identifiable: " << m_Identifiable << " (" << m_IdentifiabilityMessage << ")" << std::endl;
  os << indent << "Sweep samples: " << m_Sweep.size() << ", fine iterations: " << m_History.size() << std::endl;
}

} // namespace itk
