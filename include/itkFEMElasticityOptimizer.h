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
#include "itkProcessObject.h"
#include "itkTetrahedralMeshObject.h"

#include <map>
#include <memory>
#include <string>
#include <vector>

namespace itk {

/** \class FEMElasticityOptimizer
 * \brief Joint estimation of boundary loads and Young's moduli by FEM simulation
 * (H.-P. Lee 2012, chapter 3).
 *
 * The moving anatomy is the tetrahedral mesh (input "Mesh", from
 * LabelImageToTetrahedralMeshFilter with the same scene); the fixed anatomy is
 * given by one signed distance map [mm] per objective label of the scene
 * (SetDistanceMap(); negative inside, as SignedMaurerDistanceMapImageFilter
 * makes them, see ComputeSceneDistanceMaps()). The unknowns are the loads on the
 * scene's force surfaces (bladder and rectum walls) and the moduli of the
 * labels with the role unknown_material. The objective is
 * \f[ \Phi(E, F) = \tfrac12 \sum_s w_s \sum_{l \in s} \phi_s(x_l + u_l(E, F))^2 \f]
 * with K(E) u = F (linear elasticity, u = 0 on fixed walls).
 *
 * Nested optimization:
 * - inner: \f$\Phi^*(E) = \min_F \Phi(E, F)\f$. The loads are parameterized
 *   by the wall displacements d they cause (F = S(E) d with S the Schur
 *   complement on the walls, an exact change of variables, so Phi* is
 *   unchanged), measured in mm, which makes the inner problem well conditioned
 *   and its gradient of the same size as the outer one. By default every wall
 *   node moves along its wall's normal, d_k = n_k s_k (WallMotionAlongNormals:
 *   the tangential part, invisible to the objective, would otherwise compete
 *   with E), with the E-independent regularizer WallRegularization/2 |s|^2, and
 *   the inner problem is solved by L-BFGS (itk::LBFGS2Optimizerv4, More-Thuente
 *   line search) with the adjoint gradient. With WallControlSpacing > 0 the wall
 *   motion is spanned by a smooth reduced basis (bmr::WallBasis) and solved by
 *   Levenberg-Marquardt (bmr::SurfaceMatchingObjective::SolveWalls);
 * - outer: \f$\min_{\log E} \Phi^*(E)\f$ within the scene's bounds by
 *   itk::LBFGSBOptimizerv4, with the envelope-theorem gradient
 *   \f$ d\Phi^{*} / d\log E_m = -E_m \lambda^T \hat K_m u \f$ at the inner optimum;
 * - initial loads by surface matching (dissertation 5.3.1.1); initial E from a
 *   sweep of Phi*(E) over the bounds (log-spaced) on the coarse mesh (input
 *   "CoarseMesh"; the fine mesh when none is given), each sample warm-started
 *   from the previous one; the minimum is bracketed by the sign change of
 *   dPhi* / dlog E and interpolated, then refined on the fine mesh.
 *
 * Stopping rules (dissertation): inner when \f$\|\partial\Phi/\partial d\| \le
 * \epsilon_F \max(1, \|d\|)\f$ (InnerGradientTolerance, default 1e-5) or after
 * MaximumNumberOfInnerIterations; outer when the projected gradient in log E
 * falls below OuterGradientTolerance (default 1e-4) times Phi* at the start of
 * the fine stage, the relative decrease stalls, or after
 * MaximumNumberOfOuterIterations function evaluations. The envelope gradient
 * is only as accurate as the inner solve (about 1e-3 mm^2 on the pelvis), so a
 * tighter outer tolerance only makes L-BFGS-B repeat its line search at the
 * optimum; 1e-4 Phi* corresponds to well under 1 % in E there.
 *
 * Gauge: only ratios of moduli are identifiable without measured forces; the
 * scene's gauge label keeps its modulus (GetGaugeLabel()).
 * Identifiability: the sweep Phi*(E) is reported (GetSweep()); when its
 * relative variation over the bounds is below FlatnessThreshold, or its
 * minimum lies on a bound, IsIdentifiable() is false with a message.
 *
 * Uncertainty (EstimateUncertainty, default on): how well the surfaces determine
 * log E. At the estimate the curvature \f$H = \partial^2\Phi^{*} / \partial(\log E)^2\f$
 * is taken from central differences of the envelope gradient at
 * \f$\log E \pm \delta\f$ (UncertaintyStep, default 0.05; two inner solves per
 * unknown), and the residual variance of the objective nodes from the fit,
 * \f$s^2 = \sum_s w_s \sum_{l \in s}\phi_s^2 / \sum_s w_s n_s\f$ [mm^2].
 * Treating the residuals as independent noise of variance s^2 (the voxel
 * staircase of the fixed labels is about h/\sqrt{12} per node), the
 * linearized least-squares estimate has
 * \f$\mathrm{Cov}(\log E) = s^2 w_{\mathrm{eff}} H^{-1}\f$ with
 * \f$w_{\mathrm{eff}} = \sum_s w_s^2 n_s / \sum_s w_s n_s\f$ (exact for equal
 * weights; invariant under scaling all weights), and
 * GetModulusUncertainty() returns its standard deviations: E is known to a
 * factor \f$e^{\pm\sigma}\f$. Not computed when the estimate lies on a bound;
 * infinite when H is not positive definite.
 *
 * Step limit (LimitElementInversion, default off): linear elasticity lets an
 * element turn inside out when the walls move far. With the limit on, every
 * trial point of the inner L-BFGS line search that inverts more elements than
 * the inner solve's start point is answered with a value above Phi(start), so
 * the line search shortens the step and the walls stop where the mesh would
 * invert. The inner result is then the best fit without new inversions, not a
 * stationary point, and the envelope gradient there is approximate; the count
 * of rejected trial points is GetNumberOfRejectedSteps(). Only with one
 * parameter per wall node (the reduced-basis solver evaluates the objective
 * nodes only).
 *
 * Output: the mesh with nodal displacement [mm] and the estimated wall forces
 * [mN]; the estimated moduli [kPa]; every fine-mesh inner solve (GetHistory())
 * and the accepted outer iterates (GetOuterIterations()); the surface
 * distances [mm]. An IterationEvent is invoked after every inner
 * solve (GetCurrentValue(), GetCurrentYoungsModuli()).
 * Deterministic: sequential, no random numbers.
 * \ingroup BiomechanicalRegistration
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

  itkSetMacro(NumberOfSweepSamples, unsigned int);
  itkGetConstMacro(NumberOfSweepSamples, unsigned int);
  itkSetMacro(MaximumNumberOfInnerIterations, unsigned int);
  itkGetConstMacro(MaximumNumberOfInnerIterations, unsigned int);
  itkSetMacro(MaximumNumberOfOuterIterations, unsigned int);
  itkGetConstMacro(MaximumNumberOfOuterIterations, unsigned int);
  itkSetMacro(InnerGradientTolerance, double);
  itkGetConstMacro(InnerGradientTolerance, double);
  itkSetMacro(OuterGradientTolerance, double);
  itkGetConstMacro(OuterGradientTolerance, double);
  /** Spacing [mm] of the control points of the smooth wall basis (bmr::WallBasis); 0: one per wall node. */
  itkSetMacro(WallControlSpacing, double);
  itkGetConstMacro(WallControlSpacing, double);
  /** Weight of the E-independent regularizer alpha/2 |p|^2 on the wall parameters (bmr::SurfaceMatchingObjective). */
  itkSetMacro(WallRegularization, double);
  itkGetConstMacro(WallRegularization, double);
  /** Walls move along their normals (default on; bmr::SurfaceMatchingObjective::SetWallMotionAlongNormals). */
  itkSetMacro(WallMotionAlongNormals, bool);
  itkGetConstMacro(WallMotionAlongNormals, bool);
  itkBooleanMacro(WallMotionAlongNormals);
  itkSetMacro(FlatnessThreshold, double);
  itkGetConstMacro(FlatnessThreshold, double);
  /** Step limit against element inversion (default off; needs WallControlSpacing 0): the inner L-BFGS line
   * search rejects every trial point that inverts more elements than its start point. */
  itkSetMacro(LimitElementInversion, bool);
  itkGetConstMacro(LimitElementInversion, bool);
  itkBooleanMacro(LimitElementInversion);
  /** Trial points rejected by LimitElementInversion over the last Update(). */
  itkGetConstMacro(NumberOfRejectedSteps, SizeValueType);
  /** Elements turned inside out by the estimated displacement (deformed volume <= 0). */
  itkGetConstMacro(NumberOfInvertedElements, SizeValueType);
  /** Compute the standard uncertainty of log E at the estimate (two extra inner solves per unknown). */
  itkSetMacro(EstimateUncertainty, bool);
  itkGetConstMacro(EstimateUncertainty, bool);
  itkBooleanMacro(EstimateUncertainty);
  /** Step delta in log E of the central differences for the curvature of Phi* (default 0.05). */
  itkSetClampMacro(UncertaintyStep, double, 1e-4, 1.0);
  itkGetConstMacro(UncertaintyStep, double);

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
    return m_Sweep;
  }
  const std::vector<IterationRecord> &
  GetHistory() const
  {
    return m_History;
  }
  /** The accepted iterates of the outer L-BFGS-B (Phi* at each, E); empty without unknown moduli. */
  const std::vector<IterationRecord> &
  GetOuterIterations() const
  {
    return m_OuterIterations;
  }
  const std::string &
  GetOuterStopCondition() const
  {
    return m_OuterStopCondition;
  }
  const std::vector<SurfaceDistance> &
  GetSurfaceDistances() const
  {
    return m_SurfaceDistances;
  }
  itkGetConstMacro(FinalValue, double);
  /** Standard deviation of log E [dimensionless] by unknown label name: E is known to a factor exp(+-sigma).
   * Empty when not computed (EstimateUncertainty off, no unknown, estimate on a bound). */
  const std::map<std::string, double> &
  GetModulusUncertainty() const
  {
    return m_ModulusUncertainty;
  }
  /** Residual standard deviation s of the objective nodes at the estimate [mm]. */
  itkGetConstMacro(ResidualStandardDeviation, double);
  /** Curvature d2 Phi* / d(log E)^2 [mm^2] at the estimate (first unknown; 0 when not computed). */
  itkGetConstMacro(ModulusCurvature, double);
  itkGetConstMacro(Identifiable, bool);
  const std::string &
  GetIdentifiabilityMessage() const
  {
    return m_IdentifiabilityMessage;
  }
  /** Wall time [s] of the stages: "sweep", "initial loads", "fine", "uncertainty". */
  const std::map<std::string, double> &
  GetTimings() const
  {
    return m_Timings;
  }
  /** Everything the last Update() found (bmr::ElasticityEstimator's result; vectors in scene order of the
   * unknown labels). */
  const bmr::EstimationResult &
  GetResult() const
  {
    return m_Result;
  }
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
  /** The estimator's settings from this object's. */
  bmr::EstimatorSettings
  Settings() const;
  /** The scene's objective on \a mesh with this object's wall settings. */
  std::unique_ptr<bmr::SurfaceMatchingObjective>
  MakeObjective(const bmr::TetrahedralMesh &                                                      mesh,
                const std::map<std::int32_t, std::shared_ptr<const bmr::SignedDistanceSampler>> & samplers) const;
  /** Copies the estimator's result into the outputs. */
  void
  TakeResult(const bmr::EstimationResult & result);

  bmr::Scene               m_Scene;
  std::vector<std::string> m_DistanceMapNames;
  // Defaults: those of the library's estimator and wall loads (one place, read by the CLI too).
  unsigned int  m_NumberOfSweepSamples{ bmr::EstimatorSettings{}.numberOfSweepSamples };
  unsigned int  m_MaximumNumberOfInnerIterations{ bmr::EstimatorSettings{}.maximumInnerIterations };
  unsigned int  m_MaximumNumberOfOuterIterations{ bmr::EstimatorSettings{}.maximumOuterIterations };
  double        m_InnerGradientTolerance{ bmr::EstimatorSettings{}.innerGradientTolerance };
  double        m_OuterGradientTolerance{ bmr::EstimatorSettings{}.outerGradientTolerance };
  double        m_FlatnessThreshold{ bmr::EstimatorSettings{}.flatnessThreshold };
  bool          m_EstimateUncertainty{ bmr::EstimatorSettings{}.estimateUncertainty };
  bool          m_LimitElementInversion{ bmr::EstimatorSettings{}.limitElementInversion };
  double        m_UncertaintyStep{ bmr::EstimatorSettings{}.uncertaintyStep };
  double        m_WallControlSpacing{ bmr::WallLoadSettings{}.controlSpacing };
  double        m_WallRegularization{ bmr::WallLoadSettings{}.regularization };
  bool          m_WallMotionAlongNormals{ bmr::WallLoadSettings{}.motion == bmr::WallMotionEnum::AlongNormals };
  SizeValueType m_NumberOfRejectedSteps{ 0 };
  SizeValueType m_NumberOfInvertedElements{ 0 };
  std::map<std::string, double> m_ModulusUncertainty;
  double                        m_ResidualStandardDeviation{ 0.0 };
  double                        m_ModulusCurvature{ 0.0 };
  std::map<std::string, double> m_EstimatedYoungsModuli;
  std::string                   m_GaugeLabel;
  std::vector<IterationRecord>  m_Sweep;
  std::vector<IterationRecord>  m_History;
  std::vector<SurfaceDistance>  m_SurfaceDistances;
  std::vector<IterationRecord>  m_OuterIterations;
  std::string                   m_OuterStopCondition;
  double                        m_FinalValue{ 0.0 };
  bool                          m_Identifiable{ true };
  std::string                   m_IdentifiabilityMessage;
  std::map<std::string, double> m_Timings;
  IterationRecord               m_CurrentRecord;
  bmr::EstimationResult         m_Result;
};

} // namespace itk

#endif
