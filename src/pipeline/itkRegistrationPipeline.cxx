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

#include "bmrError.h"
#include "itkFEMElasticityOptimizer.h"
#include "itkRegistrationQualityMeasures.h"
#include "itkSceneDistanceMaps.h"

#include "itkCommand.h"

#include <cmath>
#include <iomanip>
#include <limits>
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

/** Images that do not overlap in physical space cannot be registered (wrong origin, wrong file). */
void
CheckOverlap(const ImageBase<3> * moving, const ImageBase<3> * fixed)
{
  const auto movingBox = PhysicalBounds(moving);
  const auto fixedBox = PhysicalBounds(fixed);
  for (unsigned int a = 0; a < 3; ++a)
  {
    if (movingBox[a][1] <= fixedBox[a][0] || fixedBox[a][1] <= movingBox[a][0])
    {
      bmr::Fail("RegisterSegmentedPair",
                "the moving and fixed label images do not overlap in physical space (axis " + std::to_string(a) +
                  ": moving " + std::to_string(movingBox[a][0]) + " .. " + std::to_string(movingBox[a][1]) +
                  " mm, fixed " + std::to_string(fixedBox[a][0]) + " .. " + std::to_string(fixedBox[a][1]) + " mm)");
    }
  }
}

/** The estimation warnings of the label images' voxel sizes (bmr::Scene::EstimationWarnings). */
std::vector<std::string>
VoxelWarnings(const bmr::Scene & scene, const ImageBase<3> * moving, const ImageBase<3> * fixed)
{
  double finest = std::numeric_limits<double>::infinity(), coarsest = 0.0;
  for (const ImageBase<3> * image : { moving, fixed })
  {
    for (unsigned int a = 0; a < 3; ++a)
    {
      finest = std::min(finest, image->GetSpacing()[a]);
      coarsest = std::max(coarsest, image->GetSpacing()[a]);
    }
  }
  return scene.EstimationWarnings(finest, coarsest);
}

