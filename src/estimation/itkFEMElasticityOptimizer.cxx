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

#include "bmrWallMotionBasis.h"
#include "itkGridGeometryConversion.h"
#include "itkMultiThreaderBase.h"

#include <algorithm>
#include <cmath>

namespace itk {
namespace {

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
  if (this->GetMesh() == nullptr)
  {
    itkExceptionMacro(<< "no mesh (SetMesh)");
  }
  this->VerifySceneAndSettings();
  if (!m_Sweep.unknowns.empty() && m_Sweep.unknowns.size() != bmr::SceneUnknownModuli(m_Scene).size())
  {
    itkExceptionMacro(<< "the sweep given (SetSweep) has " << m_Sweep.unknowns.size() << " unknowns, the scene "
                      << bmr::SceneUnknownModuli(m_Scene).size());
  }
}

void
FEMElasticityOptimizer::VerifySceneAndSettings() const
{
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
  m_EstimatorSettings.Validate();
  m_WallLoadSettings.Validate();
  if (m_EstimatorSettings.limitElementInversion && m_WallLoadSettings.ReducedBasis())
  {
    itkExceptionMacro(<< "LimitElementInversion needs one parameter per wall node (WallControlSpacing 0, got "
                      << m_WallLoadSettings.controlSpacing << " mm; WallMotion " << m_WallLoadSettings.motion
                      << "): the reduced-basis solver sees only the objective nodes");
  }
}

void
FEMElasticityOptimizer::SetEstimatorSettings(const bmr::EstimatorSettings & settings)
{
  m_EstimatorSettings = settings;
  this->Modified();
}

void
FEMElasticityOptimizer::SetWallLoadSettings(const bmr::WallLoadSettings & settings)
{
  m_WallLoadSettings = settings;
  this->Modified();
}

unsigned int
FEMElasticityOptimizer::FineSolveThreads() const
{
  return std::min<unsigned int>(m_NumberOfFineSolveThreads, MultiThreaderBase::GetGlobalDefaultNumberOfThreads());
}

std::vector<double>
FEMElasticityOptimizer::WarmStartInOrder(const std::vector<bmr::UnknownModulus> & unknowns) const
{
  std::vector<double> moduli;
  for (const bmr::UnknownModulus & u : unknowns)
  {
    const auto it = m_WarmStartModuli.find(u.name);
    if (it == m_WarmStartModuli.end())
    {
      itkExceptionMacro(<< "the warm start gives no modulus for the unknown label \"" << u.name << "\"");
    }
    moduli.push_back(it->second);
  }
  return moduli;
}

std::unique_ptr<bmr::SurfaceMatchingObjective>
FEMElasticityOptimizer::MakeObjective(
  const bmr::TetrahedralMesh &                                                      mesh,
  const std::map<std::int32_t, std::shared_ptr<const bmr::SignedDistanceSampler>> & samplers) const
{
  std::vector<bmr::ObjectiveSurface> surfaces = bmr::SceneObjectiveSurfaces(m_Scene, mesh, samplers);
  if (m_WallLoadSettings.trainedBasis)
  {
    return std::make_unique<bmr::SurfaceMatchingObjective>(mesh, m_Scene, std::move(surfaces), m_WallLoadSettings);
  }
  std::unique_ptr<bmr::SurfaceMatchingObjective> objective(
    new bmr::SurfaceMatchingObjective(mesh, m_Scene, std::move(surfaces)));
  objective->SetWallControlSpacing(m_WallLoadSettings.controlSpacing);
  objective->SetWallRegularization(m_WallLoadSettings.regularization);
  objective->SetWallMotion(m_WallLoadSettings.motion);
  return objective;
}

void
FEMElasticityOptimizer::TakeResult(const bmr::EstimationResult & result)
{
  const std::vector<bmr::UnknownModulus> unknowns = bmr::SceneUnknownModuli(m_Scene);
  m_EstimatedYoungsModuli.clear();
  m_ModulusUncertainty.clear();
  for (std::size_t k = 0; k < unknowns.size(); ++k)
  {
    m_EstimatedYoungsModuli[unknowns[k].name] = result.youngsModuli[k];
    if (!result.logModulusSigma.empty())
    {
      m_ModulusUncertainty[unknowns[k].name] = result.logModulusSigma[k];
    }
  }
  m_Result = result;
}

std::map<std::int32_t, std::shared_ptr<const bmr::SignedDistanceSampler>>
FEMElasticityOptimizer::Samplers() const
{
  std::map<std::int32_t, std::shared_ptr<const bmr::SignedDistanceSampler>> samplers;
  for (const auto & term : m_Scene.objective)
  {
    samplers[m_Scene.FindLabel(term.label)->value] = ToSampler(this->GetDistanceMap(term.label), term.label);
  }
  return samplers;
}

void
FEMElasticityOptimizer::Observe(bmr::ElasticityEstimator & estimator)
{
  estimator.SetObserver([this](const IterationRecord & record, double progress) {
    m_CurrentRecord = record;
    this->InvokeEvent(IterationEvent());
    this->UpdateProgress(static_cast<float>(progress));
  });
}

std::unique_ptr<bmr::SurfaceMatchingObjective>
FEMElasticityOptimizer::MakeObjective(const bmr::TetrahedralMesh & mesh) const
{
  this->VerifySceneAndSettings();
  return this->MakeObjective(mesh, this->Samplers());
}

bmr::ModulusSweep
FEMElasticityOptimizer::SweepCoarseMesh()
{
  this->VerifySceneAndSettings();
  if (this->GetCoarseMesh() == nullptr)
  {
    itkExceptionMacro(<< "SweepCoarseMesh: no coarse mesh (SetCoarseMesh)");
  }
  const std::vector<bmr::UnknownModulus> unknowns = bmr::SceneUnknownModuli(m_Scene);
  if (unknowns.empty())
  {
    itkExceptionMacro(<< "SweepCoarseMesh: the scene has no unknown modulus to sweep");
  }
  const std::unique_ptr<bmr::SurfaceMatchingObjective> coarse =
    this->MakeObjective(this->GetCoarseMesh()->Get(), this->Samplers());
  coarse->GetForwardModel().SetNumberOfSolveThreads(this->FineSolveThreads());
  // The coarse objective as the estimator's only one: Sweep() sweeps on it, as Run() would on the coarse one.
  bmr::ElasticityEstimator estimator(*coarse, nullptr, unknowns, m_EstimatorSettings);
  this->Observe(estimator);
  return estimator.Sweep();
}

void
FEMElasticityOptimizer::SetSweep(const bmr::ModulusSweep & sweep)
{
  m_Sweep = sweep;
  this->Modified();
}

void
FEMElasticityOptimizer::GenerateData()
{
  const auto                             samplers = this->Samplers(); // shared by the coarse and the fine objective
  const bmr::SceneLabel *                gauge = m_Scene.GaugeLabel();
  const std::vector<bmr::UnknownModulus> unknowns = bmr::SceneUnknownModuli(m_Scene);
  m_GaugeLabel = gauge ? gauge->name : std::string();

  const std::unique_ptr<bmr::SurfaceMatchingObjective> fine = this->MakeObjective(this->GetMesh()->Get(), samplers);
  fine->GetForwardModel().SetNumberOfSolveThreads(this->FineSolveThreads());
  fine->GetForwardModel().Prepare();
  // The coarse mesh serves the sweep only: not used when there is no modulus to sweep or the sweep is given.
  std::unique_ptr<bmr::SurfaceMatchingObjective> coarse;
  if (this->GetCoarseMesh() && !unknowns.empty() && m_WarmStartModuli.empty() && m_Sweep.unknowns.empty())
  {
    coarse = this->MakeObjective(this->GetCoarseMesh()->Get(), samplers);
    coarse->GetForwardModel().SetNumberOfSolveThreads(this->FineSolveThreads());
  }
  bmr::ElasticityEstimator estimator(*fine, coarse.get(), unknowns, m_EstimatorSettings);
  if (!m_WarmStartModuli.empty())
  {
    estimator.SetWarmStart(this->WarmStartInOrder(unknowns), m_WarmStartRelativeCurvature);
  }
  else if (!m_Sweep.unknowns.empty() && !unknowns.empty())
  {
    estimator.SetSweep(m_Sweep);
  }
  this->Observe(estimator);
  const bmr::EstimationResult result = estimator.Run();
  this->TakeResult(result);

  bmr::TetrahedralMesh out = this->GetMesh()->Get();
  out.displacement = result.displacement;
  out.force = result.boundaryForces;
  this->GetOutput()->Set(out);
  this->UpdateProgress(1.0f);
}

void
FEMElasticityOptimizer::PrintSelf(std::ostream & os, Indent indent) const
{
  Superclass::PrintSelf(os, indent);
  os << indent << "Scene: " << m_Scene.name << " (" << m_Scene.labels.size() << " labels)" << std::endl;
  const bmr::EstimatorSettings & e = m_EstimatorSettings;
  os << indent << "NumberOfSweepSamples: " << e.numberOfSweepSamples << std::endl;
  os << indent << "MaximumNumberOfInnerIterations: " << e.maximumInnerIterations << std::endl;
  os << indent << "MaximumNumberOfOuterIterations: " << e.maximumOuterIterations << std::endl;
  os << indent << "InnerGradientTolerance: " << e.innerGradientTolerance << std::endl;
  os << indent << "LooseInnerGradientTolerance: " << e.looseInnerGradientTolerance << std::endl;
  os << indent << "OuterGradientTolerance: " << e.outerGradientTolerance << std::endl;
  os << indent << "OuterStepTolerance: " << e.outerStepTolerance << std::endl;
  os << indent << "FlatnessThreshold: " << e.flatnessThreshold << std::endl;
  os << indent << "EstimateUncertainty: " << (e.estimateUncertainty ? "On" : "Off") << std::endl;
  os << indent << "UncertaintyStep: " << e.uncertaintyStep << std::endl;
  os << indent << "WarmStart: " << m_WarmStartModuli.size() << " moduli, relative curvature "
     << m_WarmStartRelativeCurvature << std::endl;
  os << indent << "Sweep: " << (m_Sweep.unknowns.empty() ? "none given" : "given (SetSweep)") << std::endl;
  os << indent << "LimitElementInversion: " << (e.limitElementInversion ? "On" : "Off") << std::endl;
  os << indent << "NumberOfFineSolveThreads: " << m_NumberOfFineSolveThreads << std::endl;
  os << indent << "NumberOfRejectedSteps: " << m_Result.rejectedSteps << std::endl;
  os << indent << "NumberOfInvertedElements: " << m_Result.invertedElements << std::endl;
  os << indent << "WallControlSpacing: " << m_WallLoadSettings.controlSpacing << " mm" << std::endl;
  os << indent << "WallRegularization: " << m_WallLoadSettings.regularization << std::endl;
  os << indent << "WallMotion: " << m_WallLoadSettings.motion << std::endl;
  if (m_WallLoadSettings.trainedBasis)
  {
    os << indent << "TrainedWallBasis: " << m_WallLoadSettings.trainedBasis->GetNumberOfModes() << " modes (using "
       << m_WallLoadSettings.basisModes << ", 0: all), prior weight " << m_WallLoadSettings.basisPriorWeight << " mm^2"
       << std::endl;
  }
  os << indent << "GaugeLabel: " << m_GaugeLabel << std::endl;
  for (const auto & kv : m_EstimatedYoungsModuli)
  {
    os << indent << "EstimatedYoungsModulus[" << kv.first << "]: " << kv.second << " kPa" << std::endl;
  }
  os << indent << "FinalValue: " << m_Result.value << " mm^2" << std::endl;
  for (const auto & kv : m_ModulusUncertainty)
  {
    os << indent << "ModulusUncertainty[" << kv.first << "]: " << kv.second << " (standard deviation of log E)"
       << std::endl;
  }
  os << indent << "ResidualStandardDeviation: " << m_Result.residualStandardDeviation << " mm" << std::endl;
  os << indent << "ModulusCurvature: " << this->GetModulusCurvature() << " mm^2" << std::endl;
  os << indent << "Identifiable: " << m_Result.identifiable << " (" << m_Result.identifiabilityMessage << ")"
     << std::endl;
  os << indent << "Sweep samples: " << m_Result.sweep.size() << ", fine iterations: " << m_Result.history.size()
     << std::endl;
}

} // namespace itk
