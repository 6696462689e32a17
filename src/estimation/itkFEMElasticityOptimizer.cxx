#include "itkFEMElasticityOptimizer.h"

#include "bmrMemoryWarmUp.h"
#include "bmrTaskTrace.h"
#include "itkGridGeometryConversion.h"
#include "itkMultiThreaderBase.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <functional>
#include <future>
#include <optional>

namespace itk {
namespace {
// The most memory the waiting main thread faults in for the fine factorization [bytes]: about the fine factor of
// the default pelvis mesh, the part a change of the prostate's modulus refactorizes (kept by
// bmr::LinearElasticModel::Factorize), the update workspaces and K_ff's values split by label.
constexpr std::size_t FineFactorWarmUpBytes = std::size_t{ 480 } << 20;

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

/** \brief The fine objective in the making on a second thread while the sweep runs on the coarse one (one core each):
 * its mesh (when a source makes it), the objective, its sparse analysis and, at the moduli the fine stage starts
 * from, its factorization. The sweep tells those moduli (TellStartModuli) as soon as it brackets the minimum, so the
 * factorization overlaps its last samples: the same objective and factor, sooner.
 *
 * The thread that then asks for the objective (Take) and would otherwise wait faults in the memory of the fine
 * factor while the objective is made (bmr::MemoryWarmUp: page faults would otherwise slow the first fine
 * factorization; docs/estimation.md), computes the fine stage's start loads as soon as
 * the objective exists, while the second thread analyzes its matrix (StartLoads hands them over), and then warms
 * on until the factorization starts. */
class FineObjectiveInMaking
{
public:
  using Maker = std::function<std::unique_ptr<bmr::SurfaceMatchingObjective>()>;

  FineObjectiveInMaking(Maker make, unsigned int solveThreads)
    : m_WarmUp(FineFactorWarmUpBytes)
    , m_StartModuliKnown(m_StartModuli.get_future())
    , m_ObjectiveKnown(m_Objective.get_future())
  {
    m_Made = std::async(std::launch::async, [this, make = std::move(make), solveThreads]() {
      const bmr::TracedSpan span(bmr::TracedSpan::Kind::Background, "fine objective alongside");
      return this->Make(make, solveThreads);
    });
  }
  /** Should the sweep throw, the second thread learns there is nothing to factorize; m_Made then joins it. */
  ~FineObjectiveInMaking() { TellStartModuli({}); }
  ITK_DISALLOW_COPY_AND_MOVE(FineObjectiveInMaking);

  /** The moduli to factorize at (empty: none); the first call counts. */
  void
  TellStartModuli(const std::vector<double> & moduli)
  {
    if (!m_StartModuliTold)
    {
      m_StartModuliTold = true;
      m_StartModuli.set_value(moduli);
    }
  }

  /** Waits for the objective (rethrowing what making it threw), computing the start loads meanwhile. */
  std::shared_ptr<bmr::SurfaceMatchingObjective>
  Take()
  {
    // On a trace, the start loads computed while waiting count as hidden behind the other thread's work.
    const bmr::TracedSpan wait(bmr::TracedSpan::Kind::Wait, "fine objective alongside");
    TellStartModuli({}); // a sweep without a bracket has told nothing
    if (m_Made.wait_for(std::chrono::seconds(0)) != std::future_status::ready)
    {
      m_WarmUp.WarmWhile(
        [this]() { return m_ObjectiveKnown.wait_for(std::chrono::seconds(0)) != std::future_status::ready; });
      // Shared: should the analysis throw, the objective outlives the other thread's unwinding until this is done.
      if (const std::shared_ptr<const bmr::SurfaceMatchingObjective> made = m_ObjectiveKnown.get())
      {
        m_StartLoads = made->EstimateInitialParameters();
      }
      m_WarmUp.WarmWhileOpen();
    }
    return m_Made.get();
  }

