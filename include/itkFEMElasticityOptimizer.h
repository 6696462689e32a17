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
#ifndef itkFEMElasticityOptimizer_h
#define itkFEMElasticityOptimizer_h

#include "BiomechanicalRegistrationExport.h"
#include "bmrElasticityEstimator.h"
#include "itkImage.h"
#include "itkMultiThreaderBase.h"
#include "itkProcessObject.h"
#include "itkTetrahedralMeshObject.h"

#include <map>
#include <memory>
#include <string>
#include <vector>

/** Set/Get of one field of FEMElasticityOptimizer's settings structs: the struct is the one place the value lives. */
#define bmrFEMSettingMacro(name, type, field)                                                                          \
  void Set##name(type value)                                                                                           \
  {                                                                                                                    \
    if (field != value)                                                                                                \
    {                                                                                                                  \
      field = value;                                                                                                   \
      this->Modified();                                                                                                \
    }                                                                                                                  \
  }                                                                                                                    \
  type Get##name() const                                                                                               \
  {                                                                                                                    \
    return field;                                                                                                      \
  }

namespace itk {

/** \class FEMElasticityOptimizer
 * \brief Joint estimation of boundary loads and Young's moduli by FEM simulation (H.-P. Lee 2012, chapter 3):
 * the ITK pipeline front door of bmr::ElasticityEstimator.
 *
 * Inputs: the moving anatomy as a tetrahedral mesh (input "Mesh", from LabelImageToTetrahedralMeshFilter with
 * the same scene), optionally a coarser mesh
 * of it for the sweep of E ("CoarseMesh"), and one signed distance map [mm] per objective label of the scene
 * (SetDistanceMap(); negative inside, as SignedMaurerDistanceMapImageFilter makes them, see
 * ComputeSceneDistanceMaps()). The unknowns are the loads on the scene's force surfaces and the moduli of the labels
 * with the role unknown_material (any number).
 *
 * GenerateData() composes the scene's objective, bmr::SurfaceMatchingObjective, from its three parts:
 * - forward model bmr::LinearForwardModel: \f$ K(E) u = f \f$, P1 tetrahedra, u = 0 on fixed walls;
 * - loads bmr::WallLoads: the wall displacements they cause, along the walls' normals by default
 *   (WallMotion: or free, or normal tractions, or one pressure per wall), optionally in a smooth reduced basis
 *   (WallControlSpacing), with the E-independent prior WallRegularization/2 |p|^2;
 * - data bmr::SurfaceDistanceTerm:
 *   \f$ \Phi = \tfrac12 \sum_s w_s \sum_{l \in s} \phi_s(x_l + u_l)^2 \f$;
 * and runs bmr::ElasticityEstimator with this object's settings: the sweep of \f$\Phi^*(E) = \min_p \Phi(E,p)\f$
 * on the coarse mesh (a coordinate sweep over the unknowns), the outer bounded search over log E (a secant for one
 * unknown, L-BFGS-B for more) with the envelope gradient \f$ d\Phi^{*}/d\log E_m = -E_m \lambda^T \hat K_m u \f$,
 * identifiability, and the uncertainty of log E from the curvature of \f$\Phi^*\f$ and the residual noise
 * (\f$ \mathrm{Cov}(\log E) = s^2 w_{\mathrm{eff}} H^{-1} \f$). The estimator's documentation gives the
 * stopping rules, the sweep and the uncertainty; docs/estimation.md the choices and why.
 *
 * Stages: Update() sweeps (when there is a coarse mesh and no warm start) and runs the fine stage, in order; its
 * solves take NumberOfFineSolveThreads of the caller's budget and hold no thread of their own. A caller that makes
 * the fine mesh while the sweep runs (RegisterSegmentedPair(): CGAL meshes on one core) calls SweepCoarseMesh()
 * first, without the fine mesh, then SetSweep() with its result, SetMesh() and Update(): the same result bit for bit.
 *
 * Gauge: only ratios of moduli are identifiable without measured forces; the scene's gauge label keeps its
 * modulus (GetGaugeLabel()). Step limit (LimitElementInversion, default off, one parameter per wall node
 * only): inner trial points that invert more elements than the start are rejected.
 *
 * Output: the mesh with nodal displacement [mm] and the estimated wall forces [mN]; the estimated moduli
 * [kPa]; every fine-mesh inner solve (GetHistory()), the accepted outer iterates (GetOuterIterations()), the
 * surface distances [mm] and everything else in GetResult(). An IterationEvent is invoked after every inner
 * solve (GetCurrentRecord()). Deterministic: sequential, no random numbers.
 * \ingroup BiomechanicalRegistration BiomechanicalRegistrationEstimation
 */
class BiomechanicalRegistration_EXPORT FEMElasticityOptimizer : public ProcessObject
{
public:
  ITK_DISALLOW_COPY_AND_MOVE(FEMElasticityOptimizer);

