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
#include "itkWallBasisTraining.h"

#include "bmrError.h"
#include "itkPipelineStages.h"

namespace itk {
namespace {
/** The walls' nodes of \a mesh matched to \a fixedLabels' organs [mm], 3 per atlas point (\a atlasNodes). */
std::vector<double>
MatchedWalls(const bmr::TetrahedralMesh &        mesh,
             const std::vector<std::int32_t> &   atlasNodes,
             const BiomechanicalLabelImageType * fixedLabels,
             const bmr::Scene &                  scene,
             const RegistrationSettings &        settings)
{
  const auto maps = pipeline::ObjectiveDistanceMaps(
    fixedLabels, OrganProbabilityImages(), scene, SceneDistanceExactWithinMM, settings.interpolateSlices);
  auto optimizer = FEMElasticityOptimizer::New();
  optimizer->SetScene(scene);
  for (const auto & kv : maps)
  {
    optimizer->SetDistanceMap(kv.first, kv.second);
  }
  bmr::WallLoadSettings free; // the examples may move the walls in any direction
  free.motion = bmr::WallMotionEnum::Free;
  optimizer->SetWallLoadSettings(free);
  const std::vector<double> matched = optimizer->MakeObjective(mesh)->MatchDisplacement();
  std::vector<double>       example;
  example.reserve(3 * atlasNodes.size());
  for (std::int32_t node : atlasNodes)
  {
    example.insert(example.end(), &matched[3 * static_cast<std::size_t>(node)], &matched[3 * node + 3]);
  }
  return example;
}
/** A patient's walls: the moving labels meshed as a registration meshes them, and the walls' surface. */
struct PatientWalls
{
  bmr::TetrahedralMesh      mesh;
  bmr::WallMotionBasis      surface;
  std::vector<std::int32_t> nodes; // the mesh node of each surface point
};

PatientWalls
MeshWalls(const BiomechanicalLabelImageType * movingLabels, const bmr::Scene & scene, const RegistrationSettings & s)
{
  std::vector<PipelineStage> untimed;
  pipeline::StageClock       quiet(nullptr, untimed);
  PatientWalls               walls;
  walls.mesh = pipeline::MeshLabelImage(pipeline::MeshedAnatomy(movingLabels, s), scene, quiet, "mesh");
  walls.surface = bmr::WallAtlas(walls.mesh, bmr::SceneLoadedWalls(scene, walls.mesh), &walls.nodes);
  return walls;
}
} // namespace

bmr::WallMotionBasis
TrainWallBasis(const std::vector<WallBasisTrainingPatient> & patients,
               const bmr::Scene &                            scene,
               const RegistrationSettings &                  settings,
               std::size_t                                   maximumModes,
               const std::string &                           training)
{
  std::size_t examples = 0;
  for (const WallBasisTrainingPatient & patient : patients)
  {
    const auto & fixed = patient.fixedLabels;
    if (patient.movingLabels == nullptr || std::find(fixed.begin(), fixed.end(), nullptr) != fixed.end())
    {
      bmr::FailInput("TrainWallBasis", "every patient needs its moving label image and fixed ones");
    }
    examples += fixed.size();
  }
  if (examples < 2)
  {
    bmr::FailInput("TrainWallBasis", "a basis needs at least two examples (fixed label images) in all");
  }
  settings.Validate();
  const bmr::Scene scaled = ScaledMeshSizes(scene, settings.meshScale);
  scaled.Validate();
  const PatientWalls               atlas = MeshWalls(patients.front().movingLabels, scaled, settings);
  std::vector<std::vector<double>> atAtlas;
  for (const WallBasisTrainingPatient & patient : patients)
  {
    PatientWalls         other; // the first patient's walls are the atlas's, meshed once
    const PatientWalls & walls =
      &patient == &patients.front() ? atlas : (other = MeshWalls(patient.movingLabels, scaled, settings));
    // Where each atlas point lies on this patient's walls (on the atlas's own walls: where it is).
    const std::vector<double> fitted = bmr::FitAtlasToWalls(atlas.surface, walls.surface);
    for (const BiomechanicalLabelImageType * fixed : patient.fixedLabels)
    {
      pipeline::CheckOverlap(patient.movingLabels, fixed);
      bmr::WallMotionBasis example = walls.surface; // the example as a field on the patient's walls
      example.mean = MatchedWalls(walls.mesh, walls.nodes, fixed, scaled, settings);
      atAtlas.push_back(bmr::TransferWallMotionBasis(example, 0, fitted, atlas.surface.pointWalls).mean);
    }
  }
  return bmr::TrainWallMotionBasis(atlas.surface, atAtlas, maximumModes, training);
}

bmr::WallMotionBasis
TrainWallBasis(const BiomechanicalLabelImageType *                      movingLabels,
               const std::vector<const BiomechanicalLabelImageType *> & fixedLabels,
               const bmr::Scene &                                       scene,
               const RegistrationSettings &                             settings,
               std::size_t                                              maximumModes,
               const std::string &                                      training)
{
  return TrainWallBasis({ { movingLabels, fixedLabels } }, scene, settings, maximumModes, training);
}

} // namespace itk