/** Warnings about uncertainties the surfaces leave (one sigma above 10 %, or no curvature at all). */
std::vector<std::string>
UncertaintyWarnings(const RegistrationResult & r)
{
  std::vector<std::string> warnings;
  for (const auto & kv : r.modulusUncertainty)
  {
    if (!std::isfinite(kv.second))
    {
      warnings.push_back("Phi* has no positive curvature in the modulus of \"" + kv.first +
                         "\" at the estimate: the surfaces do not determine it");
    }
    else if (kv.second > BiomechanicalUncertaintyWarningLogSigma)
    {
      const double       E = r.youngsModulus.at(kv.first);
      std::ostringstream os;
      os << "the surfaces determine the modulus of \"" << kv.first << "\" only to a factor exp(+-"
         << std::setprecision(3) << kv.second << ") (one standard deviation from the residual "
         << r.estimation.residualStandardDeviation << " mm and the curvature of Phi*): treat it as "
         << E * std::exp(-kv.second) << " to " << E * std::exp(kv.second) << " kPa";
      warnings.push_back(os.str());
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

/** Runs FEMElasticityOptimizer on the fine mesh (and a coarse one for the sweep) and keeps its outputs. */
void
Estimate(RegistrationResult &                                    r,
         const bmr::Scene &                                      scene,
         const std::map<std::string, Image<float, 3>::Pointer> & maps,
         const BiomechanicalLabelImageType *                     movingLabels,
         const RegistrationSettings &                            settings,
         pipeline::StageClock &                                  clock)
{
  auto optimizer = FEMElasticityOptimizer::New();
  auto fine = TetrahedralMeshObject::New();
  fine->Set(r.state.mesh);
  optimizer->SetMesh(fine);
  // Coarse-to-fine only when there is a modulus to sweep: nothing is meshed twice otherwise.
  if (!scene.UnknownLabels().empty() && settings.coarseFactor > 1.0)
  {
    auto coarse = TetrahedralMeshObject::New();
    coarse->Set(pipeline::MeshLabelImage(
      movingLabels, ScaledMeshSizes(scene, settings.coarseFactor), clock, "coarse mesh (sweep)"));
    optimizer->SetCoarseMesh(coarse);
  }
  optimizer->SetScene(scene);
  for (const auto & kv : maps)
  {
    optimizer->SetDistanceMap(kv.first, kv.second);
  }
  const bmr::EstimatorSettings & e = settings.estimator;
  optimizer->SetNumberOfSweepSamples(e.numberOfSweepSamples);
  optimizer->SetMaximumNumberOfInnerIterations(e.maximumInnerIterations);
  optimizer->SetMaximumNumberOfOuterIterations(e.maximumOuterIterations);
  optimizer->SetInnerGradientTolerance(e.innerGradientTolerance);
  optimizer->SetOuterGradientTolerance(e.outerGradientTolerance);
  optimizer->SetFlatnessThreshold(e.flatnessThreshold);
  optimizer->SetEstimateUncertainty(e.estimateUncertainty);
  optimizer->SetUncertaintyStep(e.uncertaintyStep);
  optimizer->SetLimitElementInversion(e.limitElementInversion);
  optimizer->SetWallControlSpacing(settings.walls.controlSpacing);
  optimizer->SetWallRegularization(settings.walls.regularization);
  optimizer->SetWallMotionAlongNormals(settings.walls.motion == bmr::WallMotionEnum::AlongNormals);
  ObserveIterations(optimizer, clock.GetObserver());
  optimizer->Update();
  for (const auto & kv : optimizer->GetTimings())
  {
    clock.Add("estimation: " + kv.first, kv.second);
  }
  r.estimation = optimizer->GetResult();
  r.youngsModulus = optimizer->GetEstimatedYoungsModuli();
  r.modulusUncertainty = optimizer->GetModulusUncertainty();
  r.gaugeLabel = optimizer->GetGaugeLabel();
  r.state.mesh = optimizer->GetOutput()->Get();
}

/** Per-element moduli, stress and the Dirichlet flags of the estimated state (for mesh.vtu). */
void
DescribeState(RegistrationResult & r, const bmr::Scene & scene)
{
  auto materials = bmr::SceneMaterials(scene);
  for (const auto & l : scene.labels)
  {
    const auto it = r.youngsModulus.find(l.name);
    if (it != r.youngsModulus.end())
    {
      materials[l.value].youngsModulus = it->second;
    }
  }
  const bmr::TetrahedralMesh &  mesh = r.state.mesh;
  const bmr::LinearElasticModel model(mesh, materials);
  bmr::ForwardSimulation &      s = r.state.simulation;
  s.displacement = mesh.displacement;
  s.force = mesh.force;
  s.vonMises = model.ComputeVonMisesStress(mesh.displacement);
  s.youngsModulus = model.GetElementYoungsModuli();
  s.poissonRatio = model.GetElementPoissonRatios();
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
} // namespace

RegistrationResult
RegisterSegmentedPair(const BiomechanicalLabelImageType * movingLabels,
                      const BiomechanicalLabelImageType * fixedLabels,
                      const BiomechanicalCTImageType *    movingCT,
                      const bmr::Scene &                  inputScene,
                      const RegistrationSettings &        settings,
                      PipelineObserver *                  observer)
{
  if (movingLabels == nullptr || fixedLabels == nullptr)
  {
    bmr::Fail("RegisterSegmentedPair", "the moving and the fixed label images are required");
  }
  CheckOverlap(movingLabels, fixedLabels);
  const bmr::Scene scene = ScaledMeshSizes(inputScene, settings.meshScale);
  scene.Validate();
  RegistrationResult   r;
  pipeline::StageClock clock(observer, r.state.stages);
  clock.Warn(r.state.warnings, scene.Warnings());
  clock.Warn(r.state.warnings, VoxelWarnings(scene, movingLabels, fixedLabels));

  clock.Begin("distance maps (fixed labels)");
  const auto maps = ComputeSceneDistanceMaps(fixedLabels, scene);
  clock.End(std::to_string(maps.size()) + " organs");
  r.state.mesh = pipeline::MeshLabelImage(movingLabels, scene, clock, "mesh (CGAL Mesh_3)");
  clock.Warn(r.state.warnings, bmr::MeshResolutionWarnings(scene, r.state.mesh));
  Estimate(r, scene, maps, movingLabels, settings, clock);
  r.unknowns = bmr::SceneUnknownModuli(scene);
  const bmr::SceneLabel * gauge = scene.FindLabel(r.gaugeLabel);
  r.gaugeModulus = gauge ? gauge->youngsModulus : 0.0;
  DescribeState(r, scene);

  pipeline::ComputeFields(r.state, fixedLabels, movingLabels, true, clock);
  clock.Begin("warp (CT linear; labels nearest)");
  r.warpedLabels = WarpImage(movingLabels, r.state.pullBack.GetPointer(), true, 0);
  if (movingCT)
  {
    r.warpedCT = WarpImage(movingCT, r.state.pullBack.GetPointer(), false, -1000.0f);
  }
  clock.End();
  clock.Begin("report (Dice, Jacobian)");
  clock.Warn(r.state.warnings, UncertaintyWarnings(r));
  Evaluate(r, scene, fixedLabels);
  clock.End();
  return r;
}

} // namespace itk