  using Self = FEMElasticityOptimizer;
  using Superclass = ProcessObject;
  using Pointer = SmartPointer<Self>;
  using ConstPointer = SmartPointer<const Self>;
  using DistanceMapType = Image<float, 3>;
  using MeshObjectType = TetrahedralMeshObject;

  itkNewMacro(Self);
  itkTypeMacro(FEMElasticityOptimizer, ProcessObject);

  /** One inner solve (bmr::IterationRecord) and the distance of one objective surface [mm]. */
  using IterationRecord = bmr::IterationRecord;
  using SurfaceDistance = bmr::ResidualStatistics;

  void
  SetMesh(const MeshObjectType * mesh);
  const MeshObjectType *
  GetMesh() const;
  /** Optional coarser mesh of the same anatomy for the initial sweep of E. */
  void
  SetCoarseMesh(const MeshObjectType * mesh);
  const MeshObjectType *
  GetCoarseMesh() const;
  /** Runs the sweep of E on the coarse mesh now and returns it, without the fine mesh (which the caller may still be
   * making): needs the coarse mesh, the distance maps, the scene and the settings Update() would sweep with, and at
   * least one unknown modulus. Invokes IterationEvent per sample, as Update() does; its solves take
   * NumberOfFineSolveThreads as set when it is called. Throws itk::ExceptionObject on a missing input. */
  bmr::ModulusSweep
  SweepCoarseMesh();
  /** The sweep the fine stage starts from instead of sweeping: SweepCoarseMesh()'s, made with the same inputs and
   * settings (an empty one, the default, sweeps). A warm start (SetWarmStart()) takes precedence. */
  void
  SetSweep(const bmr::ModulusSweep & sweep);
  /** Signed distance map [mm] of objective label \a labelName in the fixed image. */
  void
  SetDistanceMap(const std::string & labelName, const DistanceMapType * map);
  const DistanceMapType *
  GetDistanceMap(const std::string & labelName) const;

  void
  SetScene(const bmr::Scene & scene);
  const bmr::Scene &
  GetScene() const
  {
    return m_Scene;
  }

  /** The estimator's settings in one struct (bmr::EstimatorSettings; defaults there): what the setters below set
   * one at a time; the warm start is SetWarmStart()'s. Checked by Update() (bmr::EstimatorSettings::Validate()). */
  void
  SetEstimatorSettings(const bmr::EstimatorSettings & settings);
  const bmr::EstimatorSettings &
  GetEstimatorSettings() const
  {
    return m_EstimatorSettings;
  }
  /** How the walls' unknown loads act, in one struct (bmr::WallLoadSettings): what the Wall* setters below set. */
  void
  SetWallLoadSettings(const bmr::WallLoadSettings & settings);
  const bmr::WallLoadSettings &
  GetWallLoadSettings() const
  {
    return m_WallLoadSettings;
  }

