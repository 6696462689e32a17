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
// The registration pipeline: distance maps -> meshes -> FEMElasticityOptimizer -> fields -> warped images.
#include "itkPipelineStages.h"
#include "itkMultiThreaderBase.h"

#include "bmrError.h"
#include "itkFEMElasticityOptimizer.h"
#include "itkRegistrationQualityMeasures.h"
#include "itkSceneDistanceMaps.h"

#include "itkCommand.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <iterator>
#include <limits>
#include <set>
#include <sstream>

namespace itk {
namespace {
/** Axis-aligned physical bounding box [mm] of an image's voxel box (the corners at +-half a voxel). */
std::array<std::array<double, 2>, 3>
PhysicalBounds(const ImageBase<3> * image)
{
  std::array<std::array<double, 2>, 3> b;
  for (auto & axis : b)
  {
    axis = { { std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity() } };
  }
  const auto region = image->GetLargestPossibleRegion();
  for (int corner = 0; corner < 8; ++corner)
  {
    ContinuousIndex<double, 3> index;
    for (unsigned int a = 0; a < 3; ++a)
    {
      index[a] = region.GetIndex(a) - 0.5 + ((corner >> a) & 1 ? double(region.GetSize(a)) : 0.0);
    }
    Point<double, 3> x;
    image->TransformContinuousIndexToPhysicalPoint(index, x);
    for (unsigned int a = 0; a < 3; ++a)
    {
      b[a][0] = std::min(b[a][0], x[a]);
      b[a][1] = std::max(b[a][1], x[a]);
    }
  }
  return b;
}

/** The smallest and the largest voxel side [mm] of the moving and the fixed label images. */
std::array<double, 2>
VoxelRange(const ImageBase<3> * moving, const ImageBase<3> * fixed)
{
  std::array<double, 2> range{ { std::numeric_limits<double>::infinity(), 0.0 } };
  for (const ImageBase<3> * image : { moving, fixed })
  {
    for (unsigned int a = 0; a < 3; ++a)
    {
      range[0] = std::min(range[0], image->GetSpacing()[a]);
      range[1] = std::max(range[1], image->GetSpacing()[a]);
    }
  }
  return range;
}

/** Whether a modulus is stated from label voxels of up to \a coarsest mm (UncertaintySettings::statedVoxelLimitMM). */
bool
StatesModulus(double coarsest, const UncertaintySettings & u)
{
  return coarsest <= u.statedVoxelLimitMM;
}

/** The thick slices' calibration that holds for the two label images (FindSliceCalibration()); none for slices
 * interpolated between (RegistrationSettings::interpolateSlices), which no calibration measured. */
const SliceCalibration *
SliceCalibrationOf(const ImageBase<3> * moving, const ImageBase<3> * fixed, const RegistrationSettings & settings)
{
  if (settings.interpolateSlices)
  {
    return nullptr;
  }
  std::array<double, 3> movingSpacing, fixedSpacing;
  for (unsigned int a = 0; a < 3; ++a)
  {
    movingSpacing[a] = moving->GetSpacing()[a];
    fixedSpacing[a] = fixed->GetSpacing()[a];
  }
  return FindSliceCalibration(movingSpacing, fixedSpacing);
}

/** Why no modulus is stated from label voxels of up to \a coarsest mm: beyond the resamples' limit, and no thick-slice
 * calibration holds; in the words of both the warning and the report. */
std::string
NotDeterminedByVoxels(double coarsest, const UncertaintySettings & u)
{
  std::ostringstream os;
  os << bmr::VoxelLimitReason(coarsest, u.statedVoxelLimitMM)
     << ", and no thick-slice calibration holds for these scans (calibrated: both scans with slices of";
  const std::size_t count = std::size(SliceCalibrations);
  for (std::size_t k = 0; k < count; ++k)
  {
    os << (k == 0 ? " " : k + 1 == count ? " or " : ", ") << SliceCalibrations[k].sliceMM;
  }
  os << " mm +- " << SliceCalibrationToleranceMM << " mm and in-plane voxels of " << SliceCalibrationInPlaneMM[0]
     << " to " << SliceCalibrationInPlaneMM[1] << " mm)";
  return os.str();
}

/** The warning that goes with the modulus's statement at label voxels of up to \a coarsest mm: not stated above the
 * limit without a thick-slice calibration (the statement's own reason); stated, when an interval is made, beyond the
 * geometry where coverage was shown when the limit was raised. */
std::vector<std::string>
VoxelLimitWarnings(const bmr::Scene &          scene,
                   double                      coarsest,
                   const UncertaintySettings & u,
                   const SliceCalibration *    calibration)
{
  if (scene.UnknownLabels().empty())
  {
    return {};
  }
  if (!StatesModulus(coarsest, u))
  {
    if (calibration && u.method != UncertaintyMethodEnum::None)
    {
      return {};
    }
    return { NotDeterminedByVoxels(coarsest, u) + " (the registration itself is not affected)" };
  }
  if (coarsest <= bmr::StatedModulusVoxelLimitMM || u.method == UncertaintyMethodEnum::None)
  {
    return {};
  }
  std::ostringstream os;
  os << "label voxels of up to " << coarsest << " mm: the modulus's interval is stated although its coverage was "
     << "shown only at voxels of at most " << bmr::StatedModulusVoxelLimitMM
     << " mm (UncertaintySettings::statedVoxelLimitMM raised to " << u.statedVoxelLimitMM << " mm)";
  return { os.str() };
}

/** What the label images' voxels mean for the registration: the warnings about them, whether the slices are
 * interpolated (RegistrationResult::slicesInterpolated); returns the largest voxel side [mm]. */
double
ReadVoxels(RegistrationResult &                r,
           pipeline::StageClock &              clock,
           const bmr::Scene &                  scene,
           const RegistrationSettings &        settings,
           const BiomechanicalLabelImageType * movingLabels,
           const BiomechanicalLabelImageType * fixedLabels)
{
  const std::array<double, 2> voxels = VoxelRange(movingLabels, fixedLabels);
  r.slicesInterpolated =
    settings.interpolateSlices && (ThickSlices(movingLabels).axis >= 0 || ThickSlices(fixedLabels).axis >= 0);
  clock.Warn(r.state.warnings, scene.EstimationWarnings(voxels[0]));
  clock.Warn(r.state.warnings,
             VoxelLimitWarnings(
               scene, voxels[1], settings.uncertainty, SliceCalibrationOf(movingLabels, fixedLabels, settings)));
  return voxels[1];
}

/** Warnings about what the images leave open: an end of the interval at a search bound, a 68 % interval wider
 * than exp(+-0.1), or (curvature) no positive curvature at all. */
std::vector<std::string>
UncertaintyWarnings(const RegistrationResult & r)
{
  std::vector<std::string> warnings;
  for (const auto & kv : r.modulusInterval)
  {
    const ModulusInterval & i = kv.second;
    const double            halfWidth = 0.5 * std::log(i.interval68[1] / i.interval68[0]);
    if (!i.notDeterminedReason.empty())
    {
      continue; // not the images' doing: the voxel or the filling warning says why, in the same words
    }
    if (!i.lowerDetermined || !i.upperDetermined)
    {
      warnings.push_back("the images do not determine the modulus of \"" + kv.first +
                         "\": " + ModulusIntervalText(kv.first, i));
    }
    else if (halfWidth > BiomechanicalUncertaintyWarningLogSigma)
    {
      warnings.push_back("the images determine the modulus of \"" + kv.first + "\" only to a factor exp(+-" +
                         std::to_string(halfWidth).substr(0, 5) + ") (68 %): " + ModulusIntervalText(kv.first, i));
    }
  }
  return warnings;
}

/** Forwards the optimizer's IterationEvent to the observer. */
void
ObserveIterations(FEMElasticityOptimizer * optimizer, PipelineObserver * observer)
{
  if (observer == nullptr)
  {
    return;
  }
  optimizer->AddObserver(IterationEvent(), [optimizer, observer](const EventObject &) {
    observer->Iteration(optimizer->GetCurrentRecord());
  });
}

/** The organs of \a probabilities, each checked to be an objective organ of \a scene with an image. */
std::vector<std::string>
ProbabilityOrgans(const OrganProbabilityImages & probabilities, const bmr::Scene & scene)
{
  std::vector<std::string> organs;
  for (const auto & kv : probabilities)
  {
    const bool objective = std::any_of(scene.objective.begin(),
                                       scene.objective.end(),
                                       [&kv](const bmr::ObjectiveTerm & t) { return t.label == kv.first; });
    if (!objective || !kv.second)
    {
      bmr::FailInput("RegisterSegmentedPair",
                     "a fixed probability image is given for \"" + kv.first +
                       "\", which is not an objective organ of the scene (or the image is null)");
    }
    organs.push_back(kv.first);
  }
  return organs;
}

/** The fit: FEMElasticityOptimizer on \a setup, its timings as stages and its outputs in \a r. */
void
Estimate(RegistrationResult &                                    r,
         const pipeline::EstimationSetup &                       setup,
         const std::map<std::string, Image<float, 3>::Pointer> & maps,
         pipeline::StageClock &                                  clock)
{
  const bool curvature = setup.statesModulus && setup.settings->uncertainty.method == UncertaintyMethodEnum::Curvature;
  // Told to the observer as one stage (its progress: the inner solves), recorded as the optimizer's parts.
  PipelineObserver * observer = clock.GetObserver();
  const auto         start = bmr::SteadyClock::now();
  if (observer != nullptr)
  {
    observer->StageBegin("estimation");
  }
  const auto optimizer = pipeline::RunEstimation(setup, maps, curvature, observer);
  if (observer != nullptr)
  {
    observer->StageEnd("estimation", bmr::SecondsSince(start), "");
  }
  for (const auto & kv : optimizer->GetTimings())
  {
    clock.Add("estimation: " + kv.first, kv.second);
  }
  r.estimation = optimizer->GetResult();
  r.youngsModulus = optimizer->GetEstimatedYoungsModuli();
  r.modulusUncertainty = optimizer->GetModulusUncertainty();
  r.gaugeLabel = optimizer->GetGaugeLabel();
  r.state.mesh = optimizer->GetOutput()->Get();
  r.unknowns = bmr::SceneUnknownModuli(*setup.scene);
}

/** The resamples' meshes beside the fit (pipeline::ResampleMeshPrefetch, a bmr::BackgroundTask), when the interval
 * resamples, there is a modulus to estimate and more than one thread may run; null otherwise. */
std::unique_ptr<pipeline::ResampleMeshPrefetch>
StartResampleMeshes(const BiomechanicalLabelImageType * movingLabels,
                    const bmr::Scene &                  scene,
                    const RegistrationSettings &        settings)
{
  const UncertaintySettings & u = settings.uncertainty;
  const unsigned int          threads = pipeline::ResampleThreads(u);
  if (!pipeline::UsesResampleMeshes(scene, settings) || threads < 2)
  {
    return nullptr;
  }
  return std::make_unique<pipeline::ResampleMeshPrefetch>(movingLabels, scene, u);
}

/** The rescans' distance maps beside the fit (pipeline::RescanMapsPrefetch, a bmr::BackgroundTask), when the
 * interval rescans, there is a modulus to estimate and more than one thread may run; null otherwise. */
std::unique_ptr<pipeline::RescanMapsPrefetch>
StartRescanMaps(const BiomechanicalLabelImageType * fixedLabels, const pipeline::EstimationSetup & setup)
{
  const UncertaintySettings & u = setup.settings->uncertainty;
  const unsigned int          threads = pipeline::ResampleThreads(u);
  if (u.method != UncertaintyMethodEnum::Rescan || !pipeline::UsesResampleMeshes(*setup.scene, *setup.settings) ||
      threads < 2)
  {
    return nullptr;
  }
  return std::make_unique<pipeline::RescanMapsPrefetch>(fixedLabels, setup);
}

/** The stated interval of every unknown modulus, by the chosen method, and what it leaves undetermined in the
 * identifiability verdict. */
void
StateIntervals(RegistrationResult &                r,
               const pipeline::EstimationSetup &   setup,
               const BiomechanicalLabelImageType * movingLabels,
               const BiomechanicalLabelImageType * fixedLabels,
               double                              coarsestVoxel,
               pipeline::StageClock &              clock)
{
  const UncertaintyMethodEnum method = setup.settings->uncertainty.method;
  if (!setup.statesModulus && setup.sliceCalibration)
  {
    // Thick slices: the calibration's interval; none when none is asked for, as at any voxels.
    std::set<std::string> reasons;
    for (const bmr::UnknownModulus & u : r.unknowns)
    {
      if (method != UncertaintyMethodEnum::None)
      {
        const ModulusInterval & i = r.modulusInterval[u.name] = SliceCalibratedInterval(
          r.youngsModulus.at(u.name), *setup.sliceCalibration, u, r.VolumeChangeML(SliceCalibrationFillingOrgan));
        reasons.insert(i.notDeterminedReason);
      }
    }
    reasons.erase(std::string());
    // A filling outside the calibration: the warning says what the statement says.
    for (const std::string & reason : reasons)
    {
      clock.Warn(r.state.warnings,
                 { "the modulus is not determined: " + reason + " (the registration itself is not affected)" });
    }
  }
  else if (!setup.statesModulus)
  {
    // Where coverage was not shown no number is stated, whatever the method: nothing to resample for.
    for (const bmr::UnknownModulus & u : r.unknowns)
    {
      ModulusInterval & i = r.modulusInterval[u.name];
      i.fit = r.youngsModulus.at(u.name);
      i.method = "none";
      pipeline::DeclareNotDetermined(i, u, NotDeterminedByVoxels(coarsestVoxel, setup.settings->uncertainty));
    }
  }
  else if ((method == UncertaintyMethodEnum::Bootstrap || method == UncertaintyMethodEnum::Rescan) &&
           setup.settings->uncertainty.resamples > 0 && !r.unknowns.empty())
  {
    r.modulusInterval = pipeline::BootstrapModuli(setup, r, movingLabels, fixedLabels, clock);
  }
  else if (method != UncertaintyMethodEnum::None)
  {
    for (const bmr::UnknownModulus & u : r.unknowns)
    {
      const auto sigma = r.modulusUncertainty.find(u.name);
      r.modulusInterval[u.name] = pipeline::CurvatureInterval(
        r.youngsModulus.at(u.name),
        sigma == r.modulusUncertainty.end() ? std::numeric_limits<double>::infinity() : sigma->second,
        u);
    }
  }
  for (const auto & kv : r.modulusInterval)
  {
    if (!kv.second.lowerDetermined || !kv.second.upperDetermined)
    {
      r.estimation.identifiable = false;
      r.estimation.identifiabilityMessage +=
        (r.estimation.identifiabilityMessage.empty() ? "" : "; ") + ModulusIntervalText(kv.first, kv.second);
    }
  }
}

/** The estimated state's nodal displacement and force, the gauge label's modulus, and with \a elements its
 * per-element moduli, stress and Dirichlet flags (for mesh.vtu). */
void
DescribeState(RegistrationResult & r, const bmr::Scene & scene, bool elements)
{
  const bmr::SceneLabel * gauge = scene.FindLabel(r.gaugeLabel);
  r.gaugeModulus = gauge ? gauge->youngsModulus : 0.0;
  const bmr::TetrahedralMesh & mesh = r.state.mesh;
  bmr::ForwardSimulation &     s = r.state.simulation;
  s.displacement = mesh.displacement;
  s.force = mesh.force;
  if (!elements)
  {
    return;
  }
  auto materials = bmr::SceneMaterials(scene);
  for (const auto & l : scene.labels)
  {
    const auto it = r.youngsModulus.find(l.name);
    if (it != r.youngsModulus.end())
    {
      materials[l.value].youngsModulus = it->second;
    }
  }
  s.vonMises = bmr::SceneVonMisesStress(scene, mesh, materials, mesh.displacement);
  bmr::SetElementMaterials(mesh, materials, s);
  s.dirichlet.assign(mesh.GetNumberOfPoints(), 0);
  for (std::int32_t n : bmr::SceneBoundaryConditions(scene, mesh).dirichletNodes)
  {
    s.dirichlet[n] = 1;
  }
}

/** Dice per organ of the warped labels and the Jacobian of the pull-back field. */
void
Evaluate(RegistrationResult & r, const bmr::Scene & scene, const BiomechanicalLabelImageType * fixedLabels)
{
  const auto overlaps = ComputeLabelOverlaps<BiomechanicalLabelImageType>(r.warpedLabels, fixedLabels);
  for (const auto & l : scene.labels)
  {
    const auto found = overlaps.find(l.value);
    if (l.role != bmr::LabelRoleEnum::Outside && found != overlaps.end() && found->second.inA + found->second.inB > 0)
    {
      r.dice[l.name] = found->second.dice;
    }
  }
  const auto jacobian = ComputeJacobianDeterminantStatistics(r.state.pullBack.GetPointer());
  r.jacobianMinimum = jacobian.minimum;
  r.jacobianNonPositiveFraction = jacobian.fractionNonPositive;
}

/** The meshes the estimation starts with: the premeshed ones, or the coarse mesh of the sweep (when it sweeps) and
 * the fine mesh into r.state.mesh (unless the estimation takes it from \a fineMesh after the sweep). Returns the
 * coarse mesh, empty when there is no sweep. */
bmr::TetrahedralMesh
MeshesForEstimation(RegistrationResult &                r,
                    const MovingAnatomyMeshes *         premeshed,
                    pipeline::BackgroundMesh *          fineMesh,
                    bool                                meshDuringSweep,
                    const BiomechanicalLabelImageType * anatomy,
                    const bmr::Scene &                  scene,
                    const RegistrationSettings &        settings,
                    pipeline::StageClock &              clock)
{
  if (premeshed != nullptr)
  {
    r.state.mesh = premeshed->fine;
    return premeshed->coarse;
  }
  bmr::TetrahedralMesh coarse;
  // Coarse-to-fine only when there is a modulus to sweep: nothing is meshed twice otherwise.
  if (pipeline::UsesCoarseMesh(scene, settings))
  {
    coarse =
      pipeline::MeshLabelImage(anatomy, ScaledMeshSizes(scene, settings.coarseFactor), clock, "coarse mesh (sweep)");
  }
  if (!meshDuringSweep)
  {
    r.state.mesh = fineMesh->Take(clock, "mesh (CGAL Mesh_3)");
  }
  return coarse;
}

/** The warped labels (nearest) and CT (linear, when given) through the pull-back field, then Dice and the Jacobian. */
void
WarpAndEvaluate(RegistrationResult &                r,
                const bmr::Scene &                  scene,
                const BiomechanicalLabelImageType * movingLabels,
                const BiomechanicalLabelImageType * fixedLabels,
                const BiomechanicalCTImageType *    movingCT,
                pipeline::StageClock &              clock)
{
  clock.Begin(movingCT ? "warp (CT linear; labels nearest)" : "warp (labels nearest)");
  r.warpedLabels = WarpImage(movingLabels, r.state.pullBack.GetPointer(), true, 0);
  r.movingGrid = ImageBase<3>::New();
  r.movingGrid->CopyInformation(movingLabels);
  r.movingGrid->SetLargestPossibleRegion(movingLabels->GetLargestPossibleRegion());
  if (movingCT)
  {
    r.warpedCT = WarpImage(movingCT, r.state.pullBack.GetPointer(), false, -1000.0f);
  }
  clock.End();
  clock.Begin("report (Dice, Jacobian)");
  clock.Warn(r.state.warnings, UncertaintyWarnings(r));
  Evaluate(r, scene, fixedLabels);
  clock.End();
}
} // namespace

namespace pipeline {
void
CheckOverlap(const ImageBase<3> * moving, const ImageBase<3> * fixed)
{
  const auto movingBox = PhysicalBounds(moving);
  const auto fixedBox = PhysicalBounds(fixed);
  for (unsigned int a = 0; a < 3; ++a)
  {
    if (movingBox[a][1] <= fixedBox[a][0] || fixedBox[a][1] <= movingBox[a][0])
    {
      bmr::FailInput("RegisterSegmentedPair",
                     "the moving and fixed label images do not overlap in physical space (axis " + std::to_string(a) +
                       ": moving " + std::to_string(movingBox[a][0]) + " .. " + std::to_string(movingBox[a][1]) +
                       " mm, fixed " + std::to_string(fixedBox[a][0]) + " .. " + std::to_string(fixedBox[a][1]) +
                       " mm)");
    }
  }
}


std::map<std::string, Image<float, 3>::Pointer>
ObjectiveDistanceMaps(const BiomechanicalLabelImageType * labels,
                      const OrganProbabilityImages &      probabilities,
                      const bmr::Scene &                  scene,
                      double                              exactWithinMM,
                      bool                                interpolateSlices)
{
  bmr::Scene fromLabels = scene;
  fromLabels.objective.clear();
  for (const bmr::ObjectiveTerm & term : scene.objective)
  {
    if (probabilities.count(term.label) == 0)
    {
      fromLabels.objective.push_back(term);
    }
  }
  auto maps = ComputeSceneDistanceMaps(labels, fromLabels, exactWithinMM, interpolateSlices);
  for (const auto & kv : probabilities)
  {
    maps[kv.first] = ComputeProbabilityDistanceMap(kv.second.GetPointer(), "fixed probability of \"" + kv.first + "\"");
  }
  return maps;
}

BiomechanicalLabelImageType::ConstPointer
MeshedAnatomy(const BiomechanicalLabelImageType * labels, const RegistrationSettings & settings)
{
  return settings.interpolateSlices ? InterpolateLabelSlices(labels)
                                    : BiomechanicalLabelImageType::ConstPointer(labels);
}

FEMElasticityOptimizer::Pointer
RunEstimation(const EstimationSetup &                                 setup,
              const std::map<std::string, Image<float, 3>::Pointer> & maps,
              bool                                                    curvature,
              PipelineObserver *                                      observer)
{
  auto optimizer = FEMElasticityOptimizer::New();
  if (setup.coarse)
  {
    auto coarse = TetrahedralMeshObject::New();
    coarse->Set(*setup.coarse);
    optimizer->SetCoarseMesh(coarse);
  }
  optimizer->SetScene(*setup.scene);
  for (const auto & kv : maps)
  {
    optimizer->SetDistanceMap(kv.first, kv.second);
  }
  bmr::EstimatorSettings estimator = setup.settings->estimator;
  estimator.estimateUncertainty = curvature && estimator.estimateUncertainty;
  optimizer->SetEstimatorSettings(estimator);
  optimizer->SetWallLoadSettings(setup.settings->walls);
  optimizer->SetNumberOfFineSolveThreads(setup.fineSolveThreads);
  if (!setup.warmStartModuli.empty())
  {
    optimizer->SetWarmStart(setup.warmStartModuli, setup.warmStartRelativeCurvature);
  }
  ObserveIterations(optimizer, observer);
  auto fine = TetrahedralMeshObject::New();
  if (setup.fine != nullptr)
  {
    fine->Set(*setup.fine);
  }
  else
  {
    // The fine mesh is still being made beside: the sweep's solves take the budget but its core, then it is taken.
    optimizer->SetNumberOfFineSolveThreads(std::max(1U, setup.fineSolveThreads - 1));
    optimizer->SetSweep(optimizer->SweepCoarseMesh());
    optimizer->SetNumberOfFineSolveThreads(setup.fineSolveThreads);
    fine->Set(setup.fineAfterSweep());
  }
  optimizer->SetMesh(fine);
  optimizer->Update();
  return optimizer;
}
} // namespace pipeline

namespace {
/** Refuses missing or disjoint label images, settings out of range, and premeshed moving anatomy
 * (RegistrationSettings::meshes) made from other inputs than \a movingLabels, \a scene and \a settings. */
void
CheckRegistrationInputs(const BiomechanicalLabelImageType * movingLabels,
                        const BiomechanicalLabelImageType * fixedLabels,
                        const bmr::Scene &                  scene,
                        const RegistrationSettings &        settings)
{
  if (movingLabels == nullptr || fixedLabels == nullptr)
  {
    bmr::FailInput("RegisterSegmentedPair", "the moving and the fixed label images are required");
  }
  pipeline::CheckOverlap(movingLabels, fixedLabels);
  settings.Validate();
  if (settings.meshes != nullptr &&
      settings.meshes->fingerprint != pipeline::MovingAnatomyFingerprint(movingLabels, scene, settings))
  {
    bmr::FailInput(
      "RegisterSegmentedPair",
      "RegistrationSettings::meshes were made for other moving labels, another scene or other mesh settings "
      "(MeshMovingAnatomy)");
  }
}

/** How \a setup states the modulus from label voxels of up to \a coarsestVoxel mm (whether at all, and with which
 * thick slices' calibration) and how many threads its fine solves take; returns whether the interval resamples. */
bool
PlanStatement(pipeline::EstimationSetup &         setup,
              double                              coarsestVoxel,
              const BiomechanicalLabelImageType * movingLabels,
              const BiomechanicalLabelImageType * fixedLabels)
{
  const RegistrationSettings & settings = *setup.settings;
  const UncertaintyMethodEnum  method = settings.uncertainty.method;
  setup.statesModulus = StatesModulus(coarsestVoxel, settings.uncertainty);
  setup.sliceCalibration = SliceCalibrationOf(movingLabels, fixedLabels, settings);
  const bool resamples =
    setup.statesModulus && (method == UncertaintyMethodEnum::Bootstrap || method == UncertaintyMethodEnum::Rescan);
  // The fine solves take every core but the one the interval's prefetches may run on.
  const unsigned threads = MultiThreaderBase::GetGlobalDefaultNumberOfThreads();
  setup.fineSolveThreads = resamples ? std::max(1U, threads - 1) : threads;
  return resamples;
}

/** The fine mesh's stage when it was made alongside the sweep: the wait for it after the sweep (\a waitSeconds), so
 * that the stages add up to the wall time; its \a detail and how long the meshing took (\a meshingSeconds). */
void
ReportMeshedAlongside(pipeline::StageClock & clock,
                      const std::string &    detail,
                      double                 meshingSeconds,
                      double                 waitSeconds)
{
  clock.Record("mesh (CGAL Mesh_3)",
               waitSeconds,
               detail + " (meshed alongside the sweep: " + bmr::SecondsText(meshingSeconds) +
                 " s, this stage the wait)");
}
} // namespace

RegistrationResult
RegisterSegmentedPair(const BiomechanicalLabelImageType * movingLabels,
                      const BiomechanicalLabelImageType * fixedLabels,
                      const BiomechanicalCTImageType *    movingCT,
                      const bmr::Scene &                  scene,
                      const RegistrationSettings &        settings,
                      PipelineObserver *                  observer)
{
  return RegisterSegmentedPair(
    movingLabels, fixedLabels, OrganProbabilityImages(), movingCT, scene, settings, observer);
}

RegistrationResult
RegisterSegmentedPair(const BiomechanicalLabelImageType * movingLabels,
                      const BiomechanicalLabelImageType * fixedLabels,
                      const OrganProbabilityImages &      fixedProbabilities,
                      const BiomechanicalCTImageType *    movingCT,
                      const bmr::Scene &                  inputScene,
                      const RegistrationSettings &        settings,
                      PipelineObserver *                  observer)
{
  const std::vector<std::string> probabilityOrgans = ProbabilityOrgans(fixedProbabilities, inputScene);
  CheckRegistrationInputs(movingLabels, fixedLabels, inputScene, settings);
  const bmr::Scene scene = ScaledMeshSizes(inputScene, settings.meshScale);
  scene.Validate();
  RegistrationResult   r;
  pipeline::StageClock clock(observer, r.state.stages);
  clock.Warn(r.state.warnings, scene.Warnings());
  const double coarsestVoxel = ReadVoxels(r, clock, scene, settings, movingLabels, fixedLabels);
  pipeline::MeasureLabelVolumes(
    r, scene, movingLabels, fixedLabels); // before the interval: its filling term needs them

  const MovingAnatomyMeshes * premeshed = settings.meshes;
  // What is meshed (here, or by MeshMovingAnatomy() for premeshed, and by the interval's resamples): the moving
  // labels, interpolated between thick slices when asked. The fields and warps keep the labels.
  const BiomechanicalLabelImageType::ConstPointer anatomy = pipeline::MeshedAnatomy(movingLabels, settings);
  // The fine mesh (CGAL, one core) is made alongside the distance maps, the coarse mesh and the sweep.
  const std::unique_ptr<pipeline::BackgroundMesh> fineMesh =
    premeshed ? nullptr : std::make_unique<pipeline::BackgroundMesh>(anatomy.GetPointer(), scene);
  // With a sweep to run, the estimation takes the fine mesh when the sweep is done
  // (FEMElasticityOptimizer::SweepCoarseMesh()); without, it is taken before.
  const bool meshDuringSweep = fineMesh && fineMesh->Alongside() && pipeline::UsesCoarseMesh(scene, settings);
  clock.Begin("distance maps (fixed labels)");
  const auto maps = pipeline::ObjectiveDistanceMaps(
    fixedLabels, fixedProbabilities, scene, SceneDistanceExactWithinMM, settings.interpolateSlices);
  clock.End(std::to_string(maps.size()) + " organs");
  const bmr::TetrahedralMesh coarse =
    MeshesForEstimation(r, premeshed, fineMesh.get(), meshDuringSweep, anatomy.GetPointer(), scene, settings, clock);
  pipeline::EstimationSetup setup{
    nullptr, {}, coarse.points.empty() ? nullptr : &coarse, &scene, &settings, probabilityOrgans, &fixedProbabilities
  };
  setup.resampleMeshes = premeshed ? &premeshed->resamples : nullptr;
  const bool resamples = PlanStatement(setup, coarsestVoxel, movingLabels, fixedLabels);
  // The interval's prefetches (background tasks) start once the fit's mesh is made, so as not to slow its meshing: on
  // the estimation's thread that takes the mesh when it is finished during the sweep.
  std::unique_ptr<pipeline::ResampleMeshPrefetch> prefetch;
  std::unique_ptr<pipeline::RescanMapsPrefetch>   rescanMaps;
  const auto                                      startPrefetches = [&]() {
    if (resamples) // nothing is resampled where no modulus is stated
    {
      prefetch = premeshed ? nullptr : StartResampleMeshes(anatomy.GetPointer(), scene, settings);
      rescanMaps = StartRescanMaps(fixedLabels, setup);
    }
  };
  std::string                fineMeshDetail;
  double                     fineMeshWait = 0.0;
  const bmr::TetrahedralMesh estimationMesh = r.state.mesh; // empty when made during the sweep
  if (meshDuringSweep)
  {
    setup.fineAfterSweep = [&]() {
      const auto           waitStart = bmr::SteadyClock::now();
      bmr::TetrahedralMesh mesh = fineMesh->TakeAlongside(fineMeshDetail);
      fineMeshWait = bmr::SecondsSince(waitStart);
      startPrefetches();
      return mesh;
    };
  }
  else
  {
    setup.fine = &estimationMesh;
    startPrefetches();
  }
  Estimate(r, setup, maps, clock);
  if (meshDuringSweep)
  {
    ReportMeshedAlongside(clock, fineMeshDetail, fineMesh->MeshingSeconds(), fineMeshWait);
  }
  clock.Warn(r.state.warnings, bmr::MeshResolutionWarnings(scene, r.state.mesh));
  setup.prefetch = prefetch.get();
  setup.rescanMaps = rescanMaps.get();
  StateIntervals(r, setup, anatomy.GetPointer(), fixedLabels, coarsestVoxel, clock);
  DescribeState(r, scene, settings.elementState);

  pipeline::ComputeFields(r.state, fixedLabels, movingLabels, settings.pushField, scene, clock);
  WarpAndEvaluate(r, scene, movingLabels, fixedLabels, movingCT, clock);
  return r;
}

} // namespace itk
