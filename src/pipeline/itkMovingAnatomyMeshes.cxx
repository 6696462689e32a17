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
// MeshMovingAnatomy: the meshes RegisterSegmentedPair() needs, made before the fixed scan is there.
#include "itkPipelineStages.h"

#include "bmrError.h"
#include "bmrHash.h"

namespace itk {
namespace pipeline {
namespace {
template<typename T>
std::uint64_t
HashValue(const T & value, std::uint64_t hash)
{
  return bmr::Fnv1a(&value, sizeof(T), hash);
}
} // namespace

std::uint64_t
MovingAnatomyFingerprint(const BiomechanicalLabelImageType * labels,
                         const bmr::Scene &                  scene,
                         const RegistrationSettings &        settings)
{
  std::uint64_t hash = bmr::Fnv1a(labels->GetBufferPointer(),
                                  labels->GetBufferedRegion().GetNumberOfPixels() * sizeof(*labels->GetBufferPointer()),
                                  bmr::FnvOffsetBasis);
  for (unsigned int a = 0; a < 3; ++a)
  {
    hash = HashValue(labels->GetLargestPossibleRegion().GetSize(a), hash);
    hash = HashValue(labels->GetSpacing()[a], hash);
    hash = HashValue(labels->GetOrigin()[a], hash);
    for (unsigned int b = 0; b < 3; ++b)
    {
      hash = HashValue(labels->GetDirection()[a][b], hash);
    }
  }
  const std::string json = bmr::SceneToJson(scene);
  hash = bmr::Fnv1a(json.data(), json.size(), hash);
  const UncertaintySettings & u = settings.uncertainty;
  for (double value : { settings.meshScale, settings.coarseFactor, u.meshJitter })
  {
    hash = HashValue(value, hash);
  }
  hash = HashValue(settings.interpolateSlices, hash);
  hash = HashValue(static_cast<int>(u.method), hash);
  hash = HashValue(u.resamples, hash);
  return HashValue(u.seed, hash);
}

bool
UsesCoarseMesh(const bmr::Scene & scaledScene, const RegistrationSettings & settings)
{
  return !scaledScene.UnknownLabels().empty() && settings.coarseFactor > 1.0;
}

bool
UsesResampleMeshes(const bmr::Scene & scaledScene, const RegistrationSettings & settings)
{
  const UncertaintySettings & u = settings.uncertainty;
  return (u.method == UncertaintyMethodEnum::Rescan || u.method == UncertaintyMethodEnum::Bootstrap) &&
         u.resamples > 0 && !scaledScene.UnknownLabels().empty();
}
} // namespace pipeline

MovingAnatomyMeshes
MeshMovingAnatomy(const BiomechanicalLabelImageType * movingLabels,
                  const bmr::Scene &                  scene,
                  const RegistrationSettings &        settings)
{
  settings.Validate(); // the mesh sizes and the resamples' jitter, as RegisterSegmentedPair() checks them
  if (movingLabels == nullptr)
  {
    bmr::FailInput("MeshMovingAnatomy", "the moving label image is required");
  }
  const bmr::Scene scaled = ScaledMeshSizes(scene, settings.meshScale);
  scaled.Validate();
  MovingAnatomyMeshes                             meshes;
  pipeline::StageClock                            clock(nullptr, meshes.stages);
  const BiomechanicalLabelImageType::ConstPointer anatomy = pipeline::MeshedAnatomy(movingLabels, settings);
  meshes.fine = pipeline::MeshLabelImage(anatomy, scaled, clock, "mesh (CGAL Mesh_3)");
  if (pipeline::UsesCoarseMesh(scaled, settings))
  {
    meshes.coarse =
      pipeline::MeshLabelImage(anatomy, ScaledMeshSizes(scaled, settings.coarseFactor), clock, "coarse mesh (sweep)");
  }
  if (pipeline::UsesResampleMeshes(scaled, settings))
  {
    clock.Begin("resample meshes");
    std::vector<PipelineStage> untimed;
    pipeline::StageClock       quiet(nullptr, untimed);
    for (unsigned int k = 0; k < settings.uncertainty.resamples; ++k)
    {
      meshes.resamples.push_back(pipeline::MeshLabelImage(
        anatomy, pipeline::ResampleMeshScene(scaled, settings.uncertainty, k), quiet, "resample mesh"));
    }
    clock.End(std::to_string(meshes.resamples.size()) + " meshes");
  }
  meshes.fingerprint = pipeline::MovingAnatomyFingerprint(movingLabels, scene, settings);
  return meshes;
}

} // namespace itk