  /** The start loads computed in Take(), or computed now: the same values either way. */
  std::vector<double>
  StartLoads(bmr::EstimationObjective & objective) const
  {
    return m_StartLoads ? *m_StartLoads : objective.EstimateInitialParameters();
  }

private:
  std::shared_ptr<bmr::SurfaceMatchingObjective>
  Make(const Maker & make, unsigned int solveThreads)
  {
    struct OnExit // the waiting thread's warm-up ends, and it learns when the objective will not come
    {
      FineObjectiveInMaking & self;
      bool                    told{ false };
      ~OnExit()
      {
        self.m_WarmUp.Close();
        if (!told)
        {
          self.m_Objective.set_value(nullptr);
        }
      }
    } onExit{ *this };
    const std::shared_ptr<bmr::SurfaceMatchingObjective> objective = make();
    // Read-only from here on in the other thread: EstimateInitialParameters() reads the mesh, the loads and the data
    // terms, none of which the analysis and the factorization below write.
    m_Objective.set_value(objective);
    onExit.told = true;
    // The sweep is ending or over: its core joins the analysis (the element stiffnesses are summed alongside the
    // ordering) and the factorization, the same factor on any number of threads.
    objective->GetForwardModel().SetNumberOfSolveThreads(solveThreads);
    objective->GetForwardModel().Prepare();
    const std::vector<double> moduli = m_StartModuliKnown.get();
    m_WarmUp.Close(); // its memory released just before the factorization allocates
    if (!moduli.empty() && objective->GetForwardModel().IsLinear()) // a nonlinear model factorizes per state
    {
      objective->SetYoungsModuli(moduli);
      objective->GetForwardModel().PrepareSolves();
    }
    return objective;
  }

