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
#ifndef bmrInnerSolve_h
#define bmrInnerSolve_h

// The inner problem of the estimation, min_p Phi(E, p) at fixed E (private to src/estimation).
#include "bmrSurfaceMatchingObjective.h"

#include "itkObjectToObjectMetricBase.h"

#include <functional>

namespace bmr {

/** Adapts a function with gradient to ITK's v4 metric interface, which v4 optimizers minimize; by ITK's
 * convention the "derivative" handed to the optimizer is the negative gradient. */
class FunctionMetric : public itk::ObjectToObjectMetricBaseTemplate<double>
{
public:
  ITK_DISALLOW_COPY_AND_MOVE(FunctionMetric);
  using Self = FunctionMetric;
  using Superclass = itk::ObjectToObjectMetricBaseTemplate<double>;
  using Pointer = itk::SmartPointer<Self>;
  itkNewMacro(Self);
  itkTypeMacro(FunctionMetric, ObjectToObjectMetricBaseTemplate);

  /** value(x, gradient or null) */
  using FunctionType = std::function<double(const std::vector<double> &, std::vector<double> *)>;
  FunctionType m_Function;

  void
  Initialize() override
  {}
  MeasureType
  GetValue() const override;
  void
  GetDerivative(DerivativeType & derivative) const override;
  void
  GetValueAndDerivative(MeasureType & value, DerivativeType & derivative) const override;
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
  UpdateTransformParameters(const DerivativeType & update, ParametersValueType factor) override;
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

/** Stopping rules and solver of the inner problem. */
struct InnerSettings
{
  unsigned int maximumIterations{ 2000 };
  double       tolerance{ 1e-5 };
  bool         levenbergMarquardt{ false }; ///< Levenberg-Marquardt (EstimationObjective::SolveLoadsLevenbergMarquardt)
  bool         limitInversion{ false };     ///< L-BFGS only: reject trial points that invert new elements
};

/** min_p Phi(E, p) from \a start at the moduli \a moduli: Levenberg-Marquardt, or L-BFGS (libLBFGS through
 * ITK); then the gradients at the optimum. With limitInversion a trial point that inverts more elements
 * than the start is answered with a value above Phi(start), so that the line search shortens the step;
 * the number of such rejections is added to \a rejected. */
LoadSolution
SolveInner(EstimationObjective &       objective,
           const std::vector<double> & moduli,
           const std::vector<double> & start,
           const InnerSettings &       settings,
           std::size_t &               rejected);

} // namespace bmr

#endif
