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
#include "bmrInnerSolve.h"
#include "bmrError.h"

#include "itkLBFGS2Optimizerv4.h"

#include <algorithm>

namespace bmr {

FunctionMetric::MeasureType
FunctionMetric::GetValue() const
{
  this->m_Value = m_Function(AsVector(), nullptr);
  return this->m_Value;
}

void
FunctionMetric::GetDerivative(DerivativeType & derivative) const
{
  MeasureType value;
  GetValueAndDerivative(value, derivative);
}

void
FunctionMetric::GetValueAndDerivative(MeasureType & value, DerivativeType & derivative) const
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

void
FunctionMetric::UpdateTransformParameters(const DerivativeType & update, ParametersValueType factor)
{
  for (unsigned int i = 0; i < m_Parameters.GetSize(); ++i)
  {
    m_Parameters[i] += factor * update[i];
  }
}

namespace {
/** \a start, or when it inverts more elements than the unloaded boundary (p = 0) does, the largest
 * fraction t start (bisection to 1/1024) that does not: the step limit's feasible start, e.g. after
 * surface matching pulled the walls through thin tissue. */
std::vector<double>
WithoutNewInversions(EstimationObjective & objective, const std::vector<double> & start)
{
  objective.Evaluate(start, nullptr, nullptr);
  const std::size_t atStart = objective.GetNumberOfInvertedElements();
  if (atStart == 0)
  {
    return start;
  }
  objective.Evaluate(std::vector<double>(start.size(), 0.0), nullptr, nullptr);
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

/** L-BFGS over the load parameters from \a start; returns the end point, iterations and stop condition. */
LoadSolution
MinimizeLoadsLBFGS(EstimationObjective &       objective,
                   const std::vector<double> & start,
                   const InnerSettings &       settings,
                   std::size_t &               rejected)
{
  // Inverted elements are counted after every evaluation: whole states.
  struct WholeStates
  {
    EstimationObjective & objective;
    const bool            observed{ objective.GetObservedSolves() };
    ~WholeStates() { objective.SetObservedSolves(observed); }
  } whole{ objective };
  objective.SetObservedSolves(whole.observed && !settings.limitInversion);
  std::size_t         allowed = 0;
  double              ceiling = 0.0;
  double              bestFeasibleValue = 0.0;
  std::vector<double> bestFeasible = start;
  if (settings.limitInversion)
  {
    bestFeasible = WithoutNewInversions(objective, start);
    bestFeasibleValue = objective.Evaluate(bestFeasible, nullptr, nullptr);
    allowed = objective.GetNumberOfInvertedElements();
    ceiling = 2.0 * bestFeasibleValue + 1.0; // above Phi(start): fails the line search's sufficient decrease
  }
  auto metric = FunctionMetric::New();
  metric->m_Function = [&](const std::vector<double> & p, std::vector<double> * g) {
    const double value = objective.Evaluate(p, g, nullptr);
    if (!settings.limitInversion)
    {
      return value;
    }
    if (objective.GetNumberOfInvertedElements() > allowed)
    {
      ++rejected;
      return std::max(value, ceiling);
    }
    if (value < bestFeasibleValue)
    {
      bestFeasibleValue = value;
      bestFeasible = p;
    }
    return value;
  };
  FunctionMetric::ParametersType p(static_cast<unsigned int>(start.size()));
  std::copy(bestFeasible.begin(), bestFeasible.end(), p.begin());
  metric->SetParameters(p);
  auto optimizer = itk::LBFGS2Optimizerv4::New();
  optimizer->SetMetric(metric);
  optimizer->SetSolutionAccuracy(settings.tolerance);
  optimizer->SetMaximumIterations(static_cast<int>(settings.maximumIterations));
  optimizer->SetHessianApproximationAccuracy(10);
  // Stop also when Phi has decreased by less than 1e-10 relative over 10 iterations (a flat valley).
  optimizer->SetDeltaConvergenceDistance(10);
  optimizer->SetDeltaConvergenceTolerance(1e-10);
  optimizer->StartOptimization();
  LoadSolution result;
  // libLBFGS returns its last accepted point, which never inverts; the best feasible point visited is kept
  // in case an implementation does otherwise.
  result.parameters = settings.limitInversion ? bestFeasible : metric->AsVector();
  result.iterations = static_cast<unsigned int>(optimizer->GetCurrentIteration() + 1);
  result.stop = optimizer->GetStopConditionDescription();
  return result;
}
} // namespace

LoadSolution
SolveInner(EstimationObjective &       objective,
           const std::vector<double> & moduli,
           const std::vector<double> & start,
           const InnerSettings &       settings,
           std::size_t &               rejected)
{
  objective.SetYoungsModuli(moduli);
  if (settings.levenbergMarquardt && objective.GetNumberOfParameters() > 0)
  {
    return objective.SolveLoadsLevenbergMarquardt(start, settings.maximumIterations, settings.tolerance);
  }
  LoadSolution result;
  result.parameters = start;
  if (objective.GetNumberOfParameters() > 0)
  {
    result = MinimizeLoadsLBFGS(objective, start, settings, rejected);
  }
  const std::size_t infeasible = objective.GetNumberOfInfeasibleEvaluations();
  result.value = objective.Evaluate(result.parameters, &result.gradient, &result.logModulusGradient);
  if (objective.GetNumberOfInfeasibleEvaluations() > infeasible)
  {
    // L-BFGS ended where no nonlinear state follows the loads: a start no state reaches has a zero gradient, so it
    // never left it. Again from zero loads, the unloaded state, which always is one.
    const std::vector<double> zero(start.size(), 0.0);
    if (start == zero)
    {
      Fail("SolveInner", "no equilibrium at zero loads");
    }
    return SolveInner(objective, moduli, zero, settings, rejected);
  }
  return result;
}

} // namespace bmr