  bmrFEMSettingMacro(NumberOfSweepSamples, unsigned int, m_EstimatorSettings.numberOfSweepSamples);
  bmrFEMSettingMacro(MaximumNumberOfInnerIterations, unsigned int, m_EstimatorSettings.maximumInnerIterations);
  bmrFEMSettingMacro(MaximumNumberOfOuterIterations, unsigned int, m_EstimatorSettings.maximumOuterIterations);
  bmrFEMSettingMacro(InnerGradientTolerance, double, m_EstimatorSettings.innerGradientTolerance);
  /** L-BFGS inner solves: the looser inner tolerance (relative, as InnerGradientTolerance) of the sweep's samples
   * and, with one unknown modulus, of the fine evaluations the secant search only passes through; the point it
   * stops on is solved on to InnerGradientTolerance (default 3e-4; not above InnerGradientTolerance: every solve
   * in full). */
  bmrFEMSettingMacro(LooseInnerGradientTolerance, double, m_EstimatorSettings.looseInnerGradientTolerance);
  bmrFEMSettingMacro(OuterGradientTolerance, double, m_EstimatorSettings.outerGradientTolerance);
  /** One unknown modulus: the secant search stops when its next step in log E would be shorter than this
   * (default 1e-3, 0.1 % of E). */
  bmrFEMSettingMacro(OuterStepTolerance, double, m_EstimatorSettings.outerStepTolerance);
  /** Spacing [mm] of the control points of the smooth wall basis (bmr::WallBasis); 0: one per wall node; not used
   * with WallMotion UniformPressure. */
  bmrFEMSettingMacro(WallControlSpacing, double, m_WallLoadSettings.controlSpacing);
  /** Weight of the E-independent prior alpha/2 |p|^2 on the wall parameters (bmr::WallLoads::SetRegularization()). */
  bmrFEMSettingMacro(WallRegularization, double, m_WallLoadSettings.regularization);
  /** How the walls' unknown loads act (bmr::WallLoads::SetMotion()): displacements along the walls' normals
   * (default), free displacements, normal tractions (lumen pressures that may vary along a wall) under which the
   * walls move as the tissue lets them, or one uniform pressure per wall (UniformPressure). */
  bmrFEMSettingMacro(WallMotion, bmr::WallMotionEnum, m_WallLoadSettings.motion);
  /** Shorthand: along the normals (on) or free (off). */
  void
  SetWallMotionAlongNormals(bool normal)
  {
    this->SetWallMotion(normal ? bmr::WallMotionEnum::AlongNormals : bmr::WallMotionEnum::Free);
  }
  bool
  GetWallMotionAlongNormals() const
  {
    return m_WallLoadSettings.motion == bmr::WallMotionEnum::AlongNormals;
  }
  itkBooleanMacro(WallMotionAlongNormals);
  bmrFEMSettingMacro(FlatnessThreshold, double, m_EstimatorSettings.flatnessThreshold);
  /** Step limit against element inversion (default off; needs WallControlSpacing 0): the inner L-BFGS line
   * search rejects every trial point that inverts more elements than its start point. */
  bmrFEMSettingMacro(LimitElementInversion, bool, m_EstimatorSettings.limitElementInversion);
  itkBooleanMacro(LimitElementInversion);
  /** Threads for the fine model's factorizations and triangular solves (default, and never more than,
   * MultiThreaderBase::GetGlobalDefaultNumberOfThreads(): all cores unless the program says otherwise). Set fewer
   * when other work runs beside the optimizer. The estimate is the same bit for bit whatever the number
   * (bmr::LinearElasticModel::SetNumberOfSolveThreads()). */
  itkSetClampMacro(NumberOfFineSolveThreads, unsigned int, 1, NumericTraits<unsigned int>::max());
  itkGetConstMacro(NumberOfFineSolveThreads, unsigned int);
  /** Trial points rejected by LimitElementInversion over the last Update(). */
  SizeValueType
  GetNumberOfRejectedSteps() const
  {
    return m_Result.rejectedSteps;
  }
  /** Elements turned inside out by the estimated displacement (deformed volume <= 0). */
  SizeValueType
  GetNumberOfInvertedElements() const
  {
    return m_Result.invertedElements;
  }
  /** Compute the standard uncertainty of log E at the estimate (two extra inner solves per unknown). */
  bmrFEMSettingMacro(EstimateUncertainty, bool, m_EstimatorSettings.estimateUncertainty);
  itkBooleanMacro(EstimateUncertainty);
  /** Step delta in log E of the central differences for the curvature of Phi* (default 0.05; 1e-4 to 1). */
  bmrFEMSettingMacro(UncertaintyStep, double, m_EstimatorSettings.uncertaintyStep);
  /** Warm start from an earlier estimate of nearly the same data: moduli [kPa] by unknown label name (all of
   * them, within their bounds) and that estimate's GetResult().relativeCurvature. The sweep is then skipped (no
   * coarse mesh needed) and the outer search starts there. Empty (default): sweep. */
  void
  SetWarmStart(const std::map<std::string, double> & youngsModuli, double relativeCurvature)
  {
    m_WarmStartModuli = youngsModuli;
    m_WarmStartRelativeCurvature = relativeCurvature;
    this->Modified();
  }

  /** The mesh with displacement [mm] and estimated wall forces [mN]. */
  MeshObjectType *
  GetOutput();

