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
} // namespace

bmr::WallMotionBasis
TrainWallBasis(const BiomechanicalLabelImageType *                      movingLabels,
               const std::vector<const BiomechanicalLabelImageType *> & fixedLabels,
               const bmr::Scene &                                       scene,
               const RegistrationSettings &                             settings,
               std::size_t                                              maximumModes,
               const std::string &                                      training)
{
  if (movingLabels == nullptr || fixedLabels.size() < 2 ||
      std::find(fixedLabels.begin(), fixedLabels.end(), nullptr) != fixedLabels.end())
  {
    bmr::FailInput("TrainWallBasis", "a moving label image and at least two fixed ones are required");
  }
  settings.Validate();
  const bmr::Scene scaled = ScaledMeshSizes(scene, settings.meshScale);
  scaled.Validate();
  std::vector<PipelineStage> untimed;
  pipeline::StageClock       quiet(nullptr, untimed);
  const bmr::TetrahedralMesh mesh =
    pipeline::MeshLabelImage(pipeline::MeshedAnatomy(movingLabels, settings), scaled, quiet, "mesh");
  std::vector<std::int32_t>        atlasNodes;
  bmr::WallMotionBasis             atlas = bmr::WallAtlas(mesh, bmr::SceneLoadedWalls(scaled, mesh), &atlasNodes);
  std::vector<std::vector<double>> examples;
  for (const BiomechanicalLabelImageType * fixed : fixedLabels)
  {
    pipeline::CheckOverlap(movingLabels, fixed);
    examples.push_back(MatchedWalls(mesh, atlasNodes, fixed, scaled, settings));
  }
  return bmr::TrainWallMotionBasis(std::move(atlas), examples, maximumModes, training);
}

} // namespace itk