  bmr::MemoryWarmUp                                                  m_WarmUp;
  std::promise<std::vector<double>>                                  m_StartModuli;
  bool                                                               m_StartModuliTold{ false };
  std::future<std::vector<double>>                                   m_StartModuliKnown;
  std::promise<std::shared_ptr<const bmr::SurfaceMatchingObjective>> m_Objective;
  std::future<std::shared_ptr<const bmr::SurfaceMatchingObjective>>  m_ObjectiveKnown;
  std::optional<std::vector<double>>                                 m_StartLoads;
  // Last: destroyed first, which waits for the thread while everything it uses still exists.
  std::future<std::shared_ptr<bmr::SurfaceMatchingObjective>> m_Made;
};
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
FEMElasticityOptimizer::SetMeshSource(MeshSourceType source)
{
  // With a source the indexed input "Mesh" is not needed; VerifyPreconditions() asks for one of the two.
  this->SetNumberOfRequiredInputs(source ? 0 : 1);
  if (source)
  {
    this->RemoveRequiredInputName("Primary");
  }
  else if (!this->IsRequiredInputName("Primary"))
  {
    this->AddRequiredInputName("Primary");
  }
  m_MeshSource = std::move(source);
  this->Modified();
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
  if (!m_MeshSource && this->GetMesh() == nullptr)
  {
    itkExceptionMacro(<< "no mesh: SetMesh() or SetMeshSource()");
  }
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

bmr::EstimatorSettings
FEMElasticityOptimizer::EffectiveSettings() const
{
  bmr::EstimatorSettings s = m_EstimatorSettings;
  // Levenberg-Marquardt needs one solve per parameter: only with the reduced wall basis.
  s.levenbergMarquardtInner = m_WallLoadSettings.ReducedBasis();
  return s;
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
  std::unique_ptr<bmr::SurfaceMatchingObjective> objective(
    new bmr::SurfaceMatchingObjective(mesh, m_Scene, bmr::SceneObjectiveSurfaces(m_Scene, mesh, samplers)));
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

void
FEMElasticityOptimizer::GenerateData()
{
  // Distance maps are shared by the coarse and the fine objective.
  std::map<std::int32_t, std::shared_ptr<const bmr::SignedDistanceSampler>> samplers;
  for (const auto & term : m_Scene.objective)
  {
    samplers[m_Scene.FindLabel(term.label)->value] = ToSampler(this->GetDistanceMap(term.label), term.label);
  }
  const bmr::SceneLabel * gauge = m_Scene.GaugeLabel();
  m_GaugeLabel = gauge ? gauge->name : std::string();
  const std::vector<bmr::UnknownModulus> unknowns = bmr::SceneUnknownModuli(m_Scene);

  // The coarse mesh serves the sweep only: not built when there is no modulus to sweep.
  const bool sweeps = this->GetCoarseMesh() && !unknowns.empty() && m_WarmStartModuli.empty();
  // The fine mesh: input "Mesh", or the source's, which is asked for only when the fine objective is made.
  bmr::TetrahedralMesh         sourced;
  const bmr::TetrahedralMesh * fine = m_MeshSource ? nullptr : &this->GetMesh()->Get();
  const auto                   makeFineObjective = [this, &fine, &sourced, &samplers]() {
    if (fine == nullptr)
    {
      sourced = m_MeshSource();
      fine = &sourced;
    }
    return this->MakeObjective(*fine, samplers);
  };
  // Declared after what the second thread reads (fine, sourced, samplers), so destroyed (joined) before it.
  std::unique_ptr<FineObjectiveInMaking>         inMaking;
  std::shared_ptr<bmr::SurfaceMatchingObjective> fineObjective;
  const bool alongside = sweeps && MultiThreaderBase::GetGlobalDefaultNumberOfThreads() > 1;
  if (alongside)
  {
    inMaking = std::make_unique<FineObjectiveInMaking>(makeFineObjective, this->FineSolveThreads());
  }
  else
  {
    fineObjective = makeFineObjective();
    fineObjective->GetForwardModel().Prepare();
  }
  std::unique_ptr<bmr::SurfaceMatchingObjective> coarseObjective;
  if (sweeps)
  {
    coarseObjective = this->MakeObjective(this->GetCoarseMesh()->Get(), samplers);
    // The sweep's solves take the budget but the core that makes the fine objective alongside.
    const unsigned int threads = this->FineSolveThreads();
    coarseObjective->GetForwardModel().SetNumberOfSolveThreads(alongside ? std::max(1U, threads - 1) : threads);
  }
  bmr::ElasticityEstimator estimator(
    [&]() -> bmr::EstimationObjective & {
      if (!fineObjective)
      {
        fineObjective = inMaking->Take();
      }
      fineObjective->GetForwardModel().SetNumberOfSolveThreads(this->FineSolveThreads());
      return *fineObjective;
    },
    coarseObjective.get(),
    unknowns,
    this->EffectiveSettings());
  if (!m_WarmStartModuli.empty())
  {
    estimator.SetWarmStart(this->WarmStartInOrder(unknowns), m_WarmStartRelativeCurvature);
  }
  if (alongside)
  {
    estimator.SetSweepPrediction(
      [&inMaking](const std::vector<double> & moduli) { inMaking->TellStartModuli(moduli); });
    estimator.SetFineStartLoads(
      [&inMaking](bmr::EstimationObjective & objective) { return inMaking->StartLoads(objective); });
  }
  estimator.SetObserver([this](const IterationRecord & record, double progress) {
    m_CurrentRecord = record;
    this->InvokeEvent(IterationEvent());
    this->UpdateProgress(static_cast<float>(progress));
  });
  const bmr::EstimationResult result = estimator.Run();
  this->TakeResult(result);

  bmr::TetrahedralMesh out = *fine; // set: the estimator always asks for the fine objective
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
  os << indent << "MeshSource: " << (m_MeshSource ? "set" : "none (input Mesh)") << std::endl;
  os << indent << "LimitElementInversion: " << (e.limitElementInversion ? "On" : "Off") << std::endl;
  os << indent << "NumberOfFineSolveThreads: " << m_NumberOfFineSolveThreads << std::endl;
  os << indent << "NumberOfRejectedSteps: " << m_Result.rejectedSteps << std::endl;
  os << indent << "NumberOfInvertedElements: " << m_Result.invertedElements << std::endl;
  os << indent << "WallControlSpacing: " << m_WallLoadSettings.controlSpacing << " mm" << std::endl;
  os << indent << "WallRegularization: " << m_WallLoadSettings.regularization << std::endl;
  os << indent << "WallMotion: " << m_WallLoadSettings.motion << std::endl;
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