  /** Estimated moduli [kPa] by label name (unknown labels only). */
  const std::map<std::string, double> &
  GetEstimatedYoungsModuli() const
  {
    return m_EstimatedYoungsModuli;
  }
  const std::string &
  GetGaugeLabel() const
  {
    return m_GaugeLabel;
  }
  const std::vector<IterationRecord> &
  GetSweep() const
  {
    return m_Result.sweep;
  }
  const std::vector<IterationRecord> &
  GetHistory() const
  {
    return m_Result.history;
  }
  /** The accepted iterates of the outer search (Phi* at each, E); empty without unknown moduli. */
  const std::vector<IterationRecord> &
  GetOuterIterations() const
  {
    return m_Result.outerIterations;
  }
  const std::string &
  GetOuterStopCondition() const
  {
    return m_Result.outerStopCondition;
  }
  const std::vector<SurfaceDistance> &
  GetSurfaceDistances() const
  {
    return m_Result.residuals;
  }
  /** Phi* at the estimate [mm^2]. */
  double
  GetFinalValue() const
  {
    return m_Result.value;
  }
  /** Standard deviation of log E [dimensionless] by unknown label name: E is known to a factor exp(+-sigma).
   * Empty when not computed (EstimateUncertainty off, no unknown, estimate on a bound). */
  const std::map<std::string, double> &
  GetModulusUncertainty() const
  {
    return m_ModulusUncertainty;
  }
  /** Residual standard deviation s of the objective nodes at the estimate [mm]. */
  double
  GetResidualStandardDeviation() const
  {
    return m_Result.residualStandardDeviation;
  }
  /** Curvature d2 Phi* / d(log E)^2 [mm^2] at the estimate (first unknown; 0 when not computed). */
  double
  GetModulusCurvature() const
  {
    return m_Result.curvature.empty() ? 0.0 : m_Result.curvature[0];
  }
  bool
  GetIdentifiable() const
  {
    return m_Result.identifiable;
  }
  const std::string &
  GetIdentifiabilityMessage() const
  {
    return m_Result.identifiabilityMessage;
  }
  /** Wall time [s] of the stages: "sweep", "initial loads", "fine", "uncertainty". */
  const std::map<std::string, double> &
  GetTimings() const
  {
    return m_Result.timings;
  }
  /** Everything the last Update() found (bmr::ElasticityEstimator's result; vectors in scene order of the
   * unknown labels). */
  const bmr::EstimationResult &
  GetResult() const
  {
    return m_Result;
  }
  /** The scene's objective on \a mesh as Update() composes it from the distance maps, the scene and the wall settings
   * set here: to evaluate it, or to match its surfaces (bmr::EstimationObjective::MatchDisplacement(), what a trained
   * wall basis learns from). Throws itk::ExceptionObject on a missing map or an invalid setting. */
  std::unique_ptr<bmr::SurfaceMatchingObjective>
  MakeObjective(const bmr::TetrahedralMesh & mesh) const;

  /** Last inner solve, for observers of IterationEvent. */
  const IterationRecord &
  GetCurrentRecord() const
  {
    return m_CurrentRecord;
  }

protected:
  FEMElasticityOptimizer();
  ~FEMElasticityOptimizer() override = default;
  void
  PrintSelf(std::ostream & os, Indent indent) const override;
  void
  VerifyPreconditions() ITKv5_CONST override;
  void
  GenerateData() override;

private:
  /** The warm start's moduli (SetWarmStart) in the order of \a unknowns; throws naming an unknown it does not give. */
  std::vector<double>
  WarmStartInOrder(const std::vector<bmr::UnknownModulus> & unknowns) const;
  /** NumberOfFineSolveThreads, at most ITK's global default number of threads. */
  unsigned int
  FineSolveThreads() const;
  /** What Update() and SweepCoarseMesh() need besides the meshes: the scene, its distance maps, valid settings. */
  void
  VerifySceneAndSettings() const;
  /** The distance maps as samplers, by label value. */
  std::map<std::int32_t, std::shared_ptr<const bmr::SignedDistanceSampler>>
  Samplers() const;
  /** Turns \a estimator's records into IterationEvents and progress. */
  void
  Observe(bmr::ElasticityEstimator & estimator);
  /** The scene's objective on \a mesh with this object's wall settings. */
  std::unique_ptr<bmr::SurfaceMatchingObjective>
  MakeObjective(const bmr::TetrahedralMesh &                                                      mesh,
                const std::map<std::int32_t, std::shared_ptr<const bmr::SignedDistanceSampler>> & samplers) const;
  /** Keeps the estimator's result (GetResult(), which the getters read) and its moduli by label name. */
  void
  TakeResult(const bmr::EstimationResult & result);

  bmr::Scene                    m_Scene;
  std::vector<std::string>      m_DistanceMapNames;
  bmr::EstimatorSettings        m_EstimatorSettings;
  bmr::WallLoadSettings         m_WallLoadSettings;
  unsigned int                  m_NumberOfFineSolveThreads{ MultiThreaderBase::GetGlobalDefaultNumberOfThreads() };
  std::map<std::string, double> m_WarmStartModuli;
  double                        m_WarmStartRelativeCurvature{ 0.0 };
  bmr::ModulusSweep             m_Sweep;
  std::map<std::string, double> m_ModulusUncertainty;
  std::map<std::string, double> m_EstimatedYoungsModuli;
  std::string                   m_GaugeLabel;
  IterationRecord               m_CurrentRecord;
  bmr::EstimationResult         m_Result;
};

} // namespace itk

#undef bmrFEMSettingMacro

#endif
